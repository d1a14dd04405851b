//! `hce render`: refine a scene on the GPU and draw it headless to PNG (tone-mapped) or EXR
//! (linear).
//!
//! A baked asset (`.glb`/`.gltf` with `EXT_hce_baked_lighting`, or `.hce`) is opened with
//! [`hce_runtime::asset::Asset`] and drawn by [`hce_runtime::gpu::render_asset`]: every object
//! refined (multiresolution objects to the chosen level, flat ones to their tree depth), with its
//! baked HCE colours and no other lighting, each instance at its node's transform, through the
//! scene's camera when the file has one.
//!
//! Any other mesh (OBJ, or glTF without the extension) is previewed as a flat object: one colour
//! per coarse triangle (its `COLOR_0` mean, or grey under a fixed preview light), refined
//! linearly by the flat kernel and averaged at the vertices.
//!
//! PNG output is tone-mapped: exposure `2^--exposure`, the ACES filmic fit of Narkowicz (2016),
//! then sRGB encoding ([`hce_runtime::gpu::tone_map_aces`]). EXR output is the linear radiance.

// Without the GPU there is no `hce render`; its argument helpers stay compiled and tested.
#![cfg_attr(not(feature = "gpu"), allow(dead_code))]

use std::path::{Path, PathBuf};

use anyhow::{bail, Context, Result};
use clap::Args;

#[derive(Args, Debug)]
pub struct RenderArgs {
    /// Baked asset (.glb/.gltf with EXT_hce_baked_lighting, or .hce) drawn with its baked
    /// colours, or a plain mesh (.obj, .gltf, .glb) previewed flat.
    pub file: PathBuf,
    /// Output image: .png (exposure, ACES filmic tone curve, 8-bit sRGB) or .exr (linear,
    /// 32-bit float).
    #[arg(short, long)]
    pub output: PathBuf,
    /// Refine every multiresolution object to this level (0 = coarse mesh; at most 6 for
    /// multiresolution objects, 15 for a plain mesh's preview); flat objects of a baked asset
    /// are always refined to their tree depth (up to 7, and deeper while an object stays within
    /// 2^22 fine triangles).
    #[arg(long, conflicts_with = "auto", value_parser = level_parser())]
    pub level: Option<u32>,
    /// Choose the level from the view (the default): edges of about 8 pixels.
    #[arg(long)]
    pub auto: bool,
    /// Image size, WIDTHxHEIGHT.
    #[arg(long, default_value = "800x600", value_parser = parse_size)]
    pub size: (u32, u32),
    /// `scene` (the file's camera), `auto` (inside a closed room, in front of an open box, or
    /// outside an object), or EYE:TARGET[:FOV] with EYE and TARGET as x,y,z and FOV the
    /// vertical field of view in degrees (default 40), e.g. `3,2,5:0,0,0:35`. Default: the
    /// file's camera when it has one, else `auto`.
    #[arg(long)]
    pub camera: Option<String>,
    /// Exposure in stops applied before tone mapping (PNG only).
    #[arg(long, default_value_t = 0.0, allow_hyphen_values = true)]
    pub exposure: f32,
    /// Refuse levels whose output exceeds this many triangles (the level is lowered, with a
    /// note, when chosen automatically).
    #[arg(long, default_value_t = 16_000_000)]
    pub max_triangles: u64,
    /// Use a software adapter even if a GPU is present.
    #[arg(long)]
    pub software: bool,
    /// Refine multiresolution objects with the CPU reference (Loop subdivision and colour
    /// application on the CPU, then uploaded) instead of the GPU Loop kernel: for checking the
    /// kernel, never needed otherwise.
    #[arg(long)]
    pub cpu_reference: bool,
    /// How baked colours become vertex colours: `smooth` (continuous over the surface and
    /// linear in the normal, SPEC.md Appendix G), `nearest` (the paper's rule: each subtriangle
    /// takes the colour of its closest representative normal, averaged at vertices) or, for
    /// comparison, `gouraud` (classic radiosity rendering: the elements' colours for their
    /// geometric normals, averaged at element corners and interpolated; normals ignored).
    #[arg(long, default_value = "smooth", value_parser = parse_reconstruction)]
    pub reconstruction: hce_geometry::lighting::Reconstruction,
    /// Multisample anti-aliasing: samples per pixel, 1 (none), 2, 4, 8 or 16. The adapter's
    /// largest supported count up to this is used (printed). `hce reference --msaa` traces
    /// rays through the same sample positions.
    #[arg(long, default_value_t = 4, value_parser = parse_msaa)]
    pub msaa: u32,
    /// How flat objects are refined: `adaptive` (the default: from their trees, one triangle per
    /// leaf plus those finer neighbours need, SPEC.md F.7.1) or `uniform` (every coarse triangle
    /// split 1-to-4 to the depth of its deepest leaf, bounded by its size, F.7.2).
    #[arg(long, default_value = "adaptive", value_parser = super::subdivide::parse_flat)]
    pub flat: hce_geometry::refine::FlatRefinement,
}

/// Parses a multisample count: 1, 2, 4, 8 or 16 (the counts with standard sample positions).
pub fn parse_msaa(s: &str) -> Result<u32, String> {
    match s.trim().parse::<u32>() {
        Ok(n @ (1 | 2 | 4 | 8 | 16)) => Ok(n),
        _ => Err(format!(
            "'{s}': expected 1, 2, 4, 8 or 16 samples per pixel"
        )),
    }
}

/// `--level`: 0 to the deepest level a subtriangle path can name (`MAX_PATH_LEVEL`, the flat
/// kernel's); Loop subdivision's own bound (6) is checked where a multiresolution object is
/// refined, as a usage error too.
fn level_parser() -> clap::builder::RangedI64ValueParser<u32> {
    clap::value_parser!(u32).range(0..=i64::from(hce_geometry::decode::MAX_PATH_LEVEL))
}

pub fn parse_reconstruction(s: &str) -> Result<hce_geometry::lighting::Reconstruction, String> {
    s.parse()
}

/// Parses `WIDTHxHEIGHT`.
pub fn parse_size(s: &str) -> Result<(u32, u32)> {
    let (w, h) = s
        .split_once(['x', 'X'])
        .with_context(|| format!("--size {s:?}: expected WIDTHxHEIGHT, e.g. 800x600"))?;
    let w: u32 = w
        .trim()
        .parse()
        .with_context(|| format!("--size {s:?}: bad width"))?;
    let h: u32 = h
        .trim()
        .parse()
        .with_context(|| format!("--size {s:?}: bad height"))?;
    if w == 0 || h == 0 || w > 16384 || h > 16384 {
        bail!("--size {s:?}: each side must be 1 to 16384 pixels");
    }
    Ok((w, h))
}

fn parse_vec3(s: &str, what: &str) -> Result<[f32; 3]> {
    let v: Vec<f32> = s
        .split(',')
        .map(|x| x.trim().parse::<f32>())
        .collect::<Result<_, _>>()
        .with_context(|| format!("--camera: {what} {s:?} is not x,y,z"))?;
    match v[..] {
        [x, y, z] if v.iter().all(|c| c.is_finite()) => Ok([x, y, z]),
        _ => bail!("--camera: {what} {s:?} must be three finite numbers x,y,z"),
    }
}

/// Parses `auto` or `EYE:TARGET[:FOV]`; `None` means auto-framing.
#[cfg(feature = "gpu")]
pub fn parse_camera(s: &str) -> Result<Option<hce_runtime::gpu::Camera>> {
    if s == "auto" {
        return Ok(None);
    }
    let parts: Vec<&str> = s.split(':').collect();
    if parts.len() < 2 || parts.len() > 3 {
        bail!("--camera {s:?}: expected auto or EYE:TARGET[:FOV], e.g. 3,2,5:0,0,0:35");
    }
    let eye = parse_vec3(parts[0], "eye")?;
    let target = parse_vec3(parts[1], "target")?;
    let fov = match parts.get(2) {
        Some(f) => f
            .trim()
            .parse::<f32>()
            .ok()
            .filter(|f| *f > 0.0 && *f < 180.0)
            .with_context(|| format!("--camera: FOV {f:?} must be between 0 and 180 degrees"))?,
        None => 40.0,
    };
    if eye == target {
        bail!("--camera {s:?}: eye and target must differ");
    }
    Ok(Some(hce_runtime::gpu::Camera {
        eye,
        target,
        fov_y_degrees: fov,
    }))
}

pub enum Format {
    Png,
    Exr,
}

pub fn output_format(path: &Path) -> Result<Format> {
    match path
        .extension()
        .and_then(|e| e.to_str())
        .map(|e| e.to_ascii_lowercase())
        .as_deref()
    {
        Some("png") => Ok(Format::Png),
        Some("exr") => Ok(Format::Exr),
        _ => bail!(
            "{}: output must end in .png (tone-mapped) or .exr (linear)",
            path.display()
        ),
    }
}

/// Writes 8-bit sRGB RGBA to a PNG, tagged sRGB, through `hce_meshio::write_atomic_with`.
pub fn write_png(path: &Path, width: u32, height: u32, rgba8: &[u8]) -> Result<()> {
    hce_meshio::write_atomic_with(path, |w| {
        let mut enc = png::Encoder::new(w, width, height);
        enc.set_color(png::ColorType::Rgba);
        enc.set_depth(png::BitDepth::Eight);
        enc.set_source_srgb(png::SrgbRenderingIntent::Perceptual);
        let mut writer = enc.write_header().map_err(std::io::Error::other)?;
        writer
            .write_image_data(rgba8)
            .map_err(std::io::Error::other)?;
        writer.finish().map_err(std::io::Error::other)
    })
    .with_context(|| format!("writing {}", path.display()))
}

/// Writes linear RGBA f32 (rows top to bottom) to an OpenEXR file, encoded in memory (the
/// encoder seeks) and written through `hce_meshio::write_atomic`.
pub fn write_exr(path: &Path, width: u32, height: u32, rgba: &[f32]) -> Result<()> {
    use exr::prelude::{Image, SpecificChannels, Vec2, WritableImage};
    let w = width as usize;
    let channels = SpecificChannels::rgba(|Vec2(x, y): Vec2<usize>| {
        let p = &rgba[4 * (y * w + x)..4 * (y * w + x) + 4];
        (p[0], p[1], p[2], p[3])
    });
    let mut bytes = std::io::Cursor::new(Vec::new());
    Image::from_channels((w, height as usize), channels)
        .write()
        .to_buffered(&mut bytes)
        .map_err(|e| anyhow::anyhow!("{e}"))
        .with_context(|| format!("encoding {}", path.display()))?;
    hce_meshio::write_atomic(path, bytes.get_ref())
        .with_context(|| format!("writing {}", path.display()))
}

/// The camera `--camera` asks for.
#[cfg(feature = "gpu")]
pub fn camera_choice(arg: Option<&str>) -> Result<hce_runtime::gpu::CameraChoice> {
    use hce_runtime::gpu::CameraChoice;
    Ok(match arg {
        None => CameraChoice::SceneOrAuto,
        Some("scene") => CameraChoice::Scene,
        Some(s) => match parse_camera(s)? {
            None => CameraChoice::Auto,
            Some(c) => CameraChoice::Explicit(c),
        },
    })
}

#[cfg(feature = "gpu")]
pub fn open_context(software: bool) -> Result<hce_runtime::gpu::GpuContext> {
    use hce_runtime::gpu::{ContextOptions, GpuContext};
    let ctx = GpuContext::new(&ContextOptions {
        force_software: software,
    })?;
    report_adapter(&ctx.description);
    Ok(ctx)
}

/// Prints the adapter, and says so when it is a software rasteriser.
#[cfg(feature = "gpu")]
pub fn report_adapter(adapter: &hce_runtime::gpu::AdapterDescription) {
    println!("adapter: {adapter}");
    if adapter.kind == hce_runtime::gpu::AdapterKind::Software {
        println!(
            "note: rendering on a software rasteriser (no hardware GPU in use); expect it to be slow"
        );
    }
}

#[cfg(feature = "gpu")]
fn write_image(args: &RenderArgs, image: &hce_runtime::gpu::RenderedImage) -> Result<()> {
    let (w, h) = (image.width, image.height);
    match output_format(&args.output)? {
        Format::Png => write_png(&args.output, w, h, &image.to_srgb8(args.exposure))?,
        Format::Exr => write_exr(&args.output, w, h, &image.pixels)?,
    }
    println!(
        "wrote {} ({w}x{h}, {} samples per pixel, camera {})",
        args.output.display(),
        image.samples,
        camera_text(&image.camera)
    );
    if image.samples < args.msaa {
        eprintln!(
            "note: the adapter multisamples this image at most {}x; compare it with \
             `hce reference --msaa {}`",
            image.samples, image.samples
        );
    }
    Ok(())
}

/// A camera as `--camera` reads it back: `EYE:TARGET:FOV`.
#[cfg(feature = "gpu")]
pub fn camera_text(c: &hce_runtime::gpu::Camera) -> String {
    format!(
        "{},{},{}:{},{},{}:{}",
        c.eye[0], c.eye[1], c.eye[2], c.target[0], c.target[1], c.target[2], c.fov_y_degrees
    )
}

#[cfg(feature = "gpu")]
pub fn run(args: RenderArgs) -> Result<()> {
    use hce_runtime::asset::{Asset, AssetError};

    output_format(&args.output)?;
    // A bad --camera is a usage error (exit 2), as clap's own are.
    let choice = camera_choice(args.camera.as_deref()).map_err(crate::exit::usage)?;
    let is_obj = args
        .file
        .extension()
        .is_some_and(|e| e.eq_ignore_ascii_case("obj"));
    if is_obj {
        return run_plain(&args, choice);
    }
    match Asset::open(&args.file) {
        Ok(asset) => run_baked(&args, &asset, choice),
        Err(AssetError::NotBaked { .. }) => {
            println!(
                "{}: no baked lighting; previewing the plain mesh flat",
                args.file.display()
            );
            run_plain(&args, choice)
        }
        Err(e) => Err(e.into()),
    }
}

/// Draws a baked asset with its HCE colours.
#[cfg(feature = "gpu")]
fn run_baked(
    args: &RenderArgs,
    asset: &hce_runtime::asset::Asset,
    camera: hce_runtime::gpu::CameraChoice,
) -> Result<()> {
    use hce_runtime::gpu::{render_asset, AssetRenderOptions, CameraSource};

    let (width, height) = args.size;
    for w in &asset.warnings {
        eprintln!("warning: {w}");
    }
    let ctx = open_context(args.software)?;
    let result = render_asset(
        &ctx,
        asset,
        &AssetRenderOptions {
            width,
            height,
            camera,
            level: args.level,
            max_triangles: args.max_triangles,
            scene: hce_runtime::gpu::SceneOptions {
                multires: if args.cpu_reference {
                    hce_runtime::gpu::MultiresPath::CpuReference
                } else {
                    hce_runtime::gpu::MultiresPath::Gpu
                },
                reconstruction: args.reconstruction,
                flat_refinement: args.flat,
                ..Default::default()
            },
            samples: args.msaa,
            ..Default::default()
        },
    )?;
    for n in &result.notes {
        eprintln!("note: {n}");
    }
    match &result.camera_source {
        CameraSource::Scene(name) => println!("camera: the scene's camera '{name}'"),
        CameraSource::Auto(p) => println!("camera: automatic ({p:?})"),
        CameraSource::Explicit => println!("camera: as given"),
    }
    for (name, kind, level, triangles, instances) in &result.objects {
        println!(
            "  {name}: {kind:?}, level {level}, {triangles} triangles{}",
            if *instances == 1 {
                String::new()
            } else {
                format!(" x {instances} instances")
            }
        );
    }
    println!(
        "{}: {} objects, {} triangles drawn with their baked colours",
        args.file.display(),
        result.objects.len(),
        result.triangles
    );
    write_image(args, &result.image)
}

/// A plain mesh (OBJ, or glTF without baked lighting) as the flat object its preview draws:
/// one colour per coarse triangle, equal positions welded. A glTF is read as the browser reads
/// it (`Asset::plain_preview`: its `COLOR_0` as a glTF viewer draws it), its warnings printed.
#[cfg(feature = "gpu")]
pub fn plain_object(file: &Path) -> Result<hce_format::Object> {
    use hce_meshio::plain as plain_mesh;
    use hce_runtime::asset::{buffer_files, Asset, GltfSource};

    let gltf = file
        .extension()
        .and_then(|e| e.to_str())
        .is_some_and(|e| e.eq_ignore_ascii_case("glb") || e.eq_ignore_ascii_case("gltf"));
    let object = if gltf {
        let bytes =
            std::fs::read(file).with_context(|| format!("{}: cannot read", file.display()))?;
        let dir = file.parent().unwrap_or(Path::new("."));
        let source = GltfSource::parse(&bytes, buffer_files(dir))
            .with_context(|| format!("{}: cannot read", file.display()))?;
        let mut asset = Asset::plain_preview(file, &source)?;
        for w in &asset.warnings {
            eprintln!("warning: {w}");
        }
        asset.objects.swap_remove(0).object
    } else {
        let mesh = plain_mesh::load_plain_mesh(file)?;
        let name = file
            .file_stem()
            .map(|s| s.to_string_lossy().into_owned())
            .unwrap_or_default();
        let (object, dropped) = hce_runtime::plain::to_flat_object(&name, &mesh);
        if dropped > 0 {
            eprintln!("note: {dropped} degenerate triangles dropped after welding equal positions");
        }
        object
    };
    if object.triangles.is_empty() {
        bail!("{}: no non-degenerate triangles to render", file.display());
    }
    Ok(object)
}

/// How a plain mesh's preview is framed and refined: its bounds, its automatic camera and the
/// level chosen for a view.
#[cfg(feature = "gpu")]
pub struct PlainView {
    pub bounds: ([f32; 3], [f32; 3]),
    mean_edge: f32,
}

#[cfg(feature = "gpu")]
impl PlainView {
    pub fn new(object: &hce_format::Object) -> Result<Self> {
        let bounds = hce_runtime::gpu::mesh_bounds(&object.mesh.positions)
            .context("mesh has no finite positions")?;
        Ok(Self {
            bounds,
            mean_edge: mean_edge_length(&object.mesh.positions, &object.mesh.triangles),
        })
    }

    /// [`hce_runtime::gpu::auto_scene_camera`] on the mesh.
    pub fn auto_camera(
        &self,
        object: &hce_format::Object,
        aspect: f32,
    ) -> hce_runtime::gpu::Camera {
        let m = &object.mesh;
        let triangles: Vec<[[f32; 3]; 3]> = (0..m.triangle_count())
            .map(|t| m.triangle(t).map(|v| m.position(v)))
            .collect();
        hce_runtime::gpu::auto_scene_camera(&triangles, self.bounds.0, self.bounds.1, aspect).0
    }

    /// The level [`hce_runtime::gpu::choose_level`] gives the mesh seen by `view`, lowered
    /// (with a note) until it makes at most `max_triangles` from `coarse` triangles.
    pub fn level(
        &self,
        view: &hce_runtime::gpu::Camera,
        viewport_height: u32,
        lod: &hce_runtime::gpu::LodParams,
        coarse: u64,
        max_triangles: u64,
    ) -> (u32, Option<String>) {
        let (lo, hi) = self.bounds;
        let chosen =
            hce_runtime::gpu::choose_level(lo, hi, self.mean_edge, view, viewport_height, lod);
        let mut level = chosen;
        while level > 0 && coarse << (2 * level) > max_triangles {
            level -= 1;
        }
        let note = (level < chosen)
            .then(|| format!("level lowered to {level} to stay under --max-triangles"));
        (level, note)
    }
}

/// Checks a forced level of a plain mesh against the triangle budget.
#[cfg(feature = "gpu")]
pub fn check_plain_level(level: u32, coarse: u64, max_triangles: u64) -> Result<u32> {
    let out = coarse << (2 * level.min(31));
    if level > hce_geometry::decode::MAX_PATH_LEVEL || out > max_triangles {
        bail!(
            "--level {level} would make {out} triangles from {coarse}; the limit is \
             {max_triangles} (raise --max-triangles or lower --level)"
        );
    }
    Ok(level)
}

/// Previews a plain mesh as a flat object.
#[cfg(feature = "gpu")]
fn run_plain(args: &RenderArgs, camera: hce_runtime::gpu::CameraChoice) -> Result<()> {
    use hce_runtime::gpu::{
        render_gpu_mesh, CameraChoice, FlatKernel, Framing, GpuMesh, LodParams, RenderParams,
    };

    let (width, height) = args.size;
    let object = plain_object(&args.file)?;
    let ctx = open_context(args.software)?;

    let plain = PlainView::new(&object)?;
    let aspect = width as f32 / height as f32;
    let view = match camera {
        CameraChoice::Explicit(c) => c,
        CameraChoice::Scene => bail!(
            "--camera scene: {} is previewed as a plain mesh, without its cameras",
            args.file.display()
        ),
        CameraChoice::Auto | CameraChoice::SceneOrAuto => plain.auto_camera(&object, aspect),
    };
    let f = object.triangles.len() as u64;
    let level = match args.level {
        Some(level) => {
            check_plain_level(level, f, args.max_triangles).map_err(crate::exit::usage)?
        }
        None => {
            let (level, note) =
                plain.level(&view, height, &LodParams::default(), f, args.max_triangles);
            if let Some(note) = note {
                eprintln!("note: {note}");
            }
            level
        }
    };

    let kernel = FlatKernel::new(&ctx);
    let uploaded = kernel.upload(
        &ctx,
        &object,
        hce_geometry::lighting::Reconstruction::default(),
        hce_geometry::refine::FlatRefinement::Uniform,
    )?;
    let mut out = None;
    kernel.refine_into(&ctx, &uploaded, level, &mut out, false)?;
    let out = out.context("refinement produced no output")?;
    println!(
        "{}: {} coarse triangles refined to level {level}: {} triangles, {} vertices",
        args.file.display(),
        f,
        out.triangle_count,
        out.vertex_count
    );
    let image = render_gpu_mesh(
        &ctx,
        &GpuMesh {
            positions: &out.positions,
            colours: &out.colours,
            indices: &out.indices,
            index_count: out.triangle_count * 3,
            bounds: plain.bounds,
        },
        &RenderParams {
            width,
            height,
            framing: Framing::Camera(view),
            background: [0.0; 3],
            samples: args.msaa,
        },
    )?;
    write_image(args, &image)
}

fn mean_edge_length(positions: &[f32], triangles: &[u32]) -> f32 {
    let p = |i: u32| {
        let i = i as usize * 3;
        [positions[i], positions[i + 1], positions[i + 2]]
    };
    let mut sum = 0f64;
    for t in triangles.chunks_exact(3) {
        for e in 0..3 {
            let (a, b) = (p(t[e]), p(t[(e + 1) % 3]));
            let d = ((a[0] - b[0]).powi(2) + (a[1] - b[1]).powi(2) + (a[2] - b[2]).powi(2)).sqrt();
            sum += f64::from(d);
        }
    }
    (sum / triangles.len().max(1) as f64) as f32
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn sizes_and_cameras_parse_or_explain() {
        assert_eq!(parse_size("640x480").unwrap(), (640, 480));
        assert!(parse_size("640")
            .unwrap_err()
            .to_string()
            .contains("WIDTHxHEIGHT"));
        assert!(parse_size("0x10").is_err());
        #[cfg(feature = "gpu")]
        {
            let c = parse_camera("3,2,5:0,0,0:35").unwrap().unwrap();
            assert_eq!(
                (c.eye, c.target, c.fov_y_degrees),
                ([3.0, 2.0, 5.0], [0.0; 3], 35.0)
            );
            assert_eq!(
                parse_camera("1,1,1:0,0,0").unwrap().unwrap().fov_y_degrees,
                40.0
            );
            assert!(parse_camera("auto").unwrap().is_none());
            assert!(parse_camera("1,1:0,0,0").is_err());
            assert!(parse_camera("1,1,1:1,1,1").is_err());
            assert!(parse_camera("1,1,1:0,0,0:200").is_err());
            use hce_runtime::gpu::CameraChoice;
            assert_eq!(camera_choice(None).unwrap(), CameraChoice::SceneOrAuto);
            assert_eq!(camera_choice(Some("scene")).unwrap(), CameraChoice::Scene);
            assert_eq!(camera_choice(Some("auto")).unwrap(), CameraChoice::Auto);
            assert!(matches!(
                camera_choice(Some("1,1,1:0,0,0")).unwrap(),
                CameraChoice::Explicit(c) if c.eye == [1.0; 3]
            ));
            assert!(camera_choice(Some("sceen")).is_err());
        }
    }

    #[test]
    fn png_is_written_atomically_and_reads_back() {
        let dir = tempfile::tempdir().unwrap();
        let path = dir.path().join("out.png");
        let pixels: Vec<u8> = (0..2 * 3 * 4).map(|i| i as u8 * 10).collect();
        write_png(&path, 2, 3, &pixels).unwrap();
        let names: Vec<_> = std::fs::read_dir(dir.path()).unwrap().collect();
        assert_eq!(names.len(), 1, "temporary file left behind");
        let dec = png::Decoder::new(std::io::BufReader::new(std::fs::File::open(&path).unwrap()));
        let mut reader = dec.read_info().unwrap();
        let mut buf = vec![0; reader.output_buffer_size().unwrap()];
        reader.next_frame(&mut buf).unwrap();
        assert_eq!(&buf[..pixels.len()], &pixels[..]);
    }

    #[test]
    fn exr_keeps_linear_values_and_row_order() {
        let dir = tempfile::tempdir().unwrap();
        let path = dir.path().join("out.exr");
        // 3x2 image; pixel (x, y) = (x, y, 10 + x + 3y, 1), values above 1 kept as they are.
        let rgba: Vec<f32> = (0..2)
            .flat_map(|y| {
                (0..3).flat_map(move |x| [x as f32, y as f32, 10.0 + (x + 3 * y) as f32, 1.0])
            })
            .collect();
        write_exr(&path, 3, 2, &rgba).unwrap();
        let image = exr::prelude::read_first_rgba_layer_from_file(
            &path,
            |size, _| vec![[0f32; 4]; size.width() * size.height()],
            |pixels, pos, (r, g, b, a): (f32, f32, f32, f32)| {
                pixels[pos.y() * 3 + pos.x()] = [r, g, b, a]
            },
        )
        .unwrap();
        let pixels = image.layer_data.channel_data.pixels;
        assert_eq!(pixels.as_flattened(), &rgba[..]);
    }
}
