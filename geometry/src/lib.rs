//! # hce-geometry
//!
//! The geometry of hce, without I/O and without a GPU: everything the baker and the runtime
//! compute on meshes, in one place each.
//!
//! * [`weld`](mod@weld): joining equal positions.
//! * [`topology`]: a welded triangle soup to the control-mesh adjacency tables
//!   ([`hce_format::ControlMesh`]) that Loop subdivision reads, on the CPU and on the GPU.
//! * [`tables`]: the one validation of what refinement and colouring index: triangles and edge
//!   ids (every refinement), rings and neighbours (Loop), records and trees (colouring).
//! * [`lattice`]: the 1-to-4 lattice of a refined triangle and its vertex numbering.
//! * [`subdivide`](mod@subdivide): Loop subdivision, the CPU reference of the GPU Loop kernel.
//! * [`loop_tables`]: the per-triangle flags, crease spokes and weights the GPU Loop kernel
//!   reads beside the control mesh.
//! * [`incidence`]: the triangles around each edge and vertex ([`flat::FlatTopology`]), which
//!   flat refinement and the split read.
//! * [`flat`]: flat (linear) refinement, the CPU reference of the GPU flat kernel.
//! * [`adaptive_flat`]: a flat object refined from its trees, one triangle per leaf plus those
//!   its finer neighbours need (SPEC.md F.7.1), what `hce subdivide` writes.
//! * [`split`]: a multiresolution object's refined vertices split at sharp edges (SPEC.md F.5).
//! * [`decode`]: the paper's per-subtriangle colour (tree walk, nearest representative normal).
//! * [`lighting`], [`colour`]: the reconstruction of baked lighting on a refined mesh
//!   (SPEC.md, Appendix G).
//! * [`refine`]: one object refined as the runtime draws it (Loop or flat, coloured).
//! * [`normal`]: triangle normals (area-weighted, and unit for glTF).
//!
//! No `unsafe` outside `os` (one `madvise` hint, argued there): the crate denies `unsafe_code`
//! and every other module forbids it.
#![deny(unsafe_code)]

#[forbid(unsafe_code)]
pub mod adaptive_flat;
#[forbid(unsafe_code)]
pub mod colour;
#[forbid(unsafe_code)]
pub mod decode;
#[forbid(unsafe_code)]
pub mod flat;
#[forbid(unsafe_code)]
pub mod incidence;
#[forbid(unsafe_code)]
pub mod lattice;
#[forbid(unsafe_code)]
pub mod lighting;
#[forbid(unsafe_code)]
pub mod loop_tables;
#[forbid(unsafe_code)]
pub mod normal;
mod os;
#[forbid(unsafe_code)]
pub mod refine;
#[forbid(unsafe_code)]
pub mod split;
#[forbid(unsafe_code)]
pub mod subdivide;
#[forbid(unsafe_code)]
pub mod tables;
#[forbid(unsafe_code)]
pub mod topology;
#[forbid(unsafe_code)]
pub mod weld;

pub use lattice::subtriangle_cells;
pub use lighting::Reconstruction;
pub use subdivide::{subdivide, subdivide_into, Refined, SubdivError};
pub use topology::{
    build_control_mesh, Creases, NonManifold, Topology, TopologyConfig, TopologyError,
    TopologyReport,
};
pub use weld::{weld, Weld};
