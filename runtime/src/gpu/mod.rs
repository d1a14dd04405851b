//! The GPU side of the runtime (feature `gpu`), in three layers, each usable on its own:
//!
//! * a scene: [`GpuScene`], the GPU resources of a loaded [`crate::asset::Asset`] (per object
//!   its level, chosen by [`choose_level`] from a [`Camera`] or fixed, its refined buffers
//!   reused from frame to frame, one [`SceneDraw`] per instance), and [`render_asset`], which
//!   draws one headless;
//! * the kernels of one object: [`LoopKernel`] (Loop subdivision of multiresolution objects
//!   with their colours) and [`FlatKernel`] (flat objects and plain meshes), each `new` once
//!   per device, `upload` once per object, `refine_into` per level change;
//! * a device: [`GpuContext`], which prefers a hardware adapter, falls back to a software one
//!   and says which, or wraps the caller's own device ([`GpuContext::from_existing`]); and a
//!   headless renderer ([`render_mesh`], [`render_gpu_mesh`]) for images and thumbnails.
//!
//! Every kernel has a plain-Rust twin in `hce-geometry` that follows the same steps in the same
//! order, so that tests can compare GPU output with it value by value: [`hce_geometry::decode`]
//! and [`hce_geometry::flat`] for decoding and flat refinement, [`hce_geometry::subdivide`] and
//! [`hce_geometry::colour`] for the Loop kernel.
//!
//! [`hce_geometry::subdivide`]: mod@hce_geometry::subdivide
//!
//! The method is Concheiro et al., "Synthesis of multiresolution scenes with global illumination
//! on a GPU" (GRAPP 2012): colours are chosen per subtriangle by walking the coarse triangle's
//! breadth-first HCE tree and taking the representative normal closest to the subtriangle's.

// The modules are private: what a viewer, `hce render` and `hce reference` call is re-exported
// below, one flat list. Test and benchmark support sit behind the `testing` and `bench`
// features.
mod batch;
#[cfg(feature = "bench")]
pub mod bench;
mod bindings;
mod context;
#[cfg(feature = "testing")]
mod decode;
mod draw;
mod flat;
mod framing;
#[cfg(any(feature = "testing", feature = "bench"))]
mod inputs;
mod job;
mod lod;
mod loop_kernel;
mod outputs;
mod render;
mod scene;
#[cfg(feature = "testing")]
pub mod testing;
mod util;
mod wgsl;

pub use batch::BATCH_MAX_FINE;
pub use context::{AdapterDescription, AdapterKind, ContextOptions, GpuContext};
pub use draw::{
    colour_pass, float_texture_entry, read_texture, render_pipeline, storage_entry, target_texture,
    uniform_entry, PipelineSpec,
};
pub use flat::{
    refine_flat, refine_flat_adaptive, refine_flat_with, FlatKernel, FlatObject, FlatOutput,
    KernelTiming,
};
pub use framing::{auto_scene_camera, Placement};
pub use hce_geometry::flat::RefinedMesh;
pub use job::{Encoded, RefineJob};
pub use lod::{choose_level, Camera, LodParams};
pub use loop_kernel::{LoopKernel, LoopObject, LoopOutput, PatchScheme};
pub use outputs::RefinedOutput;
pub use render::{
    mesh_bounds, render_gpu_mesh, render_mesh, sample_positions, supported_samples, tone_map_aces,
    view_projection, Framing, GpuMesh, MeshDraw, MeshPipeline, RenderParams, RenderedImage,
};
pub use scene::{
    flat_level, render_asset, resolve_camera, AssetRender, AssetRenderOptions, BatchReport,
    CameraChoice, CameraSource, FlatRefinement, GpuScene, LevelChoice, MultiresPath, ObjectBuffers,
    ObjectMesh, SceneDraw, SceneOptions,
};
pub use util::PassTimer;

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
