// GENERATED from the Rust constants by runtime/src/gpu/wgsl.rs (`CONSTANTS`); do not edit.
// Change the Rust constant, then `HCE_WRITE_WGSL=1 cargo test -p hce-runtime --lib
// constants` rewrites this file. Prepended first to every kernel, by wgsl.rs and by
// web/src/wgsl.js alike.

// << e: the triangle owns edge e (writes its points); loop_kernel.rs
const OWNS_EDGE: u32 = 0x1u;
// << c: the triangle's corner c writes coarse vertex v_c; loop_kernel.rs
const OWNS_VERTEX: u32 = 0x8u;
// << e: edge e has a neighbour (a band); loop_kernel.rs
const INTERIOR: u32 = 0x40u;
// << e: edge e is infinitely sharp; loop_kernel.rs
const SHARP: u32 = 0x200u;
// the crease vertex rule (SPEC.md A.7); hce_format
const RULE_CREASE: u32 = 0x1u;
// the corner vertex rule (SPEC.md A.7); hce_format
const RULE_CORNER: u32 = 0x2u;
// a spoke's sharp bit (SPEC.md A.7); hce_format
const SPOKE_SHARP: u32 = 0x1u;
// a vertex's boundary bit (SPEC.md A.7); hce_format
const VERTEX_BOUNDARY: u32 = 0x1u;
// bits of the lattice in which points are evaluated; lighting.rs EVAL_LATTICE_BITS
const HCE_EVAL_BITS: u32 = 0x10u;
// bits of the lattice of the leaf corners (SPEC.md G.2, F.7.1); lighting.rs TREE_LATTICE_BITS
const HCE_TREE_BITS: u32 = 0xcu;
// a leaf's node word; lighting.rs LEAF
const HCE_LEAF: u32 = 0x80000000u;
// words of a batch entry before the object's Params; batch.rs ENTRY_BASES
const BATCH_ENTRY_BASES: u32 = 0x6u;
// words of a flat batch entry; batch.rs FLAT_ENTRY_WORDS
const FLAT_ENTRY_WORDS: u32 = 0x22u;
// words of a Loop batch entry; batch.rs LOOP_ENTRY_WORDS
const LOOP_ENTRY_WORDS: u32 = 0x29u;
