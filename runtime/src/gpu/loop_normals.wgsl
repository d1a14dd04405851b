// The vertex normals of a refined patch at its final level (subdivide.rs, `Patch::grid_normal`
// and `Patch::corner_normal`), written once for both patch kernels.
//
// The two kernels keep their patches in different memory: patch_main (loop.wgsl) in a scratch
// region of a storage buffer, patch_wg_main (loop_workgroup.wgsl) in workgroup memory, and WGSL
// cannot hand one function a pointer to either. So this file is a template: loop_kernel.rs
// instantiates it once per patch memory (wgsl.rs, `patch_normals`), replacing `{patch}` with the
// prefix of that memory's accessors: nothing for the scratch kernel (`sq_at`, `ring_at`), `wg_`
// for the workgroup kernel (`wg_sq_at`, `wg_ring_at`). Both accessors have one signature:
//
//   {patch}sq_at(sq, n, i, j)   lattice point (i, j) of the square at `sq` with n segments,
//   {patch}ring_at(rg, r)       point r of the ring set at `rg`, where the ring of a corner
//                               starts at its `ro` (the caller's: c * ring_cap in scratch
//                               memory, the sum of the valences before it in workgroup memory).
//
// The rest (`available`, `grid_neighbours`, `cross3`, `ring_next`, `Corner`) reads no patch
// memory and is loop.wgsl's, once.

// Area-weighted normal at lattice point (i, j), not a corner, from its six neighbours in
// counter-clockwise order, skipping faces across boundary edges: points across a boundary may
// be stale, but they only enter faces that are skipped.
fn {patch}grid_normal(sq: u32, flags: u32, n: i32, i: i32, j: i32) -> vec3<f32> {
    var d = grid_neighbours();
    var p: array<vec3<f32>, 6>;
    for (var k = 0u; k < 6u; k++) {
        p[k] = {patch}sq_at(sq, n, i + d[k].x, j + d[k].y);
    }
    let v = {patch}sq_at(sq, n, i, j);
    var s = vec3<f32>(0.0);
    for (var k = 0u; k < 6u; k++) {
        let k1 = (k + 1u) % 6u;
        let d0 = d[k];
        let d1 = d[k1];
        if (available(flags, n, i + d0.x, j + d0.y) && available(flags, n, i + d1.x, j + d1.y)) {
            s = s + cross3(p[k] - v, p[k1] - v);
        }
    }
    return s;
}

// Area-weighted normal at corner c, from the fan of its ring (the ring's last spoke closes the
// fan only around an interior vertex).
fn {patch}corner_normal(sq: u32, rg: u32, cr: Corner, ro: u32, n: i32, c: u32) -> vec3<f32> {
    let lc = corner_lattice(n, c);
    let v = {patch}sq_at(sq, n, lc.x, lc.y);
    var faces = cr.n;
    if (!cr.closed) {
        faces = cr.n - 1u;
    }
    var s = vec3<f32>(0.0);
    for (var f = 0u; f < faces; f++) {
        s = s + cross3({patch}ring_at(rg, ro + f) - v, {patch}ring_at(rg, ro + ring_next(f, cr.n)) - v);
    }
    return s;
}
