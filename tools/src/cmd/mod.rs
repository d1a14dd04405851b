//! One module per `hce` subcommand.

pub mod bake;
pub mod bench_gpu;
pub mod compare;
pub mod demo;
pub mod inspect;
#[cfg(feature = "gpu")]
pub mod reference;
pub mod render;
pub mod subdivide;
pub mod validate;
