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
const TREE_WGSL: &str = include_str!("hce_tree.wgsl");
const LIGHT_WGSL: &str = include_str!("hce_light.wgsl");
const LATTICE_WGSL: &str = include_str!("hce_lattice.wgsl");
const GATHER_WGSL: &str = include_str!("hce_gather.wgsl");
const LOOP_WGSL: &str = include_str!("loop.wgsl");
const LOOP_WORKGROUP_WGSL: &str = include_str!("loop_workgroup.wgsl");
const LOOP_NORMALS_TEMPLATE: &str = include_str!("loop_normals.wgsl");
const FLAT_WGSL: &str = include_str!("flat.wgsl");
#[cfg(any(test, feature = "testing"))]
const DECODE_WGSL: &str = include_str!("decode.wgsl");

/// The placeholder of `loop_normals.wgsl`: the prefix of a patch memory's accessors.
const PATCH: &str = "{patch}";

/// The shared modules of a refinement kernel (flat and Loop), in dependency order, followed by
/// `kernel`.
pub(crate) fn refinement_source(kernel: &str) -> String {
    format!("{TREE_WGSL}\n{LIGHT_WGSL}\n{LATTICE_WGSL}\n{GATHER_WGSL}\n{kernel}")
}

/// The flat (linear 1-to-4) refinement kernel.
pub(crate) fn flat_source() -> String {
    refinement_source(FLAT_WGSL)
}

/// The colour-decoding kernel (`gpu::testing`): the tree walk, then `decode.wgsl`.
#[cfg(any(test, feature = "testing"))]
pub(crate) fn decode_source() -> String {
    format!("{TREE_WGSL}\n{DECODE_WGSL}")
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

    /// Every WGSL module the runtime compiles, as it hands them to wgpu: the assembled kernels
    /// (each variant of the workgroup kernel) and the standalone shaders.
    fn every_module() -> Vec<(String, String)> {
        let mut modules = vec![
            ("flat".to_string(), flat_source()),
            ("decode".to_string(), decode_source()),
            ("loop".to_string(), loop_source()),
            (
                "render".to_string(),
                include_str!("render.wgsl").to_string(),
            ),
            ("fill".to_string(), include_str!("fill.wgsl").to_string()),
        ];
        for (name, header) in super::super::loop_kernel::workgroup_headers() {
            modules.push((name, loop_workgroup_source(&header)));
        }
        modules
    }

    /// `source` parsed and validated by naga (the WGSL front end wgpu compiles with).
    fn parse(name: &str, source: &str) -> naga::Module {
        let module = naga::front::wgsl::parse_str(source)
            .unwrap_or_else(|e| panic!("{name}: {}", e.emit_to_string(source)));
        naga::valid::Validator::new(
            naga::valid::ValidationFlags::all(),
            naga::valid::Capabilities::default(),
        )
        .validate(&module)
        .unwrap_or_else(|e| panic!("{name}: {}", e.emit_to_string(source)));
        module
    }

    /// naga parses and validates every module, on any machine: a kernel that would fail to
    /// compile fails here, not only where a GPU is.
    #[test]
    fn every_assembled_module_parses_and_validates() {
        let modules = every_module();
        assert!(modules.len() >= 11, "{} modules", modules.len());
        for (name, source) in &modules {
            let module = parse(name, source);
            assert!(!module.entry_points.is_empty(), "{name}: no entry point");
        }
    }

    /// The value of the WGSL `const NAME: u32 = …u;` of `module`.
    fn u32_constant(module: &naga::Module, name: &str) -> u32 {
        let (_, c) = module
            .constants
            .iter()
            .find(|(_, c)| c.name.as_deref() == Some(name))
            .unwrap_or_else(|| panic!("no const {name}"));
        match module.global_expressions[c.init] {
            naga::Expression::Literal(naga::Literal::U32(v)) => v,
            ref e => panic!("{name}: {e:?} is not a u32 literal"),
        }
    }

    /// The constants the WGSL restates are the Rust ones they mirror.
    #[test]
    fn wgsl_constants_equal_their_rust_twins() {
        use super::super::loop_kernel::{INTERIOR, OWNS_EDGE, OWNS_VERTEX, SHARP};
        let module = parse("loop", &loop_source());
        for (name, rust) in [
            ("OWNS_EDGE", OWNS_EDGE),
            ("OWNS_VERTEX", OWNS_VERTEX),
            ("INTERIOR", INTERIOR),
            ("SHARP", SHARP),
            ("RULE_CREASE", hce_format::RULE_CREASE),
            ("RULE_CORNER", hce_format::RULE_CORNER),
            ("SPOKE_SHARP", hce_format::SPOKE_SHARP),
            ("VERTEX_BOUNDARY", hce_format::VERTEX_BOUNDARY),
            ("HCE_EVAL_BITS", hce_geometry::lighting::EVAL_LATTICE_BITS),
            ("HCE_LEAF", hce_geometry::lighting::LEAF),
        ] {
            assert_eq!(u32_constant(&module, name), rust, "{name}");
        }
    }

    /// Size and member offsets (by name) of the WGSL struct `name` of `module`.
    fn wgsl_struct(module: &naga::Module, name: &str) -> (u32, Vec<(String, u32)>) {
        let ty = module
            .types
            .iter()
            .find(|(_, t)| t.name.as_deref() == Some(name))
            .unwrap_or_else(|| panic!("no struct {name}"))
            .1;
        match &ty.inner {
            naga::TypeInner::Struct { members, span } => (
                *span,
                members
                    .iter()
                    .map(|m| (m.name.clone().unwrap_or_default(), m.offset))
                    .collect(),
            ),
            other => panic!("{name}: {other:?} is not a struct"),
        }
    }

    /// Each `#[repr(C)]` Rust twin of a WGSL struct the kernels read has its size, and the
    /// members both name sit at the same offsets.
    #[test]
    fn uniform_structs_match_their_rust_twins() {
        use std::mem::{offset_of, size_of};
        type LoopParams = super::super::loop_kernel::Params;
        type FlatParams = super::super::flat::Params;
        type Query = super::super::decode::ColourQuery;
        let flat = parse("flat", &flat_source());
        let (size, members) = wgsl_struct(&flat, "Params");
        assert_eq!(size as usize, size_of::<FlatParams>());
        assert_eq!(members.len() * 4, size_of::<FlatParams>(), "{members:?}");
        let at = |members: &[(String, u32)], n: &str| {
            members
                .iter()
                .find(|(m, _)| m == n)
                .unwrap_or_else(|| panic!("no member {n}"))
                .1 as usize
        };
        assert_eq!(at(&members, "level"), offset_of!(FlatParams, level));
        assert_eq!(
            at(&members, "vertex_corners_off"),
            offset_of!(FlatParams, vertex_corners_off)
        );
        assert_eq!(
            at(&members, "smooth_light"),
            offset_of!(FlatParams, smooth_light)
        );

        let lp = parse("loop", &loop_source());
        let (size, members) = wgsl_struct(&lp, "Params");
        assert_eq!(size as usize, size_of::<LoopParams>());
        // The Rust twin holds the section offsets as one array, from `tri_off` to
        // `slot_split_off` (the split's, SPEC.md F.5, last).
        assert_eq!(at(&members, "tri_off"), offset_of!(LoopParams, offsets));
        assert_eq!(
            at(&members, "slot_split_off"),
            offset_of!(LoopParams, offsets) + 4 * (super::super::loop_kernel::SECTIONS - 1)
        );
        assert_eq!(
            at(&members, "split_copies"),
            offset_of!(LoopParams, split_copies)
        );
        assert_eq!(at(&members, "ring_cap"), offset_of!(LoopParams, ring_cap));
        assert_eq!(at(&members, "exact"), offset_of!(LoopParams, exact));
        assert_eq!(
            at(&members, "smooth_light"),
            offset_of!(LoopParams, smooth_light)
        );

        let decode = parse("decode", &decode_source());
        let (size, members) = wgsl_struct(&decode, "Query");
        assert_eq!(size as usize, size_of::<Query>());
        assert_eq!(at(&members, "normal"), offset_of!(Query, normal));
    }

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
