// HCE colour decoding, shared by the kernels that colour subtriangles.
//
// Concheiro et al., "Synthesis of multiresolution scenes with global illumination on a GPU"
// (GRAPP 2012), section 4. It reads the object's records, bitstream, representative normals
// and colours (`hce_records`, `hce_bits`, `hce_normals`, `hce_colours` of hce_bindings.wgsl).
// The Rust side validates every record against those arrays before upload, so the indices
// below stay in bounds for any input that reaches the GPU.

// #import hce_constants
// #import hce_bindings

// Step 1: read one bit of the stream.
fn hce_bit(i: u32) -> u32 {
    return (hce_bits[i >> 5u] >> (i & 31u)) & 1u;
}

// Step 2: count the set bits in [start, start + len), a word (or part of one) at a time.
// A node's rank among the subdivided nodes before it is this count from the tree's start.
fn hce_popcount(start: u32, len: u32) -> u32 {
    var count = 0u;
    var i = start;
    let end = start + len;
    while (i < end) {
        let lo = i & 31u;
        let take = min(32u - lo, end - i);
        var mask = 0xffffffffu;
        if (take < 32u) {
            mask = (1u << take) - 1u;
        }
        count += countOneBits((hce_bits[i >> 5u] >> lo) & mask);
        i += take;
    }
    return count;
}

// Step 3: walk the breadth-first tree along `path` (two bits per level, first level most
// significant). Node k's "subdivided" bit is bits_start + k; if r subdivided nodes precede it,
// its children are 1 + 4r + child. Stop at a leaf or after `depth` levels.
fn hce_tree_node(rec: TriRecord, depth: u32, path: u32) -> u32 {
    var node = 0u;
    for (var k = 0u; k < depth; k++) {
        if (hce_bit(rec.bits_start + node) == 0u) {
            break;
        }
        let rank = hce_popcount(rec.bits_start, node);
        let child = (path >> (2u * (depth - 1u - k))) & 3u;
        node = 1u + 4u * rank + child;
    }
    return node;
}

// Step 4: the representative normal closest to the subtriangle's (largest dot product; ties go
// to the lower index, so a degenerate subtriangle takes the geometric normal).
fn hce_choose_normal(rec: TriRecord, n: vec3<f32>) -> u32 {
    var best = 0u;
    var best_dot = -3.0e38;
    for (var j = 0u; j < rec.normal_count; j++) {
        let b = 3u * (rec.normal_start + j);
        let m = vec3<f32>(hce_normals[b], hce_normals[b + 1u], hce_normals[b + 2u]);
        let d = m.x * n.x + m.y * n.y + m.z * n.z;
        if (j == 0u || d > best_dot) {
            best = j;
            best_dot = d;
        }
    }
    return best;
}

// Step 5: RGB9E5 → linear RGB: three 9-bit mantissas scaled by 2^(exponent − 15 − 9).
fn hce_rgb9e5(v: u32) -> vec3<f32> {
    let e = i32(v >> 27u) - 24;
    let m = vec3<f32>(f32(v & 511u), f32((v >> 9u) & 511u), f32((v >> 18u) & 511u));
    return m * ldexp(1.0, e);
}

// Where the object's tables start when the arrays pool many objects' (the batched entry points
// of flat.wgsl): its first record, and the first bit, colour and normal its records count from.
// Zero (a private variable's initial value) for arrays of one object, in every other kernel.
var<private> hce_tree_base: vec4<u32>;

// Step 6: the paper's colour of a fine triangle (SPEC.md G.5): the node along its path (at most
// `depth` levels) and, of that node's colours, the one of the representative normal closest to
// `n` (the kernel passes the fine triangle's normal, unit or not: the choice is the same).
fn hce_nearest_colour(t: u32, depth: u32, path: u32, n: vec3<f32>) -> vec3<f32> {
    let rec = hce_record(t);
    return hce_node_colour(rec, hce_tree_node(rec, depth, path), n);
}

// The same for a triangle that names its node (a leaf of the adaptive flat refinement, SPEC.md
// F.7.1).
fn hce_leaf_colour(t: u32, node: u32, n: vec3<f32>) -> vec3<f32> {
    return hce_node_colour(hce_record(t), node, n);
}

fn hce_record(t: u32) -> TriRecord {
    var rec = hce_records[hce_tree_base.x + t];
    rec.bits_start += hce_tree_base.y;
    rec.colour_start += hce_tree_base.z;
    rec.normal_start += hce_tree_base.w;
    return rec;
}

fn hce_node_colour(rec: TriRecord, node: u32, n: vec3<f32>) -> vec3<f32> {
    let j = hce_choose_normal(rec, n);
    return hce_rgb9e5(hce_colours[rec.colour_start + node * rec.normal_count + j]);
}
