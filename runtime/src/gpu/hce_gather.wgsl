// Vertex colours of a refined object: the area-weighted mean of the colours of the fine
// triangles around each output vertex, across coarse edges and vertices (geometry/src/colour.rs,
// geometry/src/lattice.rs `incident_paths`), shared by flat.wgsl and loop.wgsl. A pure gather with one
// writer per vertex and a fixed order of summation, so the result does not depend on scheduling.
//
// This file is prepended after hce_tree.wgsl, hce_light.wgsl and hce_lattice.wgsl to a kernel
// that declares, with these names:
//   params:     the kernel's uniform, with `level`, `coarse_vertices`, `edge_count`,
//               `edge_side_offsets_off`, `edge_sides_off`, `vertex_corner_offsets_off`,
//               `vertex_corners_off` (sections of `topo`) and `smooth_light`
//   topo:       array<u32>
//   out_faces:  array<vec4<f32>>   per fine triangle: its colour and, in w, its area

// Step 1: area-weighted sums, with a plain mean as the fallback for zero-area neighbourhoods.
struct Acc {
    weighted: vec3<f32>,
    area: f32,
    plain: vec3<f32>,
    count: f32,
    // The vertex's unit normal, for which the smooth reconstruction evaluates the field (zero
    // where the field does not depend on it: a flat object has one normal per triangle).
    normal: vec3<f32>,
}

fn acc_add(acc: ptr<function, Acc>, g: u32) {
    let f = out_faces[g];
    (*acc).weighted = (*acc).weighted + f.xyz * f.w;
    (*acc).plain += f.xyz;
    (*acc).area += f.w;
    (*acc).count += 1.0;
}

// Step 2: add the fine triangles of coarse triangle t around lattice point (b, c), in the fixed
// order of hce_geometry::lattice::incident_paths: up triangles at (b, c), (b − 1, c), (b, c − 1), then
// down triangles at (b, c), (b + 1, c), (b, c + 1).
fn gather(acc: ptr<function, Acc>, t: u32, b: i32, c: i32) {
    let area_before = (*acc).area;
    let count_before = (*acc).count;
    let n = i32(lattice_n());
    let base = t << (2u * params.level);
    // Indexed dynamically below: variables, not values (naga copies a value array to a
    // temporary at every dynamic index).
    var ups = array<vec2<i32>, 3>(vec2<i32>(b, c), vec2<i32>(b - 1, c), vec2<i32>(b, c - 1));
    for (var k = 0; k < 3; k++) {
        let u = ups[k];
        if (u.x >= 0 && u.y >= 0 && u.x + u.y < n) {
            acc_add(acc, base + locate(vec2<i32>(3 * u.x + 1, 3 * u.y + 1)));
        }
    }
    var downs = array<vec2<i32>, 3>(vec2<i32>(b, c), vec2<i32>(b + 1, c), vec2<i32>(b, c + 1));
    for (var k = 0; k < 3; k++) {
        let d = downs[k];
        if (d.x >= 1 && d.y >= 1 && d.x + d.y <= n) {
            acc_add(acc, base + locate(vec2<i32>(3 * d.x - 1, 3 * d.y - 1)));
        }
    }
    // Smooth reconstruction: the field of coarse triangle t at this lattice point, weighted by
    // the area of t's fine triangles around it (their own colours are zero in this mode).
    if (params.smooth_light == 1u) {
        let shift = HCE_EVAL_BITS - params.level;
        let rgb = hce_light_eval(t, u32(b) << shift, u32(c) << shift, (*acc).normal);
        (*acc).weighted += rgb * ((*acc).area - area_before);
        (*acc).plain += rgb * ((*acc).count - count_before);
    }
}

// Step 3: the colour of output vertex v with unit normal `normal`. A coarse vertex gathers from
// every coarse triangle at it, an edge point from both sides of its coarse edge, an interior
// point from its one triangle.
fn vertex_colour(v: u32, normal: vec3<f32>) -> vec3<f32> {
    let n = i32(lattice_n());
    let ep = lattice_n() - 1u;
    let edge_base = params.coarse_vertices;
    let interior_base = edge_base + params.edge_count * ep;
    var acc = Acc(vec3<f32>(0.0), 0.0, vec3<f32>(0.0), 0.0, normal);
    if (v < edge_base) {
        let s = topo[params.vertex_corner_offsets_off + v];
        let e = topo[params.vertex_corner_offsets_off + v + 1u];
        for (var k = s; k < e; k++) {
            let cr = topo[params.vertex_corners_off + k];
            let l = corner_lattice(n, cr % 3u);
            gather(&acc, cr / 3u, l.x, l.y);
        }
    } else if (v < interior_base) {
        let id = (v - edge_base) / ep;
        let kk = i32((v - edge_base) % ep) + 1;
        let s = topo[params.edge_side_offsets_off + id];
        let e = topo[params.edge_side_offsets_off + id + 1u];
        for (var q = s; q < e; q++) {
            let side = topo[params.edge_sides_off + q];
            let t = side / 3u;
            let ed = side % 3u;
            var k = kk;
            if (!edge_from_owner(t, ed)) {
                k = n - kk;
            }
            let l = edge_lattice(n, ed, k);
            gather(&acc, t, l.x, l.y);
        }
    } else {
        let local = v - interior_base;
        let per_tri = (lattice_n() - 1u) * (lattice_n() - 2u) / 2u;
        let l = interior_coords(local % per_tri);
        gather(&acc, local / per_tri, l.x, l.y);
    }
    if (acc.area > 0.0) {
        return acc.weighted / acc.area;
    } else if (acc.count > 0.0) {
        return acc.plain / acc.count;
    }
    return vec3<f32>(0.0);
}
