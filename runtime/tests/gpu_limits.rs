//! Every kernel fits WebGPU's default limits (at most 8 storage buffers per shader stage per
//! entry point, 16 KiB of workgroup memory, ...), so that the same WGSL runs in a browser,
//! whose devices start with those limits (`web/`, issue 17).
//!
//! The test asks the adapter for a second device with `wgpu::Limits::default()` (WebGPU's
//! defaults) and builds and runs every pipeline on it, flat and Loop (both patch kernels, both
//! reconstructions, levels 0 to 3), the decoding kernel and the renderer, inside a validation
//! error scope: a layout or a pipeline over a limit is a validation error, which fails the
//! test with wgpu's message.
//!
//! Runs on any adapter, Mesa lavapipe included. Without one the test skips with a message,
//! unless `HCE_REQUIRE_GPU=1`, which makes it fail.
#![cfg(feature = "gpu")]

use hce_format::ObjectKind;
use hce_geometry::lighting::Reconstruction;
use hce_geometry::refine::FlatRefinement;
use hce_geometry::topology::{build_control_mesh, TopologyConfig};
use hce_runtime::gpu::testing::{
    context_or_skip, decode_colours, random_object, ColourQuery, RandomTrees,
};
use hce_runtime::gpu::{
    render_mesh, FlatKernel, GpuContext, LoopKernel, PatchScheme, RenderParams,
};

/// WebGPU's default per-stage storage-buffer limit.
const WEBGPU_STORAGE_BUFFERS: u32 = 8;

/// A closed bipyramid over a hexagon with random trees, as a multiresolution object.
fn bipyramid() -> hce_format::Object {
    let mut p = vec![[0.0, 0.0, 0.8], [0.0, 0.0, -0.7]];
    for k in 0..6 {
        let a = std::f32::consts::TAU * k as f32 / 6.0;
        p.push([a.cos(), a.sin(), 0.1 * (3.0 * a).sin()]);
    }
    let mut t = Vec::new();
    for k in 0..6u32 {
        let (a, b) = (2 + k, 2 + (k + 1) % 6);
        t.push([0, a, b]);
        t.push([1, b, a]);
    }
    let mesh = build_control_mesh(&p, &t, None, &TopologyConfig::default())
        .unwrap()
        .mesh;
    let mut o = random_object(
        "bipyramid",
        mesh.positions.clone(),
        mesh.triangles.clone(),
        RandomTrees::default(),
        7,
    );
    o.kind = ObjectKind::Multiresolution;
    o.mesh = mesh;
    o
}

#[test]
fn every_kernel_runs_within_webgpu_default_limits() {
    let Some(full) = context_or_skip("every_kernel_runs_within_webgpu_default_limits") else {
        return;
    };
    let limits = wgpu::Limits::default();
    assert_eq!(
        limits.max_storage_buffers_per_shader_stage,
        WEBGPU_STORAGE_BUFFERS
    );
    let (device, queue) =
        pollster::block_on(full.adapter.request_device(&wgpu::DeviceDescriptor {
            label: Some("hce at WebGPU's default limits"),
            required_limits: limits,
            ..Default::default()
        }))
        .expect("every adapter supports the default limits");
    assert_eq!(
        device.limits().max_storage_buffers_per_shader_stage,
        WEBGPU_STORAGE_BUFFERS
    );
    let ctx = GpuContext::from_existing(&full.adapter, &device, &queue);
    let scope = device.push_error_scope(wgpu::ErrorFilter::Validation);

    let object = bipyramid();
    let flat = FlatKernel::new(&ctx);
    let mut triangles = Vec::new();
    for reconstruction in [Reconstruction::default(), Reconstruction::NearestNormal] {
        let uploaded = flat
            .upload(&ctx, &object, reconstruction, FlatRefinement::Uniform)
            .unwrap();
        for level in 0..=3 {
            let mut out = None;
            flat.refine_into(&ctx, &uploaded, level, &mut out, false)
                .unwrap();
            let mesh = out.unwrap().read_back(&ctx).unwrap();
            triangles.push(mesh.indices.len() / 3);
        }
        for scheme in [PatchScheme::Scratch, PatchScheme::Workgroup] {
            let kernel = LoopKernel::with_scheme(&ctx, scheme);
            let uploaded = kernel.upload(&ctx, &object, reconstruction).unwrap();
            for level in 0..=3 {
                let mut out = None;
                kernel
                    .refine_into(&ctx, &uploaded, level, &mut out, false)
                    .unwrap();
                let mesh = out.unwrap().read_back(&ctx).unwrap();
                triangles.push(mesh.indices.len() / 3);
            }
        }
    }
    // Each refinement ran and gave 12 · 4^level triangles (flat, scratch, workgroup; twice).
    let expected: Vec<usize> = (0..6)
        .flat_map(|_| (0..4).map(|l| 12usize << (2 * l)))
        .collect();
    assert_eq!(triangles, expected);

    let decoded = decode_colours(
        &ctx,
        &object,
        &[ColourQuery {
            triangle: 0,
            level: 0,
            path: 0,
            _pad: 0,
            normal: [0.0, 0.0, 1.0, 0.0],
        }],
    )
    .unwrap();
    assert_eq!(decoded.len(), 1);

    let image = render_mesh(
        &ctx,
        &object.mesh.positions,
        &vec![1.0; 4 * object.mesh.positions.len() / 3],
        &object.mesh.triangles,
        &RenderParams {
            width: 16,
            height: 16,
            ..Default::default()
        },
    )
    .unwrap();
    assert_eq!(image.pixels.len(), 16 * 16 * 4);

    if let Some(error) = pollster::block_on(scope.pop()) {
        panic!("a kernel exceeds WebGPU's default limits: {error}");
    }
}
