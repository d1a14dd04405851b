//! Kernel throughput measurement for `hce bench-gpu` (feature `bench`): per level, coarse and output triangles,
//! kernel time (GPU timestamps where the adapter has them, wall time around submit-and-wait
//! otherwise, and labelled so), output triangles per second and bytes written per second.

use std::time::Instant;

use hce_format::Object;

use super::flat::{FlatKernel, KernelTiming};
use super::loop_kernel::{LoopKernel, PatchScheme};
use super::util::{
    bind_buffers, check_size, dispatch_size, read_back, storage_output, uniform_init, PassTimer,
};
use super::{GpuContext, GpuError, GpuScene, SceneOptions};
use crate::asset::Asset;
use hce_geometry::lighting::Reconstruction;
use hce_geometry::refine::FlatRefinement;

pub use super::inputs::{
    grid, octahedron, random_object, small_flat_scene, small_scene, RandomTrees, SplitMix,
};

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
/// vertex colours) on `object` at each level with the colour reconstruction `reconstruction`,
/// `repeats` times after one warm-up, reusing the output buffers as a viewer would.
pub fn bench_flat(
    ctx: &GpuContext,
    object: &Object,
    levels: &[u32],
    repeats: u32,
    reconstruction: Reconstruction,
) -> Result<Vec<BenchRow>, GpuError> {
    let kernel = FlatKernel::new(ctx);
    let uploaded = kernel.upload(ctx, object, reconstruction, FlatRefinement::Uniform)?;
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
/// buffers as a viewer would. Step 1 runs with `scheme` (`PatchScheme::Auto` as a viewer gets
/// it, or one forced to compare the workgroup and scratch kernels) and colours with
/// `reconstruction`. Bytes written count the outputs, not the patches' scratch.
pub fn bench_loop(
    ctx: &GpuContext,
    object: &Object,
    levels: &[u32],
    repeats: u32,
    scheme: PatchScheme,
    reconstruction: Reconstruction,
) -> Result<Vec<BenchRow>, GpuError> {
    let kernel = LoopKernel::with_scheme(ctx, scheme);
    let uploaded = kernel.upload(ctx, object, reconstruction)?;
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

/// What [`bench_scene_refine`] measured (the median frame).
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct SceneRefineRow {
    /// Objects refined per frame (every object of the scene).
    pub objects: usize,
    /// Fine triangles written per frame (the mean of the two levels' frames).
    pub triangles: u64,
    /// Wall time of the median frame: the level of every object started
    /// ([`GpuScene::begin_refine`]), all of them recorded in one submission
    /// ([`GpuScene::refine_batch`]) and waited for.
    pub seconds: f64,
}

/// Times a frame in which every object of `asset` changes level, as a viewer flying through a
/// scene of many small objects sees it: each object alternates between `levels[0]` and
/// `levels[1]`, `frames` times after two warm-up frames (which allocate both sets of output buffers); the
/// median frame's wall time, submission to completion.
pub fn bench_scene_refine(
    ctx: &GpuContext,
    asset: &Asset,
    options: &SceneOptions,
    levels: [u32; 2],
    frames: u32,
) -> Result<SceneRefineRow, GpuError> {
    let mut scene = GpuScene::new(ctx, asset, options)?;
    let n = scene.object_count();
    let work: Vec<(usize, u64)> = (0..n).map(|i| (i, u64::MAX)).collect();
    let mut samples = Vec::new();
    let mut triangles = 0u64;
    for frame in 0..frames.max(1) + 2 {
        let level = levels[frame as usize % 2];
        let start = Instant::now();
        for i in 0..n {
            scene.begin_refine(ctx, i, level)?;
        }
        scene.refine_batch(ctx, &work, false)?;
        ctx.wait()?;
        let seconds = start.elapsed().as_secs_f64();
        if frame >= 2 {
            samples.push(seconds);
            triangles += (0..n).map(|i| scene.triangles_at(i, level)).sum::<u64>();
        }
    }
    let count = samples.len();
    samples.sort_by(f64::total_cmp);
    Ok(SceneRefineRow {
        objects: n,
        triangles: triangles / count as u64,
        seconds: samples[count / 2],
    })
}

/// The device's write bandwidth as a compute kernel sees it: the reference the refinement
/// kernels' bytes written per second are compared with.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Bandwidth {
    /// Bytes the fill kernel wrote per run.
    pub bytes: u64,
    /// Median time of one run.
    pub seconds: f64,
    pub timer: Timer,
}

impl Bandwidth {
    pub fn bytes_per_second(&self) -> f64 {
        self.bytes as f64 / self.seconds.max(1e-12)
    }
}

/// Times a kernel that only stores 16-byte words into a buffer of (up to) `bytes`, capped by
/// the device's buffer limits, `repeats` times after one warm-up (`fill.wgsl`). Its bytes per
/// second is what a kernel that writes its outputs once, coalesced, can reach on this device.
pub fn write_bandwidth(ctx: &GpuContext, bytes: u64, repeats: u32) -> Result<Bandwidth, GpuError> {
    let limits = ctx.device.limits();
    let cap = limits
        .max_buffer_size
        .min(limits.max_storage_buffer_binding_size);
    let words = (bytes.min(cap) / 16).clamp(1, u64::from(u32::MAX));
    let size = check_size(ctx, "bandwidth buffer", words * 16)?;
    let module = ctx
        .device
        .create_shader_module(wgpu::ShaderModuleDescriptor {
            label: Some("hce fill"),
            source: wgpu::ShaderSource::Wgsl(include_str!("fill.wgsl").into()),
        });
    let pipeline = ctx
        .device
        .create_compute_pipeline(&wgpu::ComputePipelineDescriptor {
            label: Some("hce fill"),
            layout: None,
            module: &module,
            entry_point: Some("fill_main"),
            compilation_options: Default::default(),
            cache: None,
        });
    let out = storage_output(ctx, "bandwidth buffer", size, wgpu::BufferUsages::empty());
    let params = uniform_init(ctx, "fill params", &[words as u32, 0x5eed_u32, 0, 0]);
    let bind_group = bind_buffers(
        ctx,
        "hce fill",
        &pipeline.get_bind_group_layout(0),
        &[&params, &out],
    );
    let groups = dispatch_size(ctx, words)?;
    let run = || -> Result<KernelTiming, GpuError> {
        let mut timer = PassTimer::new(ctx, "hce fill timing", 1, true);
        let mut encoder = ctx
            .device
            .create_command_encoder(&wgpu::CommandEncoderDescriptor { label: None });
        {
            let mut pass = encoder.begin_compute_pass(&wgpu::ComputePassDescriptor {
                label: Some("hce fill"),
                timestamp_writes: timer.writes(0),
            });
            pass.set_pipeline(&pipeline);
            pass.set_bind_group(0, &bind_group, &[]);
            pass.dispatch_workgroups(groups.0, groups.1, 1);
        }
        timer.resolve(ctx, &mut encoder);
        ctx.queue.submit([encoder.finish()]);
        let timing = KernelTiming {
            gpu_seconds: timer.read(ctx)?.map(|(total, _)| total),
            step_seconds: None,
        };
        Ok(timing)
    };
    let (seconds, timer, _) = time_repeats(repeats, run)?;
    // The last word proves the kernel ran over the whole buffer.
    let last: Vec<u32> = read_back(ctx, &out, (size / 4) as usize)?;
    let i = (words - 1) as u32;
    let tail = &last[last.len() - 4..];
    if tail != [0x5eed, i, 0x5eed ^ i, 0x5eed_u32.wrapping_add(i)] {
        return Err(GpuError::Readback(format!(
            "the fill kernel left {tail:?} in its last word"
        )));
    }
    Ok(Bandwidth {
        bytes: words * 16,
        seconds,
        timer,
    })
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
