//! One module per `hce` subcommand. Those that need a GPU (`render`, `reference`, `view`, `demo`,
//! `bench-gpu`) are commands only with feature `gpu`: without it they are not in the CLI at all
//! (`render` keeps its argument helpers, which are tested without a GPU).

pub mod bake;
#[cfg(feature = "gpu")]
pub mod bench_gpu;
pub mod compare;
#[cfg(feature = "gpu")]
pub mod demo;
pub mod inspect;
#[cfg(feature = "gpu")]
pub mod reference;
pub mod render;
pub mod serve;
pub mod subdivide;
pub mod validate;
#[cfg(feature = "gpu")]
pub mod view;

/// The value of a flag given under its old name, with a warning naming the new one (the level
/// flags were unified: `--level` for one level, `--max-level` for the deepest, `--levels` only
/// for a list).
pub fn renamed_flag<T>(old: Option<T>, old_name: &str, new_name: &str) -> Option<T> {
    if old.is_some() {
        eprintln!("warning: {old_name} is deprecated; use {new_name}");
    }
    old
}
