//! `hce subdivide`: import a mesh, build its control-mesh tables and Loop-subdivide it on the
//! CPU (the reference the GPU kernel and the baker share), writing OBJ, glTF or GLB.
//!
//! A baked input (`.hce`, or `.glb`/`.gltf` carrying `EXT_hce_baked_lighting`) is loaded with
//! [`hce_runtime::asset::Asset::open`] (or, for glTF, read once through
//! [`hce_runtime::asset::GltfSource`] and loaded with `Asset::from_gltf`) and each object refined as the runtime refines it
//! ([`hce_geometry::refine::refine_object_as`]: Loop for multiresolution objects, flat ones
//! from their trees, one triangle per leaf plus those finer neighbours need (SPEC.md F.7.1), or
//! with `--flat uniform` linear 1-to-4 to the level (F.7.2), the vertices split at sharp edges
//! and at flat objects' folds of more than 10 degrees (SPEC.md F.5), colours from
//! [`hce_geometry::colour`]);
//! the scene is written back whole ([`hce_refined::write_refined_scene`]:
//! flat objects' vertices split further per coarse triangle, each with its face's normal), or
//! with `--merge` as one mesh in object space (the refined vertices of SPEC.md F.5, copies
//! included).

use std::path::{Path, PathBuf};
use std::time::Instant;

use anyhow::{anyhow, Context, Result};
use clap::Args;
use hce_format::ObjectKind;
use hce_geometry::refine::{refine_object_as, FlatRefinement, RefinedObject};
use hce_geometry::topology::{Creases, NonManifold, TopologyConfig};
use hce_refined::write_refined_scene;
use hce_runtime::asset::{Asset, GltfSource, OpenOptions};

#[derive(Args)]
#[command(
    after_help = "A baked input (.hce, or .glb/.gltf with EXT_hce_baked_lighting) is \
refined from every object's stored control mesh (multiresolution objects by Loop subdivision \
to --level, flat objects from their trees, one triangle per leaf element, or with --flat uniform \
linearly to --level as the GPU runtime draws them; --creases, --weld-tolerance and \
--refuse-nonmanifold do not apply) and written as a .glb/.gltf scene: every node, name, \
transform, shared mesh, material, camera and light kept, each baked primitive refined with \
NORMAL and COLOR_0 (the baked light over the base colour, one exposure per scene, as hce bake \
writes it). --merge writes instead all objects into one mesh in object space (no node \
transforms) with COLOR_0 the drawn radiosity clamped to [0, 1] (with --unclamped as it is, \
.obj only); an .obj output implies it."
)]
pub struct SubdivideArgs {
    /// Input mesh (.obj, .gltf or .glb; glTF mesh instances are placed by their node
    /// transforms), or a baked .hce / .glb / .gltf (see below).
    pub input: PathBuf,
    /// Subdivision level, 1 to 6 (0 writes the welded, manifold control mesh itself).
    #[arg(long, short = 'l', default_value_t = 1, value_parser = super::bake::level_parser())]
    pub level: u32,
    /// The old spelling of `--level`, accepted with a warning.
    #[arg(long = "levels", hide = true, conflicts_with = "level", value_parser = super::bake::level_parser())]
    pub levels_old: Option<u32>,
    /// On a baked file, how baked colours become vertex colours: `smooth` (the default,
    /// SPEC.md Appendix G), `nearest` (the paper's nearest-normal rule) or `gouraud` (normals
    /// ignored), as `hce render`.
    #[arg(long, default_value = "smooth", value_parser = super::render::parse_reconstruction)]
    pub reconstruction: hce_geometry::lighting::Reconstruction,
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
    /// Baked input: write all objects merged into one mesh in object space (node transforms
    /// not applied) instead of the scene.
    #[arg(long)]
    pub merge: bool,
    /// Baked input: how flat objects are refined: `adaptive` (the default: from their trees, one
    /// triangle per leaf plus those finer neighbours need, SPEC.md F.7.1; `--level` does not
    /// apply) or `uniform` (every coarse triangle split 1-to-4 to `--level`, F.7.2).
    #[arg(long, default_value = "adaptive", value_parser = parse_flat)]
    pub flat: FlatRefinement,
    /// Baked input, .obj output: write the vertex colours unclamped (the drawn radiosity as it
    /// is, above 1 too), to measure the light rather than to view it.
    #[arg(long)]
    pub unclamped: bool,
}

pub fn parse_flat(s: &str) -> Result<FlatRefinement, String> {
    match s {
        "adaptive" => Ok(FlatRefinement::Adaptive),
        "uniform" => Ok(FlatRefinement::Uniform),
        _ => Err(format!("'{s}': expected adaptive or uniform")),
    }
}

pub fn run(mut args: SubdivideArgs) -> Result<()> {
    if let Some(level) = super::renamed_flag(args.levels_old.take(), "--levels", "--level") {
        args.level = level;
    }
    if let Some(baked) = baked_input(&args.input)? {
        return run_baked(&args, baked);
    }
    if args.unclamped {
        return Err(anyhow!(
            "--unclamped needs a baked input: {} has no baked light",
            args.input.display()
        ));
    }
    let t0 = Instant::now();
    let input = hce_meshio::load_mesh(&args.input)?;
    let t1 = Instant::now();
    let welded = hce_geometry::weld(&input.positions, args.weld_tolerance);
    let tris = welded.triangles(&input.triangles);
    let t2 = Instant::now();
    let config = TopologyConfig {
        creases: args.creases,
        non_manifold: if args.refuse_nonmanifold {
            NonManifold::Refuse
        } else {
            NonManifold::Split
        },
    };
    let topo = hce_geometry::topology::build_control_mesh(
        &welded.positions,
        &tris,
        input.corner_normals.as_deref(),
        &config,
    )
    .with_context(|| format!("{}: cannot build the control mesh", args.input.display()))?;
    let t3 = Instant::now();
    let (refined, t4) = subdivide_and_write(&args, &topo.mesh)?;
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
            args.level,
            refined.positions.len(),
            refined.indices.len()
        );
        let ms = |a: Instant, b: Instant| (b - a).as_secs_f64() * 1e3;
        println!("time: import {:.1} ms, weld {:.1} ms, topology {:.1} ms, subdivide {:.1} ms, write {:.1} ms",
            ms(t0, t1), ms(t1, t2), ms(t2, t3), ms(t3, t4), ms(t4, t5));
    }
    Ok(())
}

/// How much of a streamed GLB is written between flushes to disk.
const FLUSH_BYTES: usize = 8 << 20;

/// Subdivides `mesh` and writes the result, returning it and when the subdivision ended. A
/// GLB is streamed ([`hce_meshio::export::GlbStream`]): its header is written from the output's
/// size and position bounds, known in advance ([`hce_geometry::subdivide::Plan::shape`]), and
/// each finished range of output is written while the rest is computed, so the disk writes
/// overlap the subdivision (the `--stats` time of the subdivision then includes them, and that
/// of the write is what is left); the file is the one [`hce_meshio::export::write_mesh`]
/// writes, byte for byte.
fn subdivide_and_write(
    args: &SubdivideArgs,
    mesh: &hce_format::ControlMesh,
) -> Result<(hce_geometry::Refined, Instant)> {
    use hce_geometry::subdivide::{plan, Written};
    let cannot = || format!("{}: cannot subdivide", args.input.display());
    let glb = args
        .output
        .extension()
        .is_some_and(|e| e.eq_ignore_ascii_case("glb"));
    #[cfg(unix)]
    if glb {
        let plan = plan(mesh, args.level).with_context(cannot)?;
        let shape = plan.shape();
        let stream = match shape.bounds {
            Some(bounds) => hce_meshio::export::GlbStream::create(
                &args.output,
                shape.vertices,
                shape.triangles,
                bounds,
            )?,
            None => None,
        };
        if let Some(stream) = stream {
            // Bytes written since the last flush to disk, by the sink's one thread: flushing
            // every few megabytes keeps the disk busy during the subdivision.
            let pending = std::sync::atomic::AtomicUsize::new(0);
            let sink = |w: Written<'_>| {
                use std::sync::atomic::Ordering::Relaxed;
                stream.positions(w.first_edge_point, w.edge_positions);
                stream.normals(w.first_edge_point, w.edge_normals);
                stream.positions(w.first_interior_point, w.interior_positions);
                stream.normals(w.first_interior_point, w.interior_normals);
                stream.indices(w.first_triangle, w.indices);
                let bytes = 24 * (w.edge_positions.len() + w.interior_positions.len())
                    + 12 * w.indices.len();
                if pending.fetch_add(bytes, Relaxed) + bytes >= FLUSH_BYTES {
                    pending.store(0, Relaxed);
                    stream.flush_written();
                }
            };
            let mut refined = hce_geometry::Refined::default();
            plan.subdivide_streamed(&mut refined, Some(&sink));
            let t4 = Instant::now();
            stream.finish(
                &args.output,
                &refined.positions,
                &refined.normals,
                &refined.indices,
                refined.coarse_vertices,
            )?;
            return Ok((refined, t4));
        }
    }
    // Only Unix streams a GLB.
    let _ = glb;
    let refined = hce_geometry::subdivide::subdivide(mesh, args.level).with_context(cannot)?;
    let t4 = Instant::now();
    hce_meshio::export::write_mesh(
        &args.output,
        &refined.positions,
        &refined.normals,
        &refined.indices,
    )?;
    Ok((refined, t4))
}

/// A baked input: a `.hce` container, or a glTF/GLB that uses the extension, read with its
/// buffers (which the refined scene is written from).
enum Baked {
    Hce,
    Gltf(GltfSource),
}

/// The input if it is baked; `None` for a plain mesh.
fn baked_input(path: &Path) -> Result<Option<Baked>> {
    let ext = path
        .extension()
        .and_then(|e| e.to_str())
        .map(str::to_ascii_lowercase);
    Ok(match ext.as_deref() {
        Some("hce") => Some(Baked::Hce),
        Some("glb") | Some("gltf") => GltfSource::open_baked(path)?.map(Baked::Gltf),
        _ => None,
    })
}

/// Refines every object of a baked asset as the runtime does and writes the scene (or, with
/// `--merge` or an OBJ output, one merged mesh).
fn run_baked(args: &SubdivideArgs, input: Baked) -> Result<()> {
    if args.creases != Creases::None || args.weld_tolerance != 0.0 || args.refuse_nonmanifold {
        eprintln!(
            "note: {} is baked; --creases, --weld-tolerance and --refuse-nonmanifold are \
             ignored (the stored control meshes are subdivided as they are)",
            args.input.display()
        );
    }
    let t0 = Instant::now();
    let (asset, gltf) = match input {
        Baked::Hce => (Asset::open(&args.input)?, None),
        Baked::Gltf(source) => (
            Asset::from_gltf(&args.input, &source, &OpenOptions::default())?,
            Some(source),
        ),
    };
    for w in &asset.warnings {
        eprintln!("warning: {w}");
    }
    let refined = asset
        .objects
        .iter()
        .map(|o| {
            refine_object_as(&o.object, args.level, args.reconstruction, args.flat).with_context(
                || {
                    format!(
                        "{}: object {} '{}'",
                        args.input.display(),
                        o.index,
                        o.name()
                    )
                },
            )
        })
        .collect::<Result<Vec<_>>>()?;
    let t1 = Instant::now();
    if args.stats {
        for (o, r) in asset.objects.iter().zip(&refined) {
            let refinement = match (o.kind(), args.flat) {
                (ObjectKind::Flat, FlatRefinement::Adaptive) => "flat, adaptive".to_string(),
                (ObjectKind::Flat, FlatRefinement::Uniform) => {
                    format!("flat, uniform: level {}", args.level)
                }
                (ObjectKind::Multiresolution, _) => {
                    format!("multiresolution, Loop: level {}", args.level)
                }
            };
            println!(
                "object '{}' ({refinement}): {} vertices, {} triangles",
                o.name(),
                r.mesh.positions.len(),
                r.mesh.indices.len()
            );
        }
    }
    let obj_output = args
        .output
        .extension()
        .is_some_and(|e| e.eq_ignore_ascii_case("obj"));
    if args.unclamped && !obj_output {
        return Err(anyhow!(
            "--unclamped needs an .obj output: glTF holds COLOR_0 in [0, 1] only"
        ));
    }
    if args.merge || obj_output {
        if obj_output && !args.merge {
            eprintln!("note: OBJ cannot hold the scene; writing all objects merged (--merge)");
        }
        write_merged(args, &refined)?;
    } else {
        let objects: Vec<&hce_format::Object> = asset.objects.iter().map(|o| &o.object).collect();
        write_refined_scene(
            &args.output,
            &objects,
            gltf.as_ref().map(|g| (&g.json, g.buffers.as_slice())),
            &refined,
        )
        .with_context(|| format!("{}: cannot write", args.output.display()))?;
    }
    if args.stats {
        let ms = |a: Instant, b: Instant| (b - a).as_secs_f64() * 1e3;
        println!(
            "{} objects; time: load, subdivide and colour {:.1} ms, write {:.1} ms",
            asset.objects.len(),
            ms(t0, t1),
            ms(t1, Instant::now())
        );
    }
    Ok(())
}

/// All objects in one mesh, in object space, `COLOR_0` the drawn radiosity (clamped).
fn write_merged(args: &SubdivideArgs, refined: &[RefinedObject]) -> Result<()> {
    let mut positions = Vec::new();
    let mut normals = Vec::new();
    let mut colours = Vec::new();
    let mut indices = Vec::new();
    for r in refined {
        let offset = u32::try_from(positions.len())
            .ok()
            .filter(|o| o.checked_add(r.mesh.positions.len() as u32).is_some())
            .ok_or_else(|| {
                anyhow!(
                    "{}: too many vertices for 32-bit indices",
                    args.input.display()
                )
            })?;
        indices.extend(r.mesh.indices.iter().map(|t| t.map(|i| i + offset)));
        positions.extend_from_slice(&r.mesh.positions);
        normals.extend_from_slice(&r.mesh.normals);
        colours.extend_from_slice(&r.colours);
    }
    let write = if args.unclamped {
        hce_meshio::export::write_obj_with_unclamped_colours
    } else {
        hce_meshio::export::write_mesh_with_colours
    };
    write(&args.output, &positions, &normals, &colours, &indices)?;
    Ok(())
}
