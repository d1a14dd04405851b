//! # hce-format
//!
//! The `.hce` container: the versioned binary file that carries baked global illumination for
//! multiresolution meshes (normal sets, HCE bitstreams, per-normal colours and the adjacency
//! tables of the GPU subdivision kernel), and the `EXT_hce_baked_lighting` glTF extension that
//! embeds it. SPEC.md at the repository root is the normative description; this crate is its
//! reference implementation.
//!
//! This crate knows nothing of GPUs or geometry algorithms: it moves plain data between bytes
//! and [`model`] types, and checks it.
#![forbid(unsafe_code)]

pub mod model;

pub use model::*;
