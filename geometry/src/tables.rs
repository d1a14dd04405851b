//! The guard, within hce-geometry, of the tables refinement and colouring index, so that a
//! malformed table is an error here and never an out-of-bounds read or a wrong vertex:
//!
//! * [`check_triangles`]: the triangle and edge-id tables every refinement reads (Loop through
//!   [`check_loop_tables`], flat through [`crate::flat::FlatTopology::new`]).
//! * [`check_loop_tables`]: in addition the rings, flags, corner spokes and neighbours Loop
//!   subdivision reads ([`crate::subdivide::prepare`], and so the GPU Loop kernel's upload).
//! * [`validate_tables`]: the HCE records, trees, normals and colours the colouring reads.
//!
//! The rules themselves are SPEC.md Appendix C's, written once in `hce_format::rules` and shared
//! with the validator: there they collect every problem, here each check stops at the first
//! ([`first_problem`]) and reports it as `location: message`. What is here beyond them is what
//! refinement needs of tables that no file rule states (an edge id joining the same two
//! vertices wherever it appears, interior edges away from the boundary spokes of open rings,
//! every vertex used) and what it derives while checking.

use rayon::prelude::*;

use hce_format::rules::{self, first_problem, Sink, Stop, Table};
use hce_format::{triangle_trees, Object};
use hce_format::{ControlMesh, NO_NEIGHBOUR, RULE_CREASE, SPOKE_SHARP, VERTEX_BOUNDARY};

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
/// positions and triangles in whole triples, vertex indices in range, no triangle repeating a
/// vertex, one edge id per triangle side, edge ids dense and numbered in order of first
/// appearance (so the first triangle to use an edge owns it), and every appearance of an edge
/// id joining the same two vertices. Returns the first fault as `location: message`.
pub fn check_triangles(mesh: &ControlMesh) -> Result<TriangleEdges, String> {
    first_problem(|s| triangle_edges(mesh, s)).map_err(|p| p.to_string())
}

fn triangle_edges(mesh: &ControlMesh, s: &mut impl Sink) -> Result<TriangleEdges, Stop> {
    rules::triples(mesh, s)?;
    for t in 0..mesh.triangle_count() {
        rules::triangle_corners(mesh, t, s)?;
    }
    rules::table_length(mesh, Table::Edges, s)?;
    rules::edge_ids(mesh, false, s)?;
    // Ids are in first-appearance order: each is at most the number seen so far.
    let mut verts: Vec<u32> = Vec::new();
    let mut sides: Vec<u32> = Vec::new();
    for t in 0..mesh.triangle_count() {
        let tri = mesh.triangle(t);
        for e in 0..3 {
            let id = mesh.edges[3 * t + e] as usize;
            let (a, b) = (tri[e], tri[(e + 1) % 3]);
            if id == sides.len() {
                verts.extend([a, b]);
                sides.push(1);
                continue;
            } else if id > sides.len() {
                continue; // Reported by `edge_ids`.
            }
            let (oa, ob) = (verts[2 * id], verts[2 * id + 1]);
            if !((oa == a && ob == b) || (oa == b && ob == a)) {
                s.report(
                    format!("mesh.edges[{}]", 3 * t + e),
                    format!(
                        "id {id} joins ({oa}, {ob}) where it first appears but ({a}, {b}) here: \
                         an edge id names one edge"
                    ),
                )?;
            }
            sides[id] += 1;
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

/// [`check_triangles`], then every other table Loop subdivision reads, by the rules of SPEC.md
/// Appendix C (array lengths, ring offsets, rings, flags and vertex rules, corner spokes,
/// neighbours, edge-id counts), and what refinement adds: interior edges away from the boundary
/// spokes of open rings, and every vertex used by a triangle (so that it has an owner to write
/// it). Returns the first fault as `location: message`; the per-vertex and per-triangle checks
/// run in parallel over fixed chunks and the first faulty chunk in order is reported, so the
/// error does not depend on scheduling.
pub fn check_loop_tables(mesh: &ControlMesh) -> Result<LoopTables, String> {
    let edges = check_triangles(mesh)?;
    let nv = mesh.vertex_count();
    let nf = mesh.triangle_count();
    first_problem(|s| {
        for table in [
            Table::RingOffsets,
            Table::SpokeFlags,
            Table::VertexFlags,
            Table::CornerSpokes,
            Table::Neighbours,
        ] {
            rules::table_length(mesh, table, s)?;
        }
        if nf == 0 {
            s.report("mesh.triangles".into(), "no triangles".into())?;
        }
        rules::ring_offsets(mesh, s)?;
        Ok(())
    })
    .map_err(fault_text)?;
    // Per chunk: the largest valence, the crease spokes, the first fault.
    type VertexChunk = (usize, Vec<[u32; 2]>, Result<(), hce_format::Problem>);
    let vertex_chunks: Vec<VertexChunk> = (0..nv.div_ceil(CHECK_CHUNK))
        .into_par_iter()
        .map(|chunk| {
            let mut max_valence = 6;
            let range = chunk * CHECK_CHUNK..((chunk + 1) * CHECK_CHUNK).min(nv);
            let mut crease_spokes = Vec::with_capacity(range.len());
            let fault = first_problem(|s| {
                for v in range {
                    rules::vertex_ring(mesh, v, s)?;
                    rules::vertex_rule(mesh, v, s)?;
                    let (a, b) = (
                        mesh.ring_offsets[v] as usize,
                        mesh.ring_offsets[v + 1] as usize,
                    );
                    max_valence = max_valence.max(b - a);
                    let mut spokes = [0u32; 2];
                    if mesh.rule(v as u32) == RULE_CREASE {
                        // Rule 3 passed: a crease vertex has exactly two sharp spokes.
                        let mut sharp = (0..b - a)
                            .filter(|&k| mesh.spoke_flags[a + k] & SPOKE_SHARP != 0)
                            .map(|k| k as u32);
                        spokes = [sharp.next().unwrap_or(0), sharp.next().unwrap_or(0)];
                    }
                    crease_spokes.push(spokes);
                }
                Ok(())
            });
            (max_valence, crease_spokes, fault)
        })
        .collect();
    let mut max_valence = 6;
    let mut crease_spokes = Vec::with_capacity(nv);
    for (m, spokes, fault) in vertex_chunks {
        fault.map_err(fault_text)?;
        max_valence = max_valence.max(m);
        crease_spokes.extend_from_slice(&spokes);
    }
    let faults: Vec<Result<(), hce_format::Problem>> = (0..nf.div_ceil(CHECK_CHUNK))
        .into_par_iter()
        .map(|chunk| {
            first_problem(|s| {
                (chunk * CHECK_CHUNK..((chunk + 1) * CHECK_CHUNK).min(nf))
                    .try_for_each(|t| check_loop_triangle(mesh, t, s))
            })
        })
        .collect();
    faults
        .into_iter()
        .collect::<Result<(), _>>()
        .map_err(fault_text)?;
    first_problem(|s| rules::edge_ids(mesh, true, s)).map_err(fault_text)?;
    let mut used = vec![false; nv];
    for &v in &mesh.triangles {
        used[v as usize] = true;
    }
    if let Some(v) = used.iter().position(|&u| !u) {
        return Err(format!("mesh.vertices[{v}]: used by no triangle"));
    }
    Ok(LoopTables {
        edges,
        max_valence,
        crease_spokes,
    })
}

fn fault_text(p: hce_format::Problem) -> String {
    p.to_string()
}

/// The checks of one triangle's adjacency entries that do not depend on other triangles, for a
/// mesh whose triangles and rings passed the checks before: rules 4 and 5 of Appendix C, and
/// interior edges away from the boundary spokes of open rings (both ends of an interior edge
/// need a spoke before and after the triangle).
fn check_loop_triangle(mesh: &ControlMesh, t: usize, s: &mut impl Sink) -> Result<(), Stop> {
    let tri = mesh.triangle(t);
    for c in 0..3 {
        rules::corner_spoke(mesh, t, c, s)?;
        rules::neighbour(mesh, t, c, true, true, s)?;
    }
    for c in 0..3 {
        if mesh.neighbours[3 * t + c] == NO_NEIGHBOUR {
            continue;
        }
        // Edge c runs from corner c (its spoke `k` there) to corner c + 1 (whose spoke back
        // to corner c is the one after its corner spoke).
        for (end, last) in [(c, false), ((c + 1) % 3, true)] {
            let v = tri[end];
            if mesh.vertex_flags[v as usize] & VERTEX_BOUNDARY == 0 {
                continue;
            }
            let k = mesh.corner_spokes[3 * t + end] as usize;
            let on_boundary = if last {
                k + 2 >= mesh.ring_of(v).len()
            } else {
                k == 0
            };
            if on_boundary {
                s.report(
                    format!("mesh.neighbours[{}]", 3 * t + c),
                    format!(
                        "interior edge on the {} (boundary) spoke of vertex {v}",
                        if last { "last" } else { "first" }
                    ),
                )?;
            }
        }
    }
    Ok(())
}

/// Checks everything the colour kernels index, so that a malformed table is an error here and
/// never an out-of-bounds read on the GPU, by the rules of SPEC.md Appendix C: one record per
/// triangle, the bitstream's words, each record's normals and colours in range and its tree
/// decodable by the format's codec (so no deeper than [`hce_format::MAX_TREE_DEPTH`], and not
/// overlapping another); and what the GPU adds, a bitstream of at most 2^32 bits. Work is
/// linear in the bitstream ([`triangle_trees`]).
pub fn validate_tables(object: &Object) -> Result<TreeSummary, InvalidObject> {
    let err = |reason: String| InvalidObject {
        object: object.name.clone(),
        reason,
    };
    if object.bits.len() as u64 > u64::from(u32::MAX) / 32 {
        return Err(err("bits: HCE bitstream longer than 2^32 bits".into()));
    }
    first_problem(|s| {
        rules::record_count(object, s)?;
        rules::bitstream_words(object, s)?;
        let shapes = triangle_trees(object);
        let mut summary = TreeSummary::default();
        for (t, shape) in shapes.iter().enumerate() {
            rules::record_normal_count(object, t, s)?;
            rules::record_ranges(object, t, shape, s)?;
            if let Ok(shape) = shape {
                summary.nodes += u64::from(shape.node_count);
                summary.max_depth = summary.max_depth.max(shape.depth);
            }
        }
        Ok(summary)
    })
    .map_err(|p| err(p.to_string()))
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
            (
                "mesh.triangles[1]: vertex index 6 is out of range (6 vertices)",
                |m| m.triangles[5] = 6,
            ),
            (
                "mesh.triangles[0]: degenerate triangle [0, 0, 4] repeats a vertex",
                |m| m.triangles[1] = 0,
            ),
            (
                "mesh.edges: length 36, expected 24 (three per triangle)",
                |m| m.edges.extend([0; 12]),
            ),
            (
                "mesh.edges[5]: id 1000 skips ahead of 5: ids must be numbered in order of first \
                 appearance",
                |m| m.edges[5] = 1000,
            ),
            (
                // Two different edges under one id, still in first-appearance order: Loop used
                // to accept this and read one edge's points for the other.
                "mesh.edges[5]: id 0 joins (0, 2) where it first appears but (4, 2) here: an edge \
                 id names one edge",
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
                "mesh.neighbours: length 23, expected 24 (three per triangle)",
                |m| {
                    m.neighbours.pop();
                },
            ),
            (
                "mesh.ring[0]: spoke 99 of vertex 0 is out of range or the vertex itself",
                |m| m.ring[0] = 99,
            ),
            (
                "mesh.corner_spokes[4]: spoke 99 is out of vertex 1's ring of 4",
                |m| m.corner_spokes[4] = 99,
            ),
            (
                "mesh.neighbours[0]: neighbour 8 is out of range (8 triangles)",
                |m| m.neighbours[0] = 8,
            ),
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
            Err("mesh.vertices[6]: used by no triangle".to_string())
        );
    }
}
