//! The incidence tables of a control mesh that refinement needs beyond the mesh itself: each
//! edge's end points as its owner sees them, and the triangles around every edge and vertex.
//! Flat refinement ([`crate::flat`]) walks them, and the split ([`crate::split`]) finds the
//! regions around each vertex with them, so they live below both.

use hce_format::ControlMesh;

use crate::lattice::Numbering;
use crate::tables::{check_triangles, InvalidObject, TriangleEdges};

/// The refined-mesh connectivity a flat refinement needs beyond the control mesh: edge end
/// points in the owner's direction, and for each vertex and edge the triangles that touch it.
#[derive(Clone, Debug, Default, PartialEq, Eq)]
pub struct FlatTopology {
    pub vertex_count: u32,
    pub triangle_count: u32,
    pub edge_count: u32,
    /// `[v_e, v_{e+1}]` of each edge as its owner (first appearance) sees it.
    pub edge_verts: Vec<u32>,
    /// CSR: sides `3 t + e` of edge `id` are `edge_sides[edge_side_offsets[id]..[id + 1]]`,
    /// owner first.
    pub edge_side_offsets: Vec<u32>,
    pub edge_sides: Vec<u32>,
    /// CSR: corners `3 t + c` at vertex `v`, in increasing `t`.
    pub vertex_corner_offsets: Vec<u32>,
    pub vertex_corners: Vec<u32>,
}

impl FlatTopology {
    /// Builds the tables from a control mesh whose triangles pass
    /// [`check_triangles`] (indices in range, no degenerate
    /// triangle, edge ids dense, numbered in order of first appearance and joining the same two
    /// vertices wherever they appear) and whose indices fit the kernels' 32-bit arithmetic.
    pub fn new(name: &str, mesh: &ControlMesh) -> Result<Self, InvalidObject> {
        let err = |reason: String| InvalidObject {
            object: name.to_string(),
            reason,
        };
        let v = mesh.vertex_count();
        let f = mesh.triangle_count();
        if v > u32::MAX as usize / 2 || f > u32::MAX as usize / 4 {
            return Err(err("mesh too large for 32-bit indices".into()));
        }
        let TriangleEdges {
            verts: edge_verts,
            sides: side_count,
        } = check_triangles(mesh).map_err(err)?;
        let edge_side_offsets = prefix(&side_count);
        let mut fill = edge_side_offsets.clone();
        let mut edge_sides = vec![0u32; 3 * f];
        for (s, &id) in mesh.edges.iter().enumerate() {
            edge_sides[fill[id as usize] as usize] = s as u32;
            fill[id as usize] += 1;
        }
        let mut corner_count = vec![0u32; v];
        for &x in &mesh.triangles {
            corner_count[x as usize] += 1;
        }
        let vertex_corner_offsets = prefix(&corner_count);
        let mut fill = vertex_corner_offsets.clone();
        let mut vertex_corners = vec![0u32; 3 * f];
        for (s, &x) in mesh.triangles.iter().enumerate() {
            vertex_corners[fill[x as usize] as usize] = s as u32;
            fill[x as usize] += 1;
        }
        Ok(Self {
            vertex_count: v as u32,
            triangle_count: f as u32,
            edge_count: side_count.len() as u32,
            edge_verts,
            edge_side_offsets,
            edge_sides,
            vertex_corner_offsets,
            vertex_corners,
        })
    }

    /// The output numbering at `level`.
    pub fn numbering(&self, level: u32) -> Numbering {
        Numbering {
            level,
            vertices: self.vertex_count,
            edges: self.edge_count,
            triangles: self.triangle_count,
        }
    }

    /// Output vertex count at `level`.
    pub fn refined_vertex_count(&self, level: u32) -> u64 {
        self.numbering(level).vertex_count()
    }

    pub fn refined_triangle_count(&self, level: u32) -> u64 {
        self.numbering(level).triangle_count()
    }
}

fn prefix(counts: &[u32]) -> Vec<u32> {
    let mut out = Vec::with_capacity(counts.len() + 1);
    let mut s = 0;
    out.push(0);
    for &c in counts {
        s += c;
        out.push(s);
    }
    out
}
