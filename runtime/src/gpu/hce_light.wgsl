// Smooth reconstruction of the baked lighting (SPEC.md, Appendix G), shared by the kernels that
// colour refined vertices. Prepended after hce_tree.wgsl to a kernel that declares, with these
// names:
//   hce_records: array<TriRecord>   one per coarse triangle (hce_tree.wgsl)
//   hce_bits:    array<u32>         the HCE bitstream (hce_tree.wgsl)
//   hce_light:   array<u32>         the object's lighting table (runtime/src/lighting.rs
//                                   `to_words`): word 0 the offset of the models, then the
//                                   first leaf of each of the F coarse triangles, three point
//                                   indices per leaf, and 12 f32 (bit patterns) per point
// The Rust side builds the table from the validated object, so every index stays in bounds.

// Bits of the lattice in which points are evaluated (lighting.rs EVAL_LATTICE_BITS).
const HCE_EVAL_BITS: u32 = 16u;

// Step 1: `c + G n` of one point's model, per channel, in the order of lighting.rs
// `eval_model`: c + ((g.x n.x + g.y n.y) + g.z n.z).
fn hce_light_model(point: u32, n: vec3<f32>) -> vec3<f32> {
    let b = hce_light[0] + 12u * point;
    var out = vec3<f32>(0.0);
    for (var ch = 0u; ch < 3u; ch++) {
        let g = b + 3u + 3u * ch;
        let gx = bitcast<f32>(hce_light[g]);
        let gy = bitcast<f32>(hce_light[g + 1u]);
        let gz = bitcast<f32>(hce_light[g + 2u]);
        out[ch] = bitcast<f32>(hce_light[b + ch]) + (gx * n.x + gy * n.y + gz * n.z);
    }
    return out;
}

// Step 2: the leaf holding lattice point (x, y) (denominator 2^16) of coarse triangle t and the
// point's weights of its three corners, then the corners' values blended by those weights. A
// point on the border between children goes to Left (u at least half the side), else Right
// (v at least half), else Top (u + v at most half), else Center (lighting.rs `locate`).
fn hce_light_eval(t: u32, x: u32, y: u32, n: vec3<f32>) -> vec3<f32> {
    let rec = hce_records[t];
    var u = x;
    var v = y;
    var side = 1u << HCE_EVAL_BITS;
    var node = 0u;
    while (side > 1u && hce_bit(rec.bits_start + node) == 1u) {
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
        node = 1u + 4u * hce_popcount(rec.bits_start, node) + c;
        side = h;
    }
    let leaf = hce_light[1u + t] + node - hce_popcount(rec.bits_start, node);
    let corners = 1u + params.triangle_count + 3u * leaf;
    let s = f32(side);
    let w1 = f32(u) / s;
    let w2 = f32(v) / s;
    let w0 = 1.0 - w1 - w2;
    let b0 = hce_light_model(hce_light[corners], n);
    let b1 = hce_light_model(hce_light[corners + 1u], n);
    let b2 = hce_light_model(hce_light[corners + 2u], n);
    return max(b0 * w0 + b1 * w1 + b2 * w2, vec3<f32>(0.0));
}
