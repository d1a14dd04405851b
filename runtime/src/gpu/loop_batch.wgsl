// Batched Loop refinement (hce_batch.wgsl, runtime/src/gpu/batch.rs): the three steps of many
// small Loop objects in one dispatch each. Assembled by wgsl.rs (`loop_batch_source`) after
// loop.wgsl with its `params` uniform made a private variable, which batch_enter sets from the
// object's entry of the batch table. Step 1 runs the scratch patch kernel, whose output the
// workgroup kernel matches bit for bit, with one slot per invocation over all the batch's
// coarse triangles: float k of slot s is scratch[k * batch.slots + s], whatever the object's
// level.

// #import loop
// #import hce_batch

fn batch_enter(k: u32) {
    let p = batch_bases(k, batch.entries + LOOP_ENTRY_WORDS * k);
    params = Params(topo[p], topo[p + 1u], topo[p + 2u], topo[p + 3u], topo[p + 4u], topo[p + 5u],
                    topo[p + 6u], topo[p + 7u], topo[p + 8u], topo[p + 9u], topo[p + 10u],
                    topo[p + 11u], topo[p + 12u], topo[p + 13u], topo[p + 14u], topo[p + 15u],
                    topo[p + 16u], topo[p + 17u], topo[p + 18u], topo[p + 19u], topo[p + 20u],
                    topo[p + 21u], topo[p + 22u], topo[p + 23u], topo[p + 24u], topo[p + 25u],
                    topo[p + 26u], topo[p + 27u], topo[p + 28u], topo[p + 29u], topo[p + 30u],
                    topo[p + 31u], topo[p + 32u], topo[p + 33u], topo[p + 34u]);
}

@compute @workgroup_size(64)
fn patch_batch_main(@builtin(global_invocation_id) gid: vec3<u32>,
                    @builtin(num_workgroups) groups: vec3<u32>) {
    let slot = linear_id(gid, groups);
    if (slot >= batch.slots) {
        return;
    }
    slot_id = slot;
    for (var g = slot; g < batch.triangle_total; g += batch.slots) {
        let k = batch_object(batch.first_triangles, g);
        batch_enter(k);
        params.slots = batch.slots;
        loop_patch(g - topo[batch.first_triangles + k]);
    }
}

@compute @workgroup_size(64)
fn faces_batch_main(@builtin(global_invocation_id) gid: vec3<u32>,
                    @builtin(num_workgroups) groups: vec3<u32>) {
    let g = linear_id(gid, groups);
    if (g >= batch.fine_total) {
        return;
    }
    batch_enter(batch_object(batch.first_faces, g));
    loop_face(g - gather_face_base);
}

@compute @workgroup_size(64)
fn colours_batch_main(@builtin(global_invocation_id) gid: vec3<u32>,
                      @builtin(num_workgroups) groups: vec3<u32>) {
    let g = linear_id(gid, groups);
    if (g >= batch.vertex_total) {
        return;
    }
    batch_enter(batch_object(batch.first_vertices, g));
    loop_colour(g - lattice_out_base);
}
