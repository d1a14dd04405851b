//! Kernel throughput measurement for `hce bench-gpu`: per level, coarse and output triangles,
//! kernel time (GPU timestamps where the adapter has them, wall time around submit-and-wait
//! otherwise, and labelled so), output triangles per second and bytes written per second.

use std::time::Instant;

use hce_format::Object;

use super::flat::{FlatKernel, KernelTiming};
use super::loop_kernel::{LoopKernel, PatchScheme};
use super::{GpuContext, GpuError};

/// Where a time came from.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum Timer {
    /// Timestamps written by the GPU around the dispatches.
    GpuTimestamps,
    /// Host wall clock around submission and completion (includes driver overhead).
    Wall,
}

/// One level's figures (the median of the repeats).
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct BenchRow {
    pub level: u32,
    pub coarse_triangles: u64,
    pub output_triangles: u64,
    pub output_vertices: u64,
    pub seconds: f64,
    pub timer: Timer,
    /// Bytes the kernel writes to its outputs: positions, (Loop: normals,) vertex colours,
    /// indices and per-face colours.
    pub bytes_written: u64,
    /// GPU time of each dispatch in the repeat whose total is the median, when the kernel times
    /// its dispatches separately (the Loop kernel: patches, faces, vertex colours).
    pub step_seconds: Option<[f64; 3]>,
}

impl BenchRow {
    pub fn triangles_per_second(&self) -> f64 {
        self.output_triangles as f64 / self.seconds.max(1e-12)
    }
    pub fn bytes_per_second(&self) -> f64 {
        self.bytes_written as f64 / self.seconds.max(1e-12)
    }
}

/// Times the flat refinement kernel (three dispatches: positions, faces with HCE decoding,
/// vertex colours) on `object` at each level, `repeats` times after one warm-up, reusing the
/// output buffers as a viewer would.
pub fn bench_flat(
    ctx: &GpuContext,
    object: &Object,
    levels: &[u32],
    repeats: u32,
) -> Result<Vec<BenchRow>, GpuError> {
    let kernel = FlatKernel::new(ctx);
    let uploaded = kernel.upload(ctx, object)?;
    let coarse = u64::from(uploaded.topology.triangle_count);
    let mut rows = Vec::new();
    for &level in levels {
        let mut out = None;
        let (seconds, timer, step_seconds) = time_repeats(repeats, || {
            kernel.refine_into(ctx, &uploaded, level, &mut out, true)
        })?;
        let o = out.as_ref().expect("refine_into allocates");
        rows.push(BenchRow {
            level,
            coarse_triangles: coarse,
            output_triangles: u64::from(o.triangle_count),
            output_vertices: u64::from(o.vertex_count),
            seconds,
            timer,
            bytes_written: o.bytes_written(),
            step_seconds,
        });
    }
    Ok(rows)
}

/// Times the Loop subdivision kernel (three dispatches: per-triangle patches with positions and
/// normals, faces with HCE decoding, vertex colours) on `object`, whose control mesh must carry
/// its adjacency tables, at each level, `repeats` times after one warm-up, reusing the output
/// buffers as a viewer would. Bytes written count the outputs, not the patches' scratch.
pub fn bench_loop(
    ctx: &GpuContext,
    object: &Object,
    levels: &[u32],
    repeats: u32,
) -> Result<Vec<BenchRow>, GpuError> {
    bench_loop_with(ctx, object, levels, repeats, PatchScheme::Auto)
}

/// [`bench_loop`] with step 1 forced to `scheme`, to compare the workgroup and scratch kernels
/// in one run.
pub fn bench_loop_with(
    ctx: &GpuContext,
    object: &Object,
    levels: &[u32],
    repeats: u32,
    scheme: PatchScheme,
) -> Result<Vec<BenchRow>, GpuError> {
    let kernel = LoopKernel::with_scheme(ctx, scheme);
    let uploaded = kernel.upload(ctx, object)?;
    let coarse = u64::from(uploaded.triangle_count);
    let mut rows = Vec::new();
    for &level in levels {
        let mut out = None;
        let (seconds, timer, step_seconds) = time_repeats(repeats, || {
            kernel.refine_into(ctx, &uploaded, level, &mut out, true)
        })?;
        let o = out.as_ref().expect("refine_into allocates");
        rows.push(BenchRow {
            level,
            coarse_triangles: coarse,
            output_triangles: u64::from(o.triangle_count),
            output_vertices: u64::from(o.vertex_count),
            seconds,
            timer,
            bytes_written: o.bytes_written(),
            step_seconds,
        });
    }
    Ok(rows)
}

/// Runs `refine` once to warm up, then `repeats` times; the median time, where it came from
/// (GPU timestamps when every sample had them, wall time around submit-and-wait otherwise) and
/// the per-dispatch times of the median sample.
fn time_repeats(
    repeats: u32,
    mut refine: impl FnMut() -> Result<KernelTiming, GpuError>,
) -> Result<(f64, Timer, Option<[f64; 3]>), GpuError> {
    refine()?;
    let mut samples = Vec::new();
    let mut timer = Timer::Wall;
    for _ in 0..repeats.max(1) {
        let start = Instant::now();
        let timing = refine()?;
        let wall = start.elapsed().as_secs_f64();
        match timing.gpu_seconds {
            Some(s) if s > 0.0 => {
                timer = Timer::GpuTimestamps;
                samples.push((s, timing.step_seconds));
            }
            _ => samples.push((wall, None)),
        }
    }
    samples.sort_by(|a, b| a.0.total_cmp(&b.0));
    let (seconds, steps) = samples[samples.len() / 2];
    Ok((seconds, timer, steps))
}
