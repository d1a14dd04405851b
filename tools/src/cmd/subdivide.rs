//! `hce subdivide`: import a mesh, build its control-mesh tables and Loop-subdivide it on the
//! CPU (the reference the GPU kernel and the baker share), writing OBJ, glTF or GLB.
//!
//! A baked input (`.hce`, or `.glb`/`.gltf` carrying `EXT_hce_baked_lighting`) is instead
//! refined from each object's stored control mesh, and its baked colours are applied as the
//! runtime applies them ([`hce_runtime::colour::apply_baked_colours`]), written as `COLOR_0`.

use std::path::{Path, PathBuf};
use std::time::Instant;

use anyhow::{anyhow, Context, Result};
use clap::Args;
use hce_runtime::topology::{Creases, NonManifold, TopologyConfig};

#[derive(Args)]
#[command(
    after_help = "A baked input (.hce, or .glb/.gltf with EXT_hce_baked_lighting) is \
refined from every object's stored control mesh (--creases, --weld-tolerance and \
--refuse-nonmanifold do not apply), its baked colours are applied per subtriangle and averaged \
at the vertices, and all objects are written into one mesh in object space (no node transforms \
applied) with COLOR_0 as linear floats, clamped to [0, 1]."
)]
pub struct SubdivideArgs {
    /// Input mesh (.obj, .gltf or .glb; glTF mesh instances are placed by their node
    /// transforms), or a baked .hce / .glb / .gltf (see below).
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
    if let Some(container) = baked_container(&args.input)? {
        return run_baked(&args, &container);
    }
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

/// The container of a baked input, or `None` for a plain mesh.
fn baked_container(path: &Path) -> Result<Option<hce_format::Container>> {
    let ext = path
        .extension()
        .and_then(|e| e.to_str())
        .map(str::to_ascii_lowercase);
    match ext.as_deref() {
        Some("hce") => {
            let bytes =
                std::fs::read(path).with_context(|| format!("{}: cannot read", path.display()))?;
            let c = hce_format::read(&bytes)
                .with_context(|| format!("{}: not a valid .hce container", path.display()))?;
            Ok(Some(c))
        }
        Some("glb") | Some("gltf") => {
            let bytes =
                std::fs::read(path).with_context(|| format!("{}: cannot read", path.display()))?;
            let asset = hce_format::gltf::Asset::parse(&bytes)
                .with_context(|| format!("{}: not a valid glTF asset", path.display()))?;
            if hce_format::gltf::root_link(&asset.json)
                .with_context(|| format!("{}: bad EXT_hce_baked_lighting", path.display()))?
                .is_none()
            {
                return Ok(None);
            }
            let dir = path.parent().map(Path::to_owned).unwrap_or_default();
            let buffers = asset
                .buffers(|uri| {
                    std::fs::read(dir.join(uri)).map_err(|e| format!("cannot read {uri}: {e}"))
                })
                .with_context(|| format!("{}: cannot load buffers", path.display()))?;
            let data = hce_format::gltf::container_bytes(&asset.json, &buffers)
                .with_context(|| format!("{}: cannot find the baked container", path.display()))?
                .ok_or_else(|| anyhow!("{}: the baked container is missing", path.display()))?;
            let c = hce_format::read(data).with_context(|| {
                format!("{}: the embedded container is not valid", path.display())
            })?;
            Ok(Some(c))
        }
        _ => Ok(None),
    }
}

/// Refines every object of a baked container, applies its colours and writes one mesh.
fn run_baked(args: &SubdivideArgs, container: &hce_format::Container) -> Result<()> {
    if args.creases != Creases::None || args.weld_tolerance != 0.0 || args.refuse_nonmanifold {
        eprintln!(
            "note: {} is baked; --creases, --weld-tolerance and --refuse-nonmanifold are \
             ignored (the stored control meshes are subdivided as they are)",
            args.input.display()
        );
    }
    let t0 = Instant::now();
    let mut positions = Vec::new();
    let mut normals = Vec::new();
    let mut colours = Vec::new();
    let mut indices = Vec::new();
    for object in &container.objects {
        let refined =
            hce_runtime::subdivide::subdivide(&object.mesh, args.levels).with_context(|| {
                format!(
                    "{}: object '{}': cannot subdivide",
                    args.input.display(),
                    object.name
                )
            })?;
        let rgb = hce_runtime::colour::apply_baked_colours(object, &refined, args.levels)
            .with_context(|| format!("{}: cannot apply colours", args.input.display()))?;
        let offset = u32::try_from(positions.len())
            .ok()
            .filter(|o| o.checked_add(refined.positions.len() as u32).is_some())
            .ok_or_else(|| {
                anyhow!(
                    "{}: too many vertices for 32-bit indices",
                    args.input.display()
                )
            })?;
        indices.extend(refined.indices.iter().map(|t| t.map(|i| i + offset)));
        positions.extend_from_slice(&refined.positions);
        normals.extend_from_slice(&refined.normals);
        colours.extend(rgb);
        if args.stats {
            println!(
                "object '{}': level {}: {} vertices, {} triangles",
                object.name,
                args.levels,
                refined.positions.len(),
                refined.indices.len()
            );
        }
    }
    let t1 = Instant::now();
    hce_runtime::export::write_mesh_with_colours(
        &args.output,
        &positions,
        &normals,
        &colours,
        &indices,
    )?;
    if args.stats {
        let ms = |a: Instant, b: Instant| (b - a).as_secs_f64() * 1e3;
        println!(
            "{} objects: {} vertices, {} triangles; time: subdivide and colour {:.1} ms, write {:.1} ms",
            container.objects.len(),
            positions.len(),
            indices.len(),
            ms(t0, t1),
            ms(t1, Instant::now())
        );
    }
    Ok(())
}
