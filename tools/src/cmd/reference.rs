//! `hce reference`: path-trace the picture `hce render FILE --level L` draws, as ground truth
//! for it.
//!
//! Geometry is what the renderer draws: the baked asset opened with
//! [`hce_runtime::asset::Asset`], every multiresolution object Loop-subdivided to `--level` on
//! the CPU with its vertices split at sharp edges ([`hce_geometry::refine::subdivide_split`],
//! from the file's control mesh, as `hce render
//! --cpu-reference` does), flat objects as they are (their refinement is linear), each instance
//! placed by its node's world transform. Materials and lights are the baker's: the same file read
//! by [`hce_meshio::scene::import_scene`] (reflectance and emission per coarse triangle, which
//! every fine triangle of it inherits; textured reflectance averaged over each fine triangle;
//! KHR_lights_punctual). Multiresolution objects shade with the refined mesh's vertex normals
//! (`Refined::normals`), so the reference is the smooth refined surface
//! ([`hce_reference`]).
//!
//! The camera and the pixel grid are the renderer's: the same camera choice
//! ([`hce_runtime::gpu::resolve_camera`]) and rays from the inverse of the renderer's own
//! view-projection matrix through the pixel's multisample positions
//! ([`hce_runtime::gpu::sample_positions`] of `--msaa`, default 4 as `hce render`; 1 is the
//! pixel centre), so each pixel covers what the rasteriser covers: at a silhouette both images
//! average the same sample positions, and inside a surface both are that surface's light. The
//! `--samples` paths of a pixel are shared out among its sample positions (the first ones get
//! one more when they do not divide evenly), each position's radiance averaged over its paths
//! and the pixel the mean of its positions, as the renderer's resolve averages its samples. A
//! pixel holds the outgoing radiance `Le + ρ E / π`: the units of the baked colours, which
//! `hce render -o x.exr` writes unchanged. Background and triangle backs are black; alpha is 1,
//! as in `hce render`.
//!
//! `--mask PATH.png` writes where comparisons are meaningful: white where the pixel and every
//! pixel within `--mask-margin` pixels (a square, default 2) see the front of the same instance
//! of a multiresolution object, black elsewhere (silhouettes, flat objects, background).

use std::path::{Path, PathBuf};
use std::sync::atomic::{AtomicU64, Ordering};
use std::time::Instant;

use anyhow::{bail, Context, Result};
use clap::Args;
use glam::{DMat4, DVec3, DVec4, Mat3, Mat4, Vec3};
use hce_format::ObjectKind;
use hce_meshio::scene::{import_scene, ImportOptions, ToSolver};
use hce_meshio::{Scene, SolverObject};
use hce_reference::PathTracer;
use hce_runtime::asset::{Asset, AssetError};
use indicatif::{ProgressBar, ProgressStyle};

use super::render::{output_format, parse_size, write_exr, write_png, Format};

#[derive(Args, Debug)]
pub struct ReferenceArgs {
    /// Baked asset (.glb or .gltf with EXT_hce_baked_lighting and its materials and lights).
    pub file: PathBuf,
    /// Output image: .exr (linear radiance, as `hce render -o x.exr`) or .png (tone-mapped as
    /// `hce render` does).
    #[arg(short, long)]
    pub output: PathBuf,
    /// Loop subdivision level of every multiresolution object (as `hce render --level`).
    #[arg(long, value_parser = super::bake::level_parser())]
    pub level: u32,
    /// Image size, WIDTHxHEIGHT.
    #[arg(long, default_value = "800x600")]
    pub size: String,
    /// `scene`, `auto` or EYE:TARGET[:FOV], exactly as `hce render --camera`. Default: the
    /// file's camera when it has one, else `auto`.
    #[arg(long)]
    pub camera: Option<String>,
    /// Paths per pixel (at least --msaa).
    #[arg(long, default_value_t = 256, value_parser = clap::value_parser!(u32).range(1..))]
    pub samples: u32,
    /// Sample positions per pixel, as `hce render --msaa` (1 is the pixel centre).
    #[arg(long, default_value_t = 4, value_parser = super::render::parse_msaa)]
    pub msaa: u32,
    /// Also write a mask PNG: white on pixels whose neighbourhood sees one multiresolution
    /// object instance (see --mask-margin), black elsewhere.
    #[arg(long, value_name = "PATH.png")]
    pub mask: Option<PathBuf>,
    /// Neighbourhood of the mask, in pixels each way.
    #[arg(long, default_value_t = 2)]
    pub mask_margin: u32,
    /// Seed of the random numbers; the image is the same for any thread count.
    #[arg(long, default_value_t = 0)]
    pub seed: u64,
    /// Exposure in stops applied before tone mapping (PNG only).
    #[arg(long, default_value_t = 0.0, allow_hyphen_values = true)]
    pub exposure: f32,
    /// Worker threads (default: all cores).
    #[arg(long, value_parser = super::bake::thread_count_parser())]
    pub threads: Option<usize>,
    /// No progress bar.
    #[arg(long, short = 'q')]
    pub quiet: bool,
}

/// What one path-traced object is: an instance of an asset object.
struct Placed {
    name: String,
    multires: bool,
    triangles: usize,
}

pub fn run(args: ReferenceArgs) -> Result<()> {
    use crate::exit::{usage, Usage};
    let format = output_format(&args.output).map_err(usage)?;
    if let Some(m) = &args.mask {
        if !matches!(output_format(m).map_err(usage)?, Format::Png) {
            bail!(Usage(format!("{}: the mask must be a .png", m.display())));
        }
    }
    let (width, height) = parse_size(&args.size).map_err(usage)?;
    if args.samples < args.msaa {
        bail!(Usage(format!(
            "--samples {} must be at least --msaa {}: every sample position needs a path",
            args.samples, args.msaa
        )));
    }
    let choice = super::render::camera_choice(args.camera.as_deref()).map_err(usage)?;
    let asset = match Asset::open(&args.file) {
        Ok(a) => a,
        Err(e @ AssetError::NotBaked { .. }) => {
            return Err(anyhow::Error::new(e).context(format!(
                "{}: the reference needs a baked file (run `hce bake` first)",
                args.file.display()
            )))
        }
        Err(e) => return Err(e.into()),
    };
    let t0 = Instant::now();
    let (scene, placed, normals) = build_scene(&asset, &args.file, args.level)?;
    let aspect = width as f32 / height as f32;
    let (camera, _) = hce_runtime::gpu::resolve_camera(&asset, choice, aspect)?;
    let bounds = asset.bounds().context("the asset has nothing to draw")?;
    let view_proj = hce_runtime::gpu::view_projection(&camera, bounds.min, bounds.max, aspect);
    let inv = view_proj.as_dmat4().inverse();
    let eye = Vec3::from(camera.eye).as_dvec3();

    let mut tracer = PathTracer::new(&scene);
    for (i, n) in normals.iter().enumerate() {
        if let Some(n) = n {
            tracer
                .set_vertex_normals(i, n)
                .map_err(|e| anyhow::anyhow!(e))?;
        }
    }
    let setup_s = t0.elapsed().as_secs_f64();
    let positions = hce_runtime::gpu::sample_positions(args.msaa)
        .context("--msaa has no standard sample positions")?;
    let ray = |x: u32, y: u32, s: usize| pixel_ray(&inv, eye, width, height, x, y, positions[s]);

    let mut pool = rayon::ThreadPoolBuilder::new();
    if let Some(n) = args.threads {
        pool = pool.num_threads(n);
    }
    let pool = pool.build().context("cannot start the worker threads")?;
    let bar = if args.quiet || !std::io::IsTerminal::is_terminal(&std::io::stderr()) {
        ProgressBar::hidden()
    } else {
        let bar = ProgressBar::new(u64::from(height));
        if let Ok(style) = ProgressStyle::with_template(
            "{prefix:>12} [{bar:30}] {pos}/{len} rows {elapsed} (eta {eta})",
        ) {
            bar.set_style(style.progress_chars("=> "));
        }
        bar.set_prefix("path tracing");
        bar
    };
    let rows = AtomicU64::new(0);
    let t1 = Instant::now();
    let pixels = pool.install(|| {
        tracer.render(
            width,
            height,
            args.samples,
            positions.len(),
            args.seed,
            ray,
            || {
                bar.set_position(rows.fetch_add(1, Ordering::Relaxed) + 1);
            },
        )
    });
    bar.finish_and_clear();
    let trace_s = t1.elapsed().as_secs_f64();

    let rgba: Vec<f32> = pixels
        .iter()
        .flat_map(|(l, _)| [l[0], l[1], l[2], 1.0])
        .collect();
    match format {
        Format::Exr => write_exr(&args.output, width, height, &rgba)?,
        Format::Png => {
            let rgba8: Vec<u8> = rgba
                .chunks_exact(4)
                .flat_map(|p| {
                    let [r, g, b] =
                        hce_runtime::gpu::tone_map_aces([p[0], p[1], p[2]], args.exposure);
                    [r, g, b, 255]
                })
                .collect();
            write_png(&args.output, width, height, &rgba8)?
        }
    }
    let total: usize = placed.iter().map(|p| p.triangles).sum();
    println!(
        "{}: {} objects, {total} triangles at level {}",
        args.file.display(),
        placed.len(),
        args.level
    );
    for p in &placed {
        println!(
            "  {}: {}, {} triangles",
            p.name,
            if p.multires { "multires" } else { "flat" },
            p.triangles
        );
    }
    println!(
        "wrote {} ({width}x{height}, {} paths per pixel, camera {}); setup {setup_s:.2}s, tracing {trace_s:.2}s",
        args.output.display(),
        args.samples,
        super::render::camera_text(&camera)
    );
    if let Some(path) = &args.mask {
        let ids: Vec<Option<usize>> = pixels
            .iter()
            .map(|(_, h)| {
                h.filter(|h| !h.back && placed[h.object].multires)
                    .map(|h| h.object)
            })
            .collect();
        let mask = interior_mask(&ids, width, height, args.mask_margin);
        let on = mask.iter().filter(|&&m| m).count();
        let rgba8: Vec<u8> = mask
            .iter()
            .flat_map(|&m| {
                let v = if m { 255 } else { 0 };
                [v, v, v, 255]
            })
            .collect();
        write_png(path, width, height, &rgba8)?;
        println!(
            "wrote {} ({on} pixels on multiresolution objects)",
            path.display()
        );
    }
    Ok(())
}

/// The ray through the point `at` (pixel units from its top-left corner, rows downwards) of
/// pixel `(x, y)` (rows top to bottom), from the inverse of the renderer's view-projection
/// matrix: origin the eye, unit direction.
fn pixel_ray(
    inv: &DMat4,
    eye: DVec3,
    w: u32,
    h: u32,
    x: u32,
    y: u32,
    at: [f32; 2],
) -> ([f64; 3], [f64; 3]) {
    let nx = 2.0 * (f64::from(x) + f64::from(at[0])) / f64::from(w) - 1.0;
    let ny = 1.0 - 2.0 * (f64::from(y) + f64::from(at[1])) / f64::from(h);
    let unproject = |z: f64| {
        let p = *inv * DVec4::new(nx, ny, z, 1.0);
        p.truncate() / p.w
    };
    let d = (unproject(1.0) - unproject(0.0)).normalize();
    (eye.to_array(), d.to_array())
}

/// Pixels whose square neighbourhood of `margin` pixels each way (clipped to the image) holds
/// one id only, and that id is `Some`.
pub fn interior_mask(ids: &[Option<usize>], w: u32, h: u32, margin: u32) -> Vec<bool> {
    let (w, h, m) = (w as i64, h as i64, i64::from(margin));
    let at = |x: i64, y: i64| ids[(y * w + x) as usize];
    let mut out = Vec::with_capacity(ids.len());
    for y in 0..h {
        for x in 0..w {
            let id = at(x, y);
            let same = id.is_some()
                && (y - m..=y + m).filter(|yy| (0..h).contains(yy)).all(|yy| {
                    (x - m..=x + m)
                        .filter(|xx| (0..w).contains(xx))
                        .all(|xx| at(xx, yy) == id)
                });
            out.push(same);
        }
    }
    out
}

/// The path tracer's scene: one object per instance of every asset object, in world space,
/// with per-triangle materials from the baker's import of the same file; per object its
/// world-space vertex normals for multiresolution objects.
#[allow(clippy::type_complexity)]
fn build_scene(
    asset: &Asset,
    file: &Path,
    level: u32,
) -> Result<(Scene, Vec<Placed>, Vec<Option<Vec<[f32; 3]>>>)> {
    let imported = import_scene(file, &ImportOptions::default())
        .with_context(|| format!("{}: reading materials and lights", file.display()))?;
    let mut scene = Scene {
        objects: Vec::new(),
        lights: imported.solver_scene().lights,
    };
    let mut placed = Vec::new();
    let mut normals = Vec::new();
    for ao in &asset.objects {
        let object = &ao.object;
        let coarse = object.mesh.triangles.len() / 3;
        let multires = object.kind == ObjectKind::Multiresolution;
        let refined = if multires {
            Some(
                hce_geometry::refine::subdivide_split(&object.name, &object.mesh, level)
                    .map_err(anyhow::Error::msg)
                    .with_context(|| format!("object '{}': subdividing", object.name))?,
            )
        } else {
            None
        };
        for inst in &ao.instances {
            // The imported object of this instance: the same node, the same corner positions.
            let k = imported
                .objects
                .iter()
                .position(|o| {
                    o.node == inst.node
                        && o.triangle_count() == coarse
                        && o.geometry_hash() == object.geometry_hash
                })
                .with_context(|| {
                    format!(
                        "object '{}' at node '{}': no primitive of the glTF scene matches it \
                         (was the file edited after baking?)",
                        object.name, inst.name
                    )
                })?;
            let source = imported.solver_object(k);
            let m: Mat4 = inst.transform;
            let mirrored = m.determinant() < 0.0;
            let normal_m = Mat3::from_mat4(m).inverse().transpose();
            let place = |p: [f32; 3]| m.transform_point3(Vec3::from(p)).to_array();
            let wind = |t: [u32; 3]| if mirrored { [t[0], t[2], t[1]] } else { t };
            let (positions, triangles, vertex_normals, cells): (
                Vec<[f32; 3]>,
                Vec<[u32; 3]>,
                _,
                _,
            ) = match &refined {
                Some(r) => (
                    r.positions.iter().map(|&p| place(p)).collect(),
                    r.indices.iter().map(|&t| wind(t)).collect(),
                    Some(
                        r.normals
                            .iter()
                            .map(|&n| (normal_m * Vec3::from(n)).normalize_or_zero().to_array())
                            .collect::<Vec<_>>(),
                    ),
                    Some(hce_geometry::subtriangle_cells(level)),
                ),
                None => (
                    object
                        .mesh
                        .positions
                        .chunks_exact(3)
                        .map(|p| place([p[0], p[1], p[2]]))
                        .collect(),
                    object
                        .mesh
                        .triangles
                        .chunks_exact(3)
                        .map(|t| wind([t[0], t[1], t[2]]))
                        .collect(),
                    None,
                    None,
                ),
            };
            let per_coarse = 1usize << (2 * if refined.is_some() { level } else { 0 });
            let n = triangles.len();
            let reflectance: Vec<[f32; 3]> = (0..n)
                .map(|f| {
                    let t = f / per_coarse;
                    match (&source.reflectance_fn, &cells) {
                        (Some(rf), Some(cells)) => {
                            let side = f32::from(1u16 << level.min(15));
                            let mut bary = cells[f % per_coarse].map(|[i, j]| {
                                let (u, v) = (i as f32 / side, j as f32 / side);
                                [1.0 - u - v, u, v]
                            });
                            if mirrored {
                                // The solver's triangle has corners 1 and 2 swapped.
                                bary = bary.map(|b| [b[0], b[2], b[1]]);
                            }
                            rf(t, bary)
                        }
                        _ => source.reflectance[t],
                    }
                })
                .collect();
            let emission: Vec<[f32; 3]> = if source.emission.is_empty() {
                Vec::new()
            } else {
                (0..n).map(|f| source.emission_of(f / per_coarse)).collect()
            };
            placed.push(Placed {
                name: if ao.instances.len() == 1 {
                    object.name.clone()
                } else {
                    format!("{} ({})", object.name, inst.name)
                },
                multires,
                triangles: n,
            });
            normals.push(vertex_normals);
            scene.objects.push(SolverObject {
                name: object.name.clone(),
                multires,
                positions,
                triangles,
                reflectance,
                reflectance_fn: None,
                emission,
                normal_sets: Vec::new(),
                occluder: Vec::new(),
            });
        }
    }
    Ok((scene, placed, normals))
}
