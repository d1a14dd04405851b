//! The rules of SPEC.md Appendix C on one object's tables, each written once. A rule reports
//! what it finds to a [`Sink`] chosen by its caller:
//!
//! * the validator ([`crate::validate_bytes`]) collects every problem with its location and
//!   goes on;
//! * the guard of the code that indexes the tables (`hce_geometry::tables`) keeps the first
//!   problem and stops ([`first_problem`]), so that a malformed table is an error and never an
//!   out-of-bounds read.
//!
//! Locations are relative to the object (`mesh.triangles[3]`); the validator prefixes
//! `objects[i].`. A rule that needs another table to be well formed says so; its caller runs
//! it only when that one passed. The rules that only the validator applies (finite positions,
//! spoke pairs, unit normals, the geometry hash) stay in `validate.rs`.

use crate::model::*;
use crate::problem::Problem;
use crate::tree::{TreeError, TreeShape};

/// What a sink returns to end a check: the rule returns at once, and so does its caller.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub struct Stop;

/// The outcome of a rule: `Err(Stop)` when the sink asked to stop.
pub type Flow = Result<(), Stop>;

/// Where rules report problems.
pub trait Sink {
    /// One problem at `location` (relative to the object). `Err(Stop)` ends the check.
    fn report(&mut self, location: String, message: String) -> Flow;
}

/// A sink that keeps the first problem and stops.
#[derive(Debug, Default)]
pub struct FirstProblem(pub Option<Problem>);

impl Sink for FirstProblem {
    fn report(&mut self, location: String, message: String) -> Flow {
        self.0 = Some(Problem { location, message });
        Err(Stop)
    }
}

/// Runs `check` against a [`FirstProblem`] sink: its value, or the first problem reported.
pub fn first_problem<T>(
    check: impl FnOnce(&mut FirstProblem) -> Result<T, Stop>,
) -> Result<T, Problem> {
    let mut sink = FirstProblem::default();
    check(&mut sink).map_err(|Stop| {
        sink.0.take().unwrap_or_else(|| Problem {
            location: "object".into(),
            message: "check stopped without a problem".into(),
        })
    })
}

/// The range of vertex `v`'s spokes in the ring array, when its offsets allow one.
pub(crate) fn ring_range(m: &ControlMesh, v: usize) -> Option<(usize, usize)> {
    let a = *m.ring_offsets.get(v)? as usize;
    let b = *m.ring_offsets.get(v + 1)? as usize;
    (a <= b && b <= m.ring.len()).then_some((a, b))
}

/// Rule 1: positions and triangles come in whole triples.
pub fn triples(m: &ControlMesh, s: &mut impl Sink) -> Flow {
    for (field, len) in [
        ("positions", m.positions.len()),
        ("triangles", m.triangles.len()),
    ] {
        if len % 3 != 0 {
            s.report(
                format!("mesh.{field}"),
                format!("length {len} is not a multiple of 3"),
            )?;
        }
    }
    Ok(())
}

/// Rule 1: triangle `t`'s corners are vertices in range, three different ones. Returns whether
/// the corners are in range (the rules that follow them need that).
pub fn triangle_corners(m: &ControlMesh, t: usize, s: &mut impl Sink) -> Result<bool, Stop> {
    let nv = m.positions.len() / 3;
    let tri = m.triangle(t);
    if let Some(&v) = tri.iter().find(|&&v| v as usize >= nv) {
        s.report(
            format!("mesh.triangles[{t}]"),
            format!("vertex index {v} is out of range ({nv} vertices)"),
        )?;
        return Ok(false);
    }
    if tri[0] == tri[1] || tri[1] == tri[2] || tri[2] == tri[0] {
        s.report(
            format!("mesh.triangles[{t}]"),
            format!("degenerate triangle {tri:?} repeats a vertex"),
        )?;
    }
    Ok(true)
}

/// A table of a control mesh whose length the vertex and triangle counts fix.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum Table {
    RingOffsets,
    SpokeFlags,
    VertexFlags,
    CornerSpokes,
    Neighbours,
    Edges,
}

/// Rules 2 to 6: the length of `table`. Returns whether it is right.
pub fn table_length(m: &ControlMesh, table: Table, s: &mut impl Sink) -> Result<bool, Stop> {
    let nv = m.positions.len() / 3;
    let nf = m.triangles.len() / 3;
    let (field, len, want, what) = match table {
        Table::RingOffsets => ("ring_offsets", m.ring_offsets.len(), nv + 1, "vertices + 1"),
        Table::SpokeFlags => (
            "spoke_flags",
            m.spoke_flags.len(),
            m.ring.len(),
            "one per ring entry",
        ),
        Table::VertexFlags => ("vertex_flags", m.vertex_flags.len(), nv, "one per vertex"),
        Table::CornerSpokes => (
            "corner_spokes",
            m.corner_spokes.len(),
            3 * nf,
            "three per triangle",
        ),
        Table::Neighbours => (
            "neighbours",
            m.neighbours.len(),
            3 * nf,
            "three per triangle",
        ),
        Table::Edges => ("edges", m.edges.len(), 3 * nf, "three per triangle"),
    };
    if len != want {
        s.report(
            format!("mesh.{field}"),
            format!("length {len}, expected {want} ({what})"),
        )?;
        return Ok(false);
    }
    Ok(true)
}

/// Rule 2: the ring offsets start at 0, never decrease and end at the ring's length. Needs the
/// lengths of `ring_offsets` and `spoke_flags`. Returns whether they do.
pub fn ring_offsets(m: &ControlMesh, s: &mut impl Sink) -> Result<bool, Stop> {
    let nv = m.positions.len() / 3;
    let mut ok = true;
    if m.ring_offsets[0] != 0 {
        s.report(
            "mesh.ring_offsets[0]".into(),
            format!("is {}, must be 0", m.ring_offsets[0]),
        )?;
        ok = false;
    }
    if let Some(v) = (0..nv).find(|&v| m.ring_offsets[v] > m.ring_offsets[v + 1]) {
        s.report(
            format!("mesh.ring_offsets[{v}]"),
            "ring offsets decrease".into(),
        )?;
        ok = false;
    }
    if m.ring_offsets[nv] as usize != m.ring.len() {
        s.report(
            format!("mesh.ring_offsets[{nv}]"),
            format!(
                "is {}, must equal the ring length {}",
                m.ring_offsets[nv],
                m.ring.len()
            ),
        )?;
        ok = false;
    }
    Ok(ok)
}

/// Rule 2 at vertex `v`: at least two spokes, each another vertex in range, with known flag bits,
/// and boundary spokes sharp. Needs [`ring_offsets`].
pub fn vertex_ring(m: &ControlMesh, v: usize, s: &mut impl Sink) -> Flow {
    let nv = m.positions.len() / 3;
    let Some((a, b)) = ring_range(m, v) else {
        return Ok(());
    };
    if b - a < 2 {
        s.report(
            format!("mesh.vertices[{v}]"),
            format!(
                "valence {} < 2: the vertex is unused by any triangle or the ring is wrong",
                b - a
            ),
        )?;
    }
    for k in a..b {
        let w = m.ring[k];
        if w as usize >= nv || w as usize == v {
            s.report(
                format!("mesh.ring[{k}]"),
                format!("spoke {w} of vertex {v} is out of range or the vertex itself"),
            )?;
        }
        let f = m.spoke_flags[k];
        if f & !(SPOKE_SHARP | SPOKE_BOUNDARY) != 0 {
            s.report(
                format!("mesh.spoke_flags[{k}]"),
                format!("unknown bits in {f:#x}"),
            )?;
        }
        if f & SPOKE_BOUNDARY != 0 && f & SPOKE_SHARP == 0 {
            s.report(
                format!("mesh.spoke_flags[{k}]"),
                "boundary spoke is not marked sharp".into(),
            )?;
        }
    }
    Ok(())
}

/// Rule 3 at vertex `v`: known flag bits, a boundary flag that agrees with the boundary spokes
/// (exactly the first and last of a boundary vertex's ring) and the vertex rule its sharp spokes
/// call for (SPEC.md C.3). Needs [`ring_offsets`] and the length of `vertex_flags`.
pub fn vertex_rule(m: &ControlMesh, v: usize, s: &mut impl Sink) -> Flow {
    let Some((a, b)) = ring_range(m, v) else {
        return Ok(());
    };
    let flags = m.vertex_flags[v];
    let at = || format!("mesh.vertex_flags[{v}]");
    if flags & !(VERTEX_BOUNDARY | VERTEX_RULE_MASK) != 0 {
        s.report(at(), format!("unknown bits in {flags:#x}"))?;
    }
    let mut boundary_spokes = (a..b).filter(|&k| m.spoke_flags[k] & SPOKE_BOUNDARY != 0);
    let is_boundary = flags & VERTEX_BOUNDARY != 0;
    if is_boundary {
        let exactly_ends = b - a >= 2
            && boundary_spokes.next() == Some(a)
            && boundary_spokes.next() == Some(b - 1)
            && boundary_spokes.next().is_none();
        if !exactly_ends {
            s.report(
                at(),
                "boundary vertex whose first and last spokes are not exactly its boundary spokes"
                    .into(),
            )?;
        }
    } else if boundary_spokes.next().is_some() {
        s.report(at(), "interior vertex with a boundary spoke".into())?;
    }
    let sharp = (a..b)
        .filter(|&k| m.spoke_flags[k] & SPOKE_SHARP != 0)
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
        s.report(
            at(),
            format!(
                "rule {rule} but {sharp} sharp spokes (valence {}) make it {expected} (SPEC.md C.3)",
                b - a
            ),
        )?;
    }
    Ok(())
}

/// Rule 4 at corner `c` of triangle `t`: its spoke is the triangle's edge to the next corner,
/// and the spoke after it (cyclically at an interior vertex) the edge to the corner after that.
/// Needs [`triangle_corners`], [`ring_offsets`] and the lengths of `vertex_flags` and
/// `corner_spokes`.
pub fn corner_spoke(m: &ControlMesh, t: usize, c: usize, s: &mut impl Sink) -> Flow {
    let tri = m.triangle(t);
    let v = tri[c] as usize;
    let Some((a, b)) = ring_range(m, v) else {
        return Ok(());
    };
    let val = b - a;
    let k = m.corner_spokes[3 * t + c] as usize;
    let at = || format!("mesh.corner_spokes[{}]", 3 * t + c);
    if k >= val {
        return s.report(
            at(),
            format!("spoke {k} is out of vertex {v}'s ring of {val}"),
        );
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
        s.report(
            at(),
            format!(
                "ring of vertex {v} has {} at position {k}, triangle {t} needs {v1}",
                m.ring[a + k]
            ),
        )?;
    } else if next.map(|n| m.ring[a + n]) != Some(v2) {
        s.report(at(), format!("the spoke after position {k} in vertex {v}'s ring is not {v2}: the ring is not counter-clockwise or misses triangle {t}"))?;
    }
    Ok(())
}

/// Rule 5 at edge `e` of triangle `t`: an edge without a neighbour is a boundary spoke (checked
/// when `spokes_ok`: [`ring_offsets`] and the `corner_spokes` length passed); a neighbour is a
/// triangle in range that has the reversed edge and names `t` back, with the same edge id
/// (checked when `edges_ok`, the `edges` length passed). Needs [`triangle_corners`] and the
/// length of `neighbours`.
pub fn neighbour(
    m: &ControlMesh,
    t: usize,
    e: usize,
    spokes_ok: bool,
    edges_ok: bool,
    s: &mut impl Sink,
) -> Flow {
    let nf = m.triangles.len() / 3;
    let tri = m.triangle(t);
    let n = m.neighbours[3 * t + e];
    let at = || format!("mesh.neighbours[{}]", 3 * t + e);
    let (va, vb) = (tri[e], tri[(e + 1) % 3]);
    if n == NO_NEIGHBOUR {
        if spokes_ok {
            if let Some((a, b)) = ring_range(m, va as usize) {
                let k = m.corner_spokes[3 * t + e] as usize;
                if a + k < b && m.spoke_flags[a + k] & SPOKE_BOUNDARY == 0 {
                    s.report(
                        at(),
                        format!(
                            "edge ({va}, {vb}) has no neighbour but its spoke is not marked boundary"
                        ),
                    )?;
                }
            }
        }
        return Ok(());
    }
    if n as usize >= nf {
        return s.report(
            at(),
            format!("neighbour {n} is out of range ({nf} triangles)"),
        );
    }
    let u = n as usize;
    let ut = m.triangle(u);
    match (0..3).find(|&f| ut[f] == vb && ut[(f + 1) % 3] == va) {
        None => s.report(
            at(),
            format!("triangle {u} does not have edge ({vb}, {va})"),
        )?,
        Some(f) => {
            if m.neighbours[3 * u + f] != t as u32 {
                s.report(
                    at(),
                    format!(
                        "triangle {u} does not name {t} as its neighbour across the shared edge"
                    ),
                )?;
            }
            if edges_ok && m.edges[3 * u + f] != m.edges[3 * t + e] {
                s.report(
                    format!("mesh.edges[{}]", 3 * t + e),
                    format!(
                        "id {} differs from id {} of the same edge in triangle {u}",
                        m.edges[3 * t + e],
                        m.edges[3 * u + f]
                    ),
                )?;
            }
        }
    }
    Ok(())
}

/// Rule 6: edge ids dense and numbered in order of first appearance (so the first triangle to
/// use an edge owns it), and, when `neighbours_ok` (the `neighbours` length passed), an interior
/// edge's id appearing twice and a boundary edge's once. Needs the length of `edges`.
pub fn edge_ids(m: &ControlMesh, neighbours_ok: bool, s: &mut impl Sink) -> Flow {
    let mut next: u32 = 0;
    let mut seen = vec![0u8; 0];
    for (i, &id) in m.edges.iter().enumerate() {
        if id == next {
            next += 1;
            seen.push(1);
        } else if id > next {
            s.report(
                format!("mesh.edges[{i}]"),
                format!("id {id} skips ahead of {next}: ids must be numbered in order of first appearance"),
            )?;
        } else {
            let count = &mut seen[id as usize];
            *count = count.saturating_add(1);
        }
    }
    if neighbours_ok {
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
                s.report(
                    format!("mesh.edges[{i}]"),
                    format!(
                        "id {id} appears {count} times, a {} edge's id appears {want}",
                        if want == 1 { "boundary" } else { "interior" }
                    ),
                )?;
            }
        }
    }
    Ok(())
}

/// Rule 7: one triangle record per control triangle.
pub fn record_count(o: &Object, s: &mut impl Sink) -> Flow {
    let nf = o.mesh.triangles.len() / 3;
    if o.triangles.len() != nf {
        s.report(
            "triangles".into(),
            format!("{} records for {nf} mesh triangles", o.triangles.len()),
        )?;
    }
    Ok(())
}

/// Rule 9: the bitstream is `ceil(bit_len / 32)` words, zero past `bit_len`.
pub fn bitstream_words(o: &Object, s: &mut impl Sink) -> Flow {
    let words = o.bit_len.div_ceil(32);
    if words != o.bits.len() as u64 {
        s.report(
            "bits".into(),
            format!(
                "{} words, but bit_len {} needs {words}",
                o.bits.len(),
                o.bit_len
            ),
        )?;
    } else if o.bit_len % 32 != 0 {
        if let Some(&last) = o.bits.last() {
            if last >> (o.bit_len % 32) != 0 {
                s.report("bits".into(), "bits past bit_len are not zero".into())?;
            }
        }
    }
    Ok(())
}

/// Rule 7 at triangle record `t`: at least one normal, the geometric one.
pub fn record_normal_count(o: &Object, t: usize, s: &mut impl Sink) -> Flow {
    if o.triangles[t].normal_count == 0 {
        s.report(
            format!("triangles[{t}]"),
            "normal_count is 0; every triangle has at least its geometric normal".into(),
        )?;
    }
    Ok(())
}

/// Rule 7 at triangle record `t` of a flat object: one normal only. (Refinement does not need
/// it: the kernels read the first normal of each record.)
pub fn flat_record(o: &Object, t: usize, s: &mut impl Sink) -> Flow {
    let r = &o.triangles[t];
    if o.kind == ObjectKind::Flat && r.normal_count > 1 {
        s.report(
            format!("triangles[{t}]"),
            format!(
                "flat objects have one normal per triangle, found {}",
                r.normal_count
            ),
        )?;
    }
    Ok(())
}

/// Rule 7 at triangle record `t`, whose tree decoded to `shape` ([`crate::triangle_trees`]):
/// its normals and colours inside the object's, its tree decodable.
pub fn record_ranges(
    o: &Object,
    t: usize,
    shape: &Result<TreeShape, TreeError>,
    s: &mut impl Sink,
) -> Flow {
    let r = &o.triangles[t];
    let at = || format!("triangles[{t}]");
    let n = u64::from(r.normal_count);
    if u64::from(r.normal_start) + n > o.normals.len() as u64 {
        s.report(
            at(),
            format!(
                "normals {}..{} run past the {} normals",
                r.normal_start,
                u64::from(r.normal_start) + n,
                o.normals.len()
            ),
        )?;
    }
    match shape {
        Ok(shape) => {
            let end = u64::from(r.colour_start) + u64::from(shape.node_count) * n;
            if end > o.colours.len() as u64 {
                s.report(
                    at(),
                    format!(
                        "colours {}..{end} for {} nodes x {n} normals run past the {} colours",
                        r.colour_start,
                        shape.node_count,
                        o.colours.len()
                    ),
                )?;
            }
        }
        Err(e) => s.report(at(), e.to_string())?,
    }
    Ok(())
}
