//! # hce-runtime
//!
//! Loads baked assets and draws them: [`asset::Asset::open`] reads and checks a baked
//! `.glb`/`.gltf`/`.hce` (no GPU needed); behind the `gpu` feature, `gpu::scene::GpuScene`
//! refines every object on the GPU (Loop subdivision for multiresolution objects, the flat
//! kernel for flat ones) with its baked lighting, and `gpu::scene::render_asset` renders it to an
//! image in one call.
//!
//! The CPU twins of the kernels, which tests compare the GPU with, live in `hce-geometry`.

#[cfg(feature = "gpu")]
pub mod gpu;

pub mod asset;

pub use asset::{Asset, AssetError, OpenOptions};
