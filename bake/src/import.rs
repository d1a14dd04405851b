//! Scene input for the baker: the scene importer of [`hce_meshio::scene`] (glTF and OBJ through
//! hce's one guarded reader and scene-graph walk), re-exported here with [`ToSolver`], which
//! turns an imported scene into the solver's world-space [`Scene`](crate::scene::Scene).

pub use hce_meshio::scene::*;
