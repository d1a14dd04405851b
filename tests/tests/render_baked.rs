//! Baked assets through the runtime: `hce_runtime::asset::Asset` on real bakes of the bundled
//! samples (damaged copies must be errors, never panics), and the golden image of the Cornell box
//! rendered with its baked colours.
//!
//! # The golden image
//!
//! `samples/cornell-box.glb` is baked here at the low settings below (the bake is deterministic
//! whatever the thread count), opened with `Asset::open`, refined and drawn by
//! `hce_runtime::gpu::render_asset` at 160 × 120 from a fixed camera (the sample's own view) and
//! tone-mapped as `hce render` does for PNG. The result is compared with
//! `tests/data/golden/cornell-box-160x120.png` by the mean absolute difference over all RGB
//! channels, in 8-bit steps, which must stay under [`GOLDEN_MAD_LIMIT`]: rasterisers may differ
//! on which pixels an edge covers, which moves the mean by a small fraction of a step, while a
//! wrong colour on a wall moves it by several steps. Run with `HCE_UPDATE_GOLDEN=1` to rewrite
//! the stored image after a deliberate change (and look at it before committing it).

use std::path::{Path, PathBuf};
use std::sync::OnceLock;

use hce_bake::BakeParams;
use hce_bake::{bake_file, PipelineOptions};
use hce_format::ObjectKind;
use hce_geometry::Creases;
use hce_meshio::scene::ImportOptions;
use hce_runtime::asset::{Asset, AssetFormat, OpenOptions};

/// Largest accepted mean absolute difference from the golden image, in 8-bit steps.
const GOLDEN_MAD_LIMIT: f64 = 1.5;
const UPDATE_ENV: &str = "HCE_UPDATE_GOLDEN";

fn sample(name: &str) -> PathBuf {
    Path::new(env!("CARGO_MANIFEST_DIR"))
        .join("../samples")
        .join(name)
}

fn golden_path() -> PathBuf {
    Path::new(env!("CARGO_MANIFEST_DIR")).join("data/golden/cornell-box-160x120.png")
}

/// Bakes a sample once per test binary (into a directory kept for the run).
fn baked(name: &str) -> PathBuf {
    static DIR: OnceLock<tempfile::TempDir> = OnceLock::new();
    static LOCK: std::sync::Mutex<()> = std::sync::Mutex::new(());
    let dir = DIR.get_or_init(|| tempfile::tempdir().unwrap());
    let out = dir.path().join(name);
    let _guard = LOCK.lock().unwrap_or_else(|e| e.into_inner());
    if !out.exists() {
        let options = PipelineOptions {
            import: ImportOptions::default(),
            levels: 2,
            creases: Creases::Auto,
            bake: BakeParams {
                bf_epsilon: 1e-2,
                visibility_rays: 4,
                ..BakeParams::default()
            },
            output: out.clone(),
            ..PipelineOptions::default()
        };
        bake_file(&sample(name), &options, &|_: &str, _: usize, _: usize| {}).unwrap();
    }
    out
}

#[test]
fn baked_samples_open_with_instances_camera_and_bounds() {
    let asset = Asset::open(baked("cornell-box.glb")).unwrap();
    assert_eq!(asset.format, AssetFormat::Glb);
    let names: Vec<&str> = asset.objects.iter().map(|o| o.name()).collect();
    assert!(names.iter().any(|n| n.contains("red")), "{names:?}");
    for o in &asset.objects {
        assert_eq!(o.instances.len(), 1, "{}", o.name());
    }
    let cam = asset.camera.as_ref().expect("the sample has a camera");
    // The sample's view stands at z = -0.8 and looks along +z into the box.
    assert!((cam.eye[2] + 0.8).abs() < 1e-5, "{cam:?}");
    assert!(cam.forward[2] > 0.99, "{cam:?}");
    let b = asset.bounds().unwrap();
    assert!(b.min[2] > cam.eye[2] && b.max[1] > b.min[1]);

    // Teatime: multiresolution objects placed by node translations.
    let tea = Asset::open(baked("teatime.glb")).unwrap();
    let teapot = tea
        .objects
        .iter()
        .find(|o| o.name().contains("teapot"))
        .expect("teapot object");
    assert_eq!(teapot.kind(), ObjectKind::Multiresolution);
    let t = teapot.instances[0].transform.w_axis;
    assert_eq!([t.x, t.y, t.z], [-0.15, 0.7505, -0.05]);
}

#[test]
fn damaged_baked_files_are_errors_not_panics() {
    let bytes = std::fs::read(baked("cornell-box.glb")).unwrap();
    let open = |b: &[u8]| {
        Asset::from_bytes(
            Path::new("damaged.glb"),
            AssetFormat::Glb,
            b,
            |_| Err("no external buffers".into()),
            &OpenOptions::default(),
        )
    };
    assert!(open(&bytes).is_ok());
    let step = (bytes.len() / 150).max(1);
    for len in (0..bytes.len()).step_by(step) {
        let e = open(&bytes[..len]).unwrap_err();
        assert!(e.to_string().starts_with("damaged.glb"), "{e}");
    }
    // Flips in the BIN chunk (geometry and container) must all be caught: by the container's
    // checksums and padding rule, or by the primitives' geometry hashes. Vertex colours
    // (COLOR_0, the fallback for other viewers) are not checked by anything, so flips there
    // are allowed through.
    let json_len = u32::from_le_bytes(bytes[12..16].try_into().unwrap()) as usize;
    let bin_start = 20 + json_len + 8;
    let mut accepted = 0;
    for i in (bin_start..bytes.len()).step_by(step) {
        let mut b = bytes.clone();
        b[i] ^= 0x10;
        if open(&b).is_ok() {
            accepted += 1;
        }
    }
    let tried = (bin_start..bytes.len()).step_by(step).count();
    assert!(accepted * 2 < tried, "{accepted} of {tried} flips accepted");
}

mod gpu {
    use super::*;
    use hce_runtime::gpu::testing::context_or_skip;
    use hce_runtime::gpu::{render_asset, AssetRenderOptions, Camera, CameraChoice};
    use hce_runtime::gpu::{GpuScene, MultiresPath, SceneOptions};

    /// Both paths of multiresolution objects: the GPU Loop kernel (the default) must give the
    /// CPU reference's positions, indices and normals to the bit on this scene and its colours
    /// within 1e-3 relative (the kernel sums vertex colours in another order); the CPU path
    /// must give them exactly.
    #[test]
    fn gpu_scene_matches_the_cpu_reference_and_reuses_buffers() {
        let Some(ctx) = context_or_skip("gpu_scene_matches_the_cpu_reference_and_reuses_buffers")
        else {
            return;
        };
        let asset = Asset::open(baked("teatime.glb")).unwrap();
        for path in [MultiresPath::Gpu, MultiresPath::CpuReference] {
            let options = SceneOptions {
                multires: path,
                ..SceneOptions::default()
            };
            scene_matches(&ctx, &asset, &options);
        }
    }

    /// A refinement recorded in pieces over several submissions (as `hce view` spreads a level
    /// change over frames) leaves the object drawing its old buffers, to the bit, until the
    /// last piece, and then draws exactly what a refinement in one submission gives; several
    /// objects' refinements share one submission, each timed where the adapter has timestamps.
    #[test]
    fn a_refinement_in_pieces_is_drawn_only_when_complete() {
        let Some(ctx) = context_or_skip("a_refinement_in_pieces_is_drawn_only_when_complete")
        else {
            return;
        };
        let asset = Asset::open(baked("teatime.glb")).unwrap();
        let options = SceneOptions::default();
        let multires: Vec<usize> = (0..asset.objects.len())
            .filter(|&k| asset.objects[k].kind() == ObjectKind::Multiresolution)
            .collect();
        let i = multires[0];
        let mut whole = GpuScene::new(&ctx, &asset, &options).unwrap();
        whole.refine(&ctx, i, 3).unwrap();
        let want = whole.read_back(&ctx, i).unwrap();

        let mut scene = GpuScene::new(&ctx, &asset, &options).unwrap();
        scene.refine(&ctx, i, 1).unwrap();
        let old = scene.read_back(&ctx, i).unwrap();
        assert!(scene.begin_refine(&ctx, i, 3).unwrap());
        let (level, left, total) = scene.refine_progress(i).unwrap();
        assert_eq!((level, left), (3, total));
        let mut batches = 0;
        loop {
            let report = scene.refine_batch(&ctx, &[(i, total / 7)], false).unwrap();
            batches += 1;
            assert_eq!(report.len(), 1);
            if report[0].finished {
                break;
            }
            assert!(report[0].work > 0 && report[0].work <= total / 7 + total / 3);
            assert_eq!(scene.level(i), Some(1), "drawn before the last piece");
            assert_eq!(scene.read_back(&ctx, i).unwrap(), old, "batch {batches}");
            assert!(batches < 100, "the refinement does not end");
        }
        assert!(batches >= 7, "{batches} batches for pieces of a seventh");
        assert_eq!(scene.refine_progress(i), None);
        assert_eq!(scene.read_back(&ctx, i).unwrap(), want);
        // Already there: nothing starts. A refinement under way is dropped when the drawn
        // level is asked for again.
        assert!(!scene.begin_refine(&ctx, i, 3).unwrap());
        assert!(scene.begin_refine(&ctx, i, 2).unwrap());
        assert!(!scene.begin_refine(&ctx, i, 3).unwrap());
        assert_eq!(scene.refine_progress(i), None);
        assert_eq!(scene.read_back(&ctx, i).unwrap(), want);

        // Two objects in one submission, each timed.
        let j = multires[1];
        assert!(scene.begin_refine(&ctx, i, 2).unwrap());
        assert!(scene.begin_refine(&ctx, j, 2).unwrap());
        let report = scene
            .refine_batch(&ctx, &[(i, u64::MAX), (j, u64::MAX)], true)
            .unwrap();
        assert_eq!(report.len(), 2);
        for r in &report {
            assert!(r.finished);
            assert_eq!(r.gpu_seconds.is_some(), ctx.description.timestamps);
            assert_eq!(scene.level(r.object), Some(2));
        }
        whole.refine(&ctx, j, 2).unwrap();
        assert_eq!(
            scene.read_back(&ctx, j).unwrap(),
            whole.read_back(&ctx, j).unwrap()
        );
    }

    fn scene_matches(ctx: &hce_runtime::gpu::GpuContext, asset: &Asset, options: &SceneOptions) {
        let mut scene = GpuScene::new(ctx, asset, options).unwrap();
        let i = asset
            .objects
            .iter()
            .position(|o| o.name().contains("teapot"))
            .unwrap();
        let object = &asset.objects[i].object;
        let check = |scene: &GpuScene, level: u32| {
            let got = scene.read_back(ctx, i).unwrap();
            let refined =
                hce_geometry::refine::subdivide_split(&object.name, &object.mesh, level).unwrap();
            let colours =
                hce_geometry::colour::apply_baked_colours(object, &refined, level).unwrap();
            assert_eq!(got.level, level);
            assert_eq!(got.positions, refined.positions.as_flattened());
            assert_eq!(got.indices, refined.indices.as_flattened());
            let want: Vec<f32> = colours
                .iter()
                .flat_map(|c| [c[0], c[1], c[2], 1.0])
                .collect();
            assert_eq!(got.colours.len(), want.len());
            for (v, (g, w)) in got.colours.chunks(4).zip(want.chunks(4)).enumerate() {
                let scale = w[..3].iter().fold(1e-6f32, |a, &b| a.max(b.abs()));
                for k in 0..4 {
                    let d = (g[k] - w[k]).abs() / w[k].abs().max(1e-3 * scale);
                    assert!(
                        d <= 1e-3 || (options.multires == MultiresPath::CpuReference && d == 0.0),
                        "{:?}, level {level}, vertex {v}: colour {g:?}, CPU {w:?}",
                        options.multires
                    );
                }
            }
            if options.multires == MultiresPath::CpuReference {
                assert_eq!(got.colours, want);
            }
            let normals = got.normals.unwrap();
            let want_n = refined.normals.as_flattened();
            assert_eq!(normals.len(), want_n.len());
            let worst = normals
                .iter()
                .zip(want_n)
                .fold(0f32, |a, (g, w)| a.max((g - w).abs()));
            assert!(
                worst <= 1e-5,
                "{:?}, level {level}: normals differ by {worst}",
                options.multires
            );
        };
        let positions = |scene: &GpuScene| scene.buffers(i).unwrap().positions.clone();
        scene.refine(ctx, i, 2).unwrap();
        check(&scene, 2);
        let a = positions(&scene);
        // On the GPU a refinement writes beside the buffers being drawn, never into them (it
        // may be recorded over several frames); the CPU path uploads into them ...
        scene.refine(ctx, i, 1).unwrap();
        check(&scene, 1);
        let b = positions(&scene);
        let gpu = options.multires == MultiresPath::Gpu;
        assert_eq!(b != a, gpu);
        // ... and the set it replaced is kept for the next one: no reallocation while the
        // level fits.
        scene.refine(ctx, i, 2).unwrap();
        check(&scene, 2);
        assert!(positions(&scene) == a);
        scene.refine(ctx, i, 1).unwrap();
        check(&scene, 1);
        assert!(positions(&scene) == b);
        // Level 3 fits neither set.
        scene.refine(ctx, i, 3).unwrap();
        check(&scene, 3);
        assert!(positions(&scene) != a && positions(&scene) != b);
        // Flat objects go to their tree depth whatever level is asked for.
        let flat = asset
            .objects
            .iter()
            .position(|o| o.kind() == ObjectKind::Flat)
            .unwrap();
        let depth = hce_runtime::gpu::flat_level(
            asset.objects[flat].tree_depth,
            asset.objects[flat].object.triangles.len() as u64,
            options.flat_max_level,
            options.flat_max_triangles,
        );
        let levels = scene
            .refine_all(ctx, &hce_runtime::gpu::LevelChoice::Fixed(1))
            .unwrap();
        assert_eq!(levels[flat], Some(depth));
        assert_eq!(levels[i], Some(1));
        assert_eq!(scene.draws().len(), asset.instance_count());
    }

    fn read_png(path: &Path) -> (u32, u32, Vec<u8>) {
        let file = std::fs::File::open(path).unwrap_or_else(|e| {
            panic!(
                "{}: {e}; run with {UPDATE_ENV}=1 to create it",
                path.display()
            )
        });
        let mut reader = png::Decoder::new(std::io::BufReader::new(file))
            .read_info()
            .unwrap();
        let mut buf = vec![0; reader.output_buffer_size().unwrap()];
        let info = reader.next_frame(&mut buf).unwrap();
        assert_eq!(info.color_type, png::ColorType::Rgba);
        buf.truncate(info.buffer_size());
        (info.width, info.height, buf)
    }

    fn write_png(path: &Path, w: u32, h: u32, rgba: &[u8]) {
        std::fs::create_dir_all(path.parent().unwrap()).unwrap();
        let file = std::fs::File::create(path).unwrap();
        let mut enc = png::Encoder::new(std::io::BufWriter::new(file), w, h);
        enc.set_color(png::ColorType::Rgba);
        enc.set_depth(png::BitDepth::Eight);
        let mut writer = enc.write_header().unwrap();
        writer.write_image_data(rgba).unwrap();
    }

    /// Mean of the pixels of a rectangle, as linear RGB.
    fn mean(
        pixels: &[f32],
        width: u32,
        x: std::ops::Range<u32>,
        y: std::ops::Range<u32>,
    ) -> [f32; 3] {
        let mut s = [0f32; 3];
        let n = (x.len() * y.len()) as f32;
        for yy in y {
            for xx in x.clone() {
                let i = 4 * (yy * width + xx) as usize;
                for k in 0..3 {
                    s[k] += pixels[i + k] / n;
                }
            }
        }
        s
    }

    #[test]
    fn cornell_box_matches_the_golden_image() {
        let Some(ctx) = context_or_skip("cornell_box_matches_the_golden_image") else {
            return;
        };
        let asset = Asset::open(baked("cornell-box.glb")).unwrap();
        let (w, h) = (160, 120);
        let r = render_asset(
            &ctx,
            &asset,
            &AssetRenderOptions {
                width: w,
                height: h,
                camera: CameraChoice::Explicit(Camera {
                    eye: [0.278, 0.273, -0.8],
                    target: [0.278, 0.273, 0.0],
                    fov_y_degrees: 39.3,
                }),
                level: Some(2),
                ..Default::default()
            },
        )
        .unwrap();
        let px = &r.image.pixels;
        // What the image must show whatever the golden says: a red wall on the left, a green
        // one on the right (the camera looks along +z, so +x is on the left), and a lit
        // ceiling above a darker floor corner.
        let left = mean(px, w, 20..30, 50..70);
        let right = mean(px, w, 130..140, 50..70);
        assert!(left[0] > 2.0 * left[1], "left wall {left:?}");
        assert!(right[1] > 2.0 * right[0], "right wall {right:?}");
        let ceiling = mean(px, w, 60..100, 12..18);
        assert!(ceiling.iter().sum::<f32>() > 0.05, "ceiling {ceiling:?}");

        let rgba = r.image.to_srgb8(0.0);
        let path = golden_path();
        if std::env::var(UPDATE_ENV).is_ok_and(|v| v == "1") {
            write_png(&path, w, h, &rgba);
            eprintln!("wrote {}", path.display());
        }
        let (gw, gh, golden) = read_png(&path);
        assert_eq!((gw, gh), (w, h));
        let mut sum = 0u64;
        for (a, b) in rgba.chunks_exact(4).zip(golden.chunks_exact(4)) {
            for k in 0..3 {
                sum += u64::from(a[k].abs_diff(b[k]));
            }
        }
        let mad = sum as f64 / f64::from(w * h * 3);
        assert!(
            mad < GOLDEN_MAD_LIMIT,
            "mean absolute difference {mad:.3} from {} (limit {GOLDEN_MAD_LIMIT})",
            path.display()
        );
    }
}
