// Smooth reconstruction of the baked lighting (SPEC.md, Appendix G), shared by the kernels that
// colour refined vertices. It reads `hce_light` (hce_bindings.wgsl), the object's lighting
// table (geometry/src/lighting.rs `to_words`): word 0 where the point indices start, word 1
// where the models start; then per coarse triangle the word of its tree's node 0; the node
// words (a subdivided node: its first child's number; a leaf: LEAF | its index); three point
// indices per leaf; 12 f32 (bit patterns) per point: c (RGB), then the red, green, blue
// gradients. The Rust side builds the table from the validated object, so every index stays in
// bounds.
//
// HCE_EVAL_BITS (the bits of the lattice in which points are evaluated) and HCE_LEAF (a leaf's
// node word) come from hce_constants.wgsl, generated from lighting.rs's constants.

// #import hce_constants
// #import hce_bindings

// Where the object's table starts when `hce_light` pools many objects' tables (the batched
// entry points of flat.wgsl); zero (a private variable's initial value) in every other kernel.
// Every word is read through hce_light_word, the table's own offsets counted from its start.
var<private> hce_light_base: u32;

fn hce_light_word(i: u32) -> u32 {
    return hce_light[hce_light_base + i];
}

// Step 1: `c + G n` of one point's model, per channel, in the order of lighting.rs
// `eval_model`: c + ((g.x n.x + g.y n.y) + g.z n.z).
fn hce_light_model(point: u32, n: vec3<f32>) -> vec3<f32> {
    let b = hce_light_word(1u) + 12u * point;
    var out = vec3<f32>(0.0);
    for (var ch = 0u; ch < 3u; ch++) {
        let g = b + 3u + 3u * ch;
        let gx = bitcast<f32>(hce_light_word(g));
        let gy = bitcast<f32>(hce_light_word(g + 1u));
        let gz = bitcast<f32>(hce_light_word(g + 2u));
        out[ch] = bitcast<f32>(hce_light_word(b + ch)) + (gx * n.x + gy * n.y + gz * n.z);
    }
    return out;
}

// Step 2: walk coarse triangle t's node words down to the leaf holding lattice point (x, y)
// (denominator 2^16): a point on the border between children goes to Left (u at least half
// the side), else Right (v at least half), else Top (u + v at most half), else Center
// (lighting.rs `locate`). Then blend the leaf's three corner values by the point's weights.
fn hce_light_eval(t: u32, x: u32, y: u32, n: vec3<f32>) -> vec3<f32> {
    let base = hce_light_word(2u + t);
    var u = x;
    var v = y;
    var side = 1u << HCE_EVAL_BITS;
    var word = hce_light_word(base);
    while ((word & HCE_LEAF) == 0u && side > 1u) {
        let h = side / 2u;
        var c = 2u;
        if (u >= h) {
            u -= h;
            c = 1u;
        } else if (v >= h) {
            v -= h;
            c = 3u;
        } else if (u + v <= h) {
            c = 0u;
        } else {
            u = h - u;
            v = h - v;
        }
        word = hce_light_word(base + word + c);
        side = h;
    }
    let corners = hce_light_word(0u) + 3u * (word & ~HCE_LEAF);
    let s = f32(side);
    let w1 = f32(u) / s;
    let w2 = f32(v) / s;
    let w0 = 1.0 - w1 - w2;
    let b0 = hce_light_model(hce_light_word(corners), n);
    let b1 = hce_light_model(hce_light_word(corners + 1u), n);
    let b2 = hce_light_model(hce_light_word(corners + 2u), n);
    return max(b0 * w0 + b1 * w1 + b2 * w2, vec3<f32>(0.0));
}
