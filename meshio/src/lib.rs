//! # hce-meshio
//!
//! Reading and writing meshes and scenes for hce.
//!
//! Always built, for every crate that touches files, the runtime included:
//! * [`scene_graph`]: the one walk of a glTF node hierarchy (default scene, world transforms,
//!   trees only), over the JSON, used by every reader that places glTF meshes.
//! * [`gltf_guard`]: the guards every glTF reader goes through (URI rules here; with `import`
//!   also the guarded open, accessor checks and panic catching around the `gltf` crate).
//! * [`gpu_instancing`]: `EXT_mesh_gpu_instancing` input expanded into one node per instance,
//!   so that each copy is baked as an object of its own.
//! * [`atomic`]: [`write_atomic`], the one way every tool output is written.
//! * [`solver_scene`]: the world-space scene the radiosity solver and the reference path tracer
//!   read ([`Scene`], [`SolverObject`], [`PunctualLight`]), checked by [`Scene::validate`].
//!
//! Feature `import` (default): the readers, on the `gltf` crate, `tobj` and `image`:
//! * `scene`: the baker's scene importer (objects per node instance and primitive,
//!   materials and textures, lights, camera), and `ToSolver`, its result as a [`Scene`];
//! * `import`: `load_mesh`, one triangle mesh in world space from OBJ/glTF (`hce subdivide`),
//!   plain OBJ files read by `obj_fast` (tobj's result, bit for bit, in one scan) and the rest
//!   by tobj, into `triangles`' type;
//! * `plain`: `load_plain_mesh`, `hce render`'s preview of a plain mesh, by the same reader as
//!   `load_mesh` (the `PlainMesh` type is there without features).
//!
//! Feature `export` (default): `export`, OBJ/glTF/GLB writers of refined meshes.
//!
//! Hostile files get an error, never a panic, a hang or an unbounded allocation.
#![forbid(unsafe_code)]

pub mod atomic;
pub mod gltf_guard;
pub mod gpu_instancing;
pub mod scene_graph;
pub mod solver_scene;

#[cfg(feature = "export")]
pub mod export;
#[cfg(feature = "import")]
pub mod import;
#[cfg(feature = "import")]
mod obj_fast;
pub mod plain;
#[cfg(feature = "import")]
pub mod scene;
#[cfg(feature = "import")]
mod triangles;

pub use atomic::{write_atomic, write_atomic_with, FileWriteError};
#[cfg(feature = "export")]
pub use export::ExportError;
#[cfg(feature = "import")]
pub use import::{load_mesh, ImportError, InputMesh};
pub use solver_scene::{LightKind, PunctualLight, Scene, SceneError, SolverObject};
