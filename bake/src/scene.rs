//! The scene the solver reads, [`hce_meshio::solver_scene`]: it lives below both the solver
//! and the reference path tracer (`hce-reference`), which reads the same input and shares no
//! code with the solver.

pub use hce_meshio::solver_scene::{
    LightKind, PunctualLight, ReflectanceFn, Scene, SceneError, SolverObject,
    MAX_NORMALS_PER_TRIANGLE,
};
