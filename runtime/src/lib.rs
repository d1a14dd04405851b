//! # hce-runtime
//!
//! Loads baked assets, refines them with Loop subdivision (the CPU reference in this crate, and
//! the wgpu compute kernel behind the `gpu` feature) and colours them from their HCE trees.
//!
//! Entry points: [`asset::Asset::open`] loads and checks a baked `.glb`/`.gltf`/`.hce`;
//! `gpu::scene::GpuScene` (feature `gpu`) refines and draws it; `gpu::scene::render_asset`
//! renders it to an image in one call.

#[cfg(feature = "gpu")]
pub mod gpu;

pub mod asset;
pub mod colour;
pub mod export;
pub mod gltf_guard;
pub mod import;
pub mod lighting;
pub mod scene_export;
pub mod subdivide;
pub mod topology;

pub use asset::{Asset, AssetError, OpenOptions};
pub use import::{load_mesh, weld, ImportError, InputMesh, Weld};
pub use subdivide::{subdivide, subdivide_into, subtriangle_cells, Refined, SubdivError};
pub use topology::{
    build_control_mesh, Creases, NonManifold, Topology, TopologyConfig, TopologyError,
    TopologyReport,
};
