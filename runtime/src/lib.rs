//! # hce-runtime
//!
//! Loads baked assets and draws them: [`asset::Asset::open`] reads and checks a baked
//! `.glb`/`.gltf`/`.hce` (no GPU needed); behind the `gpu` feature, `gpu::GpuScene` refines
//! every object on the GPU (Loop subdivision for multiresolution objects, the flat kernel for
//! flat ones) with its baked lighting, and `gpu::render_asset` renders it to an image in one
//! call. The crate's README lists what a viewer calls.
//!
//! The CPU twins of the kernels, which tests compare the GPU with, live in `hce-geometry`.
//!
//! No `unsafe` outside `mmap` (one read-only file map, argued there): the crate denies
//! `unsafe_code`, its modules forbid it, and only that module allows it.
#![deny(unsafe_code)]

#[forbid(unsafe_code)]
pub mod asset;
#[cfg(feature = "gpu")]
#[forbid(unsafe_code)]
pub mod gpu;
mod mmap;
#[forbid(unsafe_code)]
pub mod plain;

pub use asset::{Asset, AssetError, OpenOptions};
