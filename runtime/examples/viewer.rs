//! The frame loop of a viewer that draws a baked asset with hce-runtime.
//!
//!     cargo run -p hce-tools -- demo                     # writes hce-demo/teatime-baked.glb
//!     cargo run -p hce-runtime --example viewer -- hce-demo/teatime-baked.glb
//!
//! A real viewer owns its wgpu device and window; this one is headless so that it runs anywhere
//! (and in CI), but the calls are the same: load once, upload once, then per frame choose the
//! levels from the camera, refine what changed and bind the buffers.
//!
//! The windowed loop is `hce view` (tools/src/cmd/view/window/): a winit window whose surface
//! comes from `GpuContext::instance()` and whose device from `GpuContext::on_instance(..,
//! Some(&surface))`, the same `GpuScene` calls as below each frame, and the scene drawn into the
//! window's own render pass with `MeshPipeline` (tools/src/cmd/view/window/frame.rs).

#[cfg(feature = "gpu")]
fn main() -> Result<(), Box<dyn std::error::Error>> {
    use hce_runtime::asset::Asset;
    use hce_runtime::gpu::{
        Camera, ContextOptions, GpuContext, GpuScene, LevelChoice, LodParams, RenderParams,
        SceneOptions,
    };

    let path = std::env::args()
        .nth(1)
        .unwrap_or_else(|| "hce-demo/teatime-baked.glb".into());
    // Opening validates the container and the links between it and the glTF meshes.
    let asset = Asset::open(&path)?;
    // A viewer that already has a device wraps it with `GpuContext::from_existing`.
    let ctx = GpuContext::new(&ContextOptions::default())?;
    let mut scene = GpuScene::new(&ctx, &asset, &SceneOptions::default())?;

    // Walk towards the middle of the scene from outside it: levels rise as objects get closer.
    let bounds = asset.bounds().ok_or("the asset has nothing to draw")?;
    let (centre, radius) = (bounds.centre(), bounds.radius());
    let mut camera = Camera {
        eye: [centre[0], centre[1], centre[2] + 2.0 * radius],
        target: centre,
        fov_y_degrees: 45.0,
    };
    for frame in 0..4 {
        // Only objects whose level changed are refined again, all in one submission; buffers
        // are reused unless they grow. To spread a large level change over frames instead,
        // `begin_refine` it and record a frame's worth per frame with `refine_batch`.
        scene.refine_all(
            &ctx,
            &LevelChoice::Auto {
                camera,
                viewport_height: 720,
                lod: LodParams::default(),
            },
        )?;
        let draws = scene.draws();
        // Bind draw.positions (3 x f32), draw.colours (4 x f32, linear: the baked lighting, so
        // no shading is applied) and draw.indices (u32), with draw.transform as the model
        // matrix.
        let levels: Vec<String> = draws
            .iter()
            .map(|d| {
                let name = scene.object_name(d.object).unwrap_or("?");
                format!("{name}@{}", scene.level(d.object).unwrap_or(0))
            })
            .collect();
        println!(
            "frame {frame}: {} draws, {} triangles: {}",
            draws.len(),
            scene.drawn_triangles(),
            levels.join(" ")
        );
        camera.eye[2] -= 0.5 * radius;
    }

    // The same buffers drawn headless, e.g. for a thumbnail.
    let image = scene.render(&ctx, camera, &RenderParams::default())?;
    println!(
        "rendered {}x{} from the last frame's camera",
        image.width, image.height
    );
    Ok(())
}

#[cfg(not(feature = "gpu"))]
fn main() {
    eprintln!("this example needs hce-runtime's `gpu` feature (on by default)");
}
