//! `hce bench-gpu`: throughput of the GPU kernels per level on the adapter at hand: the flat
//! refinement kernel and the Loop subdivision kernel (`--kernel`).
//!
//! The input is either a mesh file or, by default, a built-in 32×32 bumpy grid, with random HCE
//! trees (depth 4, up to 5 normals per triangle) so the colour decoding walks real trees. For
//! the flat kernel a mesh is previewed as a flat object, as `hce render` does; for the Loop
//! kernel it is welded and its control mesh built as `hce subdivide` does (no creases).
//!
//! `--kernel scene` measures instead a frame of a viewer in which every object of a generated
//! scene of many small objects (`--objects`; flat ones, multiresolution ones or both kinds in
//! turn, `--scene-kind`) changes level: all refined in one submission by
//! `GpuScene::refine_batch`, as `hce view` refines them, each object with its own dispatches
//! and then batched (`SceneOptions::batch`), with the ratio.

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
    /// Kernels to measure: flat, loop or both; or scene, a frame refining a scene of many small
    /// objects (see --objects and --scene-kind).
    #[arg(long, default_value = "both", value_parser = ["flat", "loop", "both", "scene"])]
    pub kernel: String,
    /// With --kernel scene: the scenes' object counts, comma-separated (each object 8 to 50
    /// triangles; the frames alternate between the first two of --levels).
    #[arg(long, default_value = "200,1000")]
    pub objects: String,
    /// With --kernel scene: scenes of flat objects, of multiresolution (Loop) objects, or both
    /// in turn.
    #[arg(long, default_value = "both", value_parser = ["flat", "loop", "both"])]
    pub scene_kind: String,
    /// Step 1 of the Loop kernel: auto (workgroup memory where the patches fit), workgroup,
    /// scratch, or both (scratch then auto, to compare them in one run).
    #[arg(long, default_value = "auto", value_parser = ["auto", "workgroup", "scratch", "both"])]
    pub patch: String,
    /// Colour reconstruction the kernels run: smooth (the default of the renderer), nearest
    /// (the paper's rule), or both (nearest then smooth, with the time ratio per level).
    #[arg(long, default_value = "both", value_parser = ["smooth", "nearest", "both"])]
    pub reconstruction: String,
}

#[cfg(feature = "gpu")]
pub fn run(args: BenchGpuArgs) -> Result<()> {
    use anyhow::Context;
    use hce_geometry::lighting::Reconstruction;
    use hce_meshio::plain as plain_mesh;
    use hce_runtime::gpu::bench::{
        bench_flat, bench_loop, grid, random_object, write_bandwidth, BenchRow, RandomTrees, Timer,
    };
    use hce_runtime::gpu::PatchScheme;
    use hce_runtime::gpu::{ContextOptions, GpuContext};

    let levels: Vec<u32> = args
        .levels
        .split(',')
        .map(|s| s.trim().parse::<u32>())
        .collect::<Result<_, _>>()
        .with_context(|| format!("--levels {:?}: expected e.g. 1,2,3", args.levels))?;
    let ctx = GpuContext::new(&ContextOptions {
        force_software: args.software,
    })?;
    println!("adapter: {}", ctx.description);
    if args.kernel == "scene" {
        return scene(&ctx, &args, &levels);
    }
    let label = match &args.mesh {
        Some(path) => path.display().to_string(),
        None => "built-in 32x32 grid, random trees".to_string(),
    };
    println!("input: {label}");
    let timer_name = |t: Timer| match t {
        Timer::GpuTimestamps => "gpu-ts",
        Timer::Wall => "wall",
    };
    // The reference for the kernels' bytes written per second: a kernel that only writes.
    let bandwidth = write_bandwidth(&ctx, 256 << 20, args.repeats)?;
    let peak = bandwidth.bytes_per_second();
    println!(
        "device write bandwidth (fill kernel, {} MiB, {}): {:.2} GB/s",
        bandwidth.bytes >> 20,
        timer_name(bandwidth.timer),
        peak / 1e9
    );
    let reconstructions: &[(&str, Reconstruction)] = match args.reconstruction.as_str() {
        "smooth" => &[("smooth", Reconstruction::Smooth)],
        "nearest" => &[("nearest", Reconstruction::NearestNormal)],
        _ => &[
            ("nearest", Reconstruction::NearestNormal),
            ("smooth", Reconstruction::Smooth),
        ],
    };
    // Per level, the time of the first reconstruction measured (to print the ratio of the second).
    let ratio = |rows: &[Vec<BenchRow>]| {
        if let [a, b] = rows {
            for (x, y) in a.iter().zip(b) {
                println!(
                    "level {}: smooth / nearest kernel time {:.2}x",
                    x.level,
                    y.seconds / x.seconds.max(1e-12)
                );
            }
        }
    };
    let print = |title: &str, rows: Vec<BenchRow>| {
        println!("kernel: {title}");
        println!(
            "{:>5} {:>8} {:>11} {:>11} {:>11} {:>9} {:>14} {:>10} {:>7}  steps ms",
            "level",
            "coarse",
            "out tris",
            "out verts",
            "time ms",
            "timer",
            "Mtris/s",
            "GB/s",
            "% fill"
        );
        for row in rows {
            println!(
                "{:>5} {:>8} {:>11} {:>11} {:>11.3} {:>9} {:>14.2} {:>10.3} {:>7.2}  {}",
                row.level,
                row.coarse_triangles,
                row.output_triangles,
                row.output_vertices,
                row.seconds * 1e3,
                timer_name(row.timer),
                row.triangles_per_second() / 1e6,
                row.bytes_per_second() / 1e9,
                100.0 * row.bytes_per_second() / peak,
                row.step_seconds.map_or("-".to_string(), |s| format!(
                    "{:.1} / {:.1} / {:.1}",
                    s[0] * 1e3,
                    s[1] * 1e3,
                    s[2] * 1e3
                ))
            );
        }
    };
    if args.kernel != "loop" {
        let object = match &args.mesh {
            Some(path) => {
                let mesh = plain_mesh::load_plain_mesh(path)?;
                hce_runtime::plain::to_flat_object("mesh", &mesh).0
            }
            None => {
                let (p, t) = grid(32, 32);
                random_object("grid", p, t, RandomTrees::default(), 7)
            }
        };
        let mut all = Vec::new();
        for &(rname, reconstruction) in reconstructions {
            let rows = bench_flat(&ctx, &object, &levels, args.repeats, reconstruction)?;
            print(
                &format!(
                    "flat refinement, {rname} colours (positions, faces + HCE decoding, vertex \
                     colours)"
                ),
                rows.clone(),
            );
            all.push(rows);
        }
        ratio(&all);
    }
    if args.kernel != "flat" {
        let (positions, triangles, normals) = match &args.mesh {
            Some(path) => {
                let input = hce_meshio::load_mesh(path)?;
                let welded = hce_geometry::weld(&input.positions, 0.0);
                let tris = welded.triangles(&input.triangles);
                (welded.positions, tris, input.corner_normals)
            }
            None => {
                let (p, t) = grid(32, 32);
                (
                    p.chunks_exact(3).map(|c| [c[0], c[1], c[2]]).collect(),
                    t.chunks_exact(3).map(|c| [c[0], c[1], c[2]]).collect(),
                    None,
                )
            }
        };
        let topo = hce_geometry::topology::build_control_mesh(
            &positions,
            &triangles,
            normals.as_deref(),
            &Default::default(),
        )
        .with_context(|| format!("{label}: cannot build the control mesh"))?;
        let mut object = random_object(
            "mesh",
            topo.mesh.positions.clone(),
            topo.mesh.triangles.clone(),
            RandomTrees::default(),
            7,
        );
        object.kind = hce_format::ObjectKind::Multiresolution;
        object.mesh = topo.mesh;
        let schemes: &[(&str, PatchScheme)] = match args.patch.as_str() {
            "workgroup" => &[("workgroup", PatchScheme::Workgroup)],
            "scratch" => &[("scratch", PatchScheme::Scratch)],
            "both" => &[
                ("scratch", PatchScheme::Scratch),
                ("auto", PatchScheme::Auto),
            ],
            _ => &[("auto", PatchScheme::Auto)],
        };
        for &(name, scheme) in schemes {
            let mut all = Vec::new();
            for &(rname, reconstruction) in reconstructions {
                let rows =
                    bench_loop(&ctx, &object, &levels, args.repeats, scheme, reconstruction)?;
                print(
                    &format!(
                        "Loop subdivision, {name} patches, {rname} colours (patches: positions + \
                         normals, faces + HCE decoding, vertex colours)"
                    ),
                    rows.clone(),
                );
                all.push(rows);
            }
            ratio(&all);
        }
    }
    Ok(())
}

/// `--kernel scene`: the median frame in which every object of a scene of many small objects
/// of one kind changes level.
#[cfg(feature = "gpu")]
fn scene(ctx: &hce_runtime::gpu::GpuContext, args: &BenchGpuArgs, levels: &[u32]) -> Result<()> {
    use anyhow::Context;
    use hce_format::ObjectKind;
    use hce_runtime::gpu::bench::{bench_scene_refine, small_scene};
    use hce_runtime::gpu::SceneOptions;

    let counts: Vec<usize> = args
        .objects
        .split(',')
        .map(|s| s.trim().parse::<usize>())
        .collect::<Result<_, _>>()
        .with_context(|| format!("--objects {:?}: expected e.g. 200,1000", args.objects))?;
    let pair = match levels {
        [a, b, ..] => [*a, *b],
        [a] => [*a, *a],
        [] => anyhow::bail!("--levels: give two levels to alternate between"),
    };
    let kinds: &[(ObjectKind, &str)] = match args.scene_kind.as_str() {
        "flat" => &[(ObjectKind::Flat, "flat")],
        "loop" => &[(ObjectKind::Multiresolution, "multiresolution (Loop)")],
        _ => &[
            (ObjectKind::Flat, "flat"),
            (ObjectKind::Multiresolution, "multiresolution (Loop)"),
        ],
    };
    for &(kind, name) in kinds {
        println!(
            "input: generated scenes of small {name} objects (8-50 triangles, random trees), \
             every object changing level between {} and {} each frame",
            pair[0], pair[1]
        );
        println!(
            "{:>8} {:>12} {:>10} {:>12}  path",
            "objects", "tris/frame", "ms/frame", "us/object"
        );
        for &count in &counts {
            let asset = small_scene(count, 18, kind)?;
            let mut times = Vec::new();
            for (path, batch) in [("per object", false), ("batched", true)] {
                let options = SceneOptions {
                    batch,
                    ..SceneOptions::default()
                };
                let row = bench_scene_refine(ctx, &asset, &options, pair, args.repeats)?;
                println!(
                    "{:>8} {:>12} {:>10.3} {:>12.1}  {path}",
                    row.objects,
                    row.triangles,
                    row.seconds * 1e3,
                    row.seconds * 1e6 / row.objects.max(1) as f64
                );
                times.push(row.seconds);
            }
            println!(
                "{count} {name} objects: per object / batched frame time {:.1}x",
                times[0] / times[1].max(1e-12)
            );
        }
    }
    Ok(())
}
