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
pub mod scene;
pub mod visibility;

pub use hierarchical::{
    bake, bake_with_progress, BakeParams, BakeResult, BakeStats, ObjectSolution, Progress,
    TriangleSolution,
};
pub use scene::{
    LightKind, PunctualLight, Scene, SceneError, SolverObject, MAX_NORMALS_PER_TRIANGLE,
};

/// Everything that can go wrong while baking.
#[derive(Debug, thiserror::Error)]
pub enum BakeError {
    /// The scene fails [`Scene::validate`].
    #[error(transparent)]
    Scene(#[from] SceneError),
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
