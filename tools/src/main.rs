//! `hce`: bake, inspect, validate, subdivide and render assets with baked global illumination.

use clap::{Parser, Subcommand};

mod cmd;

/// Exit statuses shared by every subcommand (also in SPEC.md Appendix E and README.md).
const EXIT_CODES: &str = "\
Exit status:
  0  success (for `validate`: the file is valid)
  1  internal or other error
  2  usage error (bad arguments)
  3  invalid input (unreadable bytes, failed validation)
  4  I/O error (file missing, unreadable or unwritable)";

#[derive(Parser)]
#[command(name = "hce", version, about, long_about = None, after_help = EXIT_CODES)]
struct Cli {
    #[command(subcommand)]
    command: Command,
}

#[derive(Subcommand)]
enum Command {
    /// Bake global illumination into a glTF or OBJ scene (.glb/.gltf with the extension, or .hce).
    #[command(after_help = EXIT_CODES)]
    Bake(cmd::bake::BakeArgs),
    /// Refine a mesh on the GPU and render it headless to PNG or EXR.
    #[command(after_help = EXIT_CODES)]
    Render(cmd::render::RenderArgs),
    /// Measure the GPU kernels' throughput per level.
    BenchGpu(cmd::bench_gpu::BenchGpuArgs),
    /// Loop-subdivide a mesh on the CPU (OBJ, glTF or GLB in and out).
    Subdivide(cmd::subdivide::SubdivideArgs),
    /// Show what a .hce, .glb or .gltf file holds: header, sections, objects, links.
    #[command(after_help = EXIT_CODES)]
    Inspect(cmd::inspect::InspectArgs),
    /// Check a .hce, .glb or .gltf file deeply; one line per problem.
    #[command(after_help = EXIT_CODES)]
    Validate(cmd::validate::ValidateArgs),
}

fn main() -> anyhow::Result<()> {
    let cli = Cli::parse();
    match cli.command {
        Command::Bake(args) => cmd::bake::run(args),
        Command::Render(args) => cmd::render::run(args),
        Command::BenchGpu(args) => cmd::bench_gpu::run(args),
        Command::Subdivide(args) => cmd::subdivide::run(args),
        Command::Inspect(args) => cmd::inspect::run(args),
        Command::Validate(args) => cmd::validate::run(args),
    }
}
