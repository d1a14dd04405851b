//! Generators for the bundled sample scenes: Teatime, Chesstime and the Cornell box.
//!
//! Everything here is plain geometry built in code (so anyone can regenerate or change the
//! samples) and a small glTF 2.0 binary writer. The `gen-samples` binary writes the three
//! `.glb` files committed under `samples/`; `gen-samples room --mesh PATH -o OUT.glb` writes a
//! test room around any OBJ ([`room`]).
#![forbid(unsafe_code)]

pub mod chess;
pub mod cornell;
pub mod glb;
pub mod lathe;
pub mod mesh;
pub mod room;
pub mod scene;
pub mod scenes;
pub mod shapes;
pub mod simplify;
pub mod spoon;
pub mod teapot;
mod teapot_data;

/// The committed sample files, embedded, so that a binary (`hce demo`) works from any directory.
/// `cargo test -p hce-samples` fails if they differ from what the generators produce.
pub mod embedded {
    /// `samples/teatime.glb`.
    pub const TEATIME_GLB: &[u8] = include_bytes!("../../teatime.glb");
    /// `samples/chesstime.glb`.
    pub const CHESSTIME_GLB: &[u8] = include_bytes!("../../chesstime.glb");
    /// `samples/cornell-box.glb`.
    pub const CORNELL_BOX_GLB: &[u8] = include_bytes!("../../cornell-box.glb");
}
