//! One module per `hce` subcommand.

pub mod bench_gpu;
pub mod render;
pub mod subdivide;
