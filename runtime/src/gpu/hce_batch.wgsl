// Batched refinement (runtime/src/gpu/batch.rs): one step of many objects' refinements in one
// dispatch, over buffers that pool the objects' tables (bindings 1 to 6 and 11: each object's
// tables copied whole, one after another) and their outputs (bindings 7 to 10 and 12: each
// object's range, one after another, copied out to its own buffers afterwards). flat.wgsl and
// loop_batch.wgsl import it. Per object k of the batch, `topo` holds, from the offsets in `batch`:
//   first_vertices[k], first_faces[k],  its first output vertex, first fine triangle and first
//   first_triangles[k]                  coarse triangle in the batch (ascending: the objects'
//                                       ranges in order)
//   entries[k]: the kernel's ENTRY_WORDS  its first coarse vertex, first record, first bit,
//                                       first colour, first normal and first word of the
//                                       lighting table in the pooled buffers (the first
//                                       BATCH_ENTRY_BASES words), then its kernel's Params (the
//                                       section offsets already counted in the pool).
// An invocation finds its object by binary search over its step's first items, sets the bases
// of hce_lattice.wgsl, hce_gather.wgsl, hce_tree.wgsl and hce_light.wgsl to the object's
// (`batch_bases`; the kernel reads its Params), and runs the step on its item within the
// object: the same operations on the same values as the object's own dispatch, so the same
// bits.

// #import hce_constants
// #import hce_bindings
// #import hce_tree
// #import hce_light
// #import hce_lattice
// #import hce_gather

struct Batch {
    count: u32,
    first_vertices: u32,
    first_faces: u32,
    entries: u32,
    vertex_total: u32,
    fine_total: u32,
    first_triangles: u32,
    triangle_total: u32,
    // Invocations of a step that strides over the batch's coarse triangles (the Loop kernel's
    // scratch patches: one slot each).
    slots: u32,
}

@group(0) @binding(14) var<uniform> batch: Batch;

// The object k (of batch.count) whose items first[k] .. first[k + 1] hold item g (< the total).
fn batch_object(first: u32, g: u32) -> u32 {
    var lo = 0u;
    var hi = batch.count;
    while (hi - lo > 1u) {
        let mid = (lo + hi) / 2u;
        if (topo[first + mid] <= g) {
            lo = mid;
        } else {
            hi = mid;
        }
    }
    return lo;
}

// Sets the shared modules' bases to object k's, whose entry starts at word e of `topo`; returns
// the word where its Params start.
fn batch_bases(k: u32, e: u32) -> u32 {
    lattice_coarse_base = topo[e];
    hce_tree_base = vec4<u32>(topo[e + 1u], topo[e + 2u], topo[e + 3u], topo[e + 4u]);
    hce_light_base = topo[e + 5u];
    lattice_out_base = topo[batch.first_vertices + k];
    gather_face_base = topo[batch.first_faces + k];
    return e + BATCH_ENTRY_BASES;
}
