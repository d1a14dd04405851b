// Headless drawing of a refined, coloured mesh.
//
// The colours are baked radiance (global illumination already in them), so the fragment stage
// applies no lighting: it writes the interpolated linear colour into a floating-point target,
// and tone mapping happens on the CPU after read-back.

// One per draw: the view-projection matrix times the draw's object-to-world transform.
struct Uniforms {
    view_proj: mat4x4<f32>,
}

@group(0) @binding(0) var<uniform> uniforms: Uniforms;

// Centroid interpolation: with multisampling, a pixel that a triangle covers only in part is
// shaded at a point inside the covered part, not at the pixel centre beyond the triangle's edge,
// where the interpolated colours would be extrapolated (and can turn negative).
struct VertexOut {
    @builtin(position) clip: vec4<f32>,
    @location(0) @interpolate(perspective, centroid) colour: vec3<f32>,
}

// Step 1: project each vertex; pass its linear colour through for interpolation.
@vertex
fn vs_main(@location(0) position: vec3<f32>, @location(1) colour: vec4<f32>) -> VertexOut {
    var out: VertexOut;
    out.clip = uniforms.view_proj * vec4<f32>(position, 1.0);
    out.colour = colour.rgb;
    return out;
}

// Step 2: write the interpolated linear colour; the depth test keeps the nearest surface.
@fragment
fn fs_main(in: VertexOut) -> @location(0) vec4<f32> {
    return vec4<f32>(in.colour, 1.0);
}
