// The window's tone mapping: the linear image the scene pass drew (Rgba32Float, the target
// `hce render` reads back) to the window's 8-bit format.
//
// The same curve as `hce_runtime::gpu::tone_map_aces`, the CPU function that writes
// `hce render`'s PNGs: exposure 2^ev, Narkowicz's fit of the ACES filmic curve (2016), then the
// sRGB transfer function (IEC 61966-2-1). A window whose format is already sRGB gets the linear
// curve output and the hardware encodes it; a UNORM window gets the encoded value, which the
// hardware rounds to 8 bits as the CPU does (round to nearest).

struct Params {
    // 2^ev.
    exposure: f32,
    // 1: write sRGB-encoded values (UNORM target); 0: linear (sRGB target).
    encode_srgb: u32,
}

@group(0) @binding(0) var hdr: texture_2d<f32>;
@group(0) @binding(1) var<uniform> params: Params;

// Step 1: one triangle that covers the viewport.
@vertex
fn vs_main(@builtin(vertex_index) i: u32) -> @builtin(position) vec4<f32> {
    let uv = vec2<f32>(f32((i << 1u) & 2u), f32(i & 2u));
    return vec4<f32>(uv * 2.0 - 1.0, 0.0, 1.0);
}

fn aces(x: f32) -> f32 {
    return clamp((x * (2.51 * x + 0.03)) / (x * (2.43 * x + 0.59) + 0.14), 0.0, 1.0);
}

fn srgb(y: f32) -> f32 {
    if y <= 0.0031308 {
        return 12.92 * y;
    }
    return 1.055 * pow(y, 1.0 / 2.4) - 0.055;
}

// Step 2: each pixel reads its own texel (no filtering), exposes, tone-maps and encodes it.
@fragment
fn fs_main(@builtin(position) pos: vec4<f32>) -> @location(0) vec4<f32> {
    let c = textureLoad(hdr, vec2<i32>(pos.xy), 0).rgb;
    var out = vec3<f32>(0.0);
    for (var k = 0; k < 3; k++) {
        var x = c[k];
        // Not finite (NaN or infinite) reads as black, as on the CPU.
        if !(abs(x) <= 3.4e38) {
            x = 0.0;
        }
        let y = aces(max(x, 0.0) * params.exposure);
        out[k] = select(y, srgb(y), params.encode_srgb == 1u);
    }
    return vec4<f32>(out, 1.0);
}
