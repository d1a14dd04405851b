//! Plain-Rust twins of the GPU kernels, step for step, so tests can compare the two.
//!
//! HCE colour decoding follows Concheiro et al., "Synthesis of multiresolution scenes with
//! global illumination on a GPU" (GRAPP 2012), section 4: walk the coarse triangle's
//! breadth-first tree along the subtriangle's path (a node's children are found by ranking it
//! among the subdivided nodes, a popcount over the tree's bits), stop at a leaf or at the
//! requested depth, and take the colour of the representative normal whose dot product with the
//! subtriangle's normal is largest.
//!
//! # Bitstream addressing
//! A triangle's tree is written breadth-first: bit `k` after `bits_start` says whether node `k`
//! (breadth-first, root 0) is subdivided. If node `k` is subdivided and `r` subdivided nodes
//! precede it, its children are nodes `1 + 4r + c`, `c` in Top, Left, Center, Right order.
//! This is why the start bit and the child bits form one array indexed by node.
//!
//! # Refined-mesh numbering (flat objects)
//! At level `L` with `n = 2^L`, a point of coarse triangle `(v0, v1, v2)` has lattice coordinates
//! `(a, b, c)`, `a + b + c = n`, position `(a p0 + b p1 + c p2) / n`. Output vertices are:
//! `[coarse vertices (V)] [edge points: E × (n − 1)] [interior points: F × (n − 1)(n − 2) / 2]`.
//! Edge `id`'s point `k` (`1 ≤ k < n`) is `V + id (n − 1) + k − 1`, counted from the owning
//! triangle's `v_e` towards its `v_{e+1}` ([`ControlMesh::edges`]). Triangle `t`'s interior point
//! `(b, c)` is `V + E (n − 1) + t I + I − j (j + 1) / 2 + b − 1` with `I = (n − 1)(n − 2) / 2`
//! and `j = n − 1 − c` (rows of constant `c` in increasing `c`, each in increasing `b`: the
//! numbering of [`crate::subdivide`], so flat and Loop refinements number vertices alike).
//! Fine triangle `t · 4^L + path`.

use hce_format::tree::decode_shape;
use hce_format::{rgb9e5, ControlMesh, Object, Tree, TreeError, TriangleRecord};

use super::GpuError;

/// Deepest refinement level the kernels accept (and so the deepest level a colour query may
/// walk to; trees themselves stop at [`hce_format::MAX_DEPTH`]): paths must fit in 32 bits
/// (`4^15 < 2^32`), and fine-triangle numbers `t · 4^L` in the output must too.
pub const MAX_RENDER_LEVEL: u32 = 15;

/// The breadth-first node reached from the root along `path` (`depth` child indices, first
/// most significant), stopping early at a leaf: the twin of `tree_node` in `hce_tree.wgsl`,
/// walked by the format's codec ([`Tree::find_path`]).
pub fn tree_node(tree: &Tree<'_>, depth: u32, path: u32) -> u32 {
    tree.find_path(depth, u64::from(path)).0
}

/// The tree of triangle `record` of an object that passed [`validate_tables`].
fn triangle_tree<'a>(object: &'a Object, record: &TriangleRecord) -> Tree<'a> {
    Tree::new(&object.bits, object.bit_len, u64::from(record.bits_start))
        .expect("validate_tables decoded every tree of this object")
}

/// Index (within the triangle's normal set) of the representative normal with the largest dot
/// product with `n`; ties go to the lower index, so the geometric normal wins a zero `n`.
pub fn choose_normal(normals: &[[f32; 3]], record: &TriangleRecord, n: [f32; 3]) -> u32 {
    let dot = |j: u32| {
        let m = normals[(record.normal_start + j) as usize];
        m[0] * n[0] + m[1] * n[1] + m[2] * n[2]
    };
    let mut best = 0;
    let mut best_dot = dot(0);
    for j in 1..record.normal_count {
        let d = dot(j);
        if d > best_dot {
            best = j;
            best_dot = d;
        }
    }
    best
}

/// A decoded subtriangle colour and where it came from.
#[derive(Clone, Copy, Debug, Default, PartialEq, bytemuck::Pod, bytemuck::Zeroable)]
#[repr(C)]
pub struct DecodedColour {
    /// Linear RGB.
    pub rgb: [f32; 3],
    /// Breadth-first tree node the walk stopped at.
    pub node: u32,
    /// Index of the chosen normal within the triangle's set.
    pub normal_index: u32,
    /// The RGB9E5 word decoded.
    pub packed: u32,
    pub _pad: [u32; 2],
}

/// Decodes the colour of subtriangle `path` at level `depth` of coarse triangle `t`, whose
/// normal is `n` (need not be unit length). The object must have passed [`validate_tables`].
pub fn decode_colour(object: &Object, t: u32, depth: u32, path: u32, n: [f32; 3]) -> DecodedColour {
    let record = &object.triangles[t as usize];
    decode_colour_in(
        object,
        record,
        &triangle_tree(object, record),
        depth,
        path,
        n,
    )
}

/// [`decode_colour`] with the triangle's tree already decoded.
fn decode_colour_in(
    object: &Object,
    record: &TriangleRecord,
    tree: &Tree<'_>,
    depth: u32,
    path: u32,
    n: [f32; 3],
) -> DecodedColour {
    let node = tree_node(tree, depth, path);
    let normal_index = choose_normal(&object.normals, record, n);
    let packed =
        object.colours[(record.colour_start + node * record.normal_count + normal_index) as usize];
    DecodedColour {
        rgb: rgb9e5::decode(packed),
        node,
        normal_index,
        packed,
        _pad: [0; 2],
    }
}

/// What validation learnt about an object's trees.
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq)]
pub struct TreeSummary {
    /// Deepest leaf over all triangles (0 when every tree is a single root).
    pub max_depth: u32,
    /// Total tree nodes over all triangles.
    pub nodes: u64,
}

/// Checks everything the colour kernels index, so that a malformed table is an error here and
/// never an out-of-bounds read on the GPU: record ranges into normals and colours, every tree's
/// bits inside `bit_len`, trees decodable by the format's codec (so no deeper than
/// [`hce_format::MAX_DEPTH`]), word counts consistent. Work is bounded by `bit_len` (trees
/// together may not claim more nodes than there are bits).
pub fn validate_tables(object: &Object) -> Result<TreeSummary, GpuError> {
    let err = |reason: String| GpuError::InvalidObject {
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
    /// Builds the tables from a control mesh, checking indices, edge ids (dense, numbered in
    /// order of first appearance) and that every appearance of an edge joins the same two
    /// vertices.
    pub fn new(name: &str, mesh: &ControlMesh) -> Result<Self, GpuError> {
        let err = |reason: String| GpuError::InvalidObject {
            object: name.to_string(),
            reason,
        };
        if mesh.positions.len() % 3 != 0 || mesh.triangles.len() % 3 != 0 {
            return Err(err("positions or triangles not a multiple of 3 long".into()));
        }
        let v = mesh.vertex_count();
        let f = mesh.triangle_count();
        if v > u32::MAX as usize / 2 || f > u32::MAX as usize / 4 {
            return Err(err("mesh too large for 32-bit indices".into()));
        }
        if mesh.edges.len() != mesh.triangles.len() {
            return Err(err(format!(
                "{} edge ids for {} triangle edges",
                mesh.edges.len(),
                mesh.triangles.len()
            )));
        }
        let mut edge_verts: Vec<u32> = Vec::new();
        let mut side_count: Vec<u32> = Vec::new();
        for t in 0..f {
            let tri = mesh.triangle(t);
            for (c, &x) in tri.iter().enumerate() {
                if x as usize >= v {
                    return Err(err(format!("triangle {t} corner {c}: vertex {x} >= {v}")));
                }
            }
            if tri[0] == tri[1] || tri[1] == tri[2] || tri[2] == tri[0] {
                return Err(err(format!("triangle {t} is degenerate: {tri:?}")));
            }
            for e in 0..3 {
                let id = mesh.edges[3 * t + e];
                let (a, b) = (tri[e], tri[(e + 1) % 3]);
                let count = side_count.len() as u32;
                if id == count {
                    edge_verts.extend([a, b]);
                    side_count.push(1);
                } else if id < count {
                    let (oa, ob) = (edge_verts[2 * id as usize], edge_verts[2 * id as usize + 1]);
                    if !((oa == a && ob == b) || (oa == b && ob == a)) {
                        return Err(err(format!(
                            "triangle {t} edge {e}: edge id {id} joins ({oa}, {ob}) elsewhere \
                             but ({a}, {b}) here"
                        )));
                    }
                    side_count[id as usize] += 1;
                } else {
                    return Err(err(format!(
                        "triangle {t} edge {e}: edge id {id} skips ids (next new id is {count}); \
                         ids must be numbered in order of first appearance"
                    )));
                }
            }
        }
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

    /// Output vertex count at `level`.
    pub fn refined_vertex_count(&self, level: u32) -> u64 {
        let n = 1u64 << level;
        u64::from(self.vertex_count)
            + u64::from(self.edge_count) * (n - 1)
            + u64::from(self.triangle_count) * interior_per_triangle(n)
    }

    pub fn refined_triangle_count(&self, level: u32) -> u64 {
        u64::from(self.triangle_count) << (2 * level)
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

fn interior_per_triangle(n: u64) -> u64 {
    if n < 2 {
        0
    } else {
        (n - 1) * (n - 2) / 2
    }
}

/// The lattice corners `(b, c)` of fine triangle `path` at level `level` (`n = 2^level`), found
/// by descending the 1-to-4 split: a triangle is `(C0, σ, s)` with corners `C0`, `C0 + σ s e_b`,
/// `C0 + σ s e_c`; the Center child flips `σ`.
pub fn fine_corners(level: u32, path: u32) -> [[i32; 2]; 3] {
    let mut c0 = [0i32, 0i32];
    let mut sigma = 1i32;
    let mut s = 1i32 << level;
    for k in 0..level {
        let h = s / 2;
        let child = (path >> (2 * (level - 1 - k))) & 3;
        match child {
            0 => {}
            1 => c0[0] += sigma * h,
            2 => {
                c0 = [c0[0] + sigma * h, c0[1] + sigma * h];
                sigma = -sigma;
            }
            _ => c0[1] += sigma * h,
        }
        s = h;
    }
    [c0, [c0[0] + sigma, c0[1]], [c0[0], c0[1] + sigma]]
}

/// The path of the fine triangle whose centroid, times 3, is `q` (lattice `(b, c)` units).
pub fn locate(level: u32, q: [i32; 2]) -> u32 {
    let mut c0 = [0i32, 0i32];
    let mut sigma = 1i32;
    let mut s = 1i32 << level;
    let mut path = 0u32;
    for _ in 0..level {
        let h = s / 2;
        let l1 = sigma * (q[0] - 3 * c0[0]);
        let l2 = sigma * (q[1] - 3 * c0[1]);
        let l0 = 3 * s - l1 - l2;
        let child = if l0 > 3 * h {
            0
        } else if l1 > 3 * h {
            c0[0] += sigma * h;
            1
        } else if l2 > 3 * h {
            c0[1] += sigma * h;
            3
        } else {
            c0 = [c0[0] + sigma * h, c0[1] + sigma * h];
            sigma = -sigma;
            2
        };
        path = path * 4 + child;
        s = h;
    }
    path
}

/// Paths of the fine triangles around lattice point `(b, c)` inside one coarse triangle, in the
/// fixed order the kernels sum them: up triangles anchored at `(b, c)`, `(b − 1, c)`,
/// `(b, c − 1)`, then down triangles anchored at `(b, c)`, `(b + 1, c)`, `(b, c + 1)`.
pub fn incident_paths(level: u32, b: i32, c: i32) -> impl Iterator<Item = u32> {
    let n = 1i32 << level;
    let ups = [(b, c), (b - 1, c), (b, c - 1)];
    let downs = [(b, c), (b + 1, c), (b, c + 1)];
    let up = ups
        .into_iter()
        .filter(move |&(x, y)| x >= 0 && y >= 0 && x + y < n)
        .map(move |(x, y)| locate(level, [3 * x + 1, 3 * y + 1]));
    let down = downs
        .into_iter()
        .filter(move |&(x, y)| x >= 1 && y >= 1 && x + y <= n)
        .map(move |(x, y)| locate(level, [3 * x - 1, 3 * y - 1]));
    up.chain(down)
}

/// The lattice point of edge `e` of a triangle at `k` steps from its `v_e`.
pub fn edge_point(n: i32, e: u32, k: i32) -> [i32; 2] {
    match e {
        0 => [k, 0],
        1 => [n - k, k],
        _ => [0, n - k],
    }
}

/// Lattice point `(b, c)` of triangle `t` → output vertex index (see the module docs).
pub fn vertex_index(
    topo: &FlatTopology,
    mesh: &ControlMesh,
    level: u32,
    t: u32,
    b: i32,
    c: i32,
) -> u32 {
    let n = 1i32 << level;
    let a = n - b - c;
    let tri = mesh.triangle(t as usize);
    let (e, k) = match (a, b, c) {
        (_, 0, 0) => return tri[0],
        (0, _, 0) => return tri[1],
        (0, 0, _) => return tri[2],
        (_, _, 0) => (0, b),
        (0, _, _) => (1, c),
        (_, 0, _) => (2, a),
        _ => {
            let j = (n - 1 - c) as u32;
            let ip = interior_per_triangle(n as u64) as u32;
            return topo.vertex_count
                + topo.edge_count * (n as u32 - 1)
                + t * ip
                + (ip - j * (j + 1) / 2)
                + (b as u32 - 1);
        }
    };
    let id = mesh.edges[3 * t as usize + e];
    let forward = topo.edge_verts[2 * id as usize] == tri[e];
    let kk = if forward { k } else { n - k };
    topo.vertex_count + id * (n as u32 - 1) + (kk as u32 - 1)
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

/// Position of lattice point `(b, c)` of triangle `(p0, p1, p2)`, as the kernel computes it.
fn lattice_position(p: [[f32; 3]; 3], n: i32, b: i32, c: i32) -> [f32; 3] {
    let inv = 1.0 / n as f32;
    let (wa, wb, wc) = ((n - b - c) as f32, b as f32, c as f32);
    std::array::from_fn(|i| (p[0][i] * wa + p[1][i] * wb + p[2][i] * wc) * inv)
}

/// The CPU reference of [`super::flat::refine_flat`]: linear 1-to-4 split of every coarse
/// triangle to `level`, one colour per fine triangle from its tree node (normal chosen by the
/// fine triangle's normal), vertex colours as area-weighted means over every incident fine
/// triangle, across coarse edges and vertices. `object` must have passed [`validate_tables`].
pub fn refine_flat_cpu(object: &Object, topo: &FlatTopology, level: u32) -> RefinedMesh {
    let mesh = &object.mesh;
    let n = 1i32 << level;
    let nv = topo.refined_vertex_count(level) as usize;
    let f = topo.triangle_count as usize;
    let per = 1usize << (2 * level);

    // Step 1: vertex positions, one writer per vertex.
    let mut positions = vec![0f32; 3 * nv];
    let v = topo.vertex_count as usize;
    positions[..3 * v].copy_from_slice(&mesh.positions[..3 * v]);
    let ep = (n - 1) as usize;
    for id in 0..topo.edge_count as usize {
        let pa = mesh.position(topo.edge_verts[2 * id]);
        let pb = mesh.position(topo.edge_verts[2 * id + 1]);
        for k in 1..n {
            let p = lattice_position([pa, pb, pb], n, k, 0);
            let i = v + id * ep + (k as usize - 1);
            positions[3 * i..3 * i + 3].copy_from_slice(&p);
        }
    }
    let base = v + topo.edge_count as usize * ep;
    let ip = interior_per_triangle(n as u64) as usize;
    for t in 0..f {
        let tri = mesh.triangle(t).map(|x| mesh.position(x));
        for local in 0..ip {
            let (b, c) = interior_coords(n, local as u32);
            let p = lattice_position(tri, n, b, c);
            let i = base + t * ip + local;
            positions[3 * i..3 * i + 3].copy_from_slice(&p);
        }
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
            indices[3 * g..3 * g + 3].copy_from_slice(&idx);
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
        let mut add = |t: u32, b: i32, c: i32| {
            for path in incident_paths(level, b, c) {
                let g = t as usize * per + path as usize;
                acc.add(&face_colours[4 * g..4 * g + 4]);
            }
        };
        if i < v {
            let (s, e) = (
                topo.vertex_corner_offsets[i] as usize,
                topo.vertex_corner_offsets[i + 1] as usize,
            );
            for &corner in &topo.vertex_corners[s..e] {
                let [b, c] = match corner % 3 {
                    0 => [0, 0],
                    1 => [n, 0],
                    _ => [0, n],
                };
                add(corner / 3, b, c);
            }
        } else if i < base {
            let id = (i - v) / ep;
            let kk = ((i - v) % ep) as i32 + 1;
            let (s, e) = (
                topo.edge_side_offsets[id] as usize,
                topo.edge_side_offsets[id + 1] as usize,
            );
            for &side in &topo.edge_sides[s..e] {
                let (t, ed) = (side / 3, side % 3);
                let forward = mesh.triangles[side as usize] == topo.edge_verts[2 * id];
                let k = if forward { kk } else { n - kk };
                let [b, c] = edge_point(n, ed, k);
                add(t, b, c);
            }
        } else {
            let t = (i - base) / ip;
            let (b, c) = interior_coords(n, ((i - base) % ip) as u32);
            add(t as u32, b, c);
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

/// `(b, c)` of interior point `local` (inverse of the numbering in the module docs).
pub fn interior_coords(n: i32, local: u32) -> (i32, i32) {
    let ip = interior_per_triangle(n as u64) as u32;
    // Counted from the last point, rows have 1, 2, 3, ... points: the row of length j holds
    // r = ip − 1 − local when j (j − 1) / 2 <= r < j (j + 1) / 2. Start from the float root,
    // correct exactly.
    let r = ip - 1 - local;
    let mut j = ((1.0 + (1.0 + 8.0 * r as f64).sqrt()) / 2.0).floor() as u32;
    while j * (j - 1) / 2 > r {
        j -= 1;
    }
    while (j + 1) * j / 2 <= r {
        j += 1;
    }
    let b = (local - (ip - j * (j + 1) / 2)) as i32 + 1;
    (b, n - 1 - j as i32)
}

/// Unit normal (zero for a degenerate triangle) and area of a triangle.
pub fn normal_and_area(p: [[f32; 3]; 3]) -> ([f32; 3], f32) {
    let u = [p[1][0] - p[0][0], p[1][1] - p[0][1], p[1][2] - p[0][2]];
    let w = [p[2][0] - p[0][0], p[2][1] - p[0][1], p[2][2] - p[0][2]];
    let x = [
        u[1] * w[2] - u[2] * w[1],
        u[2] * w[0] - u[0] * w[2],
        u[0] * w[1] - u[1] * w[0],
    ];
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

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn locate_inverts_fine_corners() {
        for level in 0..5 {
            for path in 0..(1u32 << (2 * level)) {
                let [p0, p1, p2] = fine_corners(level, path);
                let q = [p0[0] + p1[0] + p2[0], p0[1] + p1[1] + p2[1]];
                assert_eq!(locate(level, q), path, "level {level}");
            }
        }
    }

    #[test]
    fn first_level_children_have_the_model_corners() {
        // n = 2: v0 = (0,0), v1 = (2,0), v2 = (0,2), m01 = (1,0), m12 = (1,1), m20 = (0,1).
        assert_eq!(fine_corners(1, 0), [[0, 0], [1, 0], [0, 1]]); // Top (v0, m01, m20)
        assert_eq!(fine_corners(1, 1), [[1, 0], [2, 0], [1, 1]]); // Left (m01, v1, m12)
        assert_eq!(fine_corners(1, 2), [[1, 1], [0, 1], [1, 0]]); // Center (m12, m20, m01)
        assert_eq!(fine_corners(1, 3), [[0, 1], [1, 1], [0, 2]]); // Right (m20, m12, v2)
    }

    #[test]
    fn interior_numbering_is_a_bijection() {
        for level in 2..6 {
            let n = 1i32 << level;
            let ip = interior_per_triangle(n as u64) as u32;
            let mut seen = std::collections::HashSet::new();
            for local in 0..ip {
                let (b, c) = interior_coords(n, local);
                assert!(b >= 1 && c >= 1 && b + c < n, "({b}, {c}) at level {level}");
                let j = (n - 1 - c) as u32;
                assert_eq!(ip - j * (j + 1) / 2 + b as u32 - 1, local);
                assert!(seen.insert((b, c)));
            }
            // The order of crate::subdivide: rows of increasing c, each of increasing b.
            let order: Vec<(i32, i32)> = (1..n)
                .flat_map(|c| (1..n - c).map(move |b| (b, c)))
                .collect();
            let ours: Vec<(i32, i32)> = (0..ip).map(|l| interior_coords(n, l)).collect();
            assert_eq!(ours, order, "level {level}");
        }
    }

    #[test]
    fn every_lattice_point_has_its_incident_fine_triangles() {
        let level = 3;
        let n = 8;
        // Interior points touch 6 fine triangles, edge points 3, corners 1.
        assert_eq!(incident_paths(level, 3, 2).count(), 6);
        assert_eq!(incident_paths(level, 3, 0).count(), 3);
        assert_eq!(incident_paths(level, 0, 0).count(), 1);
        assert_eq!(incident_paths(level, n, 0).count(), 1);
        for path in incident_paths(level, 3, 2) {
            assert!(fine_corners(level, path).contains(&[3, 2]));
        }
    }
}
