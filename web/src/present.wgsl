// The viewer's last pass (browser only; `hce render` does this on the CPU after read-back,
// runtime/src/gpu/render.rs `tone_map_aces`): exposure, the ACES filmic fit of Narkowicz
// (2016) and sRGB encoding of the linear image the refinement colours were drawn into.

@group(0) @binding(0) var hdr: texture_2d<f32>;
// x: the exposure factor 2^ev.
@group(0) @binding(1) var<uniform> present: vec4<f32>;

// Step 1: one triangle that covers the viewport.
@vertex
fn vs_present(@builtin(vertex_index) i: u32) -> @builtin(position) vec4<f32> {
    let x = f32(i32(i & 1u) * 4 - 1);
    let y = f32(i32(i >> 1u) * 4 - 1);
    return vec4<f32>(x, y, 0.0, 1.0);
}

// Step 2: the same curve as tone_map_aces, per channel.
@fragment
fn fs_present(@builtin(position) p: vec4<f32>) -> @location(0) vec4<f32> {
    let c = textureLoad(hdr, vec2<i32>(p.xy), 0).rgb;
    let x = max(c, vec3<f32>(0.0)) * present.x;
    let y = clamp((x * (2.51 * x + 0.03)) / (x * (2.43 * x + 0.59) + 0.14), vec3<f32>(0.0), vec3<f32>(1.0));
    let s = select(1.055 * pow(y, vec3<f32>(1.0 / 2.4)) - 0.055, 12.92 * y, y <= vec3<f32>(0.0031308));
    return vec4<f32>(s, 1.0);
}
