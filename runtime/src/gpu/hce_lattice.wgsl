// The 1-to-4 lattice of a refined coarse triangle and the numbering of its output vertices,
// shared by flat.wgsl and loop.wgsl (the twin of geometry/src/lattice.rs).
//
// With n = 2^L, a point of coarse triangle t = (v0, v1, v2) has lattice coordinates (b, c),
// a = n − b − c. Output vertices are [coarse][edge points, E × (n − 1), counted from the edge
// owner's v_e][interior points, F × (n − 1)(n − 2)/2], interior points of a triangle in rows of
// increasing c, each in increasing b. Fine triangle t · 4^L + path, where path is the sequence
// of 1-to-4 children from the coarse triangle down, two bits per level. A lattice triangle is
// (C0, σ, s): corners C0, C0 + σ s e_b, C0 + σ s e_c; the children Top, Left, Center, Right
// keep σ except Center, which flips it.
//
// It reads `topo`, `coarse_positions` and `out_positions` (hce_bindings.wgsl), the corner
// section of `topo` at `params.tri_off` (the importing kernel's uniform), and calls the
// functions in which the kernels differ, which the importing kernel provides:
//   lattice_level() -> u32                 L
//   lattice_n() -> u32                     n = 2^L
//   edge_from_owner(t, e) -> bool          whether edge e of triangle t starts at the vertex
//                                          its owner counts the edge's points from
//   lattice_edge_base(t, e) -> u32         output index of the first point of t's edge e
//   lattice_interior_base(t) -> u32        output index of t's first interior point

// #import hce_bindings

// Step 1: the invocation's index in a dispatch of 64-wide workgroups spread over x and y (the
// Rust side splits dispatches larger than the 65535-group limit of one dimension).
fn linear_id(gid: vec3<u32>, groups: vec3<u32>) -> u32 {
    return gid.x + gid.y * groups.x * 64u;
}

// Step 2: the buffers every refinement kernel reads. Where buffers pool many objects (the
// batched entry points of flat.wgsl and loop_batch.wgsl), the object's first coarse and first
// output vertex in them; zero (a private variable's initial value) in every other kernel.
var<private> lattice_coarse_base: u32;
var<private> lattice_out_base: u32;

fn coarse_position(i: u32) -> vec3<f32> {
    let v = lattice_coarse_base + i;
    return vec3<f32>(coarse_positions[3u * v], coarse_positions[3u * v + 1u], coarse_positions[3u * v + 2u]);
}

fn corner(t: u32, c: u32) -> u32 {
    return topo[params.tri_off + 3u * t + c];
}

fn out_position(i: u32) -> vec3<f32> {
    let v = lattice_out_base + i;
    return vec3<f32>(out_positions[3u * v], out_positions[3u * v + 1u], out_positions[3u * v + 2u]);
}

// Step 3: lattice point of corner c, and of point m of edge e counted from v_e.
fn corner_lattice(n: i32, c: u32) -> vec2<i32> {
    if (c == 0u) { return vec2<i32>(0, 0); }
    if (c == 1u) { return vec2<i32>(n, 0); }
    return vec2<i32>(0, n);
}

fn edge_lattice(n: i32, e: u32, m: i32) -> vec2<i32> {
    if (e == 0u) { return vec2<i32>(m, 0); }
    if (e == 1u) { return vec2<i32>(n - m, m); }
    return vec2<i32>(0, n - m);
}

// Step 4: interior points. Row c (1 <= c <= n − 2) holds n − 1 − c points, so it starts after
// (c − 1)(n − 1) − (c − 1) c / 2 of them.
fn interior_offset(b: i32, c: i32) -> u32 {
    let cm = u32(c - 1);
    return cm * (lattice_n() - 1u) - cm * (cm + 1u) / 2u + u32(b - 1);
}

// Interior point `local` → (b, c), without a loop over the rows: counted from the last point,
// r = I − 1 − local lies in the row of j = n − 1 − c points with j (j − 1) / 2 <= r < j (j + 1) / 2.
// The float estimate of j is corrected by the two loops, so the result is exact.
fn interior_coords(local: u32) -> vec2<i32> {
    let n = lattice_n();
    let ip = (n - 1u) * (n - 2u) / 2u;
    let r = ip - 1u - local;
    var j = u32(floor((1.0 + sqrt(1.0 + 8.0 * f32(r))) * 0.5));
    while (j * (j - 1u) / 2u > r) {
        j -= 1u;
    }
    while ((j + 1u) * j / 2u <= r) {
        j += 1u;
    }
    let b = i32(local - (ip - j * (j + 1u) / 2u)) + 1;
    return vec2<i32>(b, i32(n) - 1 - i32(j));
}

// Step 5: lattice point (b, c) of triangle t → output vertex index. A corner is its coarse
// vertex, an edge point is counted from the edge owner's v_e, an interior point by step 4.
fn vertex_index(t: u32, b: i32, c: i32) -> u32 {
    let n = i32(lattice_n());
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
        return lattice_interior_base(t) + interior_offset(b, c);
    }
    if (!edge_from_owner(t, e)) {
        k = n - k;
    }
    return lattice_edge_base(t, e) + u32(k - 1);
}

// Step 6: corners (b, c) of fine triangle `path`, descending the 1-to-4 split.
fn fine_corners(path: u32) -> array<vec2<i32>, 3> {
    let level = lattice_level();
    var c0 = vec2<i32>(0, 0);
    var sigma = 1;
    var s = i32(lattice_n());
    for (var k = 0u; k < level; k++) {
        let h = s / 2;
        let child = (path >> (2u * (level - 1u - k))) & 3u;
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

// Step 7, the inverse of step 6: the path of the fine triangle whose centroid, times 3, is q.
fn locate(q: vec2<i32>) -> u32 {
    let level = lattice_level();
    var c0 = vec2<i32>(0, 0);
    var sigma = 1;
    var s = i32(lattice_n());
    var path = 0u;
    for (var k = 0u; k < level; k++) {
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
