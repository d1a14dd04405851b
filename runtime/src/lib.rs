//! # hce-runtime
//!
//! Loads baked assets, refines them with Loop subdivision (the CPU reference in this crate, and
//! the wgpu compute kernel behind the `gpu` feature) and colours them from their HCE trees.

#[cfg(feature = "gpu")]
pub mod gpu;

pub mod colour;
pub mod export;
pub mod import;
pub mod subdivide;
pub mod topology;

pub use import::{load_mesh, weld, ImportError, InputMesh, Weld};
pub use subdivide::{subdivide, subdivide_into, subtriangle_cells, Refined, SubdivError};
pub use topology::{
    build_control_mesh, Creases, NonManifold, Topology, TopologyConfig, TopologyError,
    TopologyReport,
};
