// Resolve of a multisampled 32-bit float colour target (render.rs): the mean of each pixel's
// samples, in sample order, into a buffer of linear RGBA rows, top to bottom. WebGPU resolves
// only formats it may filter, which 32-bit float is not, so the average is written here.

struct Params {
    width: u32,
    height: u32,
    samples: u32,
    pad: u32,
}

@group(0) @binding(0) var<uniform> params: Params;
@group(0) @binding(1) var image: texture_multisampled_2d<f32>;
@group(0) @binding(2) var<storage, read_write> resolved: array<vec4<f32>>;

// One invocation per pixel: sum the samples in order (a fixed order, so the image does not
// depend on scheduling), divide by their count.
@compute @workgroup_size(8, 8)
fn resolve_main(@builtin(global_invocation_id) gid: vec3<u32>) {
    if (gid.x >= params.width || gid.y >= params.height) {
        return;
    }
    var sum = vec4<f32>(0.0);
    for (var s = 0u; s < params.samples; s++) {
        sum += textureLoad(image, vec2<i32>(gid.xy), i32(s));
    }
    resolved[gid.y * params.width + gid.x] = sum / f32(params.samples);
}
