//! `hce view`: open a baked asset (or preview a plain mesh) in a window and move around it, with
//! the levels chosen live from the view. The window itself is in [`window`].

mod window;

use std::path::PathBuf;

use anyhow::Result;
use clap::Args;

#[derive(Args, Debug)]
pub struct ViewArgs {
    /// Baked asset (.glb/.gltf with EXT_hce_baked_lighting, or .hce), or a plain mesh (.obj,
    /// .gltf, .glb) previewed flat as `hce render` previews it. Without one, the window waits
    /// for a file dropped on it.
    pub file: Option<PathBuf>,
    /// Window size, WIDTHxHEIGHT (physical pixels).
    #[arg(long, default_value = "1280x800")]
    pub size: String,
    /// Start camera: `scene`, `auto` or EYE:TARGET[:FOV], as for `hce render`. Default: the
    /// file's camera when it has one, else `auto`.
    #[arg(long)]
    pub camera: Option<String>,
    /// Force this level on every multiresolution object (0-6 on the keyboard); default: chosen
    /// from the view.
    #[arg(long)]
    pub level: Option<u32>,
    /// Screen length in pixels that a refined edge should not exceed, for levels chosen from
    /// the view.
    #[arg(long, default_value_t = 8.0)]
    pub pixels_per_edge: f32,
    /// Highest level chosen from the view.
    #[arg(long, default_value_t = 5)]
    pub max_level: u32,
    /// Lower levels chosen from the view (highest first) to draw at most this many triangles.
    #[arg(long, default_value_t = 16_000_000)]
    pub max_triangles: u64,
    /// Milliseconds of refinement per frame (wall time, GPU work waited for, at the cost
    /// measured in the frames before): a level change is refined in pieces (ranges of
    /// coarse triangles, fine triangles and vertices) over as many frames as it needs, at
    /// least 1/32 of it per frame, the object drawn at its old level until the new one is
    /// complete; 0 refines every change whole in the frame it happens.
    #[arg(long, default_value_t = 4.0)]
    pub refine_budget: f64,
    /// `smooth`, `nearest` or `gouraud`, as for `hce render` (N cycles them in the window).
    #[arg(long, default_value = "smooth", value_parser = super::render::parse_reconstruction)]
    pub reconstruction: hce_geometry::lighting::Reconstruction,
    /// How flat objects are refined: `adaptive` (the default: from their trees, one triangle per
    /// leaf plus those finer neighbours need, SPEC.md F.7.1) or `uniform` (every coarse triangle
    /// split 1-to-4 to the depth of its deepest leaf, bounded by its size, F.7.2).
    #[arg(long, default_value = "adaptive", value_parser = super::subdivide::parse_flat)]
    pub flat: hce_geometry::refine::FlatRefinement,
    /// Exposure in stops before tone mapping (the tone curve of `hce render`'s PNGs).
    #[arg(long, default_value_t = 0.0, allow_hyphen_values = true)]
    pub exposure: f32,
    /// Use a software adapter even if a GPU is present.
    #[arg(long)]
    pub software: bool,
    /// Start with the side panel hidden (Tab shows it).
    #[arg(long)]
    pub no_panel: bool,
    /// Scripted run: draw this many frames, then exit (with --screenshot, --stats,
    /// --camera-path).
    #[arg(long)]
    pub frames: Option<u32>,
    /// Scripted run: write the last frame here (PNG, exactly what the window shows). In the
    /// window: where the screenshot key (F12 or P) writes, a .png file or a directory
    /// (default: hce-view-N.png in the current directory).
    #[arg(long)]
    pub screenshot: Option<PathBuf>,
    /// Scripted run: the camera of each frame, `approach[:FRACTION]` (from the start camera
    /// towards its target, 0.9 of the way by default) or cameras EYE:TARGET[:FOV] separated
    /// by `;`, passed through at equal steps from the first frame to the last.
    #[arg(long, requires = "frames")]
    pub camera_path: Option<String>,
    /// Scripted run: write per-frame statistics (camera, levels, objects refined, refine and
    /// draw times) as JSON.
    #[arg(long, requires = "frames")]
    pub stats: Option<PathBuf>,
    /// Scripted run without a window: draw the frames into an image of --size on the adapter
    /// (no display, no panel, nothing presented), for benchmarks and machines without X. The
    /// screenshot is the one a window of that size without its panel writes.
    #[arg(long, requires = "frames")]
    pub offscreen: bool,
}

#[cfg(feature = "gpu")]
pub fn run(args: ViewArgs) -> Result<()> {
    use anyhow::bail;
    use hce_runtime::gpu::LodParams;
    use window::{camera::CameraPath, content::Levels, Options, Settings};

    let size = super::render::parse_size(&args.size)?;
    let camera = super::render::camera_choice(args.camera.as_deref())?;
    let max = hce_geometry::decode::MAX_PATH_LEVEL;
    if args.level.is_some_and(|l| l > max) || args.max_level > max {
        bail!("--level and --max-level must be 0 to {max}");
    }
    if !(args.pixels_per_edge.is_finite() && args.pixels_per_edge > 0.0) {
        bail!("--pixels-per-edge must be a positive number");
    }
    if !(args.refine_budget.is_finite() && args.refine_budget >= 0.0) {
        bail!("--refine-budget must be 0 or more milliseconds");
    }
    if args.frames == Some(0) {
        bail!("--frames must be at least 1");
    }
    if args.frames.is_some() {
        if args.file.is_none() {
            bail!("--frames needs a FILE to draw");
        }
        if let Some(s) = &args.screenshot {
            super::render::output_format(s)?;
            if !s.extension().is_some_and(|e| e.eq_ignore_ascii_case("png")) {
                bail!("{}: screenshots are PNG", s.display());
            }
        }
    }
    let camera_path = args
        .camera_path
        .as_deref()
        .map(CameraPath::parse)
        .transpose()?;
    window::run(Options {
        file: args.file,
        size,
        camera,
        software: args.software,
        panel: !args.no_panel,
        frames: args.frames,
        camera_path,
        screenshot: args.screenshot,
        stats: args.stats,
        offscreen: args.offscreen,
        settings: Settings {
            levels: Levels {
                forced: args.level,
                lod: LodParams {
                    target_pixels_per_edge: args.pixels_per_edge,
                    max_level: args.max_level,
                    ..Default::default()
                },
                max_triangles: args.max_triangles,
                refine_budget_ms: args.refine_budget,
            },
            reconstruction: args.reconstruction,
            flat: args.flat,
            exposure: args.exposure,
        },
    })
}
