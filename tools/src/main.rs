//! `hce`: bake, inspect, validate, subdivide and render assets with baked global illumination.

use clap::{Parser, Subcommand};

mod cmd;

#[derive(Parser)]
#[command(name = "hce", version, about, long_about = None)]
struct Cli {
    #[command(subcommand)]
    command: Command,
}

#[derive(Subcommand)]
enum Command {
    /// Refine a mesh on the GPU and render it headless to PNG or EXR.
    Render(cmd::render::RenderArgs),
    /// Measure the GPU kernels' throughput per level.
    BenchGpu(cmd::bench_gpu::BenchGpuArgs),
    /// Loop-subdivide a mesh on the CPU (OBJ, glTF or GLB in and out).
    Subdivide(cmd::subdivide::SubdivideArgs),
}

fn main() -> anyhow::Result<()> {
    let cli = Cli::parse();
    match cli.command {
        Command::Render(args) => cmd::render::run(args),
        Command::BenchGpu(args) => cmd::bench_gpu::run(args),
        Command::Subdivide(args) => cmd::subdivide::run(args),
    }
}
