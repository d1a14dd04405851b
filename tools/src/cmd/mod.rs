//! One module per `hce` subcommand.

pub mod bake;
pub mod bench_gpu;
pub mod compare;
pub mod demo;
pub mod inspect;
#[cfg(feature = "gpu")]
pub mod reference;
pub mod render;
pub mod serve;
pub mod subdivide;
pub mod validate;
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
