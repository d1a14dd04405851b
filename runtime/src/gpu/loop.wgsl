// Loop subdivision of a multiresolution object to level L with HCE colours: a port of the CPU
// reference in geometry/src/subdivide.rs (local patch, order of arithmetic, output numbering)
// and of geometry/src/colour.rs (colour per subtriangle, area-weighted vertex colours).
//
// Three dispatches, each a pure gather or an owned write, so the result does not depend on
// scheduling (no atomics):
//   step 1       the patches, by one of two kernels (loop_kernel.rs chooses, `PatchScheme`):
//                patch_wg_main (loop_workgroup.wgsl, which imports this file) refines 1 to 16
//                coarse triangles per workgroup in workgroup memory, the lattice points of each
//                level spread over the invocations; patch_main, below, runs one invocation per
//                coarse triangle (grid-stride over scratch slots) with the patch in a scratch
//                region of a storage buffer. Both write the positions and normals of the output
//                vertices each triangle owns; the normals are loop_normals.wgsl's, a template
//                instantiated once per patch memory.
//   faces_main   one invocation per fine triangle: its indices, area and HCE colour.
//   colours_main one invocation per output vertex: area-weighted mean of the incident fine
//                triangles, across coarse edges and vertices.
//
// patch_main keeps its padded square (n + 3)^2 in storage memory: at level 5 its two squares
// take 2 x 35^2 x 12 = 29 KiB per triangle and level 6 needs 105 KiB, beyond the 16 KiB of
// workgroup memory WebGPU guarantees. It serves level 6, extreme valences, and software
// adapters, where it is faster than the workgroup kernel (llvmpipe runs shaders with barriers
// as coroutines); the Rust side bounds the number of slots.
//
// The CPU reference rounds every product and sum separately. SPIR-V from naga lets the driver
// contract a * b + c into a fused multiply-add (Mesa does), which moves positions by an ulp, so
// every product by a factor that is not a power of two goes through `keep`, a select on a
// uniform the compiler cannot see through; products by 0.5, 0.25 and 0.125 are exact and need
// no guard (a fused and an unfused sum of an exact product round alike).

// #import hce_constants
// #import hce_bindings
// #import hce_tree
// #import hce_light
// #import hce_lattice
// #import hce_gather

struct Params {
    level: u32,
    m: u32,
    coarse_vertices: u32,
    edge_count: u32,
    triangle_count: u32,
    per_edge: u32,
    per_tri: u32,
    vertex_total: u32,
    fine_total: u32,
    slots: u32,
    // Floats per scratch square and per ring set (3 corners x ring_cap points).
    square_floats: u32,
    ring_cap: u32,
    // Offsets (in u32 words) of the sections packed into `topo`.
    tri_off: u32,
    ring_offsets_off: u32,
    ring_off: u32,
    spoke_flags_off: u32,
    vertex_flags_off: u32,
    corner_spokes_off: u32,
    edges_off: u32,
    tri_flags_off: u32,
    crease_off: u32,
    weights_off: u32,
    edge_side_offsets_off: u32,
    edge_sides_off: u32,
    vertex_corner_offsets_off: u32,
    vertex_corners_off: u32,
    // The split at sharp edges (SPEC.md F.5, geometry/src/split.rs): per corner its region's
    // copy (or NO_COPY), per edge id its rank among the split edges (or NO_COPY), per corner
    // slot then per edge slot 1 where the slot is a region of a split vertex. The incidence
    // sections above are the split's slot lists: V + X corner slots, E + S edge slots.
    corner_copy_off: u32,
    edge_copy_off: u32,
    slot_split_off: u32,
    // Always 1: the opaque condition of `keep`.
    exact: u32,
    // 1: smooth reconstruction (hce_light.wgsl), 0: the paper's nearest normal.
    smooth_light: u32,
    // The first appended vertex (the F.5 count) and the number X of corner copies.
    split_base: u32,
    split_copies: u32,
    // The range of this dispatch's items (coarse triangles in step 1, fine triangles in step
    // 2, output vertices in step 3): items range_first .. min(total, range_end). A refinement
    // split over frames dispatches each step in pieces (runtime/src/gpu/job.rs); a one-shot
    // refinement passes 0 and 0xffffffff.
    range_first: u32,
    range_end: u32,
}


// The bits of the per-triangle flags word (OWNS_EDGE, OWNS_VERTEX, INTERIOR, SHARP) and of the
// file's flags (RULE_CREASE, RULE_CORNER, SPOKE_SHARP, VERTEX_BOUNDARY) come from
// hce_constants.wgsl, generated from the Rust constants.

// The parameters every function reads: the kernel's uniform. The batched kernel
// (loop_batch.wgsl) is assembled with this declaration made a private variable, which each of
// its invocations sets from its object's entry of the batch table: read from private memory,
// the per-object kernels' steps ran up to 17 times slower on lavapipe (the colours step of a
// 2,048-triangle grid at level 1: 3.5 against 61 ms), so they keep the uniform. The other
// bindings are hce_bindings.wgsl's.
@group(0) @binding(0) var<uniform> params: Params;

// ---------------------------------------------------------------------------------------------
// The Loop rules, in the CPU's order of arithmetic.

// `x`, rounded on its own: no fused multiply-add may absorb the product that produced it.
fn keep(x: vec3<f32>) -> vec3<f32> {
    return select(vec3<f32>(0.0), x, params.exact != 0u);
}

fn mid(a: vec3<f32>, b: vec3<f32>) -> vec3<f32> {
    return (a + b) * 0.5;
}

fn odd_smooth(a: vec3<f32>, b: vec3<f32>, c: vec3<f32>, d: vec3<f32>) -> vec3<f32> {
    return keep((a + b) * 0.375) + (c + d) * 0.125;
}

fn even_crease(v: vec3<f32>, a: vec3<f32>, b: vec3<f32>) -> vec3<f32> {
    return keep(v * 0.75) + (a + b) * 0.125;
}

// `w` is 0.75 / k rounded once on the CPU (a WGSL division need not be correctly rounded).
fn even_smooth(v: vec3<f32>, sum_mid: vec3<f32>, w: f32, cf: f32) -> vec3<f32> {
    let avg = v * 0.25 + keep(sum_mid * w);
    return v + keep((avg - v) * cf);
}

// Neighbours of spoke s in a ring of n, without the integer division of a modulo (which SIMD
// hardware, lavapipe's included, does lane by lane).
fn ring_prev(s: u32, n: u32) -> u32 {
    return select(s - 1u, n - 1u, s == 0u);
}

fn ring_next(s: u32, n: u32) -> u32 {
    return select(s + 1u, 0u, s + 1u == n);
}

fn cf_of(k: u32) -> f32 {
    return bitcast<f32>(topo[params.weights_off + 2u * k]);
}

fn w_of(k: u32) -> f32 {
    return bitcast<f32>(topo[params.weights_off + 2u * k + 1u]);
}

fn cross3(a: vec3<f32>, b: vec3<f32>) -> vec3<f32> {
    return vec3<f32>(a.y * b.z - a.z * b.y, a.z * b.x - a.x * b.z, a.x * b.y - a.y * b.x);
}

fn normalize_or_z(s: vec3<f32>) -> vec3<f32> {
    let l = sqrt(s.x * s.x + s.y * s.y + s.z * s.z);
    // l == l and l < inf: finite (the CPU's `is_finite`).
    if (l > 0.0 && l < 3.402823e38) {
        return s * (1.0 / l);
    }
    return vec3<f32>(0.0, 0.0, 1.0);
}

// ---------------------------------------------------------------------------------------------
// The patch in scratch memory. A slot holds two squares (current and next level) over lattice
// points -1 ..= n + 1, index (i + 1) + (j + 1)(n + 3), three floats each, and two ring sets
// (3 corners x ring_cap points). Lattice point (i, j) is v0 + i/n (v1 - v0) + j/n (v2 - v0).
// The slots are interleaved: float k of slot s is scratch[k * slots + s], so neighbouring
// invocations, which work on the same point of different triangles, touch neighbouring words
// (coalesced on a GPU, one cache line per eight lanes on lavapipe).

// This invocation's slot (set once by patch_main, or patch_batch_main in loop_batch.wgsl).
var<private> slot_id: u32;

fn scratch_at(k: u32) -> vec3<f32> {
    let s = params.slots;
    return vec3<f32>(scratch[k * s + slot_id], scratch[(k + 1u) * s + slot_id],
                     scratch[(k + 2u) * s + slot_id]);
}

fn scratch_set(k: u32, p: vec3<f32>) {
    let s = params.slots;
    scratch[k * s + slot_id] = p.x;
    scratch[(k + 1u) * s + slot_id] = p.y;
    scratch[(k + 2u) * s + slot_id] = p.z;
}

fn sq_at(base: u32, n: i32, i: i32, j: i32) -> vec3<f32> {
    return scratch_at(base + 3u * u32((i + 1) + (j + 1) * (n + 3)));
}

fn sq_set(base: u32, n: i32, i: i32, j: i32, p: vec3<f32>) {
    scratch_set(base + 3u * u32((i + 1) + (j + 1) * (n + 3)), p);
}

// Point r of a ring set: ring point s of corner c is r = c * ring_cap + s.
fn ring_at(base: u32, r: u32) -> vec3<f32> {
    return scratch_at(base + 3u * r);
}

fn ring_set(base: u32, r: u32, p: vec3<f32>) {
    scratch_set(base + 3u * r, p);
}

// Lattice point of band point m of edge e (corners and edge points: hce_lattice.wgsl).
fn band_lattice(n: i32, e: u32, m: i32) -> vec2<i32> {
    if (e == 0u) { return vec2<i32>(m + 1, -1); }
    if (e == 1u) { return vec2<i32>(n - m, m + 1); }
    return vec2<i32>(-1, n - m);
}

// Per-corner constants of the current triangle, read from the tables once.
struct Corner {
    off: u32,
    n: u32,
    k: u32,
    closed: bool,
    rule: u32,
    crease0: u32,
    crease1: u32,
}

fn load_corner(t: u32, c: u32) -> Corner {
    let v = corner(t, c);
    let off = topo[params.ring_offsets_off + v];
    let n = topo[params.ring_offsets_off + v + 1u] - off;
    let vf = topo[params.vertex_flags_off + v];
    return Corner(off, n, topo[params.corner_spokes_off + 3u * t + c], (vf & VERTEX_BOUNDARY) == 0u,
                  (vf >> 1u) & 3u, topo[params.crease_off + 2u * v], topo[params.crease_off + 2u * v + 1u]);
}

fn spoke_sharp(cr: Corner, s: u32) -> bool {
    return (topo[params.spoke_flags_off + cr.off + s] & SPOKE_SHARP) != 0u;
}

// One level, n segments to 2n: rings and corners, then the grid in rows of increasing j, then
// the bands (subdivide.rs, `Patch::step`).
fn refine_step(sq: u32, nsq: u32, rg: u32, nrg: u32, corners: array<Corner, 3>, flags: u32, n: i32) {
    // Indexed dynamically below: a variable, not a value (naga copies a value array to a
    // temporary at every dynamic index).
    var cs = corners;
    var new_corner: array<vec3<f32>, 3>;
    for (var c = 0u; c < 3u; c++) {
        let cr = cs[c];
        let ro = c * params.ring_cap;
        let lc = corner_lattice(n, c);
        let v = sq_at(sq, n, lc.x, lc.y);
        for (var s = 0u; s < cr.n; s++) {
            let r = ring_at(rg, ro + s);
            var p: vec3<f32>;
            if (spoke_sharp(cr, s)) {
                p = mid(v, r);
            } else {
                p = odd_smooth(v, r, ring_at(rg, ro + ring_prev(s, cr.n)), ring_at(rg, ro + ring_next(s, cr.n)));
            }
            ring_set(nrg, ro + s, p);
        }
        if (cr.rule == RULE_CORNER) {
            new_corner[c] = v;
        } else if (cr.rule == RULE_CREASE) {
            new_corner[c] = even_crease(v, ring_at(rg, ro + cr.crease0), ring_at(rg, ro + cr.crease1));
        } else {
            var s = vec3<f32>(0.0);
            for (var q = 0u; q < cr.n; q++) {
                s = s + mid(v, ring_at(rg, ro + q));
            }
            new_corner[c] = even_smooth(v, s, w_of(cr.n), cf_of(cr.n));
        }
    }
    let sharp0 = (flags & (SHARP << 0u)) != 0u;
    let sharp1 = (flags & (SHARP << 1u)) != 0u;
    let sharp2 = (flags & (SHARP << 2u)) != 0u;
    let cf6 = cf_of(6u);
    let w6 = w_of(6u);
    let m2 = 2 * n;
    for (var jj = 0; jj <= m2; jj++) {
        for (var ii = 0; ii <= m2 - jj; ii++) {
            let i = ii / 2;
            let j = jj / 2;
            var p: vec3<f32>;
            if ((ii & 1) == 0 && (jj & 1) == 0) {
                if (i == 0 && j == 0) {
                    p = new_corner[0];
                } else if (i == n && j == 0) {
                    p = new_corner[1];
                } else if (i == 0 && j == n) {
                    p = new_corner[2];
                } else {
                    let v = sq_at(sq, n, i, j);
                    if (j == 0 && sharp0) {
                        p = even_crease(v, sq_at(sq, n, i - 1, j), sq_at(sq, n, i + 1, j));
                    } else if (i + j == n && sharp1) {
                        p = even_crease(v, sq_at(sq, n, i + 1, j - 1), sq_at(sq, n, i - 1, j + 1));
                    } else if (i == 0 && sharp2) {
                        p = even_crease(v, sq_at(sq, n, i, j - 1), sq_at(sq, n, i, j + 1));
                    } else {
                        var s = mid(v, sq_at(sq, n, i + 1, j));
                        s = s + mid(v, sq_at(sq, n, i, j + 1));
                        s = s + mid(v, sq_at(sq, n, i - 1, j + 1));
                        s = s + mid(v, sq_at(sq, n, i - 1, j));
                        s = s + mid(v, sq_at(sq, n, i, j - 1));
                        s = s + mid(v, sq_at(sq, n, i + 1, j - 1));
                        p = even_smooth(v, s, w6, cf6);
                    }
                }
            } else if ((jj & 1) == 0) {
                // (1, 0): between (i, j) and (i + 1, j).
                let a = sq_at(sq, n, i, j);
                let b = sq_at(sq, n, i + 1, j);
                if (j == 0 && sharp0) {
                    p = mid(a, b);
                } else {
                    p = odd_smooth(a, b, sq_at(sq, n, i, j + 1), sq_at(sq, n, i + 1, j - 1));
                }
            } else if ((ii & 1) == 0) {
                // (0, 1): between (i, j) and (i, j + 1).
                let a = sq_at(sq, n, i, j);
                let b = sq_at(sq, n, i, j + 1);
                if (i == 0 && sharp2) {
                    p = mid(a, b);
                } else {
                    p = odd_smooth(a, b, sq_at(sq, n, i + 1, j), sq_at(sq, n, i - 1, j + 1));
                }
            } else {
                // (1, 1): between (i + 1, j) and (i, j + 1).
                let a = sq_at(sq, n, i + 1, j);
                let b = sq_at(sq, n, i, j + 1);
                if (i + j + 1 == n && sharp1) {
                    p = mid(a, b);
                } else {
                    p = odd_smooth(a, b, sq_at(sq, n, i, j), sq_at(sq, n, i + 1, j + 1));
                }
            }
            sq_set(nsq, m2, ii, jj, p);
        }
    }
    for (var e = 0u; e < 3u; e++) {
        if ((flags & (INTERIOR << e)) == 0u) {
            continue;
        }
        let c0 = cs[e];
        let c1 = cs[(e + 1u) % 3u];
        var q = 0;
        var l = band_lattice(m2, e, q);
        sq_set(nsq, m2, l.x, l.y, ring_at(nrg, e * params.ring_cap + (c0.k + c0.n - 1u) % c0.n));
        q++;
        for (var m = 0; m < n; m++) {
            let bl = band_lattice(n, e, m);
            let band_m = sq_at(sq, n, bl.x, bl.y);
            let em = edge_lattice(n, e, m);
            let em1 = edge_lattice(n, e, m + 1);
            if (m >= 1) {
                let bp = band_lattice(n, e, m - 1);
                l = band_lattice(m2, e, q);
                sq_set(nsq, m2, l.x, l.y, odd_smooth(sq_at(sq, n, em.x, em.y), band_m,
                                                     sq_at(sq, n, em1.x, em1.y), sq_at(sq, n, bp.x, bp.y)));
                q++;
            }
            if (m + 2 <= n) {
                let bn = band_lattice(n, e, m + 1);
                l = band_lattice(m2, e, q);
                sq_set(nsq, m2, l.x, l.y, odd_smooth(sq_at(sq, n, em1.x, em1.y), band_m,
                                                     sq_at(sq, n, em.x, em.y), sq_at(sq, n, bn.x, bn.y)));
                q++;
            }
        }
        l = band_lattice(m2, e, q);
        sq_set(nsq, m2, l.x, l.y, ring_at(nrg, ((e + 1u) % 3u) * params.ring_cap + (c1.k + 2u) % c1.n));
    }
}

// The vertex normals of the final level, `grid_normal` and `corner_normal`, are in
// loop_normals.wgsl, written once for the scratch memory of this kernel and the workgroup memory
// of loop_workgroup.wgsl; these are the parts that read no patch memory.

// Whether lattice neighbour (a, b) of the patch exists (is not across a boundary edge).
fn available(flags: u32, n: i32, a: i32, b: i32) -> bool {
    return (b >= 0 || (flags & (INTERIOR << 0u)) != 0u)
        && (a >= 0 || (flags & (INTERIOR << 2u)) != 0u)
        && (a + b <= n || (flags & (INTERIOR << 1u)) != 0u);
}

// The six lattice neighbours of a grid point, counter-clockwise from (1, 0).
fn grid_neighbours() -> array<vec2<i32>, 6> {
    return array<vec2<i32>, 6>(vec2<i32>(1, 0), vec2<i32>(0, 1), vec2<i32>(-1, 1),
                               vec2<i32>(-1, 0), vec2<i32>(0, -1), vec2<i32>(1, -1));
}

fn write_vertex(i: u32, p: vec3<f32>, nrm: vec3<f32>) {
    let index = lattice_out_base + i;
    out_positions[3u * index] = p.x;
    out_positions[3u * index + 1u] = p.y;
    out_positions[3u * index + 2u] = p.z;
    out_normals[3u * index] = nrm.x;
    out_normals[3u * index + 1u] = nrm.y;
    out_normals[3u * index + 2u] = nrm.z;
}

// Step 1 (one invocation per scratch slot, striding over the coarse triangles): refine the
// triangle's patch from level 0 to L and write the vertices it owns.
@compute @workgroup_size(64)
fn patch_main(@builtin(global_invocation_id) gid: vec3<u32>,
              @builtin(num_workgroups) groups: vec3<u32>) {
    let slot = linear_id(gid, groups);
    if (slot >= params.slots) {
        return;
    }
    slot_id = slot;
    let t_end = min(params.triangle_count, params.range_end);
    for (var t = params.range_first + slot; t < t_end; t += params.slots) {
        loop_patch(t);
    }
}

// Refines coarse triangle t's patch in this invocation's scratch slot (`slot_id`, of
// `params.slots`) and writes the vertices it owns.
fn loop_patch(t: u32) {
    let ring_floats = 9u * params.ring_cap;
    let sq_a = 0u;
    let sq_b = params.square_floats;
    let rg_a = 2u * params.square_floats;
    let rg_b = rg_a + ring_floats;
    let mm = i32(params.m);
    var cs = array<Corner, 3>(load_corner(t, 0u), load_corner(t, 1u), load_corner(t, 2u));
    let flags = topo[params.tri_flags_off + t];
    // Level 0: the three corners, their rings and the one opposite vertex per band.
    for (var c = 0u; c < 3u; c++) {
        let lc = corner_lattice(1, c);
        sq_set(sq_a, 1, lc.x, lc.y, coarse_position(corner(t, c)));
        for (var s = 0u; s < cs[c].n; s++) {
            ring_set(rg_a, c * params.ring_cap + s, coarse_position(topo[params.ring_off + cs[c].off + s]));
        }
    }
    for (var e = 0u; e < 3u; e++) {
        if ((flags & (INTERIOR << e)) != 0u) {
            let cr = cs[e];
            let l = band_lattice(1, e, 0);
            sq_set(sq_a, 1, l.x, l.y, ring_at(rg_a, e * params.ring_cap + (cr.k + cr.n - 1u) % cr.n));
        }
    }
    // Ping-pong between the two squares and ring sets.
    var sq = sq_a;
    var nsq = sq_b;
    var rg = rg_a;
    var nrg = rg_b;
    var n = 1;
    while (n < mm) {
        refine_step(sq, nsq, rg, nrg, cs, flags, n);
        let ts = sq;
        sq = nsq;
        nsq = ts;
        let tr = rg;
        rg = nrg;
        nrg = tr;
        n *= 2;
    }
    // Owned output vertices, numbered as subdivide.rs numbers them.
    for (var c = 0u; c < 3u; c++) {
        if ((flags & (OWNS_VERTEX << c)) != 0u) {
            let lc = corner_lattice(mm, c);
            write_vertex(corner(t, c), sq_at(sq, mm, lc.x, lc.y),
                         normalize_or_z(corner_normal(sq, rg, cs[c], c * params.ring_cap, mm, c)));
        }
    }
    for (var e = 0u; e < 3u; e++) {
        if ((flags & (OWNS_EDGE << e)) == 0u) {
            continue;
        }
        let ebase = params.coarse_vertices + topo[params.edges_off + 3u * t + e] * params.per_edge;
        for (var k = 1; k < mm; k++) {
            let l = edge_lattice(mm, e, k);
            write_vertex(ebase + u32(k - 1), sq_at(sq, mm, l.x, l.y),
                         normalize_or_z(grid_normal(sq, flags, mm, l.x, l.y)));
        }
    }
    var q = params.coarse_vertices + params.edge_count * params.per_edge + t * params.per_tri;
    for (var j = 1; j < mm; j++) {
        for (var i = 1; i < mm - j; i++) {
            write_vertex(q, sq_at(sq, mm, i, j), normalize_or_z(grid_normal(sq, flags, mm, i, j)));
            q++;
        }
    }
}

// ---------------------------------------------------------------------------------------------
// Fine triangles, on the lattice of hce_lattice.wgsl (the recursive 1-to-4 split of
// `subtriangle_cells` in geometry/src/lattice.rs). An edge's points are counted from the vertex of its owner, the
// triangle whose OWNS_EDGE flag is set.

fn lattice_level() -> u32 {
    return params.level;
}

fn lattice_n() -> u32 {
    return params.m;
}

fn edge_from_owner(t: u32, e: u32) -> bool {
    return (topo[params.tri_flags_off + t] & (OWNS_EDGE << e)) != 0u;
}

fn lattice_edge_base(t: u32, e: u32) -> u32 {
    return params.coarse_vertices + topo[params.edges_off + 3u * t + e] * params.per_edge;
}

fn lattice_interior_base(t: u32) -> u32 {
    return params.coarse_vertices + params.edge_count * params.per_edge + t * params.per_tri;
}

fn lattice_split_base() -> u32 {
    return params.split_base;
}

fn lattice_split_copies() -> u32 {
    return params.split_copies;
}

// Step 2 (one invocation per fine triangle): its indices, then its area and, for the paper's
// rule, its colour from the positions of step 1: the tree node along its path and the
// representative normal with the largest dot product with its (unnormalised) face normal, as
// colour.rs chooses them. The smooth reconstruction colours vertices in step 3 instead.
@compute @workgroup_size(64)
fn faces_main(@builtin(global_invocation_id) gid: vec3<u32>,
              @builtin(num_workgroups) groups: vec3<u32>) {
    let g = params.range_first + linear_id(gid, groups);
    if (g >= min(params.fine_total, params.range_end)) {
        return;
    }
    loop_face(g);
}

fn loop_face(g: u32) {
    // 4^L fine triangles per coarse one: a shift and a mask, not a division.
    let t = g >> (2u * params.level);
    let path = g & ((1u << (2u * params.level)) - 1u);
    let cs = fine_corners(path);
    let i0 = vertex_index(t, cs[0].x, cs[0].y);
    let i1 = vertex_index(t, cs[1].x, cs[1].y);
    let i2 = vertex_index(t, cs[2].x, cs[2].y);
    // Drawn with the split vertices; measured with the F.5 ones, whose positions step 1 wrote
    // (the copies get theirs in step 3).
    let o = 3u * (gather_face_base + g);
    out_indices[o] = split_index(t, cs[0].x, cs[0].y, i0);
    out_indices[o + 1u] = split_index(t, cs[1].x, cs[1].y, i1);
    out_indices[o + 2u] = split_index(t, cs[2].x, cs[2].y, i2);

    let p0 = out_position(i0);
    let x = cross3(out_position(i1) - p0, out_position(i2) - p0);
    let len = sqrt(x.x * x.x + x.y * x.y + x.z * x.z);
    var rgb = vec3<f32>(0.0);
    if (params.smooth_light == 0u) {
        rgb = hce_nearest_colour(t, params.level, path, x);
    }
    out_faces[gather_face_base + g] = vec4<f32>(rgb, 0.5 * len);
}

// Step 3 (one invocation per output vertex, copies of the split included): a copy takes its
// original's position; a region of a split vertex its own region's normal (SPEC.md F.6); then
// the area-weighted mean colour of the fine triangles of its region (hce_gather.wgsl), the
// smooth field evaluated for the vertex's normal.
@compute @workgroup_size(64)
fn colours_main(@builtin(global_invocation_id) gid: vec3<u32>,
                @builtin(num_workgroups) groups: vec3<u32>) {
    let v = params.range_first + linear_id(gid, groups);
    if (v >= min(params.vertex_total, params.range_end)) {
        return;
    }
    loop_colour(v);
}

fn loop_colour(v: u32) {
    let slot = vertex_slot(v);
    // Where vertex v is written in the output buffers (past the first vertices of the objects
    // before it in a batch).
    let o = 3u * (lattice_out_base + v);
    if (v >= params.split_base) {
        let p = out_position(slot_source(slot));
        out_positions[o] = p.x;
        out_positions[o + 1u] = p.y;
        out_positions[o + 2u] = p.z;
    }
    var normal = vec3<f32>(out_normals[o], out_normals[o + 1u], out_normals[o + 2u]);
    var split = 0u;
    if (slot.kind == SLOT_CORNER) {
        split = topo[params.slot_split_off + slot.index];
    } else if (slot.kind == SLOT_EDGE) {
        split = topo[params.slot_split_off + params.coarse_vertices + params.split_copies + slot.index];
    }
    if (split != 0u) {
        normal = normalize_or_z(region_normal(slot));
        out_normals[o] = normal.x;
        out_normals[o + 1u] = normal.y;
        out_normals[o + 2u] = normal.z;
    }
    if (params.smooth_light == 0u) {
        normal = vec3<f32>(0.0);
    }
    out_colours[lattice_out_base + v] = vec4<f32>(slot_colour(slot, normal), 1.0);
}
