//! # hce-runtime
//!
//! Loads baked assets, refines them with Loop subdivision (the CPU reference in this crate, and
//! the wgpu compute kernel behind the `gpu` feature) and colours them from their HCE trees.

#[cfg(feature = "gpu")]
pub mod gpu;
