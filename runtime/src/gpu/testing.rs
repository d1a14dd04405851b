//! Test support (feature `testing`): a GPU context or a visible skip, synthetic objects with
//! random HCE trees (`inputs`, shared with `bench`: the inputs of `hce bench-gpu`), and the
//! colour-decoding kernel on its own ([`decode_colours`]), checked against its CPU twin by `tests/gpu_kernels.rs`.
//!
//! GPU tests must run in CI (Mesa lavapipe is enough) and must not silently pass when the
//! runner lost its driver, so `HCE_REQUIRE_GPU=1` turns "no adapter" into a failure. Without it
//! a test prints why it skipped and returns.

use super::{ContextOptions, GpuContext, GpuError};

pub use super::decode::{decode_colours, ColourQuery, DecodedColour};
pub use super::inputs::{
    grid, octahedron, random_object, small_flat_scene, small_scene, RandomTrees, SplitMix,
};

/// The environment variable that makes a missing adapter a test failure.
const REQUIRE_GPU_ENV: &str = "HCE_REQUIRE_GPU";

/// Whether `HCE_REQUIRE_GPU` asks for a GPU (`1`, `true` or `yes`).
fn gpu_required() -> bool {
    std::env::var(REQUIRE_GPU_ENV)
        .map(|v| matches!(v.trim(), "1" | "true" | "yes"))
        .unwrap_or(false)
}

/// What a test should do when no context can be made.
#[derive(Debug)]
pub enum Unavailable {
    /// `HCE_REQUIRE_GPU` is unset: skip, with this message printed.
    Skip(String),
    /// `HCE_REQUIRE_GPU=1`: fail with this message.
    Fail(String),
}

/// Tries to create a context for the test named `test`. `Ok` carries the context; `Err` says
/// whether to skip or fail, already printed to stderr in the skip case.
pub fn try_context(test: &str) -> Result<GpuContext, Unavailable> {
    match GpuContext::new(&ContextOptions::default()) {
        Ok(ctx) => {
            eprintln!("{test}: running on {}", ctx.description);
            Ok(ctx)
        }
        Err(e) => Err(classify(test, &e, gpu_required())),
    }
}

fn classify(test: &str, e: &GpuError, required: bool) -> Unavailable {
    if required {
        Unavailable::Fail(format!(
            "{test}: {REQUIRE_GPU_ENV}=1 but no GPU context could be created: {e}"
        ))
    } else {
        let msg = format!(
            "SKIPPED {test}: no GPU context ({e}); set {REQUIRE_GPU_ENV}=1 to make this a failure"
        );
        eprintln!("{msg}");
        Unavailable::Skip(msg)
    }
}

/// The usual form in a test: `let Some(ctx) = context_or_skip("name") else { return };`.
/// Panics (failing the test) when the GPU is required and absent.
pub fn context_or_skip(test: &str) -> Option<GpuContext> {
    match try_context(test) {
        Ok(ctx) => Some(ctx),
        Err(Unavailable::Skip(_)) => None,
        Err(Unavailable::Fail(msg)) => panic!("{msg}"),
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn missing_adapter_fails_only_when_required() {
        let e = GpuError::NoAdapter { hint: "install it" };
        assert!(
            matches!(classify("t", &e, true), Unavailable::Fail(m) if m.contains("install it"))
        );
        assert!(
            matches!(classify("t", &e, false), Unavailable::Skip(m) if m.starts_with("SKIPPED t"))
        );
    }
}
