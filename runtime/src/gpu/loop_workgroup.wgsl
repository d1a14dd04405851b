// Step 1 of loop.wgsl, cooperative: a workgroup refines WG_TRIS coarse triangles at once, each
// triangle's patch in workgroup memory and its lattice points spread over WG_LANES
// invocations, with a barrier between the Loop steps. It imports loop.wgsl (whose rules, tables
// and bindings it uses) and expects a header that loop_kernel.rs generates per variant:
//
//   WG_LEVEL  the level L the variant refines to (the number of steps),
//   WG_TRIS   coarse triangles per workgroup (a power of two; 64 / WG_TRIS lanes each),
//   WG_SQ_A   floats of square region A (levels L, L - 2, ...), WG_SQ_B of region B
//             (levels L - 1, L - 3, ...),
//   WG_RING   floats of one ring set: the three corner rings of a triangle, one after another.
//
// Every point is computed by the same function of the previous level as in patch_main, in the
// same order of arithmetic with the same `keep` guards, so the positions are bitwise those of
// the CPU reference whichever lane computes them. Within a step each lane writes only its own
// points and reads only the previous level, so the result does not depend on scheduling.
//
// A square holds lattice points i >= -1, j >= -1, i + j <= n + 1 (the triangle, its three bands
// and a little slack) in rows of increasing j: about half the padded square of patch_main, which
// is what lets level 5 (666 + 210 points, 10.3 KiB) fit the 16 KiB WebGPU guarantees.
//
// The normals of the final level are loop_normals.wgsl's, instantiated for workgroup memory
// (`wg_grid_normal`, `wg_corner_normal` over `wg_sq_at` and `wg_ring_at`). The stencils of the
// Loop steps stay in two forms: here one function per point, which any lane can evaluate alone;
// in patch_main one serial pass per level, which reuses values across points (a corner's
// position for its whole ring, the new corners for the grid). Both apply the same rules of
// loop.wgsl (`mid`, `odd_smooth`, `even_crease`, `even_smooth`, with `keep`), and
// tests/gpu_loop.rs checks that the two kernels agree bit for bit.

// #import loop

const WG_LANES: u32 = 64u / WG_TRIS;
const WG_SLOT: u32 = WG_SQ_A + WG_SQ_B + 2u * WG_RING;

var<workgroup> wg_patch: array<f32, WG_TRIS * WG_SLOT>;

fn wg_index(n: i32, i: i32, j: i32) -> u32 {
    // Row j + 1 starts after rows of n + 4, n + 3, ... points.
    let jj = j + 1;
    return u32(jj * (n + 4) - (jj * (jj - 1)) / 2 + (i + 1));
}

fn wg_sq_at(base: u32, n: i32, i: i32, j: i32) -> vec3<f32> {
    let k = base + 3u * wg_index(n, i, j);
    return vec3<f32>(wg_patch[k], wg_patch[k + 1u], wg_patch[k + 2u]);
}

fn wg_sq_set(base: u32, n: i32, i: i32, j: i32, p: vec3<f32>) {
    let k = base + 3u * wg_index(n, i, j);
    wg_patch[k] = p.x;
    wg_patch[k + 1u] = p.y;
    wg_patch[k + 2u] = p.z;
}

// Point r of a ring set (ring points of corner c start at the sum of the valences before it).
fn wg_ring_at(base: u32, r: u32) -> vec3<f32> {
    let k = base + 3u * r;
    return vec3<f32>(wg_patch[k], wg_patch[k + 1u], wg_patch[k + 2u]);
}

fn wg_ring_set(base: u32, r: u32, p: vec3<f32>) {
    let k = base + 3u * r;
    wg_patch[k] = p.x;
    wg_patch[k + 1u] = p.y;
    wg_patch[k + 2u] = p.z;
}

// Points of the triangle i, j >= 0, i + j <= s.
fn tri_count(s: i32) -> u32 {
    if (s < 0) {
        return 0u;
    }
    return u32((s + 1) * (s + 2) / 2);
}

// Point idx of the triangle i + j <= s, folded into a rectangle so that a lane finds it with one
// division: row r and row s - r together hold s + 2 points.
fn fold(s: i32, idx: u32) -> vec2<i32> {
    let w = u32(s + 2);
    let r = i32(idx / w);
    let c = i32(idx % w);
    if (c <= s - r) {
        return vec2<i32>(c, r);
    }
    return vec2<i32>(c - (s - r + 1), s - r);
}

// Where the square and ring set of step k (n = 2^k) live: the final level always in region A
// and ring set 0, the levels before it alternating.
fn wg_square(slot_base: u32, k: u32) -> u32 {
    if (((WG_LEVEL - k) & 1u) == 0u) {
        return slot_base;
    }
    return slot_base + WG_SQ_A;
}

fn wg_rings(slot_base: u32, k: u32) -> u32 {
    let r = slot_base + WG_SQ_A + WG_SQ_B;
    if (((WG_LEVEL - k) & 1u) == 0u) {
        return r;
    }
    return r + WG_RING;
}

// What a lane knows of its triangle: the triangle, its flags, its slot in the workgroup and
// the number of ring points (the sum of the three valences).
struct WgTri {
    t: u32,
    flags: u32,
    slot: u32,
    rings: u32,
}

// Per-corner constants of the workgroup's triangles, loaded once by three lanes of each: a
// table in workgroup memory rather than an array in every lane, which naga would copy at every
// dynamic index.
var<workgroup> wg_corners: array<Corner, 3 * WG_TRIS>;
// First ring point of each corner in a ring set.
var<workgroup> wg_ro: array<u32, 3 * WG_TRIS>;

fn wcorner(tri: WgTri, c: u32) -> Corner {
    return wg_corners[3u * tri.slot + c];
}

fn wro(tri: WgTri, c: u32) -> u32 {
    return wg_ro[3u * tri.slot + c];
}

fn valence(t: u32, c: u32) -> u32 {
    let v = corner(t, c);
    return topo[params.ring_offsets_off + v + 1u] - topo[params.ring_offsets_off + v];
}

// Vertex s of the ring of corner c of triangle t.
fn ring_vertex(t: u32, c: u32, s: u32) -> u32 {
    return topo[params.ring_off + topo[params.ring_offsets_off + corner(t, c)] + s];
}

// The corner whose ring holds ring point r.
fn wring_corner(tri: WgTri, r: u32) -> u32 {
    if (r >= wro(tri, 2u)) {
        return 2u;
    }
    if (r >= wro(tri, 1u)) {
        return 1u;
    }
    return 0u;
}

// New ring point s of corner c (the odd vertex on spoke s), from the previous level.
fn wg_ring_point(sq: u32, rg: u32, tri: WgTri, n: i32, c: u32, s: u32) -> vec3<f32> {
    let cr = wcorner(tri, c);
    let ro = wro(tri, c);
    let lc = corner_lattice(n, c);
    let v = wg_sq_at(sq, n, lc.x, lc.y);
    let r = wg_ring_at(rg, ro + s);
    if (spoke_sharp(cr, s)) {
        return mid(v, r);
    }
    return odd_smooth(v, r, wg_ring_at(rg, ro + ring_prev(s, cr.n)),
                      wg_ring_at(rg, ro + ring_next(s, cr.n)));
}

// New position of corner c by its vertex rule, from the previous level.
fn wg_corner_point(sq: u32, rg: u32, tri: WgTri, n: i32, c: u32) -> vec3<f32> {
    let cr = wcorner(tri, c);
    let ro = wro(tri, c);
    let lc = corner_lattice(n, c);
    let v = wg_sq_at(sq, n, lc.x, lc.y);
    if (cr.rule == RULE_CORNER) {
        return v;
    }
    if (cr.rule == RULE_CREASE) {
        return even_crease(v, wg_ring_at(rg, ro + cr.crease0), wg_ring_at(rg, ro + cr.crease1));
    }
    var s = vec3<f32>(0.0);
    for (var q = 0u; q < cr.n; q++) {
        s = s + mid(v, wg_ring_at(rg, ro + q));
    }
    return even_smooth(v, s, w_of(cr.n), cf_of(cr.n));
}

// Even point (2i, 2j) of the new level: the vertex rule of grid point (i, j).
fn wg_even_point(sq: u32, rg: u32, tri: WgTri, n: i32, i: i32, j: i32) -> vec3<f32> {
    if (i == 0 && j == 0) {
        return wg_corner_point(sq, rg, tri, n, 0u);
    }
    if (i == n && j == 0) {
        return wg_corner_point(sq, rg, tri, n, 1u);
    }
    if (i == 0 && j == n) {
        return wg_corner_point(sq, rg, tri, n, 2u);
    }
    let v = wg_sq_at(sq, n, i, j);
    if (j == 0 && (tri.flags & (SHARP << 0u)) != 0u) {
        return even_crease(v, wg_sq_at(sq, n, i - 1, j), wg_sq_at(sq, n, i + 1, j));
    }
    if (i + j == n && (tri.flags & (SHARP << 1u)) != 0u) {
        return even_crease(v, wg_sq_at(sq, n, i + 1, j - 1), wg_sq_at(sq, n, i - 1, j + 1));
    }
    if (i == 0 && (tri.flags & (SHARP << 2u)) != 0u) {
        return even_crease(v, wg_sq_at(sq, n, i, j - 1), wg_sq_at(sq, n, i, j + 1));
    }
    var s = mid(v, wg_sq_at(sq, n, i + 1, j));
    s = s + mid(v, wg_sq_at(sq, n, i, j + 1));
    s = s + mid(v, wg_sq_at(sq, n, i - 1, j + 1));
    s = s + mid(v, wg_sq_at(sq, n, i - 1, j));
    s = s + mid(v, wg_sq_at(sq, n, i, j - 1));
    s = s + mid(v, wg_sq_at(sq, n, i + 1, j - 1));
    return even_smooth(v, s, w_of(6u), cf_of(6u));
}

// Band point q (0 ..= 2n - 1) of edge e of the new level: the two ends are ring points of the
// edge's corners, the others odd points between the edge and the previous band.
fn wg_band_point(sq: u32, rg: u32, tri: WgTri, n: i32, e: u32, q: i32) -> vec3<f32> {
    if (q == 0) {
        let c0 = wcorner(tri, e);
        return wg_ring_point(sq, rg, tri, n, e, (c0.k + c0.n - 1u) % c0.n);
    }
    if (q == 2 * n - 1) {
        let c1 = wcorner(tri, (e + 1u) % 3u);
        return wg_ring_point(sq, rg, tri, n, (e + 1u) % 3u, (c1.k + 2u) % c1.n);
    }
    let m = q / 2;
    let bl = band_lattice(n, e, m);
    let band_m = wg_sq_at(sq, n, bl.x, bl.y);
    let em = edge_lattice(n, e, m);
    let em1 = edge_lattice(n, e, m + 1);
    if ((q & 1) == 0) {
        let bp = band_lattice(n, e, m - 1);
        return odd_smooth(wg_sq_at(sq, n, em.x, em.y), band_m, wg_sq_at(sq, n, em1.x, em1.y),
                          wg_sq_at(sq, n, bp.x, bp.y));
    }
    let bn = band_lattice(n, e, m + 1);
    return odd_smooth(wg_sq_at(sq, n, em1.x, em1.y), band_m, wg_sq_at(sq, n, em.x, em.y),
                      wg_sq_at(sq, n, bn.x, bn.y));
}

// One level, n segments to 2n, this lane's share of it: the even points, the three kinds of odd
// points (each kind a triangle of its own, so neighbouring lanes take the same branch), the
// bands and the rings.
fn wg_step(sq: u32, nsq: u32, rg: u32, nrg: u32, tri: WgTri, n: i32, lane: u32) {
    let m2 = 2 * n;
    for (var idx = lane; idx < tri_count(n); idx += WG_LANES) {
        let p = fold(n, idx);
        wg_sq_set(nsq, m2, 2 * p.x, 2 * p.y, wg_even_point(sq, rg, tri, n, p.x, p.y));
    }
    let sharp0 = (tri.flags & (SHARP << 0u)) != 0u;
    let sharp1 = (tri.flags & (SHARP << 1u)) != 0u;
    let sharp2 = (tri.flags & (SHARP << 2u)) != 0u;
    // (2i + 1, 2j): between (i, j) and (i + 1, j).
    for (var idx = lane; idx < tri_count(n - 1); idx += WG_LANES) {
        let p = fold(n - 1, idx);
        let i = p.x;
        let j = p.y;
        let a = wg_sq_at(sq, n, i, j);
        let b = wg_sq_at(sq, n, i + 1, j);
        var r: vec3<f32>;
        if (j == 0 && sharp0) {
            r = mid(a, b);
        } else {
            r = odd_smooth(a, b, wg_sq_at(sq, n, i, j + 1), wg_sq_at(sq, n, i + 1, j - 1));
        }
        wg_sq_set(nsq, m2, 2 * i + 1, 2 * j, r);
    }
    // (2i, 2j + 1): between (i, j) and (i, j + 1).
    for (var idx = lane; idx < tri_count(n - 1); idx += WG_LANES) {
        let p = fold(n - 1, idx);
        let i = p.x;
        let j = p.y;
        let a = wg_sq_at(sq, n, i, j);
        let b = wg_sq_at(sq, n, i, j + 1);
        var r: vec3<f32>;
        if (i == 0 && sharp2) {
            r = mid(a, b);
        } else {
            r = odd_smooth(a, b, wg_sq_at(sq, n, i + 1, j), wg_sq_at(sq, n, i - 1, j + 1));
        }
        wg_sq_set(nsq, m2, 2 * i, 2 * j + 1, r);
    }
    // (2i + 1, 2j + 1): between (i + 1, j) and (i, j + 1).
    for (var idx = lane; idx < tri_count(n - 1); idx += WG_LANES) {
        let p = fold(n - 1, idx);
        let i = p.x;
        let j = p.y;
        let a = wg_sq_at(sq, n, i + 1, j);
        let b = wg_sq_at(sq, n, i, j + 1);
        var r: vec3<f32>;
        if (i + j + 1 == n && sharp1) {
            r = mid(a, b);
        } else {
            r = odd_smooth(a, b, wg_sq_at(sq, n, i, j), wg_sq_at(sq, n, i + 1, j + 1));
        }
        wg_sq_set(nsq, m2, 2 * i + 1, 2 * j + 1, r);
    }
    // Bands of the edges that have a neighbour.
    let per_band = u32(m2);
    for (var idx = lane; idx < 3u * per_band; idx += WG_LANES) {
        let e = idx / per_band;
        let q = i32(idx % per_band);
        if ((tri.flags & (INTERIOR << e)) != 0u) {
            let l = band_lattice(m2, e, q);
            wg_sq_set(nsq, m2, l.x, l.y, wg_band_point(sq, rg, tri, n, e, q));
        }
    }
    // Rings.
    for (var r = lane; r < tri.rings; r += WG_LANES) {
        let c = wring_corner(tri, r);
        wg_ring_set(nrg, r, wg_ring_point(sq, rg, tri, n, c, r - wro(tri, c)));
    }
}

@compute @workgroup_size(64)
fn patch_wg_main(@builtin(local_invocation_index) lid: u32,
                 @builtin(workgroup_id) wid: vec3<u32>,
                 @builtin(num_workgroups) groups: vec3<u32>) {
    let slot = lid / WG_LANES;
    let lane = lid % WG_LANES;
    let slot_base = slot * WG_SLOT;
    let t = params.range_first + (wid.x + wid.y * groups.x) * WG_TRIS + slot;
    // Lanes past the last triangle (of the mesh or of the dispatch's range) idle but still
    // meet every barrier.
    let live = t < min(params.triangle_count, params.range_end);
    // Three lanes per triangle fill its corner table; every lane counts its ring points. Level 0
    // (the three corners, the one opposite vertex per band and the rings, straight from the
    // coarse positions) reads the tables directly, so one barrier serves both.
    var tri: WgTri;
    tri.slot = slot;
    if (live) {
        tri.t = t;
        tri.flags = topo[params.tri_flags_off + t];
        let n = vec3<u32>(valence(t, 0u), valence(t, 1u), valence(t, 2u));
        let ro = vec3<u32>(0u, n.x, n.x + n.y);
        tri.rings = ro.z + n.z;
        if (lane < 3u) {
            wg_corners[3u * slot + lane] = load_corner(t, lane);
            wg_ro[3u * slot + lane] = ro[lane];
        }
        let sq = wg_square(slot_base, 0u);
        let rg = wg_rings(slot_base, 0u);
        for (var idx = lane; idx < 6u + tri.rings; idx += WG_LANES) {
            if (idx < 3u) {
                let lc = corner_lattice(1, idx);
                wg_sq_set(sq, 1, lc.x, lc.y, coarse_position(corner(t, idx)));
            } else if (idx < 6u) {
                let e = idx - 3u;
                if ((tri.flags & (INTERIOR << e)) != 0u) {
                    let k = topo[params.corner_spokes_off + 3u * t + e];
                    let s = (k + n[e] - 1u) % n[e];
                    let l = band_lattice(1, e, 0);
                    wg_sq_set(sq, 1, l.x, l.y, coarse_position(ring_vertex(t, e, s)));
                }
            } else {
                let r = idx - 6u;
                var c = 0u;
                if (r >= ro.z) {
                    c = 2u;
                } else if (r >= ro.y) {
                    c = 1u;
                }
                wg_ring_set(rg, r, coarse_position(ring_vertex(t, c, r - ro[c])));
            }
        }
    }
    workgroupBarrier();

    // The Loop steps, each reading the level before the barrier.
    for (var k = 0u; k < WG_LEVEL; k++) {
        if (live) {
            wg_step(wg_square(slot_base, k), wg_square(slot_base, k + 1u), wg_rings(slot_base, k),
                    wg_rings(slot_base, k + 1u), tri, i32(1u << k), lane);
        }
        workgroupBarrier();
    }

    // Owned output vertices, numbered as subdivide.rs numbers them: corners, edge points, then
    // interior points in rows of increasing j.
    if (live) {
        let sq = wg_square(slot_base, WG_LEVEL);
        let rg = wg_rings(slot_base, WG_LEVEL);
        let mm = i32(params.m);
        let per_edge = params.m - 1u;
        let interior = params.coarse_vertices + params.edge_count * per_edge + t * params.per_tri;
        for (var idx = lane; idx < 3u + 3u * per_edge + params.per_tri; idx += WG_LANES) {
            if (idx < 3u) {
                if ((tri.flags & (OWNS_VERTEX << idx)) != 0u) {
                    let lc = corner_lattice(mm, idx);
                    write_vertex(corner(t, idx), wg_sq_at(sq, mm, lc.x, lc.y),
                                 normalize_or_z(wg_corner_normal(sq, rg, wcorner(tri, idx), wro(tri, idx), mm, idx)));
                }
            } else if (idx < 3u + 3u * per_edge) {
                let e = (idx - 3u) / per_edge;
                let k = i32((idx - 3u) % per_edge) + 1;
                if ((tri.flags & (OWNS_EDGE << e)) != 0u) {
                    let ebase = params.coarse_vertices + topo[params.edges_off + 3u * t + e] * per_edge;
                    let l = edge_lattice(mm, e, k);
                    write_vertex(ebase + u32(k - 1), wg_sq_at(sq, mm, l.x, l.y),
                                 normalize_or_z(wg_grid_normal(sq, tri.flags, mm, l.x, l.y)));
                }
            } else {
                let p = fold(mm - 3, idx - 3u - 3u * per_edge);
                let i = p.x + 1;
                let j = p.y + 1;
                let jm = u32(j - 1);
                let row = jm * (params.m - 1u) - jm * (jm + 1u) / 2u;
                write_vertex(interior + row + u32(i - 1), wg_sq_at(sq, mm, i, j),
                             normalize_or_z(wg_grid_normal(sq, tri.flags, mm, i, j)));
            }
        }
    }
}
