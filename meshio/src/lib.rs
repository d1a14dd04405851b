//! # hce-meshio
//!
//! Reading and writing meshes for hce: glTF 2.0 and Wavefront OBJ import behind the guards of
//! [`gltf_guard`] (hostile files get an error, never a panic, hang or unbounded allocation),
//! OBJ/glTF export of refined meshes, and the atomic file write every tool output goes through.
#![forbid(unsafe_code)]

pub mod export;
pub mod gltf_guard;
pub mod import;
pub mod plain;

pub use export::{write_atomic, write_atomic_with, ExportError};
pub use import::{load_mesh, ImportError, InputMesh};
