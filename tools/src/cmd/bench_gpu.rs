//! `hce bench-gpu`: throughput of the GPU kernels per level on the adapter at hand.
//!
//! The input is either a mesh file (previewed as a flat object, as `hce render` does) or, by
//! default, a built-in 32×32 bumpy grid with random HCE trees (depth 4, up to 5 normals per
//! triangle), so the colour decoding walks real trees.

use std::path::PathBuf;

use anyhow::Result;
use clap::Args;

#[derive(Args, Debug)]
pub struct BenchGpuArgs {
    /// Mesh to refine (.obj, .gltf, .glb); default: a built-in grid with random trees.
    #[arg(long)]
    pub mesh: Option<PathBuf>,
    /// Levels to measure, comma-separated.
    #[arg(long, default_value = "1,2,3,4,5")]
    pub levels: String,
    /// Timed repetitions per level (the median is reported).
    #[arg(long, default_value_t = 5)]
    pub repeats: u32,
    /// Use a software adapter even if a GPU is present.
    #[arg(long)]
    pub software: bool,
}

#[cfg(not(feature = "gpu"))]
pub fn run(_args: BenchGpuArgs) -> Result<()> {
    anyhow::bail!("this `hce` was built without the `gpu` feature")
}

#[cfg(feature = "gpu")]
pub fn run(args: BenchGpuArgs) -> Result<()> {
    use anyhow::Context;
    use hce_runtime::gpu::bench::{bench_flat, Timer};
    use hce_runtime::gpu::testing::{grid, random_object, RandomTrees};
    use hce_runtime::gpu::{plain_mesh, ContextOptions, GpuContext};

    let levels: Vec<u32> = args
        .levels
        .split(',')
        .map(|s| s.trim().parse::<u32>())
        .collect::<Result<_, _>>()
        .with_context(|| format!("--levels {:?}: expected e.g. 1,2,3", args.levels))?;
    let (label, object) = match &args.mesh {
        Some(path) => {
            let mesh = plain_mesh::load_plain_mesh(path)?;
            (
                path.display().to_string(),
                plain_mesh::to_flat_object("mesh", &mesh).0,
            )
        }
        None => {
            let (p, t) = grid(32, 32);
            (
                "built-in 32x32 grid, random trees".to_string(),
                random_object("grid", p, t, RandomTrees::default(), 7),
            )
        }
    };
    let ctx = GpuContext::new(&ContextOptions {
        force_software: args.software,
    })?;
    println!("adapter: {}", ctx.description);
    println!("kernel: flat refinement (positions, faces + HCE decoding, vertex colours)");
    println!("input: {label}");
    println!(
        "{:>5} {:>8} {:>11} {:>11} {:>11} {:>9} {:>14} {:>10}",
        "level", "coarse", "out tris", "out verts", "time ms", "timer", "Mtris/s", "GB/s"
    );
    for row in bench_flat(&ctx, &object, &levels, args.repeats)? {
        println!(
            "{:>5} {:>8} {:>11} {:>11} {:>11.3} {:>9} {:>14.2} {:>10.3}",
            row.level,
            row.coarse_triangles,
            row.output_triangles,
            row.output_vertices,
            row.seconds * 1e3,
            match row.timer {
                Timer::GpuTimestamps => "gpu-ts",
                Timer::Wall => "wall",
            },
            row.triangles_per_second() / 1e6,
            row.bytes_per_second() / 1e9
        );
    }
    Ok(())
}
