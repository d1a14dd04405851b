//! `hce subdivide`: import a mesh, build its control-mesh tables and Loop-subdivide it on the
//! CPU (the reference the GPU kernel and the baker share), writing OBJ, glTF or GLB.

use std::path::PathBuf;
use std::time::Instant;

use anyhow::{Context, Result};
use clap::Args;
use hce_runtime::topology::{Creases, NonManifold, TopologyConfig};

#[derive(Args)]
pub struct SubdivideArgs {
    /// Input mesh (.obj, .gltf or .glb).
    pub input: PathBuf,
    /// Subdivision level, 1 to 6 (0 writes the welded, manifold control mesh itself).
    #[arg(long, short = 'l', default_value_t = 1)]
    pub levels: u32,
    /// Output mesh (.obj, .gltf or .glb), written atomically.
    #[arg(long, short = 'o')]
    pub output: PathBuf,
    /// Hard edges kept as infinitely sharp creases: none, auto (where input normals are split)
    /// or angle=DEG (dihedral angle above DEG degrees).
    #[arg(long, default_value = "none")]
    pub creases: Creases,
    /// Weld positions within this distance (0: only bitwise-equal positions).
    #[arg(long, default_value_t = 0.0)]
    pub weld_tolerance: f32,
    /// Refuse non-manifold input with an error instead of splitting it into manifold pieces.
    #[arg(long)]
    pub refuse_nonmanifold: bool,
    /// Print the topology report and the time of each stage.
    #[arg(long)]
    pub stats: bool,
}

pub fn run(args: SubdivideArgs) -> Result<()> {
    let t0 = Instant::now();
    let input = hce_runtime::import::load_mesh(&args.input)?;
    let t1 = Instant::now();
    let welded = hce_runtime::import::weld(&input.positions, args.weld_tolerance);
    let tris: Vec<[u32; 3]> = input
        .triangles
        .iter()
        .map(|t| t.map(|i| welded.input_to_welded[i as usize]))
        .collect();
    let t2 = Instant::now();
    let config = TopologyConfig {
        creases: args.creases,
        non_manifold: if args.refuse_nonmanifold {
            NonManifold::Refuse
        } else {
            NonManifold::Split
        },
    };
    let topo = hce_runtime::topology::build_control_mesh(
        &welded.positions,
        &tris,
        input.corner_normals.as_deref(),
        &config,
    )
    .with_context(|| format!("{}: cannot build the control mesh", args.input.display()))?;
    let t3 = Instant::now();
    let refined = hce_runtime::subdivide::subdivide(&topo.mesh, args.levels)
        .with_context(|| format!("{}: cannot subdivide", args.input.display()))?;
    let t4 = Instant::now();
    hce_runtime::export::write_mesh(
        &args.output,
        &refined.positions,
        &refined.normals,
        &refined.indices,
    )?;
    let t5 = Instant::now();
    if args.stats {
        println!(
            "{}: {} input vertices, {} input triangles",
            args.input.display(),
            input.positions.len(),
            input.triangles.len()
        );
        print!("{}", topo.report);
        println!(
            "level {}: {} vertices, {} triangles",
            args.levels,
            refined.positions.len(),
            refined.indices.len()
        );
        let ms = |a: Instant, b: Instant| (b - a).as_secs_f64() * 1e3;
        println!("time: import {:.1} ms, weld {:.1} ms, topology {:.1} ms, subdivide {:.1} ms, write {:.1} ms",
            ms(t0, t1), ms(t1, t2), ms(t2, t3), ms(t3, t4), ms(t4, t5));
    }
    Ok(())
}
