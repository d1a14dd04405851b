//! The paper's colour of one subtriangle, the plain-Rust twin of `hce_tree.wgsl`
//! (`hce_tree_node`, `hce_choose_normal`, `hce_nearest_colour`) step for step, so tests can
//! compare the two.
//!
//! Based on: Concheiro et al., "Synthesis of multiresolution scenes with global illumination on
//! a GPU", GRAPP 2012, section 4. Walk the coarse triangle's breadth-first tree along the
//! subtriangle's path (a node's children are found by ranking it among the subdivided nodes, a
//! popcount over the tree's bits), stop at a leaf or at the requested depth, and take the colour
//! of the representative normal whose dot product with the subtriangle's normal is largest.
//!
//! # Bitstream addressing
//! A triangle's tree is written breadth-first: bit `k` after `bits_start` says whether node `k`
//! (breadth-first, root 0) is subdivided. If node `k` is subdivided and `r` subdivided nodes
//! precede it, its children are nodes `1 + 4r + c`, `c` in Top, Left, Center, Right order.
//! This is why the start bit and the child bits form one array indexed by node.

use hce_format::{rgb9e5, Object, Tree, TriangleRecord};

/// Deepest level a subtriangle path can name: `L` child indices of two bits each in a `u32`, with
/// `4^L` computable in 32 bits (`4^15 = 2^30`). It bounds the GPU flat kernel's levels and the
/// levels of colour queries; Loop subdivision stops earlier, at
/// [`crate::subdivide::MAX_LOOP_LEVEL`], and trees themselves at [`hce_format::MAX_TREE_DEPTH`].
pub const MAX_PATH_LEVEL: u32 = 15;

/// The breadth-first node reached from the root along `path` (`depth` child indices, first
/// most significant), stopping early at a leaf: the twin of `tree_node` in `hce_tree.wgsl`,
/// walked by the format's codec ([`Tree::find_path`]).
pub fn tree_node(tree: &Tree<'_>, depth: u32, path: u32) -> u32 {
    tree.find_path(depth, u64::from(path)).0
}

/// The tree of triangle `record` of an object that passed [`validate_tables`](crate::tables::validate_tables).
pub(crate) fn triangle_tree<'a>(object: &'a Object, record: &TriangleRecord) -> Tree<'a> {
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
/// normal is `n` (need not be unit length). The object must have passed [`validate_tables`](crate::tables::validate_tables).
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
pub(crate) fn decode_colour_in(
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
