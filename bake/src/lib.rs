//! # hce-bake
//!
//! The baker: normal sets (stage 1), enriched hierarchical radiosity (stage 2) and HCE encoding.
//!
//! Entry points: build a [`Scene`] (or import one), choose normal sets with
//! [`select_normal_sets`], solve with [`bake`], and turn the solution into container objects with
//! [`encode_object`]. [`bake_file`] does all of it for a glTF or OBJ file. Everything public is
//! re-exported here by name, and no module is public. Scenes are read by `hce_meshio::scene`
//! (glTF and OBJ through hce's one guarded reader), whose `ToSolver` turns one into a [`Scene`].
#![forbid(unsafe_code)]

mod cache_key;
mod encode;
mod normal_sets;
mod output;
mod pipeline;
mod radiosity;
mod scene;
mod visibility;

pub use cache_key::{cache_key, canonical_parameters, CacheKey, HashedInput, KEY_FORMAT};
pub use encode::{encode_object, vertex_colours};
pub use normal_sets::{
    select_normal_set, select_normal_sets, NormalSet, NormalSetParams, NormalSetReport,
};
pub use output::{bake_gltf, obj_to_gltf, write_baked_gltf, BakedAsset, ObjectLink, OutputError};
pub use pipeline::{bake_file, BakeOutcome, ObjectSummary, PipelineError, PipelineOptions};
pub use radiosity::element::{jittered_point, ElemKey, Rng};
pub use radiosity::formfactor::{point_to_polygon, stratified_points};
pub use radiosity::{
    bake, bake_with_progress, BakeParams, BakeResult, BakeStats, ObjectSolution, Progress,
    TriangleSolution, MAX_VISIBILITY_RAYS,
};
pub use scene::{
    LightKind, PunctualLight, ReflectanceFn, Scene, SceneError, SolverObject,
    MAX_NORMALS_PER_TRIANGLE,
};
pub use visibility::Occluders;

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
