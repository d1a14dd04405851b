// HCE colour decoding for a batch of subtriangles: one invocation per query.
//
// A query names a coarse triangle, a level, a path and the subtriangle's normal; the answer is
// the tree node reached, the normal chosen and the decoded linear colour. The flat-refinement
// kernel runs the same functions (hce_tree.wgsl) inline; this batch form exists so the decoding
// can be tested against the CPU on its own. The arrays it decodes from are hce_bindings.wgsl's.

// #import hce_tree

struct Query {
    triangle: u32,
    level: u32,
    path: u32,
    _pad: u32,
    normal: vec4<f32>,
}

struct Decoded {
    rgb_r: f32,
    rgb_g: f32,
    rgb_b: f32,
    node: u32,
    normal_index: u32,
    packed: u32,
    _pad0: u32,
    _pad1: u32,
}

@group(0) @binding(0) var<storage, read> queries: array<Query>;
@group(0) @binding(14) var<storage, read_write> results: array<Decoded>;

@compute @workgroup_size(64)
fn decode_main(@builtin(global_invocation_id) gid: vec3<u32>,
               @builtin(num_workgroups) groups: vec3<u32>) {
    // Step 1: the query this invocation answers (2-D grid for large batches).
    let i = gid.x + gid.y * groups.x * 64u;
    if (i >= arrayLength(&queries)) {
        return;
    }
    let q = queries[i];

    // Step 2: walk the triangle's tree and pick the normal.
    let rec = hce_records[q.triangle];
    let node = hce_tree_node(rec, q.level, q.path);
    let j = hce_choose_normal(rec, q.normal.xyz);

    // Step 3: decode the colour of (node, normal).
    let packed = hce_colours[rec.colour_start + node * rec.normal_count + j];
    let rgb = hce_rgb9e5(packed);
    results[i] = Decoded(rgb.x, rgb.y, rgb.z, node, j, packed, 0u, 0u);
}
