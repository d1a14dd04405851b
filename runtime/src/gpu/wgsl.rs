//! The WGSL sources of the kernels, assembled at load so that each function of the GPU side is
//! written once. Each module names the modules it needs in its own file, one line each, as
//! naga_oil's `#import` does (a comment, so that the file stays plain WGSL):
//!
//! ```wgsl
//! // #import hce_tree
//! ```
//!
//! and a kernel's source is its module after every module it imports, directly or not, each
//! once, in the order of a depth-first walk of the declarations ([`import_order`]).
//! `web/src/wgsl.js` walks the same declarations, so that the order is written nowhere else.
//!
//! * `hce_constants.wgsl`: the constants the kernels share with the Rust side, generated from
//!   the Rust constants (the list `CONSTANTS`; a test fails while the checked-in file differs, and
//!   `HCE_WRITE_WGSL=1` rewrites it);
//! * `hce_bindings.wgsl`: the storage buffers of the refinement and decoding kernels, one
//!   numbering for all (its Rust twin is `bindings.rs`);
//! * `hce_tree.wgsl`: the walk of a breadth-first HCE tree and the paper's face colour;
//! * `hce_light.wgsl`: the smooth reconstruction of baked lighting (SPEC.md Appendix G);
//! * `hce_lattice.wgsl`: the 1-to-4 lattice of a refined triangle and its vertex numbering;
//! * `hce_gather.wgsl`: the area-weighted vertex colours of the refinement kernels;
//! * `hce_batch.wgsl`: the table through which the batched entry points of the refinement
//!   kernels find each invocation's object;
//! * `loop_batch.wgsl`: the batched Loop kernel, assembled after `loop.wgsl` with its `params`
//!   uniform made a private variable ([`loop_batch_source`]);
//! * `loop_normals.wgsl`: the vertex normals of a Loop patch, a template over the patch memory
//!   (WGSL has no pointer that reaches both storage and workgroup memory), instantiated for the
//!   scratch kernel of `loop.wgsl` and for the workgroup kernel of `loop_workgroup.wgsl`.

/// Every module a kernel may import or be, by name (its file without `.wgsl`).
const MODULES: &[(&str, &str)] = &[
    ("hce_constants", include_str!("hce_constants.wgsl")),
    ("hce_bindings", include_str!("hce_bindings.wgsl")),
    ("hce_tree", include_str!("hce_tree.wgsl")),
    ("hce_light", include_str!("hce_light.wgsl")),
    ("hce_lattice", include_str!("hce_lattice.wgsl")),
    ("hce_gather", include_str!("hce_gather.wgsl")),
    ("hce_batch", include_str!("hce_batch.wgsl")),
    ("flat", include_str!("flat.wgsl")),
    ("loop", include_str!("loop.wgsl")),
    ("loop_workgroup", include_str!("loop_workgroup.wgsl")),
    ("loop_batch", include_str!("loop_batch.wgsl")),
    #[cfg(any(test, feature = "testing"))]
    ("decode", include_str!("decode.wgsl")),
];

const LOOP_NORMALS_TEMPLATE: &str = include_str!("loop_normals.wgsl");

/// The placeholder of `loop_normals.wgsl`: the prefix of a patch memory's accessors.
const PATCH: &str = "{patch}";

/// `loop.wgsl`'s uniform, and what the batched kernel makes of it: a variable each invocation
/// sets from its object's entry of the batch table (`loop_batch.wgsl`).
const LOOP_PARAMS_UNIFORM: &str = "@group(0) @binding(0) var<uniform> params: Params;";
const LOOP_PARAMS_PRIVATE: &str = "var<private> params: Params;";

/// The line that starts an import declaration.
const IMPORT: &str = "// #import ";

/// Why a kernel's modules cannot be put in order.
#[derive(Debug, PartialEq, Eq, thiserror::Error)]
pub(crate) enum ImportError {
    #[error("{module}.wgsl imports {import}, which is not a module (no {import}.wgsl)")]
    Missing { module: String, import: String },
    #[error("no module {module} ({module}.wgsl)")]
    Unknown { module: String },
    #[error("circular import: {}", .cycle.join(" -> "))]
    Circular { cycle: Vec<String> },
}

/// The modules a module's `text` imports, in the order it declares them.
pub(crate) fn imports(text: &str) -> impl Iterator<Item = &str> {
    text.lines()
        .filter_map(|line| line.trim().strip_prefix(IMPORT.trim_start()))
        .map(str::trim)
}

/// `root` and every module it imports, directly or not, each once, every module after the
/// modules it imports (a depth-first walk of the declarations, in their order). `text` gives a
/// module's file, `None` where there is none.
pub(crate) fn import_order<'a>(
    root: &'a str,
    text: &impl Fn(&str) -> Option<&'a str>,
) -> Result<Vec<&'a str>, ImportError> {
    fn visit<'a>(
        module: &'a str,
        text: &impl Fn(&str) -> Option<&'a str>,
        path: &mut Vec<&'a str>,
        order: &mut Vec<&'a str>,
    ) -> Result<(), ImportError> {
        if order.contains(&module) {
            return Ok(());
        }
        if let Some(at) = path.iter().position(|&m| m == module) {
            let mut cycle: Vec<String> = path[at..].iter().map(|m| m.to_string()).collect();
            cycle.push(module.to_string());
            return Err(ImportError::Circular { cycle });
        }
        let source = text(module).ok_or_else(|| match path.last() {
            Some(importer) => ImportError::Missing {
                module: importer.to_string(),
                import: module.to_string(),
            },
            None => ImportError::Unknown {
                module: module.to_string(),
            },
        })?;
        path.push(module);
        for import in imports(source) {
            visit(import, text, path, order)?;
        }
        path.pop();
        order.push(module);
        Ok(())
    }
    let mut order = Vec::new();
    visit(root, text, &mut Vec::new(), &mut order)?;
    Ok(order)
}

/// The text of module `name` of [`MODULES`].
fn module_text(name: &str) -> Option<&'static str> {
    MODULES.iter().find(|(n, _)| *n == name).map(|(_, t)| *t)
}

/// The source of kernel `root`: its modules in [`import_order`], each passed through `expand`
/// (which adds what a module is assembled with, given its name and text), joined by newlines.
fn assemble(root: &'static str, expand: impl Fn(&str, &str) -> String) -> String {
    // The modules are this crate's own files: the test of every assembled module fails on a
    // missing or circular import before any build ships it.
    let order = import_order(root, &module_text).unwrap_or_else(|e| panic!("{e}"));
    order
        .iter()
        .map(|m| expand(m, module_text(m).expect("import_order found it")))
        .collect::<Vec<_>>()
        .join("\n")
}

/// The one list of the constants the WGSL shares with the Rust side: WGSL name, value (the Rust
/// constant itself) and what it is. `hce_constants.wgsl` is generated from it
/// ([`constants_wgsl`]) and checked in, so that the browser, which fetches the same files,
/// gets it too.
#[cfg(test)]
const CONSTANTS: &[(&str, u32, &str)] = &[
    (
        "OWNS_EDGE",
        super::loop_kernel::OWNS_EDGE,
        "<< e: the triangle owns edge e (writes its points); loop_kernel.rs",
    ),
    (
        "OWNS_VERTEX",
        super::loop_kernel::OWNS_VERTEX,
        "<< c: the triangle's corner c writes coarse vertex v_c; loop_kernel.rs",
    ),
    (
        "INTERIOR",
        super::loop_kernel::INTERIOR,
        "<< e: edge e has a neighbour (a band); loop_kernel.rs",
    ),
    (
        "SHARP",
        super::loop_kernel::SHARP,
        "<< e: edge e is infinitely sharp; loop_kernel.rs",
    ),
    (
        "RULE_CREASE",
        hce_format::RULE_CREASE,
        "the crease vertex rule (SPEC.md A.7); hce_format",
    ),
    (
        "RULE_CORNER",
        hce_format::RULE_CORNER,
        "the corner vertex rule (SPEC.md A.7); hce_format",
    ),
    (
        "SPOKE_SHARP",
        hce_format::SPOKE_SHARP,
        "a spoke's sharp bit (SPEC.md A.7); hce_format",
    ),
    (
        "VERTEX_BOUNDARY",
        hce_format::VERTEX_BOUNDARY,
        "a vertex's boundary bit (SPEC.md A.7); hce_format",
    ),
    (
        "HCE_EVAL_BITS",
        hce_geometry::lighting::EVAL_LATTICE_BITS,
        "bits of the lattice in which points are evaluated; lighting.rs EVAL_LATTICE_BITS",
    ),
    (
        "HCE_TREE_BITS",
        hce_geometry::lighting::TREE_LATTICE_BITS,
        "bits of the lattice of the leaf corners (SPEC.md G.2, F.7.1); lighting.rs TREE_LATTICE_BITS",
    ),
    (
        "HCE_LEAF",
        hce_geometry::lighting::LEAF,
        "a leaf's node word; lighting.rs LEAF",
    ),
    (
        "BATCH_ENTRY_BASES",
        super::batch::ENTRY_BASES as u32,
        "words of a batch entry before the object's Params; batch.rs ENTRY_BASES",
    ),
    (
        "FLAT_ENTRY_WORDS",
        super::batch::FLAT_ENTRY_WORDS as u32,
        "words of a flat batch entry; batch.rs FLAT_ENTRY_WORDS",
    ),
    (
        "LOOP_ENTRY_WORDS",
        super::batch::LOOP_ENTRY_WORDS as u32,
        "words of a Loop batch entry; batch.rs LOOP_ENTRY_WORDS",
    ),
];

/// The text of `hce_constants.wgsl`, generated from [`CONSTANTS`].
#[cfg(test)]
fn constants_wgsl() -> String {
    let mut out = String::from(
        "// GENERATED from the Rust constants by runtime/src/gpu/wgsl.rs (`CONSTANTS`); do not edit.\n\
         // Change the Rust constant, then `HCE_WRITE_WGSL=1 cargo test -p hce-runtime --lib\n\
         // constants` rewrites this file. Prepended first to every kernel, by wgsl.rs and by\n\
         // web/src/wgsl.js alike.\n\n",
    );
    for (name, value, what) in CONSTANTS {
        out.push_str(&format!("// {what}\nconst {name}: u32 = {value:#x}u;\n"));
    }
    out
}

/// The flat (linear 1-to-4) refinement kernel.
pub(crate) fn flat_source() -> String {
    assemble("flat", |_, text| text.to_string())
}

/// The colour-decoding kernel (`gpu::testing`).
#[cfg(any(test, feature = "testing"))]
pub(crate) fn decode_source() -> String {
    assemble("decode", |_, text| text.to_string())
}

/// `loop_normals.wgsl` for the patch memory whose accessors start with `prefix` (`sq_at`,
/// `ring_at` for the scratch kernel's storage buffer; `wg_sq_at`, `wg_ring_at` for workgroup
/// memory).
fn patch_normals(prefix: &str) -> String {
    LOOP_NORMALS_TEMPLATE.replace(PATCH, prefix)
}

/// `loop.wgsl` with the normals of its scratch patch kernel; `loop_workgroup.wgsl` after
/// `header` (the variant's constants) with the normals of workgroup memory.
fn loop_module(name: &str, text: &str, header: &str) -> String {
    match name {
        "loop" => format!("{text}\n{}", patch_normals("")),
        "loop_workgroup" => format!("{header}\n{text}\n{}", patch_normals("wg_")),
        _ => text.to_string(),
    }
}

/// The Loop kernel's module: its three steps, with the scratch patch kernel (`patch_main`).
pub(crate) fn loop_source() -> String {
    assemble("loop", |name, text| loop_module(name, text, ""))
}

/// The batched Loop kernel (`patch_batch_main`, `faces_batch_main`, `colours_batch_main`): the
/// Loop kernel's module with its uniform made private, then `hce_batch.wgsl` and
/// `loop_batch.wgsl`.
pub(crate) fn loop_batch_source() -> String {
    assemble("loop_batch", |name, text| {
        let text = loop_module(name, text, "");
        if name == "loop" {
            text.replacen(LOOP_PARAMS_UNIFORM, LOOP_PARAMS_PRIVATE, 1)
        } else {
            text
        }
    })
}

/// A variant of the workgroup patch kernel (`patch_wg_main`): the Loop kernel's module, then
/// `header` (the variant's constants) and `loop_workgroup.wgsl` with its normals.
pub(crate) fn loop_workgroup_source(header: &str) -> String {
    assemble("loop_workgroup", |name, text| {
        loop_module(name, text, header)
    })
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

    /// A module table of `files` for [`import_order`].
    fn table<'a>(files: &'a [(&'a str, &'a str)]) -> impl Fn(&str) -> Option<&'a str> + 'a {
        move |name| files.iter().find(|(n, _)| *n == name).map(|(_, t)| *t)
    }

    #[test]
    fn imports_come_once_each_before_the_modules_that_import_them() {
        let files = [
            ("kernel", "// #import b\n// #import a\nfn main() {}\n"),
            ("a", "  // #import c\n"),
            ("b", "// #import c\n// #import a\n"),
            ("c", "// imports nothing: `#import` only starts a line\n"),
        ];
        assert_eq!(
            import_order("kernel", &table(&files)),
            Ok(vec!["c", "a", "b", "kernel"])
        );
        assert_eq!(import_order("c", &table(&files)), Ok(vec!["c"]));
    }

    #[test]
    fn a_missing_or_circular_import_names_the_modules() {
        let files = [
            ("kernel", "// #import a\n"),
            ("a", "// #import b\n"),
            ("b", "// #import kernel\n"),
            ("lone", "// #import hce_nothing\n"),
        ];
        let cycle = import_order("kernel", &table(&files)).unwrap_err();
        assert_eq!(
            cycle.to_string(),
            "circular import: kernel -> a -> b -> kernel"
        );
        let missing = import_order("lone", &table(&files)).unwrap_err();
        assert_eq!(
            missing.to_string(),
            "lone.wgsl imports hce_nothing, which is not a module (no hce_nothing.wgsl)"
        );
        assert_eq!(
            import_order("absent", &table(&files)),
            Err(ImportError::Unknown {
                module: "absent".into()
            })
        );
    }

    /// The refinement kernels see the shared modules in one order, from their own declarations,
    /// and every file of this folder imports only files of it, without a cycle.
    #[test]
    fn every_file_declares_imports_that_resolve() {
        let shared = [
            "hce_constants",
            "hce_bindings",
            "hce_tree",
            "hce_light",
            "hce_lattice",
            "hce_gather",
        ];
        let flat = import_order("flat", &module_text).unwrap();
        assert_eq!(flat[..shared.len()], shared);
        assert_eq!(flat[shared.len()..], ["hce_batch", "flat"]);
        let workgroup = import_order("loop_workgroup", &module_text).unwrap();
        assert_eq!(workgroup[..shared.len()], shared);
        assert_eq!(workgroup[shared.len()..], ["loop", "loop_workgroup"]);
        let batch = import_order("loop_batch", &module_text).unwrap();
        assert_eq!(batch[shared.len()..], ["loop", "hce_batch", "loop_batch"]);
        let files: Vec<(String, String)> = every_file()
            .into_iter()
            .map(|(name, text)| (name.trim_end_matches(".wgsl").to_string(), text))
            .collect();
        let text = |name: &str| {
            files
                .iter()
                .find(|(n, _)| n == name)
                .map(|(_, t)| t.as_str())
        };
        for (name, _) in &files {
            let order = import_order(name, &text).unwrap_or_else(|e| panic!("{e}"));
            assert_eq!(order.last(), Some(&name.as_str()));
        }
        // What the kernels compile is every module of this folder but the standalone shaders.
        for (name, _) in MODULES {
            assert!(text(name).is_some(), "{name}");
        }
    }

    /// Every `.wgsl` file of this folder, by name, with its text.
    fn every_file() -> Vec<(String, String)> {
        let dir = std::path::Path::new(env!("CARGO_MANIFEST_DIR")).join("src/gpu");
        let mut files: Vec<(String, String)> = std::fs::read_dir(&dir)
            .unwrap()
            .map(|e| e.unwrap().path())
            .filter(|p| p.extension().is_some_and(|x| x == "wgsl"))
            .map(|p| {
                let name = p.file_name().unwrap().to_string_lossy().into_owned();
                (name, std::fs::read_to_string(&p).unwrap())
            })
            .collect();
        files.sort();
        assert!(files.len() >= 10, "{files:?}");
        files
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

    /// `hce_bindings.wgsl` and `bindings.rs` name the same buffers at the same numbers, and
    /// the kernels that import it bind nothing else but their own (binding 0 and from
    /// `KERNEL_OWN` on).
    #[test]
    fn the_shared_bindings_match_their_rust_twin() {
        use super::super::bindings::{KERNEL_OWN, SHARED, UNIFORM};
        let bound = |module: &naga::Module| -> Vec<(String, u32)> {
            module
                .global_variables
                .iter()
                .filter_map(|(_, v)| Some((v.name.clone()?, v.binding.as_ref()?.binding)))
                .collect()
        };
        let shared = bound(&parse("hce_bindings", module_text("hce_bindings").unwrap()));
        let twin: Vec<(String, u32)> = SHARED.iter().map(|(n, b)| (n.to_string(), *b)).collect();
        assert_eq!(shared, twin);
        for (kernel, source) in [
            ("flat", flat_source()),
            ("loop", loop_source()),
            ("decode", decode_source()),
        ] {
            for (name, binding) in bound(&parse(kernel, &source)) {
                match SHARED.iter().find(|(n, _)| *n == name) {
                    Some((_, b)) => assert_eq!(binding, *b, "{kernel}: {name}"),
                    None => assert!(
                        binding == UNIFORM || binding >= KERNEL_OWN,
                        "{kernel}: {name} at {binding} is among the shared bindings' numbers"
                    ),
                }
            }
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

    /// `hce_constants.wgsl` is what [`constants_wgsl`] generates from the Rust constants
    /// (`HCE_WRITE_WGSL=1` rewrites it), and the assembled kernels see those values.
    #[test]
    fn constants_prelude_is_generated_from_the_rust_constants() {
        let path =
            std::path::Path::new(env!("CARGO_MANIFEST_DIR")).join("src/gpu/hce_constants.wgsl");
        let generated = constants_wgsl();
        if std::env::var_os("HCE_WRITE_WGSL").is_some() {
            std::fs::write(&path, &generated).unwrap();
        }
        assert_eq!(
            std::fs::read_to_string(&path).unwrap(),
            generated,
            "{} is stale: run HCE_WRITE_WGSL=1 cargo test -p hce-runtime --lib constants",
            path.display()
        );
        let module = parse("loop", &loop_source());
        for (name, rust, _) in CONSTANTS {
            assert_eq!(u32_constant(&module, name), *rust, "{name}");
        }
        // Each is declared in the prelude alone.
        for (file, text) in every_file() {
            for (name, _, _) in CONSTANTS {
                assert!(
                    file == "hce_constants.wgsl" || !text.contains(&format!("const {name}:")),
                    "{file} declares {name}"
                );
            }
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
        // A refinement in pieces (job.rs) writes the range where the twins put it.
        assert_eq!(
            at(&members, "range_first"),
            offset_of!(FlatParams, range_first)
        );
        assert_eq!(at(&members, "range_end"), offset_of!(FlatParams, range_end));
        // The batched entry points' uniform, as batch.rs `Pool::encode` writes it into its 48
        // bytes.
        let (size, members) = wgsl_struct(&flat, "Batch");
        assert!(size <= 48, "{size}");
        let order = [
            "count",
            "first_vertices",
            "first_faces",
            "entries",
            "vertex_total",
            "fine_total",
            "first_triangles",
            "triangle_total",
            "slots",
        ];
        for (i, name) in order.iter().enumerate() {
            assert_eq!(at(&members, name), 4 * i, "{name}");
        }

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
        assert_eq!(
            at(&members, "range_first"),
            offset_of!(LoopParams, range_first)
        );
        assert_eq!(at(&members, "range_end"), offset_of!(LoopParams, range_end));

        let decode = parse("decode", &decode_source());
        let (size, members) = wgsl_struct(&decode, "Query");
        assert_eq!(size as usize, size_of::<Query>());
        assert_eq!(at(&members, "normal"), offset_of!(Query, normal));
    }

    /// The per-object Loop kernels read their uniform; the batched one, the same functions,
    /// a private copy its invocations set.
    #[test]
    fn only_the_batched_loop_kernel_makes_its_params_private() {
        let (one, batched) = (loop_source(), loop_batch_source());
        assert_eq!(one.matches(LOOP_PARAMS_UNIFORM).count(), 1);
        assert_eq!(one.matches(LOOP_PARAMS_PRIVATE).count(), 0);
        assert!(!one.contains("fn patch_batch_main("));
        assert_eq!(batched.matches(LOOP_PARAMS_UNIFORM).count(), 0);
        assert_eq!(batched.matches(LOOP_PARAMS_PRIVATE).count(), 1);
        assert!(batched.contains("fn patch_batch_main("));
        parse("loop batch", &batched);
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
