//! `hce`: bake, inspect, validate, subdivide, render, view and demo assets with baked global
//! illumination; path-trace references and compare images with them.
#![forbid(unsafe_code)]

use clap::{Parser, Subcommand};

mod cmd;
mod exit;

use exit::EXIT_CODES;

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
    /// Render a baked asset (its HCE colours, refined on the GPU) or preview a mesh, headless,
    /// to PNG or EXR.
    #[cfg(feature = "gpu")]
    #[command(after_help = EXIT_CODES)]
    Render(cmd::render::RenderArgs),
    /// Path-trace what `hce render --level L` draws (same geometry, camera and units), as ground
    /// truth: a linear EXR and a mask of multiresolution-object pixels.
    #[cfg(feature = "gpu")]
    #[command(after_help = EXIT_CODES)]
    Reference(cmd::reference::ReferenceArgs),
    /// Relative RMS difference and bias of an EXR against a reference EXR, over a mask.
    #[command(after_help = EXIT_CODES)]
    Compare(cmd::compare::CompareArgs),
    /// Bake a bundled sample and render it at levels 0 to 3 side by side: a first look at hce.
    #[cfg(feature = "gpu")]
    #[command(after_help = EXIT_CODES)]
    Demo(cmd::demo::DemoArgs),
    /// Measure the GPU kernels' throughput per level.
    #[cfg(feature = "gpu")]
    BenchGpu(cmd::bench_gpu::BenchGpuArgs),
    /// Loop-subdivide a mesh on the CPU (OBJ, glTF or GLB in and out).
    Subdivide(cmd::subdivide::SubdivideArgs),
    /// Show what a .hce, .glb or .gltf file holds: header, sections, objects, links.
    #[command(after_help = EXIT_CODES)]
    Inspect(cmd::inspect::InspectArgs),
    /// Check a .hce, .glb or .gltf file deeply; one line per problem.
    #[command(after_help = EXIT_CODES)]
    Validate(cmd::validate::ValidateArgs),
    /// Open a baked asset in a window (or preview a mesh) and move around it, with each
    /// object's level chosen live from the view; `--frames N` for scripted runs.
    #[cfg(feature = "gpu")]
    #[command(after_help = EXIT_CODES)]
    View(cmd::view::ViewArgs),
    /// Serve the browser viewer (WebGPU) for a baked file on 127.0.0.1 and print its URL.
    #[command(after_help = EXIT_CODES)]
    Serve(cmd::serve::ServeArgs),
}

/// `hce inspect x.glb | head` closes the pipe early; Rust's `println!` then panics with "failed
/// printing to stdout: Broken pipe". That is the reader's choice, not a crash: end quietly, as a
/// Unix tool does on SIGPIPE, with the status `exit::quiet_panic_status` gives it.
fn quiet_on_broken_pipe() {
    let default = std::panic::take_hook();
    std::panic::set_hook(Box::new(move |info| {
        let message = info
            .payload()
            .downcast_ref::<String>()
            .map(String::as_str)
            .or_else(|| info.payload().downcast_ref::<&str>().copied())
            .unwrap_or("");
        if let Some(status) = exit::quiet_panic_status(message) {
            std::process::exit(status as i32);
        }
        default(info);
    }));
}

fn main() -> std::process::ExitCode {
    quiet_on_broken_pipe();
    let cli = match Cli::try_parse() {
        Ok(cli) => cli,
        Err(e) => {
            // Help and version go to stdout with 0; bad arguments to stderr with 2.
            let _ = e.print();
            return std::process::ExitCode::from(e.exit_code().clamp(0, 255) as u8);
        }
    };
    let result = match cli.command {
        Command::Bake(args) => cmd::bake::run(args),
        #[cfg(feature = "gpu")]
        Command::Render(args) => cmd::render::run(args),
        #[cfg(feature = "gpu")]
        Command::Reference(args) => cmd::reference::run(args),
        Command::Compare(args) => cmd::compare::run(args),
        #[cfg(feature = "gpu")]
        Command::Demo(args) => cmd::demo::run(args),
        #[cfg(feature = "gpu")]
        Command::BenchGpu(args) => cmd::bench_gpu::run(args),
        Command::Subdivide(args) => cmd::subdivide::run(args),
        Command::Inspect(args) => cmd::inspect::run(args),
        Command::Validate(args) => cmd::validate::run(args),
        #[cfg(feature = "gpu")]
        Command::View(args) => cmd::view::run(args),
        Command::Serve(args) => cmd::serve::run(args),
    };
    match result {
        Ok(()) => std::process::ExitCode::SUCCESS,
        Err(e) => exit::report(&e),
    }
}
