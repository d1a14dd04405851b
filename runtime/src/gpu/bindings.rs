//! The binding numbers of `hce_bindings.wgsl`, the storage buffers the refinement kernels
//! (`flat.wgsl`, `loop.wgsl`) and the decoding kernel (`decode.wgsl`) share: its Rust twin, which
//! a test of `wgsl.rs` compares with the WGSL by name. Binding [`UNIFORM`] and those from
//! [`KERNEL_OWN`] on are each kernel's own.

/// Each kernel's uniform (the decoding kernel's queries).
pub(super) const UNIFORM: u32 = 0;
pub(super) const COARSE_POSITIONS: u32 = 1;
pub(super) const TOPO: u32 = 2;
pub(super) const HCE_RECORDS: u32 = 3;
pub(super) const HCE_BITS: u32 = 4;
pub(super) const HCE_NORMALS: u32 = 5;
pub(super) const HCE_COLOURS: u32 = 6;
pub(super) const OUT_POSITIONS: u32 = 7;
pub(super) const OUT_INDICES: u32 = 8;
pub(super) const OUT_FACES: u32 = 9;
pub(super) const OUT_COLOURS: u32 = 10;
pub(super) const HCE_LIGHT: u32 = 11;
pub(super) const OUT_NORMALS: u32 = 12;
pub(super) const SCRATCH: u32 = 13;
/// The first binding of a kernel's own beyond its uniform: the batched flat entry points'
/// `batch`, the decoding kernel's results.
pub(super) const KERNEL_OWN: u32 = 14;

/// Every binding of `hce_bindings.wgsl`, by its WGSL name.
#[cfg(test)]
pub(super) const SHARED: &[(&str, u32)] = &[
    ("coarse_positions", COARSE_POSITIONS),
    ("topo", TOPO),
    ("hce_records", HCE_RECORDS),
    ("hce_bits", HCE_BITS),
    ("hce_normals", HCE_NORMALS),
    ("hce_colours", HCE_COLOURS),
    ("out_positions", OUT_POSITIONS),
    ("out_indices", OUT_INDICES),
    ("out_faces", OUT_FACES),
    ("out_colours", OUT_COLOURS),
    ("hce_light", HCE_LIGHT),
    ("out_normals", OUT_NORMALS),
    ("scratch", SCRATCH),
];
