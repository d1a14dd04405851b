//! The WGSL sources of the kernels, assembled at load so that each function of the GPU side is
//! written once: shared modules prepended to the kernels that use them, in dependency order,
//! and one template instantiated per memory.
//!
//! * `hce_tree.wgsl`: the walk of a breadth-first HCE tree and the paper's face colour;
//! * `hce_light.wgsl`: the smooth reconstruction of baked lighting (SPEC.md Appendix G);
//! * `hce_lattice.wgsl`: the 1-to-4 lattice of a refined triangle and its vertex numbering;
//! * `hce_gather.wgsl`: the area-weighted vertex colours of the refinement kernels;
//! * `loop_normals.wgsl`: the vertex normals of a Loop patch, a template over the patch memory
//!   (WGSL has no pointer that reaches both storage and workgroup memory), instantiated for the
//!   scratch kernel of `loop.wgsl` and for the workgroup kernel of `loop_workgroup.wgsl`.

/// The shared tree-walking functions, prepended to every kernel that colours subtriangles.
pub(crate) const TREE_WGSL: &str = include_str!("hce_tree.wgsl");
const LIGHT_WGSL: &str = include_str!("hce_light.wgsl");
const LATTICE_WGSL: &str = include_str!("hce_lattice.wgsl");
const GATHER_WGSL: &str = include_str!("hce_gather.wgsl");
const LOOP_WGSL: &str = include_str!("loop.wgsl");
const LOOP_WORKGROUP_WGSL: &str = include_str!("loop_workgroup.wgsl");
const LOOP_NORMALS_TEMPLATE: &str = include_str!("loop_normals.wgsl");

/// The placeholder of `loop_normals.wgsl`: the prefix of a patch memory's accessors.
const PATCH: &str = "{patch}";

/// The shared modules of a refinement kernel (flat and Loop), in dependency order, followed by
/// `kernel`.
pub(crate) fn refinement_source(kernel: &str) -> String {
    format!("{TREE_WGSL}\n{LIGHT_WGSL}\n{LATTICE_WGSL}\n{GATHER_WGSL}\n{kernel}")
}

/// `loop_normals.wgsl` for the patch memory whose accessors start with `prefix` (`sq_at`,
/// `ring_at` for the scratch kernel's storage buffer; `wg_sq_at`, `wg_ring_at` for workgroup
/// memory).
fn patch_normals(prefix: &str) -> String {
    LOOP_NORMALS_TEMPLATE.replace(PATCH, prefix)
}

/// The Loop kernel's module: its three steps, with the scratch patch kernel (`patch_main`).
pub(crate) fn loop_source() -> String {
    refinement_source(&format!("{LOOP_WGSL}\n{}", patch_normals("")))
}

/// A variant of the workgroup patch kernel (`patch_wg_main`): the Loop kernel's module, then
/// `header` (the variant's constants) and `loop_workgroup.wgsl` with its normals.
pub(crate) fn loop_workgroup_source(header: &str) -> String {
    format!(
        "{}\n{header}\n{LOOP_WORKGROUP_WGSL}\n{}",
        loop_source(),
        patch_normals("wg_")
    )
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn the_normals_template_is_instantiated_once_per_patch_memory() {
        let scratch = loop_source();
        let workgroup = loop_workgroup_source("");
        for source in [&scratch, &workgroup] {
            assert!(!source.contains(PATCH), "a placeholder is left");
            assert_eq!(source.matches("fn grid_normal(").count(), 1);
            assert_eq!(source.matches("fn corner_normal(").count(), 1);
        }
        assert_eq!(scratch.matches("fn wg_grid_normal(").count(), 0);
        assert_eq!(workgroup.matches("fn wg_grid_normal(").count(), 1);
        assert_eq!(workgroup.matches("fn wg_corner_normal(").count(), 1);
    }
}
