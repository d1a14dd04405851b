//! Deep validation (SPEC.md Appendix C): every rule checked, every violation reported with a
//! location, never stopping at the first. Work is linear in the size of the container, and the
//! number of stored problems is capped so that a hostile file cannot exhaust memory.

use crate::layout::*;
use crate::model::*;
use crate::problem::Problem;
use crate::read::{read_from_layout, ReadOptions};
use crate::rules::{self, ring_range, Flow, Sink, Stop, Table};

/// Problems stored before the rest are only counted.
pub const MAX_PROBLEMS: usize = 1000;

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

/// Reads and validates a container in one pass over its bytes, for a loader that needs the
/// model and may only use a valid one: every checksum computed once, the content validated once
/// (the geometry hashes included). `Err` when the structure cannot be read at all; otherwise the
/// container and its problems ([`validate_bytes`]'s list, empty when the file is valid).
pub fn read_validated(bytes: &[u8]) -> Result<(Container, Vec<Problem>), crate::ReadError> {
    let mut p = Problems::default();
    let container = read_checked(bytes, &mut p)?;
    Ok((container, p.finish()))
}

/// [`validate_bytes`] into `p`; returns the container when its content could be read.
pub(crate) fn validate_bytes_into(bytes: &[u8], p: &mut Problems) -> Option<Container> {
    match read_checked(bytes, p) {
        Ok(c) => Some(c),
        Err(e) => {
            p.push("file", e.to_string());
            None
        }
    }
}

/// The layout, checksums, padding and trailing bytes into `p`, then the content read (checksums
/// not verified twice) and validated into `p`. `Err` when the layout or the content cannot be
/// read.
fn read_checked(bytes: &[u8], p: &mut Problems) -> Result<Container, crate::ReadError> {
    let layout = read_layout(bytes)?;
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
    let c = read_from_layout(
        bytes,
        &layout,
        &ReadOptions {
            verify_checksums: false,
        },
    )?;
    validate_into(&c, p);
    Ok(c)
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

/// The validator's sink: every problem of object `at`, located, and never a stop.
struct ObjectProblems<'a> {
    at: &'a str,
    p: &'a mut Problems,
}

impl Sink for ObjectProblems<'_> {
    fn report(&mut self, location: String, message: String) -> Flow {
        self.p.push(format!("{}.{location}", self.at), message);
        Ok(())
    }
}

/// Runs a rule against the validator's sink, which never stops.
fn go<T>(r: Result<T, Stop>) -> Option<T> {
    r.ok()
}

fn validate_mesh(at: &str, m: &ControlMesh, p: &mut Problems) {
    let nv = m.positions.len() / 3;
    let nf = m.triangles.len() / 3;
    let s = &mut ObjectProblems { at, p };
    go(rules::triples(m, s));
    if let Some(k) = m.positions.iter().position(|x| !x.is_finite()) {
        go(s.report(
            format!("mesh.positions[{}]", k / 3),
            "coordinate is not finite".into(),
        ));
    }
    let tri_ok: Vec<bool> = (0..nf)
        .map(|t| go(rules::triangle_corners(m, t, s)).unwrap_or(false))
        .collect();
    let mut length = |table| go(rules::table_length(m, table, s)).unwrap_or(false);
    let mut rings_ok = length(Table::RingOffsets);
    rings_ok &= length(Table::SpokeFlags);
    let flags_ok = length(Table::VertexFlags);
    let cs_ok = length(Table::CornerSpokes);
    let nb_ok = length(Table::Neighbours);
    let ed_ok = length(Table::Edges);
    if rings_ok {
        rings_ok = go(rules::ring_offsets(m, s)).unwrap_or(false);
    }
    if rings_ok {
        for v in 0..nv {
            go(rules::vertex_ring(m, v, s));
            if flags_ok {
                go(rules::vertex_rule(m, v, s));
            }
        }
        check_spoke_pairs(at, m, s.p);
    }
    if cs_ok && rings_ok && flags_ok {
        for t in (0..nf).filter(|&t| tri_ok[t]) {
            for c in 0..3 {
                go(rules::corner_spoke(m, t, c, s));
            }
        }
    }
    if nb_ok {
        for t in (0..nf).filter(|&t| tri_ok[t]) {
            for e in 0..3 {
                go(rules::neighbour(m, t, e, cs_ok && rings_ok, ed_ok, s));
            }
        }
    }
    if ed_ok {
        go(rules::edge_ids(m, nb_ok, s));
    }
}

/// Rule 2 (the rest): every spoke `v → w` has its reverse `w → v`, both carry the same sharp
/// bit (an edge is sharp or not, whichever end looks at it), and so `R = 2·E` (SPEC.md A.7).
fn check_spoke_pairs(at: &str, m: &ControlMesh, p: &mut Problems) {
    let nv = m.positions.len() / 3;
    let mut spoke_of: std::collections::HashMap<(u32, u32), usize> =
        std::collections::HashMap::with_capacity(m.ring.len());
    for v in 0..nv {
        let Some((a, b)) = ring_range(m, v) else {
            continue;
        };
        for s in a..b {
            spoke_of.insert((v as u32, m.ring[s]), s);
        }
    }
    for v in 0..nv {
        let Some((a, b)) = ring_range(m, v) else {
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
    let s = &mut ObjectProblems { at, p };
    go(rules::record_count(o, s));
    // Rule 8: normals.
    for (k, n) in o.normals.iter().enumerate() {
        let len = (n[0] * n[0] + n[1] * n[1] + n[2] * n[2]).sqrt();
        if !len.is_finite() || (len - 1.0).abs() > 1e-3 {
            go(s.report(
                format!("normals[{k}]"),
                format!("{n:?} has length {len}, not 1"),
            ));
        }
    }
    go(rules::bitstream_words(o, s));
    // Rule 7: triangle records; trees decoded in linear time (see `triangle_trees`).
    let shapes = crate::tree::triangle_trees(o);
    for (t, shape) in shapes.iter().enumerate() {
        go(rules::record_normal_count(o, t, s));
        go(rules::flat_record(o, t, s));
        go(rules::record_ranges(o, t, shape, s));
    }
}
