//! # hce-bake
//!
//! The baker: normal sets (stage 1), enriched hierarchical radiosity (stage 2) and HCE encoding.
//!
//! Entry points: build a [`scene::Scene`] (or import one), choose normal sets with
//! [`normal_sets::select_normal_sets`], solve with [`hierarchical::bake`], and turn the solution
//! into container objects with [`encode::encode_object`].
#![forbid(unsafe_code)]

pub mod cache_key;
pub mod cluster;
pub mod element;
pub mod encode;
pub mod formfactor;
pub mod hierarchical;
pub mod import;
pub mod normal_sets;
pub mod output;
pub mod pipeline;
pub mod reference;
pub mod scene;
pub mod visibility;

pub use hierarchical::{
    bake, bake_with_progress, BakeParams, BakeResult, BakeStats, ObjectSolution, Progress,
    TriangleSolution,
};
pub use scene::{LightKind, PunctualLight, Scene, SolverObject};

/// Most normals a triangle's set may hold (n0 included).
pub const MAX_NORMALS_PER_TRIANGLE: usize = 64;

/// Everything that can go wrong while baking.
#[derive(Debug, thiserror::Error)]
pub enum BakeError {
    #[error("{object}: {reason}")]
    InvalidScene { object: String, reason: String },
    #[error("{light}: {reason}")]
    InvalidLight { light: String, reason: String },
    #[error(
        "the scene has no light source: add a punctual light (KHR_lights_punctual) or an \
         emissive material"
    )]
    NoLight,
    #[error("invalid bake parameter: {0}")]
    InvalidParameter(String),
    #[error("object '{object}' triangle {triangle}: {reason}")]
    Encode {
        object: String,
        triangle: usize,
        reason: String,
    },
    /// The HCE tree codec refused a triangle's element tree.
    #[error("object '{object}' triangle {triangle}: {source}")]
    Tree {
        object: String,
        triangle: usize,
        source: hce_format::TreeError,
    },
}
