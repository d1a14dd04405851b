//! Topology of a welded triangle mesh and the control-mesh adjacency tables
//! ([`hce_format::ControlMesh`]) that Loop subdivision reads, on the CPU and on the GPU.
//!
//! # Non-manifold input: split, not refuse (by default)
//!
//! Real assets are often slightly non-manifold (Blender's Suzanne has an edge shared by three
//! faces). Loop subdivision is only defined on manifolds, so by default such input is split
//! into manifold pieces, deterministically:
//!
//! 1. Degenerate triangles (a repeated welded vertex) are dropped.
//! 2. Triangles are oriented consistently per connected component (a breadth-first walk over
//!    edges shared by exactly two triangles flips the triangles that disagree with the first
//!    triangle of their component).
//! 3. An edge is *paired* (interior) only when exactly two triangles share it in opposite
//!    directions. Every other edge use (three or more triangles, or two that still agree in
//!    direction on a non-orientable surface) becomes a boundary edge of each triangle: the
//!    surface is cut there.
//! 4. Around each vertex the triangles form fans connected through paired edges; a vertex with
//!    more than one fan (a non-manifold vertex, e.g. two cones touching at their tips or an end
//!    of a cut edge) becomes one control vertex per fan, at the same position.
//!
//! The result is always a manifold with boundary, the pieces are reported in
//! [`TopologyReport`], and [`NonManifold::Refuse`] turns the split into an error that names the
//! edge or vertex and its triangles instead.
//!
//! # From fans to tables
//!
//! 5. Boundary and cut edges are sharp, and so are the creases [`Creases`] asks for.
//! 6. Each fan's corners, in counter-clockwise order, give its control vertex's ring, vertex
//!    flags (boundary, rule) and spoke flags, and each corner's position in that ring.
//! 7. Paired edges name each other's triangle as neighbour; edge ids are numbered in order of
//!    first appearance, which makes the first triangle that uses an edge its owner.
//!
//! Each step is one function in `steps` (the module this file's [`build_control_mesh`] calls in
//! order), documented with what it guarantees to the next; `edge_groups` groups half-edges by
//! undirected edge for steps 2 and 3.

mod edge_groups;
mod steps;

use hce_format::ControlMesh;

/// Which edges are infinitely sharp creases, besides boundaries.
#[derive(Clone, Copy, Debug, Default, PartialEq)]
pub enum Creases {
    /// No creases: only boundary edges are sharp.
    #[default]
    None,
    /// Edges whose two sides have different input normals at either end (the author split the
    /// normals, i.e. made the edge hard). Input without normals gets no creases.
    Auto,
    /// Edges whose dihedral angle (between the two face normals) exceeds this many degrees.
    Angle(f32),
}

impl std::str::FromStr for Creases {
    type Err = String;
    fn from_str(s: &str) -> Result<Self, String> {
        match s {
            "none" => Ok(Creases::None),
            "auto" => Ok(Creases::Auto),
            _ => match s.strip_prefix("angle=").map(str::parse::<f32>) {
                Some(Ok(d)) if (0.0..=180.0).contains(&d) => Ok(Creases::Angle(d)),
                _ => Err(format!(
                    "unknown crease mode '{s}': use none, auto or angle=DEG with DEG in 0..=180"
                )),
            },
        }
    }
}

/// What to do with non-manifold edges and vertices.
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq)]
pub enum NonManifold {
    /// Cut the surface into manifold pieces (see the module documentation). Default.
    #[default]
    Split,
    /// Return [`TopologyError`] naming the first offending edge or vertex.
    Refuse,
}

/// Parameters of [`build_control_mesh`].
#[derive(Clone, Copy, Debug, Default, PartialEq)]
pub struct TopologyConfig {
    /// Crease tagging; default none.
    pub creases: Creases,
    /// Non-manifold handling; default split.
    pub non_manifold: NonManifold,
}

/// Errors of topology building.
#[derive(Debug, thiserror::Error, PartialEq)]
pub enum TopologyError {
    #[error("triangle {triangle} references vertex {vertex}, but there are only {count} vertices")]
    IndexOutOfRange {
        triangle: usize,
        vertex: u32,
        count: usize,
    },
    #[error("edge ({a}, {b}) is shared by triangles {triangles:?}; Loop subdivision needs a manifold mesh (split it into manifold pieces with the default non-manifold mode)")]
    NonManifoldEdge {
        a: u32,
        b: u32,
        triangles: Vec<usize>,
    },
    #[error("vertex {vertex} joins {fans} separate fans of triangles (first triangles {triangles:?}); Loop subdivision needs a manifold mesh (split it into manifold pieces with the default non-manifold mode)")]
    NonManifoldVertex {
        vertex: u32,
        fans: usize,
        triangles: Vec<usize>,
    },
    #[error("the mesh has no non-degenerate triangle")]
    Empty,
    #[error("the mesh is too large: {what}")]
    TooLarge { what: String },
}

/// What [`build_control_mesh`] found and did. Vertex and triangle numbers are those of the
/// welded input.
#[derive(Clone, Debug, Default, PartialEq)]
pub struct TopologyReport {
    pub welded_vertices: usize,
    pub input_triangles: usize,
    /// Welded vertices no triangle uses (dropped).
    pub unused_vertices: usize,
    /// Triangles with a repeated vertex (dropped).
    pub degenerate_triangles: usize,
    /// Triangles flipped to agree with the orientation of their component.
    pub flipped_triangles: usize,
    /// Edges shared by more than two triangles (cut), with their triangles; at most 16 listed.
    pub non_manifold_edges: usize,
    pub non_manifold_edge_examples: Vec<((u32, u32), Vec<usize>)>,
    /// Edges shared by two triangles in the same direction after orientation (cut).
    pub non_orientable_edges: usize,
    /// Welded vertices split into several control vertices (non-manifold vertices).
    pub split_vertices: usize,
    pub boundary_edges: usize,
    pub crease_edges: usize,
    /// Control mesh sizes.
    pub vertices: usize,
    pub edges: usize,
    pub triangles: usize,
    /// `valence_histogram[n]`: control vertices of valence `n` (ring length).
    pub valence_histogram: Vec<usize>,
}

impl std::fmt::Display for TopologyReport {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        writeln!(
            f,
            "input: {} welded vertices, {} triangles",
            self.welded_vertices, self.input_triangles
        )?;
        writeln!(
            f,
            "dropped: {} unused vertices, {} degenerate triangles; flipped {} triangles",
            self.unused_vertices, self.degenerate_triangles, self.flipped_triangles
        )?;
        writeln!(
            f,
            "non-manifold: {} edges cut, {} non-orientable edges cut, {} vertices split",
            self.non_manifold_edges, self.non_orientable_edges, self.split_vertices
        )?;
        for ((a, b), t) in &self.non_manifold_edge_examples {
            writeln!(f, "  edge ({a}, {b}) shared by triangles {t:?}")?;
        }
        writeln!(
            f,
            "control mesh: V={} E={} F={}, {} boundary edges, {} crease edges",
            self.vertices, self.edges, self.triangles, self.boundary_edges, self.crease_edges
        )?;
        write!(f, "valence histogram:")?;
        for (n, &c) in self.valence_histogram.iter().enumerate() {
            if c > 0 {
                write!(f, " {n}:{c}")?;
            }
        }
        writeln!(f)
    }
}

/// A control mesh and how it relates to the welded input.
#[derive(Clone, Debug, Default, PartialEq)]
pub struct Topology {
    pub mesh: ControlMesh,
    /// `control_to_welded[v]`: the welded input vertex of control vertex `v`.
    pub control_to_welded: Vec<u32>,
    /// `triangle_source[t]`: the input triangle of control triangle `t`.
    pub triangle_source: Vec<u32>,
    /// Whether control triangle `t` was flipped relative to its input triangle.
    pub triangle_flipped: Vec<bool>,
    pub report: TopologyReport,
}

/// Builds the control mesh and its adjacency tables from welded positions and triangles.
/// `corner_normals` (one per input triangle corner) drive [`Creases::Auto`]. The steps are
/// those of the module documentation, one function each in `steps`.
pub fn build_control_mesh(
    positions: &[[f32; 3]],
    triangles: &[[u32; 3]],
    corner_normals: Option<&[[f32; 3]]>,
    config: &TopologyConfig,
) -> Result<Topology, TopologyError> {
    let nv = positions.len();
    if triangles.len() >= (u32::MAX / 4) as usize || nv >= u32::MAX as usize {
        return Err(TopologyError::TooLarge {
            what: format!("{} triangles, {} vertices", triangles.len(), nv),
        });
    }
    let mut report = TopologyReport {
        welded_vertices: nv,
        input_triangles: triangles.len(),
        ..Default::default()
    };
    let mut faces = steps::drop_degenerates(nv, triangles, &mut report)?;
    let orientation = steps::orient(&mut faces, &mut report);
    let pairs = steps::pair_edges(
        &faces,
        &orientation.groups,
        config.non_manifold,
        &mut report,
    )?;
    let fans = steps::fans(&faces, &pairs, nv, config.non_manifold, &mut report)?;
    let sharp = steps::sharp_edges(
        positions,
        corner_normals,
        config.creases,
        &faces,
        &orientation,
        &pairs,
        &mut report,
    );
    let rings = steps::rings(positions, &fans, &sharp, &mut report);
    let edges = steps::neighbours_and_edges(&pairs, &mut report);
    report.vertices = fans.fans.len();
    report.triangles = faces.tris.len();
    Ok(Topology {
        mesh: ControlMesh {
            positions: rings.positions,
            triangles: fans.corner_vertex,
            ring_offsets: rings.ring_offsets,
            ring: rings.ring,
            vertex_flags: rings.vertex_flags,
            spoke_flags: rings.spoke_flags,
            corner_spokes: rings.corner_spokes,
            neighbours: edges.neighbours,
            edges: edges.edges,
        },
        control_to_welded: fans.control_to_welded,
        triangle_source: faces.source,
        triangle_flipped: orientation.flip,
        report,
    })
}

#[cfg(test)]
mod tests {
    use super::*;
    use hce_format::{NO_NEIGHBOUR, RULE_CORNER, SPOKE_BOUNDARY, SPOKE_SHARP};

    fn tetra() -> (Vec<[f32; 3]>, Vec<[u32; 3]>) {
        (
            vec![
                [0.0, 0.0, 0.0],
                [1.0, 0.0, 0.0],
                [0.0, 1.0, 0.0],
                [0.0, 0.0, 1.0],
            ],
            vec![[0, 2, 1], [0, 1, 3], [1, 2, 3], [2, 0, 3]],
        )
    }

    #[test]
    fn closed_tetrahedron_has_valence_three_rings_and_six_edges() {
        let (p, t) = tetra();
        let topo = build_control_mesh(&p, &t, None, &TopologyConfig::default()).unwrap();
        let m = &topo.mesh;
        assert_eq!(topo.report.edges, 6);
        assert_eq!(topo.report.boundary_edges, 0);
        assert_eq!(m.ring_offsets, vec![0, 3, 6, 9, 12]);
        assert!(m.neighbours.iter().all(|&n| n != NO_NEIGHBOUR));
        // corner spokes: spoke k is v_{c+1}, spoke k+1 is v_{c+2}.
        for tri in 0..4 {
            let v = m.triangle(tri);
            for c in 0..3 {
                let ring = m.ring_of(v[c]);
                let k = m.corner_spokes[3 * tri + c] as usize;
                assert_eq!(ring[k], v[(c + 1) % 3]);
                assert_eq!(ring[(k + 1) % ring.len()], v[(c + 2) % 3]);
            }
        }
    }

    #[test]
    fn single_triangle_has_corner_vertices_and_boundary_spokes() {
        let p = vec![[0.0, 0.0, 0.0], [1.0, 0.0, 0.0], [0.0, 1.0, 0.0]];
        let topo = build_control_mesh(&p, &[[0, 1, 2]], None, &TopologyConfig::default()).unwrap();
        let m = &topo.mesh;
        assert_eq!(m.ring, vec![1, 2, 2, 0, 0, 1]);
        assert!(m
            .spoke_flags
            .iter()
            .all(|&s| s == SPOKE_SHARP | SPOKE_BOUNDARY));
        assert!((0..3).all(|v| m.rule(v) == RULE_CORNER));
        assert_eq!(m.edges, vec![0, 1, 2]);
    }

    #[test]
    fn edge_shared_by_three_triangles_is_cut_or_refused() {
        let p = vec![
            [0.0, 0.0, 0.0],
            [1.0, 0.0, 0.0],
            [0.5, 1.0, 0.0],
            [0.5, -1.0, 0.0],
            [0.5, 0.0, 1.0],
        ];
        let t = vec![[0, 1, 2], [1, 0, 3], [0, 1, 4]];
        let topo = build_control_mesh(&p, &t, None, &TopologyConfig::default()).unwrap();
        assert_eq!(topo.report.non_manifold_edges, 1);
        assert_eq!(topo.report.boundary_edges, 9);
        assert!(topo.mesh.neighbours.iter().all(|&n| n == NO_NEIGHBOUR));
        // Vertices 0 and 1 are each split into three fans.
        assert_eq!(topo.report.split_vertices, 2);
        assert_eq!(topo.mesh.vertex_count(), 9);
        let err = build_control_mesh(
            &p,
            &t,
            None,
            &TopologyConfig {
                non_manifold: NonManifold::Refuse,
                ..Default::default()
            },
        )
        .unwrap_err();
        assert_eq!(
            err,
            TopologyError::NonManifoldEdge {
                a: 0,
                b: 1,
                triangles: vec![0, 1, 2]
            }
        );
    }

    #[test]
    fn inconsistent_orientation_is_fixed_and_degenerates_dropped() {
        let (p, mut t) = tetra();
        t[2] = [1, 3, 2];
        t.push([1, 1, 2]);
        let topo = build_control_mesh(&p, &t, None, &TopologyConfig::default()).unwrap();
        assert_eq!(topo.report.flipped_triangles, 1);
        assert_eq!(topo.report.degenerate_triangles, 1);
        assert_eq!(topo.report.boundary_edges, 0);
        assert_eq!(topo.report.non_orientable_edges, 0);
    }

    #[test]
    fn crease_modes_parse() {
        assert_eq!("auto".parse::<Creases>(), Ok(Creases::Auto));
        assert_eq!("angle=30".parse::<Creases>(), Ok(Creases::Angle(30.0)));
        assert!("angle=x".parse::<Creases>().is_err());
    }
}
