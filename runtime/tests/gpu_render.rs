//! The headless renderer: colours come through unchanged where a surface covers a pixel, the
//! background elsewhere, and the depth test keeps the nearer surface.
#![cfg(feature = "gpu")]

use hce_runtime::gpu::testing::{context_or_skip, octahedron, random_object, RandomTrees};
use hce_runtime::gpu::{refine_flat, render_mesh, Camera, Framing, RenderParams};

#[test]
fn renders_refined_colours_and_background() {
    let Some(ctx) = context_or_skip("renders_refined_colours_and_background") else {
        return;
    };
    let (p, t) = octahedron();
    let mut object = random_object(
        "octahedron",
        p,
        t,
        RandomTrees {
            max_depth: 0,
            split_probability: 0.0,
            max_extra_normals: 0,
        },
        5,
    );
    let colour = hce_format::rgb9e5::encode([0.5, 0.25, 2.0]);
    object.colours.iter_mut().for_each(|c| *c = colour);
    let mesh = refine_flat(&ctx, &object, 2).unwrap();
    let params = RenderParams {
        width: 64,
        height: 48,
        framing: Framing::Auto,
        background: [0.0, 0.1, 0.0],
    };
    let image = render_mesh(&ctx, &mesh.positions, &mesh.colours, &mesh.indices, &params).unwrap();
    assert_eq!(image.pixels.len(), 64 * 48 * 4);
    let px = |x: usize, y: usize| &image.pixels[4 * (y * 64 + x)..4 * (y * 64 + x) + 3];
    for (k, want) in [0.5f32, 0.25, 2.0].iter().enumerate() {
        assert!(
            (px(32, 24)[k] - want).abs() < 1e-5,
            "centre {:?}",
            px(32, 24)
        );
    }
    assert_eq!(px(0, 0), [0.0, 0.1, 0.0]);
    assert_eq!(px(63, 47), [0.0, 0.1, 0.0]);
    let covered = image.pixels.chunks_exact(4).filter(|p| p[2] > 1.0).count();
    // Auto-framing fits the bounding box's sphere (radius √3) in the 48-pixel height with 10%
    // margin, so the unit octahedron spans about 48 / (1.1 √3) ≈ 25 pixels: a diamond of
    // roughly 25² / 2 ≈ 300 pixels, give or take its 3-D outline.
    assert!(covered > 150 && covered < 600, "{covered} pixels covered");
}

#[test]
fn depth_test_keeps_the_nearer_surface() {
    let Some(ctx) = context_or_skip("depth_test_keeps_the_nearer_surface") else {
        return;
    };
    // Two squares facing +z; the red one (drawn second) lies behind the green one.
    let square = |z: f32| [-1.0, -1.0, z, 1.0, -1.0, z, 1.0, 1.0, z, -1.0, 1.0, z];
    let positions: Vec<f32> = square(0.5).into_iter().chain(square(-0.5)).collect();
    let green = [0.0, 1.0, 0.0, 1.0];
    let red = [1.0, 0.0, 0.0, 1.0];
    let colours: Vec<f32> = [green; 4].into_iter().chain([red; 4]).flatten().collect();
    let indices = [0, 1, 2, 0, 2, 3, 4, 5, 6, 4, 6, 7];
    let params = RenderParams {
        width: 32,
        height: 32,
        framing: Framing::Camera(Camera {
            eye: [0.0, 0.0, 5.0],
            target: [0.0, 0.0, 0.0],
            fov_y_degrees: 30.0,
        }),
        background: [0.0; 3],
    };
    let image = render_mesh(&ctx, &positions, &colours, &indices, &params).unwrap();
    let centre = &image.pixels[4 * (16 * 32 + 16)..4 * (16 * 32 + 16) + 3];
    assert_eq!(centre, [0.0, 1.0, 0.0]);
}
