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

// The modules are private: what the crate offers is the flat list below. Two namespaces stay
// public: `rules` (each Appendix C rule once, named after the rule, for the validator and the
// refinement guard) and, behind feature `testing`, `example` (small valid files for tests).
mod accessor;
mod colour0;
mod error;
#[cfg(any(test, feature = "testing"))]
pub mod example;
mod gltf;
mod gltf_json;
mod layout;
mod meshopt;
mod model;
mod problem;
mod read;
pub mod rules;
mod same_geometry;
mod section;
mod tree;
mod validate;
mod write;

pub use accessor::{
    read_accessor, read_primitive, view_bytes, AccessorValues, PrimitiveMesh, DRACO, MESHOPT,
};
pub use colour0::{colour_exposure, ALBEDO_FLOOR};
pub use error::{ReadError, WriteError};
pub use gltf::{
    buffer_view_bytes, check_links, container_bytes, decode_base64, embed_container, hash_hex,
    link_primitive, linked_geometries, mentions_extension, primitive_geometry, primitive_links,
    root_link, root_problems, scan_primitive_links, validate_asset, validate_asset_report,
    write_glb, Asset as GltfAsset, AssetReport, CheckedLink, CheckedLinks, GltfError, LinkFault,
    LinkNext, LinkSink, PrimitiveLink, RootLink, EXTENSION_NAME,
};
pub use layout::{
    read_layout, Header, Layout, SectionEntry, DIRECTORY_ENTRY_LEN, FILE_LEVEL, HEADER_LEN,
    IDENTIFIER, MAJOR_VERSION, MINOR_VERSION, OBJECT_RECORD_LEN, SECTION_ALIGNMENT,
};
pub use model::{
    geometry_hash, rgb9e5, Container, ControlMesh, Metadata, Object, ObjectKind, TriangleRecord,
    NO_NEIGHBOUR, RULE_CORNER, RULE_CREASE, RULE_SMOOTH, SPOKE_BOUNDARY, SPOKE_SHARP,
    VERTEX_BOUNDARY, VERTEX_RULE_MASK, VERTEX_RULE_SHIFT,
};
pub use problem::Problem;
pub use read::{
    expected_length, read, read_metadata, read_object_table, read_with, ObjectRecord, ReadOptions,
};
pub use same_geometry::{primitive_box, same_surface, Mismatch, Placement};
pub use section::SectionType;
pub use tree::{
    check_flags, decode_shape, encode_tree, triangle_trees, BitWriter, NodeInfo, Tree, TreeError,
    TreeShape, MAX_NODES, MAX_TREE_DEPTH,
};
pub use validate::{read_validated, validate, validate_bytes, MAX_PROBLEMS};
pub use write::write;
