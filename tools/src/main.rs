//! `hce`: bake, inspect, validate, subdivide and render assets with baked global illumination.

use clap::{Parser, Subcommand};

mod cmd {
    pub mod subdivide;
}

#[derive(Parser)]
#[command(name = "hce", version, about, long_about = None)]
struct Cli {
    #[command(subcommand)]
    command: Command,
}

#[derive(Subcommand)]
enum Command {
    /// Loop-subdivide a mesh on the CPU (OBJ, glTF or GLB in and out).
    Subdivide(cmd::subdivide::SubdivideArgs),
}

fn main() -> anyhow::Result<()> {
    let cli = Cli::parse();
    match cli.command {
        Command::Subdivide(args) => cmd::subdivide::run(args),
    }
}
