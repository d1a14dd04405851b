//! The headless renderer: colours come through unchanged where a surface covers a pixel, the
//! background elsewhere, and the depth test keeps the nearer surface.
#![cfg(feature = "gpu")]

use hce_runtime::gpu::testing::{context_or_skip, octahedron, random_object, RandomTrees};
use hce_runtime::gpu::{
    refine_flat, render_mesh, sample_positions, supported_samples, Camera, Framing, RenderParams,
};

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
        samples: 1,
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
        samples: 1,
    };
    let image = render_mesh(&ctx, &positions, &colours, &indices, &params).unwrap();
    let centre = &image.pixels[4 * (16 * 32 + 16)..4 * (16 * 32 + 16) + 3];
    assert_eq!(centre, [0.0, 1.0, 0.0]);
}

#[test]
fn multisampling_averages_coverage_at_the_standard_positions() {
    let Some(ctx) = context_or_skip("multisampling_averages_coverage_at_the_standard_positions")
    else {
        return;
    };
    // A white rectangle facing the camera whose right edge crosses pixel column 16 at 0.4 of its
    // width (normalised x = 0.8/32), left of its centre: of the standard 4-sample positions
    // (x = 0.375, 0.875, 0.125, 0.625 of the pixel), two lie left of it.
    let fov = 30.0f32;
    let f = 1.0 / (fov.to_radians() * 0.5).tan();
    let edge = 0.8 * 5.0 / (32.0 * f);
    let positions = [
        -3.0, -3.0, 0.0, edge, -3.0, 0.0, edge, 3.0, 0.0, -3.0, 3.0, 0.0,
    ];
    let colours = [[1.0f32; 4]; 4].concat();
    let indices = [0, 1, 2, 0, 2, 3];
    let mut params = RenderParams {
        width: 32,
        height: 32,
        framing: Framing::Camera(Camera {
            eye: [0.0, 0.0, 5.0],
            target: [0.0, 0.0, 0.0],
            fov_y_degrees: fov,
        }),
        background: [0.0; 3],
        samples: 4,
    };
    let image = render_mesh(&ctx, &positions, &colours, &indices, &params).unwrap();
    assert_eq!(image.samples, supported_samples(&ctx, 4));
    let px = |image: &hce_runtime::gpu::RenderedImage, x: usize| image.pixels[4 * (16 * 32 + x)];
    assert_eq!((px(&image, 15), px(&image, 17)), (1.0, 0.0));
    if image.samples == 4 {
        assert_eq!(px(&image, 16), 0.5);
        let xs: Vec<f32> = sample_positions(4).unwrap().iter().map(|p| p[0]).collect();
        assert_eq!(xs.iter().filter(|&&x| x < 0.4).count(), 2);
    }
    // Colours falling to zero at the edge: pixel 16, covered in part, is shaded inside the
    // covered part, not at its centre beyond the edge, so nothing is extrapolated below zero.
    let gradient = [
        [1.0f32; 4],
        [0.0, 0.0, 0.0, 1.0],
        [0.0, 0.0, 0.0, 1.0],
        [1.0; 4],
    ]
    .concat();
    let shaded = render_mesh(&ctx, &positions, &gradient, &indices, &params).unwrap();
    assert!(
        shaded.pixels.iter().all(|&v| (0.0..=1.0).contains(&v)),
        "{:?}",
        shaded.pixels.iter().find(|&&v| !(0.0..=1.0).contains(&v))
    );
    // One sample is the pixel centre, right of the edge: uncovered.
    params.samples = 1;
    let single = render_mesh(&ctx, &positions, &colours, &indices, &params).unwrap();
    assert_eq!(single.samples, 1);
    assert_eq!(px(&single, 16), 0.0);
    assert_eq!((px(&single, 15), px(&single, 17)), (1.0, 0.0));
}
