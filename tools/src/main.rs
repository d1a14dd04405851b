//! `hce`: bake, inspect, validate, subdivide and render assets with baked global illumination.

use clap::{Parser, Subcommand};

#[derive(Parser)]
#[command(name = "hce", version, about, long_about = None)]
struct Cli {
    #[command(subcommand)]
    command: Command,
}

#[derive(Subcommand)]
enum Command {}

fn main() -> anyhow::Result<()> {
    let cli = Cli::parse();
    match cli.command {}
}
