//! The GPU side of the runtime (feature `gpu`): a wgpu context that prefers a hardware adapter
//! and falls back to a software one, compute kernels that decode HCE colours, refine flat
//! objects ([`flat`]) and Loop-subdivide multiresolution objects with their colours
//! ([`loop_kernel`]), a level-of-detail rule, a headless renderer, and [`scene::GpuScene`], the
//! GPU resources of a loaded [`crate::asset::Asset`].
//!
//! Every kernel has a plain-Rust twin that follows the same steps in the same order, so that
//! tests can compare GPU output with it value by value: [`cpu_reference`] for decoding and flat
//! refinement, [`hce_geometry::subdivide`] and [`hce_geometry::colour`] for the Loop kernel.
//!
//! The method is Concheiro et al., "Synthesis of multiresolution scenes with global illumination
//! on a GPU" (GRAPP 2012): colours are chosen per subtriangle by walking the coarse triangle's
//! breadth-first HCE tree and taking the representative normal closest to the subtriangle's.

pub mod bench;
pub mod context;
pub mod decode;
pub mod flat;
pub mod framing;
pub mod lod;
pub mod loop_kernel;
pub mod render;
pub mod scene;
pub mod testing;
mod util;

pub use context::{AdapterDescription, AdapterKind, ContextOptions, GpuContext};
pub use decode::{decode_colours, ColourQuery, DecodedColour};
pub use flat::{refine_flat, refine_flat_with, FlatKernel, FlatObject, FlatOutput, KernelTiming};
pub use hce_geometry::flat::RefinedMesh;
pub use lod::{choose_level, Camera, LodParams};
pub use loop_kernel::{refine_loop, LoopKernel, LoopMesh, LoopObject, LoopOutput, PatchScheme};
pub use render::{
    render_draws, render_gpu_mesh, render_mesh, tone_map_aces, Framing, GpuMesh, MeshDraw,
    RenderParams, RenderedImage,
};
pub use scene::{
    render_asset, AssetRender, AssetRenderOptions, CameraChoice, GpuScene, LevelChoice,
    MultiresPath, SceneOptions,
};

/// Everything that can go wrong on the GPU path.
#[derive(Debug, thiserror::Error)]
pub enum GpuError {
    #[error("{hint}")]
    NoAdapter { hint: &'static str },
    #[error("GPU adapter {adapter}: {reason}")]
    Device { adapter: String, reason: String },
    #[error("object {object}: {reason}")]
    InvalidObject { object: String, reason: String },
    #[error(
        "{what} needs {needed} bytes but the adapter allows at most {limit} per buffer; \
         choose a lower level"
    )]
    TooLarge {
        what: &'static str,
        needed: u64,
        limit: u64,
    },
    #[error("level {level} is above the supported maximum {max}")]
    LevelTooHigh { level: u32, max: u32 },
    #[error("cannot load {path}: {reason}")]
    Load { path: String, reason: String },
    #[error("invalid render parameters: {0}")]
    InvalidParams(String),
    #[error("reading results back from the GPU failed: {0}")]
    Readback(String),
}

impl From<hce_geometry::tables::InvalidObject> for GpuError {
    fn from(e: hce_geometry::tables::InvalidObject) -> Self {
        GpuError::InvalidObject {
            object: e.object,
            reason: e.reason,
        }
    }
}
