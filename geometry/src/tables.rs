//! The one validation, within hce-geometry, of the tables refinement and colouring index, so
//! that a malformed table is an error here and never an out-of-bounds read or a wrong vertex:
//!
//! * [`check_triangles`]: the triangle and edge-id tables every refinement reads (Loop through
//!   [`check_loop_tables`], flat through [`crate::flat::FlatTopology::new`]).
//! * [`check_loop_tables`]: in addition the rings, flags, corner spokes and neighbours Loop
//!   subdivision reads ([`crate::subdivide::prepare`], and so the GPU Loop kernel's upload).
//! * [`validate_tables`]: the HCE records, trees, normals and colours the colouring reads.
//!
//! The format's validator (`hce_format::validate`, SPEC.md Appendix C) checks files against the
//! same rules and more, reporting every problem with its location; it stays in hce-format,
//! which validates files without this crate. These functions stop at the first fault and guard
//! the code that indexes, whatever built the tables.

use rayon::prelude::*;

use hce_format::tree::decode_shape;
use hce_format::{ControlMesh, NO_NEIGHBOUR, RULE_CREASE, SPOKE_SHARP, VERTEX_BOUNDARY};
use hce_format::{Object, TreeError};

/// An object whose tables cannot be refined or coloured, with the reason.
#[derive(Clone, Debug, PartialEq, Eq, thiserror::Error)]
#[error("object {object}: {reason}")]
pub struct InvalidObject {
    /// The object's name.
    pub object: String,
    /// What is wrong, and where.
    pub reason: String,
}

/// What validation learnt about an object's trees.
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq)]
pub struct TreeSummary {
    /// Deepest leaf over all triangles (0 when every tree is a single root).
    pub max_depth: u32,
    /// Total tree nodes over all triangles.
    pub nodes: u64,
}

/// What [`check_triangles`] learnt about the edges.
#[derive(Clone, Debug, Default, PartialEq, Eq)]
pub struct TriangleEdges {
    /// `[v_e, v_{e+1}]` of each edge id as its owner (the triangle where it first appears) sees
    /// it.
    pub verts: Vec<u32>,
    /// Per edge id, how many triangle sides carry it: 1 on a boundary, 2 inside, more at a
    /// non-manifold edge of a flat object.
    pub sides: Vec<u32>,
}

/// The structural checks of a control mesh's triangle tables that every refinement relies on:
/// positions and triangles in whole triples, one edge id per triangle side, vertex indices in
/// range, no triangle repeating a vertex, edge ids dense and numbered in order of first
/// appearance (so the first triangle to use an edge owns it), and every appearance of an edge
/// id joining the same two vertices. Returns the reason of the first fault.
pub fn check_triangles(mesh: &ControlMesh) -> Result<TriangleEdges, String> {
    if mesh.positions.len() % 3 != 0 || mesh.triangles.len() % 3 != 0 {
        return Err("positions or triangles not a multiple of 3 long".into());
    }
    let v = mesh.vertex_count();
    let f = mesh.triangle_count();
    if mesh.edges.len() != mesh.triangles.len() {
        return Err(format!(
            "{} edge ids for {} triangle edges",
            mesh.edges.len(),
            mesh.triangles.len()
        ));
    }
    let mut verts: Vec<u32> = Vec::new();
    let mut sides: Vec<u32> = Vec::new();
    for t in 0..f {
        let tri = mesh.triangle(t);
        for (c, &x) in tri.iter().enumerate() {
            if x as usize >= v {
                return Err(format!("triangle {t} corner {c}: vertex {x} >= {v}"));
            }
        }
        if tri[0] == tri[1] || tri[1] == tri[2] || tri[2] == tri[0] {
            return Err(format!("triangle {t} is degenerate: {tri:?}"));
        }
        for e in 0..3 {
            let id = mesh.edges[3 * t + e];
            let (a, b) = (tri[e], tri[(e + 1) % 3]);
            let count = sides.len() as u32;
            if id == count {
                verts.extend([a, b]);
                sides.push(1);
            } else if id < count {
                let (oa, ob) = (verts[2 * id as usize], verts[2 * id as usize + 1]);
                if !((oa == a && ob == b) || (oa == b && ob == a)) {
                    return Err(format!(
                        "triangle {t} edge {e}: edge id {id} joins ({oa}, {ob}) elsewhere \
                         but ({a}, {b}) here"
                    ));
                }
                sides[id as usize] += 1;
            } else {
                return Err(format!(
                    "triangle {t} edge {e}: edge id {id} skips ids (next new id is {count}); \
                     ids must be numbered in order of first appearance"
                ));
            }
        }
    }
    Ok(TriangleEdges { verts, sides })
}

/// What [`check_loop_tables`] learnt.
#[derive(Clone, Debug, Default, PartialEq, Eq)]
pub struct LoopTables {
    pub edges: TriangleEdges,
    /// The largest ring, at least 6 (the valence of a lattice point).
    pub max_valence: usize,
    /// Per vertex with the crease rule, the positions of its two sharp spokes in its ring
    /// (`[0, 0]` for other vertices).
    pub crease_spokes: Vec<[u32; 2]>,
}

/// Vertices or triangles per parallel task of [`check_loop_tables`].
const CHECK_CHUNK: usize = 4096;

/// [`check_triangles`], then every other table Loop subdivision reads: array lengths, rings
/// (at least two spokes, in range, spanning the ring array), crease vertices with exactly two
/// sharp spokes, each corner's spokes pointing at its triangle's edges, neighbours in range,
/// interior edges away from the boundary spokes of open rings, boundary edges sharp, and every
/// vertex used by a triangle (so that it has an owner to write it). Returns the reason of the
/// first fault; the checks run in parallel over fixed chunks and the first faulty chunk in
/// order is reported, so the error does not depend on scheduling.
pub fn check_loop_tables(mesh: &ControlMesh) -> Result<LoopTables, String> {
    let edges = check_triangles(mesh)?;
    let nv = mesh.vertex_count();
    let nf = mesh.triangle_count();
    if mesh.ring_offsets.len() != nv + 1
        || mesh.vertex_flags.len() != nv
        || mesh.corner_spokes.len() != 3 * nf
        || mesh.neighbours.len() != 3 * nf
        || mesh.spoke_flags.len() != mesh.ring.len()
    {
        return Err("array lengths disagree with the vertex and triangle counts".into());
    }
    if nf == 0 {
        return Err("no triangles".into());
    }
    if mesh.ring_offsets[0] != 0 || mesh.ring_offsets[nv] as usize != mesh.ring.len() {
        return Err("ring_offsets do not span the ring array".into());
    }
    // Per chunk: the largest valence, the crease spokes, the first fault.
    type VertexChunk = (usize, Vec<[u32; 2]>, Result<(), String>);
    let vertex_chunks: Vec<VertexChunk> = (0..nv.div_ceil(CHECK_CHUNK))
        .into_par_iter()
        .map(|chunk| {
            let mut max_valence = 6;
            let range = chunk * CHECK_CHUNK..((chunk + 1) * CHECK_CHUNK).min(nv);
            let mut crease_spokes = Vec::with_capacity(range.len());
            for v in range {
                let (a, b) = (
                    mesh.ring_offsets[v] as usize,
                    mesh.ring_offsets[v + 1] as usize,
                );
                if b < a + 2 {
                    return (
                        0,
                        crease_spokes,
                        Err(format!("vertex {v}: ring shorter than 2")),
                    );
                }
                // Checked before slicing: a later offset that decreases is caught only afterwards.
                if b > mesh.ring.len() {
                    let e = format!("vertex {v}: ring_offsets run past the ring array");
                    return (0, crease_spokes, Err(e));
                }
                max_valence = max_valence.max(b - a);
                if let Some(&s) = mesh.ring[a..b].iter().find(|&&s| s as usize >= nv) {
                    let e = format!("vertex {v}: spoke {s} out of range");
                    return (0, crease_spokes, Err(e));
                }
                let mut spokes = [0u32; 2];
                if mesh.rule(v as u32) == RULE_CREASE {
                    let sharp: Vec<usize> = (0..b - a)
                        .filter(|&k| mesh.spoke_flags[a + k] & SPOKE_SHARP != 0)
                        .collect();
                    if sharp.len() != 2 {
                        let e =
                            format!("vertex {v}: crease rule with {} sharp spokes", sharp.len());
                        return (0, crease_spokes, Err(e));
                    }
                    spokes = [sharp[0] as u32, sharp[1] as u32];
                }
                crease_spokes.push(spokes);
            }
            (max_valence, crease_spokes, Ok(()))
        })
        .collect();
    let mut max_valence = 6;
    let mut crease_spokes = Vec::with_capacity(nv);
    for (m, spokes, fault) in vertex_chunks {
        fault?;
        max_valence = max_valence.max(m);
        crease_spokes.extend_from_slice(&spokes);
    }
    let faults: Vec<Result<(), String>> = (0..nf.div_ceil(CHECK_CHUNK))
        .into_par_iter()
        .map(|chunk| {
            (chunk * CHECK_CHUNK..((chunk + 1) * CHECK_CHUNK).min(nf))
                .try_for_each(|t| check_loop_triangle(mesh, t))
        })
        .collect();
    faults.into_iter().collect::<Result<(), String>>()?;
    let mut used = vec![false; nv];
    for &v in &mesh.triangles {
        used[v as usize] = true;
    }
    if let Some(v) = used.iter().position(|&u| !u) {
        return Err(format!("vertex {v} is used by no triangle"));
    }
    Ok(LoopTables {
        edges,
        max_valence,
        crease_spokes,
    })
}

/// The checks of one triangle's adjacency entries that do not depend on other triangles, for a
/// mesh whose triangles and rings passed the checks before.
// `c` is both a corner and an edge index (edge c starts at corner c).
#[allow(clippy::needless_range_loop)]
fn check_loop_triangle(mesh: &ControlMesh, t: usize) -> Result<(), String> {
    let nf = mesh.triangle_count();
    let tri = mesh.triangle(t);
    for c in 0..3 {
        let v = tri[c] as usize;
        let ring = mesh.ring_of(tri[c]);
        let k = mesh.corner_spokes[3 * t + c] as usize;
        let closed = mesh.vertex_flags[v] & VERTEX_BOUNDARY == 0;
        let k1 = if closed { (k + 1) % ring.len() } else { k + 1 };
        if k >= ring.len()
            || k1 >= ring.len()
            || ring[k] != tri[(c + 1) % 3]
            || ring[k1] != tri[(c + 2) % 3]
        {
            return Err(format!(
                "triangle {t} corner {c}: corner_spokes does not point at the triangle's edges"
            ));
        }
        let nb = mesh.neighbours[3 * t + c];
        // An interior edge needs the spokes before and after the triangle in both rings.
        if nb != NO_NEIGHBOUR {
            if nb as usize >= nf {
                return Err(format!("triangle {t} edge {c}: neighbour out of range"));
            }
            if !closed && k == 0 {
                return Err(format!(
                    "triangle {t} edge {c}: interior edge on the first (boundary) spoke"
                ));
            }
        } else if closed || mesh.spoke_flags[mesh.ring_offsets[v] as usize + k] & SPOKE_SHARP == 0 {
            return Err(format!(
                "triangle {t} edge {c}: boundary edge that is not marked sharp at an interior vertex"
            ));
        }
    }
    for c in 0..3 {
        let nb = mesh.neighbours[3 * t + c];
        let v1 = tri[(c + 1) % 3];
        let ring = mesh.ring_of(v1);
        let k = mesh.corner_spokes[3 * t + (c + 1) % 3] as usize;
        let closed = mesh.vertex_flags[v1 as usize] & VERTEX_BOUNDARY == 0;
        if nb != NO_NEIGHBOUR && !closed && k + 2 >= ring.len() {
            return Err(format!(
                "triangle {t} edge {c}: interior edge on the last (boundary) spoke"
            ));
        }
    }
    Ok(())
}

/// Checks everything the colour kernels index, so that a malformed table is an error here and
/// never an out-of-bounds read on the GPU: record ranges into normals and colours, every tree's
/// bits inside `bit_len`, trees decodable by the format's codec (so no deeper than
/// [`hce_format::MAX_TREE_DEPTH`]), word counts consistent. Work is bounded by `bit_len` (trees
/// together may not claim more nodes than there are bits).
pub fn validate_tables(object: &Object) -> Result<TreeSummary, InvalidObject> {
    let err = |reason: String| InvalidObject {
        object: object.name.clone(),
        reason,
    };
    let f = object.mesh.triangle_count();
    if object.triangles.len() != f {
        return Err(err(format!(
            "{} triangle records for {f} triangles; re-bake the asset",
            object.triangles.len()
        )));
    }
    if object.bit_len > object.bits.len() as u64 * 32 {
        return Err(err(format!(
            "bit_len {} exceeds the {} bits stored",
            object.bit_len,
            object.bits.len() as u64 * 32
        )));
    }
    if object.bits.len() as u64 > u64::from(u32::MAX) / 32 {
        return Err(err("HCE bitstream longer than 2^32 bits".into()));
    }
    let mut summary = TreeSummary::default();
    for (t, r) in object.triangles.iter().enumerate() {
        let ctx = |what: String| err(format!("triangle {t}: {what}"));
        if r.normal_count == 0 {
            return Err(ctx(
                "normal_count is 0 (needs at least the geometric normal)".into(),
            ));
        }
        if u64::from(r.normal_start) + u64::from(r.normal_count) > object.normals.len() as u64 {
            return Err(ctx(format!(
                "normals {}..+{} outside the {} stored",
                r.normal_start,
                r.normal_count,
                object.normals.len()
            )));
        }
        let shape = decode_shape(&object.bits, object.bit_len, u64::from(r.bits_start)).map_err(
            |e| match e {
                TreeError::Truncated { bit, bit_len, .. } => ctx(format!(
                    "tree runs past the end of the bitstream (bit {bit} of {bit_len})"
                )),
                e => ctx(e.to_string()),
            },
        )?;
        let total = u64::from(shape.node_count);
        let depth = shape.depth;
        if summary.nodes + total > object.bit_len {
            return Err(err(format!(
                "trees claim more nodes than the {} bits of the bitstream",
                object.bit_len
            )));
        }
        summary.nodes += total;
        summary.max_depth = summary.max_depth.max(depth);
        let colours_needed = u64::from(r.colour_start) + total * u64::from(r.normal_count);
        if colours_needed > object.colours.len() as u64 {
            return Err(ctx(format!(
                "colours up to {colours_needed} needed but {} stored",
                object.colours.len()
            )));
        }
    }
    Ok(summary)
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::flat::FlatTopology;
    use crate::subdivide::{prepare, SubdivError};
    use crate::topology::{build_control_mesh, TopologyConfig};

    fn octahedron() -> ControlMesh {
        let p = [
            [1.0, 0.0, 0.0],
            [-1.0, 0.0, 0.0],
            [0.0, 1.0, 0.0],
            [0.0, -1.0, 0.0],
            [0.0, 0.0, 1.0],
            [0.0, 0.0, -1.0],
        ];
        let t = [
            [0, 2, 4],
            [2, 1, 4],
            [1, 3, 4],
            [3, 0, 4],
            [2, 0, 5],
            [1, 2, 5],
            [3, 1, 5],
            [0, 3, 5],
        ];
        build_control_mesh(&p, &t, None, &TopologyConfig::default())
            .unwrap()
            .mesh
    }

    /// A named way of breaking a table: the reason it must be rejected with, and the damage.
    type Damage = (&'static str, fn(&mut ControlMesh));

    /// The reason Loop (`prepare`) and flat refinement (`FlatTopology::new`) give, which must
    /// be the same for a fault of the shared tables.
    fn reasons(m: &ControlMesh) -> (String, String) {
        let loop_ = match prepare(m) {
            Err(SubdivError::Tables(r)) => r,
            other => panic!("prepare accepted a damaged mesh: {:?}", other.is_ok()),
        };
        let flat = FlatTopology::new("o", m).unwrap_err().reason;
        (loop_, flat)
    }

    #[test]
    fn a_built_control_mesh_passes_and_counts_its_edges() {
        let m = octahedron();
        let edges = check_triangles(&m).unwrap();
        assert_eq!(edges.sides, vec![2; 12]);
        let t = m.triangle(0);
        assert_eq!(edges.verts[..2], [t[0], t[1]]);
        let loop_tables = check_loop_tables(&m).unwrap();
        assert_eq!(loop_tables.max_valence, 6);
        assert_eq!(loop_tables.crease_spokes, vec![[0, 0]; 6]);
    }

    #[test]
    fn loop_and_flat_refinement_reject_triangle_faults_alike() {
        let good = octahedron();
        let cases: [Damage; 5] = [
            ("triangle 1 corner 2: vertex 6 >= 6", |m| m.triangles[5] = 6),
            ("triangle 0 is degenerate: [0, 0, 4]", |m| {
                m.triangles[1] = 0
            }),
            ("36 edge ids for 24 triangle edges", |m| {
                m.edges.extend([0; 12])
            }),
            (
                "triangle 1 edge 2: edge id 1000 skips ids (next new id is 5); ids must be \
                 numbered in order of first appearance",
                |m| m.edges[5] = 1000,
            ),
            (
                // Two different edges under one id, still in first-appearance order: Loop used
                // to accept this and read one edge's points for the other.
                "triangle 1 edge 2: edge id 0 joins (0, 2) elsewhere but (4, 2) here",
                |m| m.edges[5] = 0,
            ),
        ];
        for (want, damage) in cases {
            let mut m = good.clone();
            damage(&mut m);
            let (loop_, flat) = reasons(&m);
            assert_eq!(loop_, want);
            assert_eq!(flat, want);
        }
    }

    #[test]
    fn loop_tables_reject_adjacency_faults() {
        let good = octahedron();
        let cases: [Damage; 4] = [
            (
                "array lengths disagree with the vertex and triangle counts",
                |m| {
                    m.neighbours.pop();
                },
            ),
            ("vertex 0: spoke 99 out of range", |m| m.ring[0] = 99),
            (
                "triangle 1 corner 1: corner_spokes does not point at the triangle's edges",
                |m| m.corner_spokes[4] = 99,
            ),
            ("triangle 0 edge 0: neighbour out of range", |m| {
                m.neighbours[0] = 8
            }),
        ];
        for (want, damage) in cases {
            let mut m = good.clone();
            damage(&mut m);
            assert_eq!(check_loop_tables(&m), Err(want.to_string()));
            // Flat refinement does not read these tables.
            assert!(FlatTopology::new("o", &m).is_ok(), "{want}");
        }
        // A vertex no triangle uses has no owner to write it.
        let mut m = good;
        m.positions.extend([0.0; 3]);
        m.vertex_flags.push(0);
        m.ring.extend([0, 1]);
        m.spoke_flags.extend([0, 0]);
        m.ring_offsets.push(m.ring.len() as u32);
        assert_eq!(
            check_loop_tables(&m),
            Err("vertex 6 is used by no triangle".to_string())
        );
    }
}
