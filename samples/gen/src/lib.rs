//! Generators for the bundled sample scenes: Teatime, Chesstime and the Cornell box.
//!
//! Everything here is plain geometry built in code (so anyone can regenerate or change the
//! samples) and a small glTF 2.0 binary writer. The `gen-samples` binary writes the three
//! `.glb` files committed under `samples/`.

pub mod glb;
pub mod mesh;
pub mod scene;
pub mod teapot;
mod teapot_data;
