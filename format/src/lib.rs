//! # hce-format
//!
//! The `.hce` container: the versioned binary file that carries baked global illumination for
//! multiresolution meshes (normal sets, HCE bitstreams, per-normal colours and the adjacency
//! tables of the GPU subdivision kernel), and the `EXT_hce_baked_lighting` glTF extension that
//! embeds it. SPEC.md at the repository root is the normative description; this crate is its
//! reference implementation.
//!
//! This crate knows nothing of GPUs or geometry algorithms: it moves plain data between bytes
//! and [`model`] types, and checks it. It does not write files either: every hce output goes to
//! disk through `hce_meshio::write_atomic`.
#![forbid(unsafe_code)]

pub mod error;
pub mod example;
pub mod gltf;
pub mod layout;
pub mod model;
pub mod read;
pub mod rules;
pub mod tree;
pub mod validate;
pub mod write;

pub use error::{ReadError, WriteError};
pub use layout::{read_layout, Layout, SectionEntry, SectionType, MAJOR_VERSION, MINOR_VERSION};
pub use model::*;
pub use read::{read, read_with, ReadOptions};
pub use tree::{triangle_trees, BitWriter, Tree, TreeError, TreeShape, MAX_TREE_DEPTH};
pub use validate::{read_validated, validate, validate_bytes, Problem};
pub use write::write;
