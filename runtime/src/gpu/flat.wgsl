// Flat refinement, one of two (SPEC.md F.7), three dispatches either way, each a pure gather with
// one writer per output element, so the result does not depend on scheduling (no float atomics):
//
// * uniform (F.7.2): linear 1-to-4 split of every coarse triangle to level L, the vertices split
//   where the surface folds (SPEC.md F.5: one vertex per side of every edge with a neighbour
//   that does not join it), one HCE colour per fine triangle, and vertex colours as
//   area-weighted means of the incident fine triangles of the vertex's region, across the
//   coarse edges and vertices that join;
// * adaptive (F.7.1, `params.adaptive` = 1): the triangles of the object's tree leaves, whose
//   lists the CPU builds once from the tree (geometry/src/adaptive_flat.rs): per vertex its
//   coarse triangle and point on the 4096 lattice, per triangle its coarse triangle, leaf,
//   corner points and indices, per vertex the corners that use it. The kernel computes the
//   positions, the triangles' areas and colours and the vertex colours from them, with the
//   same arithmetic as the CPU reference.
//
// The lattice and the output numbering are those of hce_lattice.wgsl, the vertex colours the
// gather of hce_gather.wgsl; a point (b, c) of coarse triangle (v0, v1, v2) lies at
// (a p0 + b p1 + c p2) / n.

// #import hce_constants
// #import hce_bindings
// #import hce_tree
// #import hce_light
// #import hce_lattice
// #import hce_gather
// #import hce_batch

struct Params {
    level: u32,
    n: u32,
    coarse_vertices: u32,
    edge_count: u32,
    triangle_count: u32,
    interior_per_triangle: u32,
    vertex_total: u32,
    fine_total: u32,
    // Offsets (in u32 words) of the sections packed into `topo`.
    tri_off: u32,
    edges_off: u32,
    edge_verts_off: u32,
    edge_side_offsets_off: u32,
    edge_sides_off: u32,
    vertex_corner_offsets_off: u32,
    vertex_corners_off: u32,
    // 1: smooth reconstruction (hce_light.wgsl), 0: the paper's nearest normal.
    smooth_light: u32,
    // The split where the surface folds (geometry/src/split.rs): the four incidence sections
    // above are its slot lists (V + X corner slots, E + S edge slots); per corner its region's
    // copy, per edge id its rank among the split edges (or NO_COPY); the first appended vertex
    // (the F.5 count) and the number X of corner copies.
    corner_copy_off: u32,
    edge_copy_off: u32,
    split_base: u32,
    split_copies: u32,
    // The range of this dispatch's items (output vertices in steps 1 and 3, fine triangles in
    // step 2): items range_first .. min(total, range_end). A refinement split over frames
    // dispatches each step in pieces (runtime/src/gpu/job.rs); a one-shot refinement passes 0
    // and 0xffffffff.
    range_first: u32,
    range_end: u32,
    // The adaptive refinement (1) or the uniform one (0), and its lists' sections of `topo`
    // (runtime/src/gpu/flat.rs `adaptive_sections`): per vertex its coarse triangle and packed
    // point (x | y << 16, 4096 lattice); per triangle its coarse triangle, leaf and three packed
    // corner points; per triangle its three indices; per vertex where its uses start (V + 1
    // words); the uses, 3 f + c each. The uniform fields above that describe the lattice
    // (level, n, counts, split) do not apply to it.
    adaptive: u32,
    sources_off: u32,
    faces_off: u32,
    indices_off: u32,
    use_offsets_off: u32,
    uses_off: u32,
}

// The parameters every function reads: the uniform's, copied at the start of the per-object
// entry points; the object's entry of the batch table in the batched ones (below,
// hce_batch.wgsl). The other bindings are hce_bindings.wgsl's.
@group(0) @binding(0) var<uniform> params_in: Params;
var<private> params: Params;

// (a p0 + b p1 + c p2) / n, the same operations in the same order as the CPU reference.
fn lattice_position(p0: vec3<f32>, p1: vec3<f32>, p2: vec3<f32>, b: i32, c: i32) -> vec3<f32> {
    return lattice_position_n(p0, p1, p2, i32(params.n), b, c);
}

fn lattice_position_n(p0: vec3<f32>, p1: vec3<f32>, p2: vec3<f32>, n: i32, b: i32,
                      c: i32) -> vec3<f32> {
    let inv = 1.0 / f32(n);
    let wa = f32(n - b - c);
    let wb = f32(b);
    let wc = f32(c);
    return vec3<f32>(
        (p0.x * wa + p1.x * wb + p2.x * wc) * inv,
        (p0.y * wa + p1.y * wb + p2.y * wc) * inv,
        (p0.z * wa + p1.z * wb + p2.z * wc) * inv,
    );
}

// The lattice of hce_lattice.wgsl: an edge's points are counted from its first vertex in the
// edge table, which is where its owner starts it.
fn lattice_level() -> u32 {
    return params.level;
}

fn lattice_n() -> u32 {
    return params.n;
}

fn edge_from_owner(t: u32, e: u32) -> bool {
    return topo[params.edge_verts_off + 2u * topo[params.edges_off + 3u * t + e]] == corner(t, e);
}

fn lattice_edge_base(t: u32, e: u32) -> u32 {
    return params.coarse_vertices + topo[params.edges_off + 3u * t + e] * (params.n - 1u);
}

fn lattice_split_base() -> u32 {
    return params.split_base;
}

fn lattice_split_copies() -> u32 {
    return params.split_copies;
}

fn lattice_interior_base(t: u32) -> u32 {
    return params.coarse_vertices + params.edge_count * (params.n - 1u) + t * params.interior_per_triangle;
}

// Step 1 (one invocation per output vertex): positions. Coarse vertices are copied, edge points
// are computed once from the owner's direction, interior points from their triangle — one
// writer per vertex, so vertices shared along coarse edges are bitwise identical. A copy of the
// split computes its original's position the same way, so it has the same bits.
@compute @workgroup_size(64)
fn positions_main(@builtin(global_invocation_id) gid: vec3<u32>,
                  @builtin(num_workgroups) groups: vec3<u32>) {
    params = params_in;
    let v = params.range_first + linear_id(gid, groups);
    if (v >= min(params.vertex_total, params.range_end)) {
        return;
    }
    flat_position(v);
}

fn flat_position(v: u32) {
    if (params.adaptive == 1u) {
        adaptive_position(v);
        return;
    }
    var i = v;
    if (v >= params.split_base) {
        i = slot_source(vertex_slot(v));
    }
    var p: vec3<f32>;
    let ep = params.n - 1u;
    let edge_base = params.coarse_vertices;
    let interior_base = edge_base + params.edge_count * ep;
    if (i < edge_base) {
        p = coarse_position(i);
    } else if (i < interior_base) {
        let id = (i - edge_base) / ep;
        let k = i32((i - edge_base) % ep) + 1;
        let pa = coarse_position(topo[params.edge_verts_off + 2u * id]);
        let pb = coarse_position(topo[params.edge_verts_off + 2u * id + 1u]);
        p = lattice_position(pa, pb, pb, k, 0);
    } else {
        let t = (i - interior_base) / params.interior_per_triangle;
        let bc = interior_coords((i - interior_base) % params.interior_per_triangle);
        p = lattice_position(coarse_position(corner(t, 0u)), coarse_position(corner(t, 1u)),
                             coarse_position(corner(t, 2u)), bc.x, bc.y);
    }
    let o = 3u * (lattice_out_base + v);
    out_positions[o] = p.x;
    out_positions[o + 1u] = p.y;
    out_positions[o + 2u] = p.z;
}

// Step 2 (one invocation per fine triangle): its three vertex indices, its normal and area from
// the positions of step 1, and, for the paper's rule, its colour from the HCE tree
// (hce_tree.wgsl). The smooth reconstruction colours vertices in step 3 instead.
@compute @workgroup_size(64)
fn faces_main(@builtin(global_invocation_id) gid: vec3<u32>,
              @builtin(num_workgroups) groups: vec3<u32>) {
    params = params_in;
    let g = params.range_first + linear_id(gid, groups);
    if (g >= min(params.fine_total, params.range_end)) {
        return;
    }
    flat_face(g);
}

fn flat_face(g: u32) {
    if (params.adaptive == 1u) {
        adaptive_face(g);
        return;
    }
    let per = 1u << (2u * params.level);
    let t = g / per;
    let path = g % per;
    let cs = fine_corners(path);
    let i0 = vertex_index(t, cs[0].x, cs[0].y);
    let i1 = vertex_index(t, cs[1].x, cs[1].y);
    let i2 = vertex_index(t, cs[2].x, cs[2].y);
    // Drawn with the split vertices (hce_gather.wgsl `split_index`); measured with the F.5
    // ones, whose positions the copies repeat.
    let o = 3u * (gather_face_base + g);
    out_indices[o] = split_index(t, cs[0].x, cs[0].y, i0);
    out_indices[o + 1u] = split_index(t, cs[1].x, cs[1].y, i1);
    out_indices[o + 2u] = split_index(t, cs[2].x, cs[2].y, i2);

    let nl = unit_normal_length(i0, i1, i2);
    var rgb = vec3<f32>(0.0);
    if (params.smooth_light == 0u) {
        rgb = hce_nearest_colour(t, params.level, path, nl.xyz);
    }
    out_faces[gather_face_base + g] = vec4<f32>(rgb, 0.5 * nl.w);
}

// The unit normal of triangle (i0, i1, i2) (zero where it has no direction) and, in w, the
// length of (p1 − p0) × (p2 − p0), from the positions of step 1.
fn unit_normal_length(i0: u32, i1: u32, i2: u32) -> vec4<f32> {
    let p0 = out_position(i0);
    let u = out_position(i1) - p0;
    let w = out_position(i2) - p0;
    let x = vec3<f32>(u.y * w.z - u.z * w.y, u.z * w.x - u.x * w.z, u.x * w.y - u.y * w.x);
    let len = sqrt(x.x * x.x + x.y * x.y + x.z * x.z);
    var normal = vec3<f32>(0.0);
    if (len > 0.0) {
        normal = x / len;
    }
    return vec4<f32>(normal, len);
}

// Step 3 (one invocation per output vertex, copies included): gather every incident fine
// triangle of the vertex's region — from each coarse triangle of its corner slot at a coarse
// vertex, from the sides of its edge slot on a coarse edge, or from the one triangle of an
// interior point — and write the area-weighted mean colour.
@compute @workgroup_size(64)
fn colours_main(@builtin(global_invocation_id) gid: vec3<u32>,
                @builtin(num_workgroups) groups: vec3<u32>) {
    params = params_in;
    let i = params.range_first + linear_id(gid, groups);
    if (i >= min(params.vertex_total, params.range_end)) {
        return;
    }
    flat_colour(i);
}

fn flat_colour(i: u32) {
    if (params.adaptive == 1u) {
        adaptive_colour(i);
        return;
    }
    // A flat object has one normal per triangle, so the smooth field does not depend on it.
    out_colours[lattice_out_base + i] = vec4<f32>(vertex_colour(i, vec3<f32>(0.0)), 1.0);
}

// The adaptive refinement's three steps (SPEC.md F.7.1), on the lists described at `Params`.
fn adaptive_point(w: u32) -> vec2<i32> {
    return vec2<i32>(i32(w & 0xffffu), i32(w >> 16u));
}

// Step 1: the vertex's position at its source point, as geometry/src/adaptive_flat.rs computes
// it: a coarse corner copied, a point on a coarse edge from the edge owner's direction (so both
// sides of a split edge get the same bits), any other point from its triangle.
fn adaptive_position(v: u32) {
    let t = topo[params.sources_off + 2u * v];
    let q = adaptive_point(topo[params.sources_off + 2u * v + 1u]);
    let n = i32(1u << HCE_TREE_BITS);
    let a = n - q.x - q.y;
    var p: vec3<f32>;
    if (q.x == 0 && q.y == 0) {
        p = coarse_position(corner(t, 0u));
    } else if (a == 0 && q.y == 0) {
        p = coarse_position(corner(t, 1u));
    } else if (a == 0 && q.x == 0) {
        p = coarse_position(corner(t, 2u));
    } else if (q.y == 0 || a == 0 || q.x == 0) {
        var e = 2u;
        var k = a;
        if (q.y == 0) {
            e = 0u;
            k = q.x;
        } else if (a == 0) {
            e = 1u;
            k = q.y;
        }
        let id = topo[params.edges_off + 3u * t + e];
        if (!edge_from_owner(t, e)) {
            k = n - k;
        }
        let pa = coarse_position(topo[params.edge_verts_off + 2u * id]);
        let pb = coarse_position(topo[params.edge_verts_off + 2u * id + 1u]);
        p = lattice_position_n(pa, pb, pb, n, k, 0);
    } else {
        p = lattice_position_n(coarse_position(corner(t, 0u)), coarse_position(corner(t, 1u)),
                               coarse_position(corner(t, 2u)), n, q.x, q.y);
    }
    let o = 3u * (lattice_out_base + v);
    out_positions[o] = p.x;
    out_positions[o + 1u] = p.y;
    out_positions[o + 2u] = p.z;
}

// Step 2: the triangle's indices, area and, for the paper's rule, the colour of its leaf for
// the representative normal nearest its own.
fn adaptive_face(g: u32) {
    let ix = params.indices_off + 3u * g;
    let i0 = topo[ix];
    let i1 = topo[ix + 1u];
    let i2 = topo[ix + 2u];
    let o = 3u * (gather_face_base + g);
    out_indices[o] = i0;
    out_indices[o + 1u] = i1;
    out_indices[o + 2u] = i2;
    let nl = unit_normal_length(i0, i1, i2);
    var rgb = vec3<f32>(0.0);
    if (params.smooth_light == 0u) {
        let r = params.faces_off + 5u * g;
        rgb = hce_leaf_colour(topo[r], topo[r + 1u], nl.xyz);
    }
    out_faces[gather_face_base + g] = vec4<f32>(rgb, 0.5 * nl.w);
}

// Step 3: the area-weighted mean over the corners that use the vertex, in their order: the
// triangle's colour (the paper's rule) or the field of G.4 at the corner's point (smooth; a
// flat object's field has no slope, so the normal passed does not matter).
fn adaptive_colour(v: u32) {
    var acc = Acc(vec3<f32>(0.0), 0.0, vec3<f32>(0.0), 0.0, vec3<f32>(0.0));
    let first = topo[params.use_offsets_off + v];
    let end = topo[params.use_offsets_off + v + 1u];
    let shift = HCE_EVAL_BITS - HCE_TREE_BITS;
    for (var q = first; q < end; q++) {
        let u = topo[params.uses_off + q];
        let g = u / 3u;
        let f = out_faces[gather_face_base + g];
        var rgb = f.xyz;
        if (params.smooth_light == 1u) {
            let r = params.faces_off + 5u * g;
            let pt = adaptive_point(topo[r + 2u + u % 3u]);
            rgb = hce_light_eval(topo[r], u32(pt.x) << shift, u32(pt.y) << shift, vec3<f32>(0.0));
        }
        acc.weighted += rgb * f.w;
        acc.plain += rgb;
        acc.area += f.w;
        acc.count += 1.0;
    }
    out_colours[lattice_out_base + v] = vec4<f32>(acc_mean(acc), 1.0);
}

// Batched refinement (hce_batch.wgsl): the three steps of many flat objects in one dispatch
// each.
fn batch_enter(k: u32) {
    let p = batch_bases(k, batch.entries + FLAT_ENTRY_WORDS * k);
    params = Params(topo[p], topo[p + 1u], topo[p + 2u], topo[p + 3u], topo[p + 4u],
                    topo[p + 5u], topo[p + 6u], topo[p + 7u], topo[p + 8u], topo[p + 9u],
                    topo[p + 10u], topo[p + 11u], topo[p + 12u], topo[p + 13u], topo[p + 14u],
                    topo[p + 15u], topo[p + 16u], topo[p + 17u], topo[p + 18u], topo[p + 19u],
                    topo[p + 20u], topo[p + 21u], topo[p + 22u], topo[p + 23u], topo[p + 24u],
                    topo[p + 25u], topo[p + 26u], topo[p + 27u]);
}

@compute @workgroup_size(64)
fn positions_batch_main(@builtin(global_invocation_id) gid: vec3<u32>,
                        @builtin(num_workgroups) groups: vec3<u32>) {
    let g = linear_id(gid, groups);
    if (g >= batch.vertex_total) {
        return;
    }
    batch_enter(batch_object(batch.first_vertices, g));
    flat_position(g - lattice_out_base);
}

@compute @workgroup_size(64)
fn faces_batch_main(@builtin(global_invocation_id) gid: vec3<u32>,
                    @builtin(num_workgroups) groups: vec3<u32>) {
    let g = linear_id(gid, groups);
    if (g >= batch.fine_total) {
        return;
    }
    batch_enter(batch_object(batch.first_faces, g));
    flat_face(g - gather_face_base);
}

@compute @workgroup_size(64)
fn colours_batch_main(@builtin(global_invocation_id) gid: vec3<u32>,
                      @builtin(num_workgroups) groups: vec3<u32>) {
    let g = linear_id(gid, groups);
    if (g >= batch.vertex_total) {
        return;
    }
    batch_enter(batch_object(batch.first_vertices, g));
    flat_colour(g - lattice_out_base);
}
