//! Adaptive flat refinement (SPEC.md F.7.1): a flat object drawn from its HCE trees, one triangle
//! per leaf element plus the few that the corners of finer neighbouring leaves need, instead of
//! every coarse triangle split to the depth of the deepest leaf (F.7.2, [`crate::flat`]).
//!
//! The vertices are the leaf corners, on the lattice of denominator 4096 where the reconstruction
//! reads the field (G.2, G.4), identified as G.2 identifies points: shared across a joined coarse
//! edge, one per side across a split edge (a fold or a sharp edge), where both sides carry the
//! same points at the same positions, so the index buffer has neither cracks nor T-junctions. A
//! leaf whose edges carry corners of finer leaves (hanging points) is tiled by the recursive
//! midpoint rule of [`tile`], the "red-green" closure of adaptive mesh refinement: a red 1-to-4
//! split where all three edge midpoints are present, green bisections where one or two are.
//!
//! Based on: R. E. Bank, A. H. Sherman and A. Weiser. Refinement algorithms and data structures
//! for regular local mesh refinement. Scientific Computing, IMACS 1983 (red-green refinement),
//! and Cohen & Wallace, Radiosity and Realistic Image Synthesis, 1993, section 9.2 (T-vertices of
//! radiosity element meshes and their triangulation for display).

use std::collections::{HashMap, HashSet};

use hce_format::{Object, NO_NEIGHBOUR};

use crate::flat::lattice_position;
use crate::incidence::FlatTopology;
use crate::lattice::{edge_point, site, LatticeTriangle, Site};
use crate::lighting::{triangle_lighting, LightingError, PointKey, Surface, TREE_LATTICE};
use crate::normal::{face_normal, unit_or_up};
use crate::tables::InvalidObject;

/// Why a flat object could not be refined adaptively.
#[derive(Debug, thiserror::Error)]
pub enum AdaptiveFlatError {
    /// The control mesh's tables are inconsistent.
    #[error(transparent)]
    Object(#[from] InvalidObject),
    /// A triangle's record or tree is inconsistent.
    #[error(transparent)]
    Lighting(#[from] LightingError),
    #[error(
        "object '{object}': its adaptive refinement has more than 2^32 vertices or triangles; \
         split the object"
    )]
    TooLarge { object: String },
}

/// A flat object refined adaptively (SPEC.md F.7.1).
#[derive(Clone, Debug, Default, PartialEq)]
pub struct AdaptiveFlat {
    /// Per vertex, numbered in order of first use.
    pub positions: Vec<[f32; 3]>,
    /// Per vertex, the coarse triangle and the point `(x, y)` on its lattice of denominator
    /// 4096 of its first use, from which its position is computed: what a GPU kernel needs to
    /// compute the same bits (`runtime/src/gpu/flat.wgsl`).
    pub sources: Vec<(u32, [u32; 2])>,
    /// Unit per-vertex normals: the normalised sum of the triangles' `(q − p) × (r − p)` in
    /// triangle order, `(0, 1, 0)` where it has no direction (F.7.2's rule).
    pub normals: Vec<[f32; 3]>,
    /// Counter-clockwise, grouped by coarse triangle.
    pub indices: Vec<[u32; 3]>,
    /// Per triangle, its corners' points `(x, y)` on its coarse triangle's lattice of
    /// denominator 4096, where the colours are evaluated (G.4).
    pub points: Vec<[[u32; 2]; 3]>,
    /// Per triangle, the tree node (a leaf, breadth-first number) it lies in.
    pub leaves: Vec<u32>,
    /// The triangles of coarse triangle `t` are `triangle_start[t]..triangle_start[t + 1]`.
    pub triangle_start: Vec<u32>,
}

impl AdaptiveFlat {
    pub fn vertex_count(&self) -> usize {
        self.positions.len()
    }
    pub fn triangle_count(&self) -> usize {
        self.indices.len()
    }
    /// The coarse triangle triangle `f` lies in.
    pub fn coarse_triangle(&self, f: usize) -> usize {
        self.triangle_start.partition_point(|&s| s as usize <= f) - 1
    }

    /// The triangle corners that use each vertex, as a list per vertex: the uses of vertex `v`
    /// are `uses[offsets[v]..offsets[v + 1]]`, each `3 f + c` (corner `c` of triangle `f`), in
    /// increasing `3 f + c`, the order in which [`crate::colour::adaptive_flat_colours`] adds
    /// them. A kernel gathers a vertex's colour over them with one writer per vertex.
    pub fn incidence(&self) -> (Vec<u32>, Vec<u32>) {
        let mut offsets = vec![0u32; self.positions.len() + 1];
        for &i in self.indices.iter().flatten() {
            offsets[i as usize + 1] += 1;
        }
        for v in 0..self.positions.len() {
            offsets[v + 1] += offsets[v];
        }
        let mut next = offsets.clone();
        let mut uses = vec![0u32; 3 * self.indices.len()];
        for (g, &i) in self.indices.iter().flatten().enumerate() {
            uses[next[i as usize] as usize] = g as u32;
            next[i as usize] += 1;
        }
        (offsets, uses)
    }

    /// The lists a GPU kernel reads to draw this refinement (`runtime/src/gpu/flat.wgsl`, its
    /// sections after `Params::range_end`; the browser packs the same words): per vertex its
    /// coarse triangle and packed point (`x | y << 16` on the 4096 lattice); per triangle its
    /// coarse triangle, leaf and three packed corner points; per triangle its indices; the
    /// offsets and the uses of [`AdaptiveFlat::incidence`].
    pub fn kernel_lists(&self) -> KernelLists {
        let pack = |[x, y]: [u32; 2]| x | y << 16;
        let sources = self
            .sources
            .iter()
            .flat_map(|&(t, p)| [t, pack(p)])
            .collect();
        let mut faces = Vec::with_capacity(5 * self.triangle_count());
        for t in 0..self.triangle_start.len().saturating_sub(1) {
            let range = self.triangle_start[t] as usize..self.triangle_start[t + 1] as usize;
            for f in range {
                faces.extend([t as u32, self.leaves[f]]);
                faces.extend(self.points[f].map(pack));
            }
        }
        let indices = self.indices.iter().flatten().copied().collect();
        let (use_offsets, uses) = self.incidence();
        KernelLists {
            // refine_adaptive_flat keeps both counts within u32.
            vertices: self.vertex_count() as u32,
            triangles: self.triangle_count() as u32,
            sections: [sources, faces, indices, use_offsets, uses],
        }
    }
}

/// What a kernel reads of an [`AdaptiveFlat`] ([`AdaptiveFlat::kernel_lists`]).
#[derive(Clone, Debug, Default, PartialEq, Eq)]
pub struct KernelLists {
    pub vertices: u32,
    pub triangles: u32,
    /// Sources, faces, indices, use offsets, uses: in the order `flat.wgsl` reads them.
    pub sections: [Vec<u32>; 5],
}

/// The leaves of coarse triangle `t`: breadth-first node number and lattice triangle (G.2).
fn leaves_of(object: &Object, t: usize) -> Result<Vec<(u32, LatticeTriangle)>, LightingError> {
    let tree = triangle_lighting(object, t)?.tree;
    let mut cells = vec![LatticeTriangle::root(TREE_LATTICE)];
    let mut subdivided_seen = 0usize;
    let mut out = Vec::new();
    for info in tree.nodes() {
        let cell = cells[info.index as usize];
        if info.subdivided {
            // The children of the r-th subdivided node are 1 + 4r + c (SPEC.md B.2), so the
            // vector only ever grows at its end.
            let first = 1 + 4 * subdivided_seen;
            subdivided_seen += 1;
            cells.resize(first + 4, cell);
            for c in 0..4 {
                cells[first + c] = cell.child(c as u32);
            }
        } else {
            out.push((info.index, cell));
        }
    }
    Ok(out)
}

/// Tiles the lattice triangle `(a, b, c)` (counter-clockwise) whose edges hold the points for
/// which `has` is true at their midpoints, recursively (SPEC.md F.7.1): no midpoint, the
/// triangle; three, the 1-to-4 split; one, a bisection towards the opposite corner; two, the
/// corner triangle at the far corner and the remaining quadrilateral cut from the corner before
/// the edge without one. Every triangle it emits is counter-clockwise and non-degenerate.
pub fn tile(
    a: [i32; 2],
    b: [i32; 2],
    c: [i32; 2],
    has: &impl Fn([i32; 2]) -> bool,
    out: &mut Vec<[[i32; 2]; 3]>,
) {
    let mid = |p: [i32; 2], q: [i32; 2]| {
        let s = [p[0] + q[0], p[1] + q[1]];
        Some([s[0] / 2, s[1] / 2]).filter(|&m| s[0] % 2 == 0 && s[1] % 2 == 0 && has(m))
    };
    match (mid(a, b), mid(b, c), mid(c, a)) {
        (None, None, None) => out.push([a, b, c]),
        (Some(ab), Some(bc), Some(ca)) => {
            tile(a, ab, ca, has, out);
            tile(ab, b, bc, has, out);
            tile(bc, ca, ab, has, out);
            tile(ca, bc, c, has, out);
        }
        // One midpoint M on P Q, R opposite: (P, M, R), (M, Q, R).
        (Some(m), None, None) => {
            tile(a, m, c, has, out);
            tile(m, b, c, has, out);
        }
        (None, Some(m), None) => {
            tile(b, m, a, has, out);
            tile(m, c, a, has, out);
        }
        (None, None, Some(m)) => {
            tile(c, m, b, has, out);
            tile(m, a, b, has, out);
        }
        // Two midpoints, none on P Q: M1 on Q R, M2 on R P: (M2, M1, R), (P, Q, M1), (P, M1, M2).
        (None, Some(m1), Some(m2)) => {
            tile(m2, m1, c, has, out);
            tile(a, b, m1, has, out);
            tile(a, m1, m2, has, out);
        }
        (Some(m2), None, Some(m1)) => {
            tile(m2, m1, a, has, out);
            tile(b, c, m1, has, out);
            tile(b, m1, m2, has, out);
        }
        (Some(m1), Some(m2), None) => {
            tile(m2, m1, b, has, out);
            tile(c, a, m1, has, out);
            tile(c, m1, m2, has, out);
        }
    }
}

/// The adaptive refinement of flat `object` (SPEC.md F.7.1): vertices, triangles, normals and
/// each triangle's lattice points and leaf. Bad tables or trees give an error, never a panic.
pub fn refine_adaptive_flat(object: &Object) -> Result<AdaptiveFlat, AdaptiveFlatError> {
    let mesh = &object.mesh;
    let topo = FlatTopology::new(&object.name, mesh)?;
    let f = topo.triangle_count as usize;
    let n = TREE_LATTICE;
    let leaves = (0..f)
        .map(|t| leaves_of(object, t))
        .collect::<Result<Vec<_>, _>>()?;

    // The leaf corners strictly inside each side 3t + e, as distances from t's v_e.
    let mut side_points: Vec<Vec<i32>> = vec![Vec::new(); 3 * f];
    for (t, list) in leaves.iter().enumerate() {
        for (_, cell) in list {
            for [x, y] in cell.corners() {
                if let Site::Edge { edge, k } = site(n, x, y) {
                    side_points[3 * t + edge].push(k);
                }
            }
        }
    }
    for s in &mut side_points {
        s.sort_unstable();
        s.dedup();
    }
    // The side of the neighbour across side 3t + e: the one with the same edge id.
    let across = |s: usize| -> Option<usize> {
        let u = *mesh.neighbours.get(s)?;
        if u == NO_NEIGHBOUR || u as usize >= f {
            return None;
        }
        (0..3).map(|e| 3 * u as usize + e).find(|&side| {
            mesh.edges[side] == mesh.edges[s] && mesh.neighbours[side] as usize == s / 3
        })
    };

    let surface = Surface::new(object);
    let too_large = || AdaptiveFlatError::TooLarge {
        object: object.name.clone(),
    };
    let mut out = AdaptiveFlat::default();
    let mut vertex_of: HashMap<PointKey, u32> = HashMap::new();
    let mut cells = Vec::new();
    out.triangle_start.push(0);
    for (t, list) in leaves.iter().enumerate() {
        // P_t: the own leaf corners and the neighbours' points along shared edges.
        let mut points: HashSet<[i32; 2]> =
            list.iter().flat_map(|(_, cell)| cell.corners()).collect();
        for e in 0..3 {
            if let Some(other) = across(3 * t + e) {
                for &k in &side_points[other] {
                    points.insert(edge_point(n, e as u32, n - k));
                }
            }
        }
        let has = |p: [i32; 2]| points.contains(&p);
        let tri = mesh.triangle(t);
        let corners = tri.map(|v| mesh.position(v));
        for &(node, cell) in list {
            cells.clear();
            let [a, b, c] = cell.corners();
            tile(a, b, c, &has, &mut cells);
            for cell_tri in &cells {
                let idx = cell_tri.map(|[x, y]| {
                    let key = surface.key(t, x, y);
                    let next = out.positions.len() as u32;
                    *vertex_of.entry(key).or_insert_with(|| {
                        out.sources.push((t as u32, [x as u32, y as u32]));
                        out.positions.push(match site(n, x, y) {
                            Site::Corner(c) => corners[c],
                            Site::Edge { edge, k } => {
                                let id = mesh.edges[3 * t + edge] as usize;
                                let (pa, pb) =
                                    (topo.edge_verts[2 * id], topo.edge_verts[2 * id + 1]);
                                let k = if tri[edge] == pa { k } else { n - k };
                                let (pa, pb) = (mesh.position(pa), mesh.position(pb));
                                lattice_position([pa, pb, pb], n, k, 0)
                            }
                            Site::Interior => lattice_position(corners, n, x, y),
                        });
                        next
                    })
                });
                out.indices.push(idx);
                out.points.push(cell_tri.map(|p| p.map(|x| x as u32)));
                out.leaves.push(node);
            }
        }
        if out.positions.len() > u32::MAX as usize || out.indices.len() > u32::MAX as usize {
            return Err(too_large());
        }
        out.triangle_start.push(out.indices.len() as u32);
    }

    let mut sums = vec![[0f32; 3]; out.positions.len()];
    for t in &out.indices {
        let normal = face_normal(t.map(|i| out.positions[i as usize]));
        for &i in t {
            for k in 0..3 {
                sums[i as usize][k] += normal[k];
            }
        }
    }
    out.normals = sums.into_iter().map(unit_or_up).collect();
    Ok(out)
}
