//! The WGSL sources of the kernels, assembled at load: shared modules prepended to the kernels
//! that use them, in dependency order, so that each function of the GPU side is written once.
//!
//! * `hce_tree.wgsl`: the walk of a breadth-first HCE tree and the paper's face colour;
//! * `hce_light.wgsl`: the smooth reconstruction of baked lighting (SPEC.md Appendix G);
//! * `hce_lattice.wgsl`: the 1-to-4 lattice of a refined triangle and its vertex numbering;
//! * `hce_gather.wgsl`: the area-weighted vertex colours of the refinement kernels.

/// The shared tree-walking functions, prepended to every kernel that colours subtriangles.
pub(crate) const TREE_WGSL: &str = include_str!("hce_tree.wgsl");
const LIGHT_WGSL: &str = include_str!("hce_light.wgsl");
const LATTICE_WGSL: &str = include_str!("hce_lattice.wgsl");
const GATHER_WGSL: &str = include_str!("hce_gather.wgsl");

/// The shared modules of a refinement kernel (flat and Loop), in dependency order, followed by
/// `kernel`.
pub(crate) fn refinement_source(kernel: &str) -> String {
    format!("{TREE_WGSL}\n{LIGHT_WGSL}\n{LATTICE_WGSL}\n{GATHER_WGSL}\n{kernel}")
}
