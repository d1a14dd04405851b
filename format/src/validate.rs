//! Deep validation (SPEC.md Appendix C): every rule checked, every violation reported with a
//! location, never stopping at the first. Work is linear in the size of the container, and the
//! number of stored problems is capped so that a hostile file cannot exhaust memory.

use crate::layout::*;
use crate::model::*;
use crate::read::{read_from_layout, ReadOptions};
use std::fmt;

/// Problems stored before the rest are only counted.
pub const MAX_PROBLEMS: usize = 1000;

/// One rule violation: where and what.
#[derive(Clone, Debug, PartialEq, Eq)]
pub struct Problem {
    /// A path such as `objects[2].triangles[517]` or `sections[4]`.
    pub location: String,
    pub message: String,
}

impl fmt::Display for Problem {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        write!(f, "{}: {}", self.location, self.message)
    }
}

#[derive(Default)]
pub(crate) struct Problems {
    list: Vec<Problem>,
    dropped: usize,
}

impl Problems {
    pub(crate) fn push(&mut self, location: impl Into<String>, message: impl Into<String>) {
        if self.list.len() < MAX_PROBLEMS {
            self.list.push(Problem {
                location: location.into(),
                message: message.into(),
            });
        } else {
            self.dropped += 1;
        }
    }

    pub(crate) fn finish(mut self) -> Vec<Problem> {
        if self.dropped > 0 {
            self.list.push(Problem {
                location: "file".into(),
                message: format!("{} more problems not listed", self.dropped),
            });
        }
        self.list
    }
}

/// Validates a container file: structure, checksums, padding, then content. An empty result
/// means the file is valid.
pub fn validate_bytes(bytes: &[u8]) -> Vec<Problem> {
    let mut p = Problems::default();
    let _ = validate_bytes_into(bytes, &mut p);
    p.finish()
}

/// [`validate_bytes`] into `p`; returns the container when its content could be read.
pub(crate) fn validate_bytes_into(bytes: &[u8], p: &mut Problems) -> Option<Container> {
    let layout = match read_layout(bytes) {
        Ok(l) => l,
        Err(e) => {
            p.push("file", e.to_string());
            return None;
        }
    };
    for (i, s) in layout.sections.iter().enumerate() {
        let computed = s.computed_crc32(bytes);
        if computed != s.crc32 {
            p.push(
                format!("sections[{i}] ({})", s.describe()),
                format!(
                    "checksum mismatch (stored {:08x}, computed {computed:08x}): the section is corrupted (SPEC.md A.4)",
                    s.crc32
                ),
            );
        }
    }
    check_padding(bytes, &layout, p);
    check_trailing(&layout, p);
    match read_from_layout(
        bytes,
        &layout,
        &ReadOptions {
            verify_checksums: false,
        },
    ) {
        Ok(c) => {
            validate_into(&c, p);
            Some(c)
        }
        Err(e) => {
            p.push("file", e.to_string());
            None
        }
    }
}

fn check_padding(bytes: &[u8], layout: &Layout, p: &mut Problems) {
    let mut covered: Vec<(u64, u64)> = layout
        .sections
        .iter()
        .map(|s| (s.offset, s.offset + s.length))
        .collect();
    covered.push((0, layout.directory_end()));
    covered.sort_unstable();
    let mut pos = 0u64;
    for (start, end) in covered {
        if start > pos {
            // Sections are inside the file (read_layout), so this range is too.
            let gap = &bytes[pos as usize..start as usize];
            if let Some(k) = gap.iter().position(|&b| b != 0) {
                p.push(
                    format!("file[{}]", pos + k as u64),
                    "padding byte between sections is not zero (SPEC.md A.1)",
                );
            }
        }
        pos = pos.max(end);
    }
}

/// SPEC.md A.1: `file_length` is the end of the section that ends last (or of the directory),
/// so bytes after it are an error even when they are zero.
fn check_trailing(layout: &Layout, p: &mut Problems) {
    let end = layout
        .sections
        .iter()
        .map(|s| s.offset + s.length)
        .max()
        .unwrap_or(0)
        .max(layout.directory_end());
    let file_length = layout.header.file_length;
    if file_length > end {
        p.push(
            format!("file[{end}]"),
            format!(
                "{} bytes after the last section: file_length must be the end of the last section (SPEC.md A.1)",
                file_length - end
            ),
        );
    }
}

/// Validates the content of a container (SPEC.md Appendix C, rules 1–11).
pub fn validate(c: &Container) -> Vec<Problem> {
    let mut p = Problems::default();
    validate_into(c, &mut p);
    p.finish()
}

fn validate_into(c: &Container, p: &mut Problems) {
    validate_metadata(&c.metadata, p);
    for (i, o) in c.objects.iter().enumerate() {
        let at = format!("objects[{i}]");
        validate_mesh(&at, &o.mesh, p);
        validate_geometry_hash(&at, o, p);
        validate_shading(&at, o, p);
    }
}

/// SPEC.md A.6: the bake parameters are a JSON object text or empty.
fn validate_metadata(m: &Metadata, p: &mut Problems) {
    if m.bake_parameters.is_empty() {
        return;
    }
    match serde_json::from_str::<serde_json::Value>(&m.bake_parameters) {
        Ok(v) if v.is_object() => {}
        Ok(_) => p.push(
            "metadata.bake_parameters",
            "is JSON but not an object; it must be a JSON object text or empty (SPEC.md A.6)",
        ),
        Err(e) => p.push(
            "metadata.bake_parameters",
            format!("is not JSON ({e}); it must be a JSON object text or empty (SPEC.md A.6)"),
        ),
    }
}

/// Rule 11 (SPEC.md A.7, 2.5): the stored geometry hash is that of the control triangles.
fn validate_geometry_hash(at: &str, o: &Object, p: &mut Problems) {
    let m = &o.mesh;
    let nv = m.positions.len() / 3;
    if m.positions.len() % 3 != 0
        || m.triangles.len() % 3 != 0
        || m.triangles.iter().any(|&v| v as usize >= nv)
    {
        return; // Reported by rule 1; the hash cannot be computed.
    }
    let computed = geometry_hash(m.triangles.iter().map(|&v| m.position(v)));
    if computed != o.geometry_hash {
        p.push(
            format!("{at}.geometry_hash"),
            format!(
                "stored {:016x} but the control triangles hash to {computed:016x}: POSN or TRIS was edited after baking (SPEC.md A.7, 2.5)",
                o.geometry_hash
            ),
        );
    }
}

fn valence_ok(m: &ControlMesh, v: usize) -> Option<(usize, usize)> {
    let a = *m.ring_offsets.get(v)? as usize;
    let b = *m.ring_offsets.get(v + 1)? as usize;
    (a <= b && b <= m.ring.len()).then_some((a, b))
}

fn validate_mesh(at: &str, m: &ControlMesh, p: &mut Problems) {
    let nv = m.positions.len() / 3;
    let nf = m.triangles.len() / 3;
    if m.positions.len() % 3 != 0 {
        p.push(
            format!("{at}.mesh.positions"),
            format!("length {} is not a multiple of 3", m.positions.len()),
        );
    }
    if m.triangles.len() % 3 != 0 {
        p.push(
            format!("{at}.mesh.triangles"),
            format!("length {} is not a multiple of 3", m.triangles.len()),
        );
    }
    if let Some(k) = m.positions.iter().position(|x| !x.is_finite()) {
        p.push(
            format!("{at}.mesh.positions[{}]", k / 3),
            "coordinate is not finite",
        );
    }
    for t in 0..nf {
        let tri = m.triangle(t);
        if let Some(&v) = tri.iter().find(|&&v| v as usize >= nv) {
            p.push(
                format!("{at}.mesh.triangles[{t}]"),
                format!("vertex index {v} is out of range ({nv} vertices)"),
            );
        } else if tri[0] == tri[1] || tri[1] == tri[2] || tri[2] == tri[0] {
            p.push(
                format!("{at}.mesh.triangles[{t}]"),
                format!("degenerate triangle {tri:?} repeats a vertex"),
            );
        }
    }

    // Rings (rule 2).
    let mut rings_ok = true;
    let check_len = |field: &str, len: usize, want: usize, what: &str, p: &mut Problems| {
        if len != want {
            p.push(
                format!("{at}.mesh.{field}"),
                format!("length {len}, expected {want} ({what})"),
            );
            false
        } else {
            true
        }
    };
    rings_ok &= check_len(
        "ring_offsets",
        m.ring_offsets.len(),
        nv + 1,
        "vertices + 1",
        p,
    );
    rings_ok &= check_len(
        "spoke_flags",
        m.spoke_flags.len(),
        m.ring.len(),
        "one per ring entry",
        p,
    );
    let flags_ok = check_len(
        "vertex_flags",
        m.vertex_flags.len(),
        nv,
        "one per vertex",
        p,
    );
    let cs_ok = check_len(
        "corner_spokes",
        m.corner_spokes.len(),
        3 * nf,
        "three per triangle",
        p,
    );
    let nb_ok = check_len(
        "neighbours",
        m.neighbours.len(),
        3 * nf,
        "three per triangle",
        p,
    );
    let ed_ok = check_len("edges", m.edges.len(), 3 * nf, "three per triangle", p);
    if rings_ok {
        if m.ring_offsets[0] != 0 {
            p.push(
                format!("{at}.mesh.ring_offsets[0]"),
                format!("is {}, must be 0", m.ring_offsets[0]),
            );
            rings_ok = false;
        }
        if let Some(v) = (0..nv).find(|&v| m.ring_offsets[v] > m.ring_offsets[v + 1]) {
            p.push(
                format!("{at}.mesh.ring_offsets[{v}]"),
                "ring offsets decrease",
            );
            rings_ok = false;
        }
        if m.ring_offsets[nv] as usize != m.ring.len() {
            p.push(
                format!("{at}.mesh.ring_offsets[{nv}]"),
                format!(
                    "is {}, must equal the ring length {}",
                    m.ring_offsets[nv],
                    m.ring.len()
                ),
            );
            rings_ok = false;
        }
    }
    if rings_ok {
        for v in 0..nv {
            let Some((a, b)) = valence_ok(m, v) else {
                continue;
            };
            if b - a < 2 {
                p.push(
                    format!("{at}.mesh.vertices[{v}]"),
                    format!(
                        "valence {} < 2: the vertex is unused by any triangle or the ring is wrong",
                        b - a
                    ),
                );
            }
            for s in a..b {
                let w = m.ring[s];
                if w as usize >= nv || w as usize == v {
                    p.push(
                        format!("{at}.mesh.ring[{s}]"),
                        format!("spoke {w} of vertex {v} is out of range or the vertex itself"),
                    );
                }
                let f = m.spoke_flags[s];
                if f & !(SPOKE_SHARP | SPOKE_BOUNDARY) != 0 {
                    p.push(
                        format!("{at}.mesh.spoke_flags[{s}]"),
                        format!("unknown bits in {f:#x}"),
                    );
                }
                if f & SPOKE_BOUNDARY != 0 && f & SPOKE_SHARP == 0 {
                    p.push(
                        format!("{at}.mesh.spoke_flags[{s}]"),
                        "boundary spoke is not marked sharp",
                    );
                }
            }
            if !flags_ok {
                continue;
            }
            // Rule 3: boundary flag and vertex rule agree with the spokes.
            let flags = m.vertex_flags[v];
            let vat = || format!("{at}.mesh.vertex_flags[{v}]");
            if flags & !(VERTEX_BOUNDARY | VERTEX_RULE_MASK) != 0 {
                p.push(vat(), format!("unknown bits in {flags:#x}"));
            }
            let boundary_spokes: Vec<usize> = (a..b)
                .filter(|&s| m.spoke_flags[s] & SPOKE_BOUNDARY != 0)
                .collect();
            let is_boundary = flags & VERTEX_BOUNDARY != 0;
            if is_boundary {
                if b - a < 2 || boundary_spokes != [a, b - 1] {
                    p.push(vat(), "boundary vertex whose first and last spokes are not exactly its boundary spokes");
                }
            } else if !boundary_spokes.is_empty() {
                p.push(vat(), "interior vertex with a boundary spoke");
            }
            let sharp = (a..b)
                .filter(|&s| m.spoke_flags[s] & SPOKE_SHARP != 0)
                .count();
            let expected = if (is_boundary && b - a == 2) || sharp >= 3 {
                RULE_CORNER
            } else if sharp == 2 {
                RULE_CREASE
            } else {
                RULE_SMOOTH
            };
            let rule = (flags & VERTEX_RULE_MASK) >> VERTEX_RULE_SHIFT;
            if rule != expected {
                p.push(vat(), format!("rule {rule} but {sharp} sharp spokes (valence {}) make it {expected} (SPEC.md C.3)", b - a));
            }
        }
    }

    if rings_ok {
        check_spoke_pairs(at, m, p);
    }

    let tri_ok = |t: usize| m.triangle(t).iter().all(|&v| (v as usize) < nv);
    // Rule 4: corner spokes.
    if cs_ok && rings_ok && flags_ok {
        for t in (0..nf).filter(|&t| tri_ok(t)) {
            let tri = m.triangle(t);
            for c in 0..3 {
                let v = tri[c] as usize;
                let Some((a, b)) = valence_ok(m, v) else {
                    continue;
                };
                let val = b - a;
                let k = m.corner_spokes[3 * t + c] as usize;
                let cat = || format!("{at}.mesh.corner_spokes[{}]", 3 * t + c);
                if k >= val {
                    p.push(
                        cat(),
                        format!("spoke {k} is out of vertex {v}'s ring of {val}"),
                    );
                    continue;
                }
                let next = if k + 1 < val {
                    Some(k + 1)
                } else if m.vertex_flags[v] & VERTEX_BOUNDARY == 0 {
                    Some(0)
                } else {
                    None
                };
                let (v1, v2) = (tri[(c + 1) % 3], tri[(c + 2) % 3]);
                if m.ring[a + k] != v1 {
                    p.push(
                        cat(),
                        format!(
                            "ring of vertex {v} has {} at position {k}, triangle {t} needs {v1}",
                            m.ring[a + k]
                        ),
                    );
                } else if next.map(|n| m.ring[a + n]) != Some(v2) {
                    p.push(cat(), format!("the spoke after position {k} in vertex {v}'s ring is not {v2}: the ring is not counter-clockwise or misses triangle {t}"));
                }
            }
        }
    }

    // Rule 5: neighbours.
    if nb_ok {
        for t in (0..nf).filter(|&t| tri_ok(t)) {
            let tri = m.triangle(t);
            for e in 0..3 {
                let n = m.neighbours[3 * t + e];
                let nat = || format!("{at}.mesh.neighbours[{}]", 3 * t + e);
                let (va, vb) = (tri[e], tri[(e + 1) % 3]);
                if n == NO_NEIGHBOUR {
                    if cs_ok && rings_ok {
                        if let Some((a, b)) = valence_ok(m, va as usize) {
                            let k = m.corner_spokes[3 * t + e] as usize;
                            if a + k < b && m.spoke_flags[a + k] & SPOKE_BOUNDARY == 0 {
                                p.push(nat(), format!("edge ({va}, {vb}) has no neighbour but its spoke is not marked boundary"));
                            }
                        }
                    }
                    continue;
                }
                if n as usize >= nf {
                    p.push(
                        nat(),
                        format!("neighbour {n} is out of range ({nf} triangles)"),
                    );
                    continue;
                }
                let u = n as usize;
                let ut = m.triangle(u);
                match (0..3).find(|&f| ut[f] == vb && ut[(f + 1) % 3] == va) {
                    None => p.push(
                        nat(),
                        format!("triangle {u} does not have edge ({vb}, {va})"),
                    ),
                    Some(f) => {
                        if m.neighbours[3 * u + f] != t as u32 {
                            p.push(nat(), format!("triangle {u} does not name {t} as its neighbour across the shared edge"));
                        }
                        if ed_ok && m.edges[3 * u + f] != m.edges[3 * t + e] {
                            p.push(
                                format!("{at}.mesh.edges[{}]", 3 * t + e),
                                format!(
                                    "id {} differs from id {} of the same edge in triangle {u}",
                                    m.edges[3 * t + e],
                                    m.edges[3 * u + f]
                                ),
                            );
                        }
                    }
                }
            }
        }
    }

    // Rule 6: edge ids dense in first-appearance order, interior twice, boundary once.
    if ed_ok {
        let mut next: u32 = 0;
        let mut seen = vec![0u8; 0];
        for (i, &id) in m.edges.iter().enumerate() {
            if id == next {
                next += 1;
                seen.push(1);
            } else if id > next {
                p.push(format!("{at}.mesh.edges[{i}]"), format!("id {id} skips ahead of {next}: ids must be numbered in order of first appearance"));
            } else {
                let s = &mut seen[id as usize];
                *s = s.saturating_add(1);
            }
        }
        if nb_ok {
            for (i, &id) in m.edges.iter().enumerate() {
                let Some(&count) = seen.get(id as usize) else {
                    continue;
                };
                let want = if m.neighbours[i] == NO_NEIGHBOUR {
                    1
                } else {
                    2
                };
                if count != want {
                    p.push(
                        format!("{at}.mesh.edges[{i}]"),
                        format!(
                            "id {id} appears {count} times, a {} edge's id appears {want}",
                            if want == 1 { "boundary" } else { "interior" }
                        ),
                    );
                }
            }
        }
    }
}

/// Rule 2 (the rest): every spoke `v → w` has its reverse `w → v`, both carry the same sharp
/// bit (an edge is sharp or not, whichever end looks at it), and so `R = 2·E` (SPEC.md A.7).
fn check_spoke_pairs(at: &str, m: &ControlMesh, p: &mut Problems) {
    let nv = m.positions.len() / 3;
    let mut spoke_of: std::collections::HashMap<(u32, u32), usize> =
        std::collections::HashMap::with_capacity(m.ring.len());
    for v in 0..nv {
        let Some((a, b)) = valence_ok(m, v) else {
            continue;
        };
        for s in a..b {
            spoke_of.insert((v as u32, m.ring[s]), s);
        }
    }
    for v in 0..nv {
        let Some((a, b)) = valence_ok(m, v) else {
            continue;
        };
        for s in a..b {
            let w = m.ring[s];
            if w as usize >= nv || w as usize == v {
                continue; // Reported above.
            }
            match spoke_of.get(&(w, v as u32)) {
                None => p.push(
                    format!("{at}.mesh.ring[{s}]"),
                    format!("vertex {v} has spoke {w} but vertex {w}'s ring has no spoke {v}: every edge is in both endpoints' rings (SPEC.md A.7)"),
                ),
                Some(&r) => {
                    // Reported once, from the end with the smaller index.
                    let sharp = m.spoke_flags[s] & SPOKE_SHARP;
                    if (v as u32) < w && sharp != m.spoke_flags[r] & SPOKE_SHARP {
                        p.push(
                            format!("{at}.mesh.spoke_flags[{s}]"),
                            format!(
                                "edge ({v}, {w}) is {} seen from {v} but {} seen from {w} (spoke_flags[{r}]): the sharp bit must be set on both ends or neither (SPEC.md C.3)",
                                if sharp != 0 { "sharp" } else { "smooth" },
                                if sharp != 0 { "smooth" } else { "sharp" },
                            ),
                        );
                    }
                }
            }
        }
    }
    let edge_count = m.edges.iter().max().map_or(0, |&e| u64::from(e) + 1);
    if m.ring.len() as u64 != 2 * edge_count {
        p.push(
            format!("{at}.mesh.ring"),
            format!(
                "ring_length {} but {edge_count} edges need 2 x {edge_count} = {} spokes (SPEC.md A.7)",
                m.ring.len(),
                2 * edge_count
            ),
        );
    }
}

fn validate_shading(at: &str, o: &Object, p: &mut Problems) {
    let nf = o.mesh.triangles.len() / 3;
    if o.triangles.len() != nf {
        p.push(
            format!("{at}.triangles"),
            format!("{} records for {nf} mesh triangles", o.triangles.len()),
        );
    }
    // Rule 8: normals.
    for (k, n) in o.normals.iter().enumerate() {
        let len = (n[0] * n[0] + n[1] * n[1] + n[2] * n[2]).sqrt();
        if !len.is_finite() || (len - 1.0).abs() > 1e-3 {
            p.push(
                format!("{at}.normals[{k}]"),
                format!("{n:?} has length {len}, not 1"),
            );
        }
    }
    // Rule 9: bitstream words.
    let words = o.bit_len.div_ceil(32);
    if words != o.bits.len() as u64 {
        p.push(
            format!("{at}.bits"),
            format!(
                "{} words, but bit_len {} needs {words}",
                o.bits.len(),
                o.bit_len
            ),
        );
    } else if o.bit_len % 32 != 0 {
        if let Some(&last) = o.bits.last() {
            if last >> (o.bit_len % 32) != 0 {
                p.push(format!("{at}.bits"), "bits past bit_len are not zero");
            }
        }
    }
    // Rule 7: triangle records; trees decoded in linear time (see `triangle_trees`).
    let shapes = crate::tree::triangle_trees(o);
    for (t, r) in o.triangles.iter().enumerate() {
        let tat = || format!("{at}.triangles[{t}]");
        if r.normal_count == 0 {
            p.push(
                tat(),
                "normal_count is 0; every triangle has at least its geometric normal",
            );
        }
        if o.kind == ObjectKind::Flat && r.normal_count > 1 {
            p.push(
                tat(),
                format!(
                    "flat objects have one normal per triangle, found {}",
                    r.normal_count
                ),
            );
        }
        let n = u64::from(r.normal_count);
        if u64::from(r.normal_start) + n > o.normals.len() as u64 {
            p.push(
                tat(),
                format!(
                    "normals {}..{} run past the {} normals",
                    r.normal_start,
                    u64::from(r.normal_start) + n,
                    o.normals.len()
                ),
            );
        }
        match &shapes[t] {
            Ok(shape) => {
                let end = u64::from(r.colour_start) + u64::from(shape.node_count) * n;
                if end > o.colours.len() as u64 {
                    p.push(
                        tat(),
                        format!(
                            "colours {}..{end} for {} nodes x {n} normals run past the {} colours",
                            r.colour_start,
                            shape.node_count,
                            o.colours.len()
                        ),
                    );
                }
            }
            Err(e) => p.push(tat(), e.to_string()),
        }
    }
}
