// Flat refinement: linear 1-to-4 split of every coarse triangle to level L, one HCE colour per
// fine triangle, and vertex colours as area-weighted means of the incident fine triangles,
// across coarse edges and vertices. Three dispatches, each a pure gather with one writer per
// output element, so the result does not depend on scheduling (no float atomics).
//
// Numbering (cpu_reference.rs has the same in prose): with n = 2^L, a point of coarse triangle
// (v0, v1, v2) has lattice coordinates (b, c), a = n − b − c; position (a p0 + b p1 + c p2) / n.
// Vertices: [coarse][edge points, E × (n − 1), from the owner's v_e][interior, F × I], interior
// points in rows of increasing c, each in increasing b (the numbering of subdivide.rs);
// fine triangle t · 4^L + path. A lattice triangle is (C0, σ, s): corners C0, C0 + σ s e_b,
// C0 + σ s e_c; the children Top, Left, Center, Right keep σ except Center, which flips it.

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
}

@group(0) @binding(0) var<uniform> params: Params;
@group(0) @binding(1) var<storage, read> coarse_positions: array<f32>;
@group(0) @binding(2) var<storage, read> topo: array<u32>;
@group(0) @binding(3) var<storage, read> hce_records: array<TriRecord>;
@group(0) @binding(4) var<storage, read> hce_bits: array<u32>;
@group(0) @binding(5) var<storage, read> hce_normals: array<f32>;
@group(0) @binding(6) var<storage, read> hce_colours: array<u32>;
@group(0) @binding(7) var<storage, read_write> out_positions: array<f32>;
@group(0) @binding(8) var<storage, read_write> out_indices: array<u32>;
@group(0) @binding(9) var<storage, read_write> out_faces: array<vec4<f32>>;
@group(0) @binding(10) var<storage, read_write> out_colours: array<vec4<f32>>;
@group(0) @binding(11) var<storage, read> hce_light: array<u32>;

fn linear_id(gid: vec3<u32>, groups: vec3<u32>) -> u32 {
    return gid.x + gid.y * groups.x * 64u;
}

fn coarse_position(v: u32) -> vec3<f32> {
    return vec3<f32>(coarse_positions[3u * v], coarse_positions[3u * v + 1u], coarse_positions[3u * v + 2u]);
}

fn corner(t: u32, c: u32) -> u32 {
    return topo[params.tri_off + 3u * t + c];
}

// (a p0 + b p1 + c p2) / n, the same operations in the same order as the CPU reference.
fn lattice_position(p0: vec3<f32>, p1: vec3<f32>, p2: vec3<f32>, b: i32, c: i32) -> vec3<f32> {
    let n = i32(params.n);
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

// Interior point `local` → (b, c): rows of constant c in increasing c, each in increasing b
// (the numbering of subdivide.rs and loop.wgsl); row c holds j = n − 1 − c points, so counted
// from the last point, r = I − 1 − local lies in the row with j (j − 1) / 2 <= r < j (j + 1) / 2.
fn interior_coords(local: u32) -> vec2<i32> {
    let ip = params.interior_per_triangle;
    let r = ip - 1u - local;
    var j = u32(floor((1.0 + sqrt(1.0 + 8.0 * f32(r))) * 0.5));
    while (j * (j - 1u) / 2u > r) {
        j -= 1u;
    }
    while ((j + 1u) * j / 2u <= r) {
        j += 1u;
    }
    let b = i32(local - (ip - j * (j + 1u) / 2u)) + 1;
    return vec2<i32>(b, i32(params.n) - 1 - i32(j));
}

// Lattice point (b, c) of triangle t → output vertex index.
fn vertex_index(t: u32, b: i32, c: i32) -> u32 {
    let n = i32(params.n);
    let a = n - b - c;
    if (b == 0 && c == 0) { return corner(t, 0u); }
    if (a == 0 && c == 0) { return corner(t, 1u); }
    if (a == 0 && b == 0) { return corner(t, 2u); }
    var e = 0u;
    var k = 0;
    if (c == 0) {
        e = 0u; k = b;
    } else if (a == 0) {
        e = 1u; k = c;
    } else if (b == 0) {
        e = 2u; k = a;
    } else {
        let j = u32(n - 1 - c);
        return params.coarse_vertices + params.edge_count * (params.n - 1u)
            + t * params.interior_per_triangle
            + (params.interior_per_triangle - j * (j + 1u) / 2u) + u32(b - 1);
    }
    let id = topo[params.edges_off + 3u * t + e];
    var kk = k;
    if (topo[params.edge_verts_off + 2u * id] != corner(t, e)) {
        kk = n - k;
    }
    return params.coarse_vertices + id * (params.n - 1u) + u32(kk - 1);
}

// Corners (b, c) of fine triangle `path`, descending the 1-to-4 split.
fn fine_corners(path: u32) -> array<vec2<i32>, 3> {
    var c0 = vec2<i32>(0, 0);
    var sigma = 1;
    var s = i32(params.n);
    for (var k = 0u; k < params.level; k++) {
        let h = s / 2;
        let child = (path >> (2u * (params.level - 1u - k))) & 3u;
        if (child == 1u) {
            c0.x += sigma * h;
        } else if (child == 2u) {
            c0 += vec2<i32>(sigma * h, sigma * h);
            sigma = -sigma;
        } else if (child == 3u) {
            c0.y += sigma * h;
        }
        s = h;
    }
    return array<vec2<i32>, 3>(c0, c0 + vec2<i32>(sigma, 0), c0 + vec2<i32>(0, sigma));
}

// The path of the fine triangle whose centroid, times 3, is q.
fn locate(q: vec2<i32>) -> u32 {
    var c0 = vec2<i32>(0, 0);
    var sigma = 1;
    var s = i32(params.n);
    var path = 0u;
    for (var k = 0u; k < params.level; k++) {
        let h = s / 2;
        let l1 = sigma * (q.x - 3 * c0.x);
        let l2 = sigma * (q.y - 3 * c0.y);
        let l0 = 3 * s - l1 - l2;
        var child = 2u;
        if (l0 > 3 * h) {
            child = 0u;
        } else if (l1 > 3 * h) {
            child = 1u;
            c0.x += sigma * h;
        } else if (l2 > 3 * h) {
            child = 3u;
            c0.y += sigma * h;
        } else {
            c0 += vec2<i32>(sigma * h, sigma * h);
            sigma = -sigma;
        }
        path = path * 4u + child;
        s = h;
    }
    return path;
}

// Step 1 (one invocation per output vertex): positions. Coarse vertices are copied, edge points
// are computed once from the owner's direction, interior points from their triangle — one
// writer per vertex, so vertices shared along coarse edges are bitwise identical.
@compute @workgroup_size(64)
fn positions_main(@builtin(global_invocation_id) gid: vec3<u32>,
                  @builtin(num_workgroups) groups: vec3<u32>) {
    let i = linear_id(gid, groups);
    if (i >= params.vertex_total) {
        return;
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
    out_positions[3u * i] = p.x;
    out_positions[3u * i + 1u] = p.y;
    out_positions[3u * i + 2u] = p.z;
}

fn out_position(v: u32) -> vec3<f32> {
    return vec3<f32>(out_positions[3u * v], out_positions[3u * v + 1u], out_positions[3u * v + 2u]);
}

// Step 2 (one invocation per fine triangle): its three vertex indices, its normal and area from
// the positions of step 1, and, for the paper's rule, its colour from the HCE tree
// (hce_tree.wgsl). The smooth reconstruction colours vertices in step 3 instead.
@compute @workgroup_size(64)
fn faces_main(@builtin(global_invocation_id) gid: vec3<u32>,
              @builtin(num_workgroups) groups: vec3<u32>) {
    let g = linear_id(gid, groups);
    if (g >= params.fine_total) {
        return;
    }
    let per = 1u << (2u * params.level);
    let t = g / per;
    let path = g % per;
    let cs = fine_corners(path);
    let i0 = vertex_index(t, cs[0].x, cs[0].y);
    let i1 = vertex_index(t, cs[1].x, cs[1].y);
    let i2 = vertex_index(t, cs[2].x, cs[2].y);
    out_indices[3u * g] = i0;
    out_indices[3u * g + 1u] = i1;
    out_indices[3u * g + 2u] = i2;

    let p0 = out_position(i0);
    let u = out_position(i1) - p0;
    let w = out_position(i2) - p0;
    let x = vec3<f32>(u.y * w.z - u.z * w.y, u.z * w.x - u.x * w.z, u.x * w.y - u.y * w.x);
    let len = sqrt(x.x * x.x + x.y * x.y + x.z * x.z);
    var normal = vec3<f32>(0.0);
    if (len > 0.0) {
        normal = x / len;
    }

    var rgb = vec3<f32>(0.0);
    if (params.smooth_light == 0u) {
        let rec = hce_records[t];
        let node = hce_tree_node(rec, params.level, path);
        let j = hce_choose_normal(rec, normal);
        rgb = hce_rgb9e5(hce_colours[rec.colour_start + node * rec.normal_count + j]);
    }
    out_faces[g] = vec4<f32>(rgb, 0.5 * len);
}

// Area-weighted sums with a plain-mean fallback for zero-area neighbourhoods.
struct Acc {
    weighted: vec3<f32>,
    area: f32,
    plain: vec3<f32>,
    count: f32,
}

fn acc_add(acc: ptr<function, Acc>, g: u32) {
    let f = out_faces[g];
    (*acc).weighted = vec3<f32>((*acc).weighted.x + f.w * f.x, (*acc).weighted.y + f.w * f.y,
                                (*acc).weighted.z + f.w * f.z);
    (*acc).plain += f.xyz;
    (*acc).area += f.w;
    (*acc).count += 1.0;
}

// Adds the fine triangles of coarse triangle t around lattice point (b, c), in the fixed order
// of cpu_reference::incident_paths: up triangles at (b, c), (b − 1, c), (b, c − 1), then down
// triangles at (b, c), (b + 1, c), (b, c + 1).
fn gather(acc: ptr<function, Acc>, t: u32, b: i32, c: i32) {
    let area_before = (*acc).area;
    let count_before = (*acc).count;
    let n = i32(params.n);
    let base = t << (2u * params.level);
    let ups = array<vec2<i32>, 3>(vec2<i32>(b, c), vec2<i32>(b - 1, c), vec2<i32>(b, c - 1));
    for (var k = 0; k < 3; k++) {
        let u = ups[k];
        if (u.x >= 0 && u.y >= 0 && u.x + u.y < n) {
            acc_add(acc, base + locate(vec2<i32>(3 * u.x + 1, 3 * u.y + 1)));
        }
    }
    let downs = array<vec2<i32>, 3>(vec2<i32>(b, c), vec2<i32>(b + 1, c), vec2<i32>(b, c + 1));
    for (var k = 0; k < 3; k++) {
        let d = downs[k];
        if (d.x >= 1 && d.y >= 1 && d.x + d.y <= n) {
            acc_add(acc, base + locate(vec2<i32>(3 * d.x - 1, 3 * d.y - 1)));
        }
    }
    // Smooth reconstruction: the field of coarse triangle t at this lattice point, weighted by
    // the area of t's fine triangles around it (their own colours are zero in this mode). A flat
    // object has one normal per triangle, so the field does not depend on the normal.
    if (params.smooth_light == 1u) {
        let shift = HCE_EVAL_BITS - params.level;
        let rgb = hce_light_eval(t, u32(b) << shift, u32(c) << shift, vec3<f32>(0.0));
        (*acc).weighted += rgb * ((*acc).area - area_before);
        (*acc).plain += rgb * ((*acc).count - count_before);
    }
}

// Step 3 (one invocation per output vertex): gather every incident fine triangle — from each
// coarse triangle at a coarse vertex, from both sides of a coarse edge, or from the one
// triangle of an interior point — and write the area-weighted mean colour.
@compute @workgroup_size(64)
fn colours_main(@builtin(global_invocation_id) gid: vec3<u32>,
                @builtin(num_workgroups) groups: vec3<u32>) {
    let i = linear_id(gid, groups);
    if (i >= params.vertex_total) {
        return;
    }
    let n = i32(params.n);
    let ep = params.n - 1u;
    let edge_base = params.coarse_vertices;
    let interior_base = edge_base + params.edge_count * ep;
    var acc = Acc(vec3<f32>(0.0), 0.0, vec3<f32>(0.0), 0.0);
    if (i < edge_base) {
        let s = topo[params.vertex_corner_offsets_off + i];
        let e = topo[params.vertex_corner_offsets_off + i + 1u];
        for (var k = s; k < e; k++) {
            let cr = topo[params.vertex_corners_off + k];
            var bc = vec2<i32>(0, 0);
            if (cr % 3u == 1u) {
                bc = vec2<i32>(n, 0);
            } else if (cr % 3u == 2u) {
                bc = vec2<i32>(0, n);
            }
            gather(&acc, cr / 3u, bc.x, bc.y);
        }
    } else if (i < interior_base) {
        let id = (i - edge_base) / ep;
        let kk = i32((i - edge_base) % ep) + 1;
        let owner_start = topo[params.edge_verts_off + 2u * id];
        let s = topo[params.edge_side_offsets_off + id];
        let e = topo[params.edge_side_offsets_off + id + 1u];
        for (var m = s; m < e; m++) {
            let side = topo[params.edge_sides_off + m];
            let t = side / 3u;
            let ed = side % 3u;
            var k = kk;
            if (topo[params.tri_off + side] != owner_start) {
                k = n - kk;
            }
            var bc = vec2<i32>(k, 0);
            if (ed == 1u) {
                bc = vec2<i32>(n - k, k);
            } else if (ed == 2u) {
                bc = vec2<i32>(0, n - k);
            }
            gather(&acc, t, bc.x, bc.y);
        }
    } else {
        let t = (i - interior_base) / params.interior_per_triangle;
        let bc = interior_coords((i - interior_base) % params.interior_per_triangle);
        gather(&acc, t, bc.x, bc.y);
    }
    var colour = vec3<f32>(0.0);
    if (acc.area > 0.0) {
        colour = acc.weighted / acc.area;
    } else if (acc.count > 0.0) {
        colour = acc.plain / acc.count;
    }
    out_colours[i] = vec4<f32>(colour, 1.0);
}
