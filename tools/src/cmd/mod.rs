//! One module per `hce` subcommand.

pub mod bake;
pub mod bench_gpu;
pub mod demo;
pub mod inspect;
pub mod render;
pub mod subdivide;
pub mod validate;
