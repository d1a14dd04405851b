// Vertex colours of a refined object: the area-weighted mean of the colours of the fine
// triangles around each output vertex, across coarse edges and vertices (geometry/src/colour.rs,
// geometry/src/lattice.rs `incident_paths`), shared by flat.wgsl and loop.wgsl. A pure gather with one
// writer per vertex and a fixed order of summation, so the result does not depend on scheduling.
//
// It reads `topo` and `out_faces` (hce_bindings.wgsl) and calls lattice_split_base() (the first
// vertex the split where the surface folds appends, SPEC.md F.5; the vertex count where nothing
// is split) and lattice_split_copies() (its corner copies X), which the importing kernel
// provides with `params`, its uniform, with `level`, `coarse_vertices`, `edge_count`,
// `edges_off`, `edge_side_offsets_off`, `edge_sides_off`, `vertex_corner_offsets_off`,
// `vertex_corners_off`, `corner_copy_off`, `edge_copy_off` (sections of `topo`: the split's slot
// lists and copy ranks, geometry/src/split.rs) and `smooth_light`.

// #import hce_constants
// #import hce_bindings
// #import hce_light
// #import hce_lattice

// Where `out_faces` pools many objects' fine triangles (the batched entry points of flat.wgsl),
// the object's first; zero (a private variable's initial value) in every other kernel.
var<private> gather_face_base: u32;

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
    let f = out_faces[gather_face_base + g];
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

// Step 3: the points a vertex gathers from, its slot. A coarse vertex (or a copy of one, SPEC.md
// F.5) gathers from the corners of its corner slot, an edge point (or a copy) from the sides of
// its edge slot, an interior point from its one triangle. The incidence sections are the
// split's slot lists (geometry/src/split.rs): V + X corner slots, E + S edge slots; a kernel
// that does not split has X = S = 0 and plain vertex and edge incidence.
const SLOT_CORNER: u32 = 0u;
const SLOT_EDGE: u32 = 1u;
const SLOT_INTERIOR: u32 = 2u;

struct Slot {
    kind: u32,
    // Corner or edge slot number; the triangle of an interior point.
    index: u32,
    // Edge point k counted from the owner's v_e; the interior point's (b, c).
    k: i32,
    b: i32,
    c: i32,
    // The range of the slot's corners or sides.
    first: u32,
    end: u32,
}

fn vertex_slot(v: u32) -> Slot {
    let n = i32(lattice_n());
    let ep = lattice_n() - 1u;
    let edge_base = params.coarse_vertices;
    let interior_base = edge_base + params.edge_count * ep;
    let split_base = lattice_split_base();
    let copies = lattice_split_copies();
    var s = Slot(SLOT_INTERIOR, 0u, 0, 0, 0, 0u, 1u);
    if (v < edge_base || (v >= split_base && v < split_base + copies)) {
        s.kind = SLOT_CORNER;
        s.index = select(v, edge_base + v - split_base, v >= split_base);
        s.first = topo[params.vertex_corner_offsets_off + s.index];
        s.end = topo[params.vertex_corner_offsets_off + s.index + 1u];
    } else if (v < interior_base || v >= split_base) {
        var local = v - edge_base;
        var id_base = 0u;
        if (v >= split_base) {
            local = v - split_base - copies;
            id_base = params.edge_count;
        }
        s.kind = SLOT_EDGE;
        s.index = id_base + local / ep;
        s.k = i32(local % ep) + 1;
        s.first = topo[params.edge_side_offsets_off + s.index];
        s.end = topo[params.edge_side_offsets_off + s.index + 1u];
    } else {
        let local = v - interior_base;
        let per_tri = (lattice_n() - 1u) * (lattice_n() - 2u) / 2u;
        let l = interior_coords(local % per_tri);
        s.index = local / per_tri;
        s.b = l.x;
        s.c = l.y;
    }
    return s;
}

// Entry q of slot s as (coarse triangle, b, c).
fn slot_point(s: Slot, q: u32) -> vec3<i32> {
    let n = i32(lattice_n());
    if (s.kind == SLOT_CORNER) {
        let cr = topo[params.vertex_corners_off + q];
        let l = corner_lattice(n, cr % 3u);
        return vec3<i32>(i32(cr / 3u), l.x, l.y);
    }
    if (s.kind == SLOT_EDGE) {
        let side = topo[params.edge_sides_off + q];
        let t = side / 3u;
        let ed = side % 3u;
        var k = s.k;
        if (!edge_from_owner(t, ed)) {
            k = n - s.k;
        }
        let l = edge_lattice(n, ed, k);
        return vec3<i32>(i32(t), l.x, l.y);
    }
    return vec3<i32>(i32(s.index), s.b, s.c);
}

// The F.5 vertex a copy repeats: the control point of its corners, or the owner's point k of
// its side's edge.
fn slot_source(s: Slot) -> u32 {
    let side = topo[select(params.edge_sides_off, params.vertex_corners_off, s.kind == SLOT_CORNER) + s.first];
    if (s.kind == SLOT_CORNER) {
        return corner(side / 3u, side % 3u);
    }
    let id = topo[params.edges_off + side];
    return params.coarse_vertices + id * (lattice_n() - 1u) + u32(s.k - 1);
}

// Step 4: the colour of a slot's vertex with unit normal `normal`: the area-weighted mean over
// the fine triangles at each of its points, in slot order.
fn slot_colour(s: Slot, normal: vec3<f32>) -> vec3<f32> {
    var acc = Acc(vec3<f32>(0.0), 0.0, vec3<f32>(0.0), 0.0, normal);
    for (var q = s.first; q < s.end; q++) {
        let p = slot_point(s, q);
        gather(&acc, u32(p.x), p.y, p.z);
    }
    return acc_mean(acc);
}

// The area-weighted mean, the plain mean where the areas sum to zero, black for no triangle.
fn acc_mean(acc: Acc) -> vec3<f32> {
    if (acc.area > 0.0) {
        return acc.weighted / acc.area;
    } else if (acc.count > 0.0) {
        return acc.plain / acc.count;
    }
    return vec3<f32>(0.0);
}

fn vertex_colour(v: u32, normal: vec3<f32>) -> vec3<f32> {
    return slot_colour(vertex_slot(v), normal);
}

// Step 5: the normal (unnormalised) of a region of a split vertex (SPEC.md F.6): the normals
// (q − p) × (r − p) of the fine triangles at each of its points, in the order of step 2's
// gather, measured on the F.5 vertices (whose positions the copies repeat).
fn fine_normal(t: u32, path: u32) -> vec3<f32> {
    let cs = fine_corners(path);
    let p = out_position(vertex_index(t, cs[0].x, cs[0].y));
    let u = out_position(vertex_index(t, cs[1].x, cs[1].y)) - p;
    let w = out_position(vertex_index(t, cs[2].x, cs[2].y)) - p;
    return vec3<f32>(u.y * w.z - u.z * w.y, u.z * w.x - u.x * w.z, u.x * w.y - u.y * w.x);
}

fn region_normal(s: Slot) -> vec3<f32> {
    let n = i32(lattice_n());
    var sum = vec3<f32>(0.0);
    var first = true;
    for (var q = s.first; q < s.end; q++) {
        let pt = slot_point(s, q);
        let t = u32(pt.x);
        let b = pt.y;
        let c = pt.z;
        var ups = array<vec2<i32>, 3>(vec2<i32>(b, c), vec2<i32>(b - 1, c), vec2<i32>(b, c - 1));
        for (var k = 0; k < 3; k++) {
            let u = ups[k];
            if (u.x >= 0 && u.y >= 0 && u.x + u.y < n) {
                let x = fine_normal(t, locate(vec2<i32>(3 * u.x + 1, 3 * u.y + 1)));
                sum = select(sum + x, x, first);
                first = false;
            }
        }
        var downs = array<vec2<i32>, 3>(vec2<i32>(b, c), vec2<i32>(b + 1, c), vec2<i32>(b, c + 1));
        for (var k = 0; k < 3; k++) {
            let d = downs[k];
            if (d.x >= 1 && d.y >= 1 && d.x + d.y <= n) {
                let x = fine_normal(t, locate(vec2<i32>(3 * d.x - 1, 3 * d.y - 1)));
                sum = select(sum + x, x, first);
                first = false;
            }
        }
    }
    return sum;
}

// Step 6: the vertex that fine triangles of t use at lattice point (b, c), whose F.5 number is
// i: the copy of t's region where the point's vertex is split (SPEC.md F.5), else i
// (geometry/src/split.rs `SplitTables::split_index`).
const NO_COPY: u32 = 0xffffffffu;

fn split_index(t: u32, b: i32, c: i32, i: u32) -> u32 {
    let n = i32(lattice_n());
    let per_edge = lattice_n() - 1u;
    let a = n - b - c;
    if (i < params.coarse_vertices) {
        var k = 0u;
        if (a == 0 && c == 0) {
            k = 1u;
        } else if (a == 0 && b == 0) {
            k = 2u;
        }
        let copy = topo[params.corner_copy_off + 3u * t + k];
        if (copy != NO_COPY) {
            return lattice_split_base() + copy;
        }
    } else if (i < params.coarse_vertices + params.edge_count * per_edge) {
        var e = 0u;
        if (a == 0) {
            e = 1u;
        } else if (b == 0) {
            e = 2u;
        }
        let local = i - params.coarse_vertices;
        let copy = topo[params.edge_copy_off + local / per_edge];
        if (copy != NO_COPY && !edge_from_owner(t, e)) {
            return lattice_split_base() + lattice_split_copies() + copy * per_edge
                + local % per_edge;
        }
    }
    return i;
}
