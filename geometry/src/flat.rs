//! Flat refinement on the CPU: the linear 1-to-4 split of every coarse triangle to a level, one
//! colour per fine triangle from its HCE tree node (the paper's nearest-normal rule), and
//! area-weighted vertex colours shared across the coarse edges that join their triangles. The
//! vertices are split where the surface folds (SPEC.md F.5, F.7, [`crate::split`]): across an
//! edge that does not join (sharp, or a fold of more than 10 degrees), each side has its own
//! vertices and colours. This is how flat objects are drawn (SPEC.md A.7, Appendix F), and the
//! step-for-step twin of the GPU flat kernel (`flat.wgsl`), which tests compare with value by
//! value. Vertices are numbered as in [`crate::lattice`], then the split's copies.
//!
//! Based on: Concheiro et al. Synthesis of multiresolution scenes with global illumination on a
//! GPU. GRAPP 2012, section 4 (colour by tree node and nearest representative normal, averaged
//! at the vertices).

use hce_format::{ControlMesh, Object};

use crate::decode::{decode_colour_in, triangle_tree};
use crate::lattice::{
    corner_point, edge_point, fine_corners, incident_paths, interior_coords, interior_index, site,
    RefinedPoint, Site,
};
use crate::normal::face_normal;
use crate::split::SplitTables;

/// The incidence tables every flat refinement takes, built once per object.
pub use crate::incidence::FlatTopology;

/// Edge ids for a plain triangle list: dense, in order of first appearance of `(t, e)`, as
/// [`ControlMesh::edges`] specifies. Non-manifold edges (three or more triangles) get one id.
pub fn edge_ids(triangles: &[u32]) -> Vec<u32> {
    let mut map = std::collections::HashMap::new();
    let mut out = Vec::with_capacity(triangles.len());
    for tri in triangles.chunks_exact(3) {
        for e in 0..3 {
            let (a, b) = (tri[e], tri[(e + 1) % 3]);
            let key = (a.min(b), a.max(b));
            let next = map.len() as u32;
            out.push(*map.entry(key).or_insert(next));
        }
    }
    out
}

/// Lattice point `(b, c)` of triangle `t` → output vertex index ([`crate::lattice`]'s
/// numbering; an edge point is counted from the edge owner's end).
pub fn vertex_index(
    topo: &FlatTopology,
    mesh: &ControlMesh,
    level: u32,
    t: u32,
    b: i32,
    c: i32,
) -> u32 {
    let n = 1i32 << level;
    let tri = mesh.triangle(t as usize);
    let numbering = topo.numbering(level);
    match site(n, b, c) {
        Site::Corner(c) => tri[c],
        Site::Edge { edge: e, k } => {
            let id = mesh.edges[3 * t as usize + e];
            let forward = topo.edge_verts[2 * id as usize] == tri[e];
            let kk = if forward { k } else { n - k };
            numbering.edge_point(id, kk as u64) as u32
        }
        Site::Interior => numbering.interior_point(t, u64::from(interior_index(n, b, c))) as u32,
    }
}

/// A refined, coloured triangle mesh, ready to draw.
#[derive(Clone, Debug, Default, PartialEq)]
pub struct RefinedMesh {
    pub level: u32,
    /// `x, y, z` per vertex.
    pub positions: Vec<f32>,
    /// Linear `r, g, b, 1` per vertex: the area-weighted mean of the incident fine triangles.
    pub colours: Vec<f32>,
    /// Three per fine triangle, counter-clockwise.
    pub indices: Vec<u32>,
    /// Linear `r, g, b` and area per fine triangle (the colour decoded from its tree node).
    pub face_colours: Vec<f32>,
}

impl RefinedMesh {
    pub fn vertex_count(&self) -> usize {
        self.positions.len() / 3
    }
    pub fn triangle_count(&self) -> usize {
        self.indices.len() / 3
    }
}

/// Position of lattice point `(b, c)` of triangle `(p0, p1, p2)`, as the kernel computes it
/// (SPEC.md F.7.2; the adaptive refinement calls it with `n = 4096`, F.7.1).
pub(crate) fn lattice_position(p: [[f32; 3]; 3], n: i32, b: i32, c: i32) -> [f32; 3] {
    let inv = 1.0 / n as f32;
    let (wa, wb, wc) = ((n - b - c) as f32, b as f32, c as f32);
    std::array::from_fn(|i| (p[0][i] * wa + p[1][i] * wb + p[2][i] * wc) * inv)
}

/// The CPU reference of the GPU flat kernel (`hce_runtime::gpu::refine_flat`): linear 1-to-4
/// split of every coarse triangle to `level`, the vertices split where the surface folds
/// (SPEC.md F.5), one colour per fine triangle from its tree node (normal chosen by the fine
/// triangle's normal), vertex colours as area-weighted means over the incident fine triangles
/// of the vertex's region, across the coarse edges and vertices that join. `object` must have
/// passed [`validate_tables`](crate::tables::validate_tables).
pub fn refine_flat_cpu(object: &Object, topo: &FlatTopology, level: u32) -> RefinedMesh {
    let split = SplitTables::from_topology(&object.mesh, topo, object.kind);
    refine_flat_split(object, topo, &split, level)
}

/// [`refine_flat_cpu`] with the split already built.
pub fn refine_flat_split(
    object: &Object,
    topo: &FlatTopology,
    split: &SplitTables,
    level: u32,
) -> RefinedMesh {
    let mesh = &object.mesh;
    let n = 1i32 << level;
    let numbering = topo.numbering(level);
    let base = numbering.vertex_count() as usize;
    let nv = base + split.appended(level) as usize;
    let f = topo.triangle_count as usize;
    let per = 1usize << (2 * level);

    // Step 1: vertex positions, one writer per vertex; a copy repeats its original's bits.
    let mut positions = vec![0f32; 3 * nv];
    let v = topo.vertex_count as usize;
    positions[..3 * v].copy_from_slice(&mesh.positions[..3 * v]);
    for id in 0..topo.edge_count {
        let pa = mesh.position(topo.edge_verts[2 * id as usize]);
        let pb = mesh.position(topo.edge_verts[2 * id as usize + 1]);
        for k in 1..n {
            let p = lattice_position([pa, pb, pb], n, k, 0);
            let i = numbering.edge_point(id, k as u64) as usize;
            positions[3 * i..3 * i + 3].copy_from_slice(&p);
        }
    }
    for t in 0..topo.triangle_count {
        let tri = mesh.triangle(t as usize).map(|x| mesh.position(x));
        for local in 0..numbering.per_triangle() {
            let (b, c) = interior_coords(n, local as u32);
            let p = lattice_position(tri, n, b, c);
            let i = numbering.interior_point(t, local) as usize;
            positions[3 * i..3 * i + 3].copy_from_slice(&p);
        }
    }
    for (j, src) in split.copy_sources(mesh, level).into_iter().enumerate() {
        let (i, src) = (base + j, src as usize);
        positions.copy_within(3 * src..3 * src + 3, 3 * i);
    }

    // Step 2: fine triangles: indices, area, decoded colour.
    let mut indices = vec![0u32; 3 * f * per];
    let mut face_colours = vec![0f32; 4 * f * per];
    for t in 0..f {
        let record = &object.triangles[t];
        let tree = triangle_tree(object, record);
        for path in 0..per as u32 {
            let g = t * per + path as usize;
            let corners = fine_corners(level, path);
            let idx = corners.map(|[b, c]| vertex_index(topo, mesh, level, t as u32, b, c));
            let tv = mesh.triangle(t);
            indices[3 * g..3 * g + 3]
                .copy_from_slice(&idx.map(|i| split.split_index(level, base, t, tv, i)));
            let p = idx.map(|i| {
                let i = i as usize * 3;
                [positions[i], positions[i + 1], positions[i + 2]]
            });
            let (normal, area) = normal_and_area(p);
            let d = decode_colour_in(object, record, &tree, level, path, normal);
            face_colours[4 * g..4 * g + 4].copy_from_slice(&[d.rgb[0], d.rgb[1], d.rgb[2], area]);
        }
    }

    // Step 3: vertex colours, gathering incident fine triangles in a fixed order.
    let mut colours = vec![0f32; 4 * nv];
    for (i, out) in colours.chunks_exact_mut(4).enumerate() {
        let mut acc = Accumulator::default();
        let mut add = |t: u32, [b, c]: [i32; 2]| {
            for path in incident_paths(level, b, c) {
                let g = t as usize * per + path as usize;
                acc.add(&face_colours[4 * g..4 * g + 4]);
            }
        };
        // The slot the vertex gathers from (SPEC.md F.5): a control point's or an edge's
        // region (the F.5 vertices, then the copies), or an interior point's triangle.
        let x = split.copies as usize;
        let pe = (n - 1) as usize;
        let (corner_slot, edge_slot) = if i >= base {
            let j = i - base;
            if j < x {
                (Some(topo.vertex_count as usize + j), None)
            } else {
                let s = (j - x) / pe;
                (None, Some((topo.edge_count as usize + s, (j - x) % pe + 1)))
            }
        } else {
            match numbering.point(i as u64) {
                RefinedPoint::Coarse(v) => (Some(v as usize), None),
                RefinedPoint::Edge { id, k } => (None, Some((id as usize, k as usize))),
                RefinedPoint::Interior { t, local } => {
                    add(t, interior_coords(n, local as u32).into());
                    (None, None)
                }
            }
        };
        if let Some(slot) = corner_slot {
            for &corner in split.corner_slot(slot) {
                add(corner / 3, corner_point(n, corner % 3));
            }
        }
        if let Some((slot, kk)) = edge_slot {
            for &side in split.edge_slot(slot) {
                let (t, ed) = (side / 3, side % 3);
                let id = mesh.edges[side as usize] as usize;
                let forward = mesh.triangles[side as usize] == topo.edge_verts[2 * id];
                let k = if forward { kk as i32 } else { n - kk as i32 };
                add(t, edge_point(n, ed, k));
            }
        }
        out.copy_from_slice(&acc.mean());
    }

    RefinedMesh {
        level,
        positions,
        colours,
        indices,
        face_colours,
    }
}

/// Unit normal (zero for a degenerate triangle) and area of a triangle.
pub fn normal_and_area(p: [[f32; 3]; 3]) -> ([f32; 3], f32) {
    let x = face_normal(p);
    let len = (x[0] * x[0] + x[1] * x[1] + x[2] * x[2]).sqrt();
    if len > 0.0 {
        ([x[0] / len, x[1] / len, x[2] / len], 0.5 * len)
    } else {
        ([0.0; 3], 0.0)
    }
}

/// Area-weighted colour sum with a plain-mean fallback when every incident area is zero.
#[derive(Default)]
struct Accumulator {
    weighted: [f32; 3],
    area: f32,
    plain: [f32; 3],
    count: f32,
}

impl Accumulator {
    fn add(&mut self, face: &[f32]) {
        for k in 0..3 {
            self.weighted[k] += face[3] * face[k];
            self.plain[k] += face[k];
        }
        self.area += face[3];
        self.count += 1.0;
    }

    fn mean(&self) -> [f32; 4] {
        if self.area > 0.0 {
            [
                self.weighted[0] / self.area,
                self.weighted[1] / self.area,
                self.weighted[2] / self.area,
                1.0,
            ]
        } else if self.count > 0.0 {
            [
                self.plain[0] / self.count,
                self.plain[1] / self.count,
                self.plain[2] / self.count,
                1.0,
            ]
        } else {
            [0.0, 0.0, 0.0, 1.0]
        }
    }
}
