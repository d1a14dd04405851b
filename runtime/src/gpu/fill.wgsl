// The memory-bandwidth reference of `hce bench-gpu`: every invocation stores one 16-byte word
// into a large storage buffer and reads nothing, so its time is the device's write bandwidth
// through a compute kernel, the same path the refinement kernels write their outputs by.

struct Params {
    words: u32,
    value: u32,
    _pad0: u32,
    _pad1: u32,
}

@group(0) @binding(0) var<uniform> params: Params;
@group(0) @binding(1) var<storage, read_write> out: array<vec4<u32>>;

@compute @workgroup_size(64)
fn fill_main(@builtin(global_invocation_id) gid: vec3<u32>,
             @builtin(num_workgroups) groups: vec3<u32>) {
    let i = gid.x + gid.y * groups.x * 64u;
    if i < params.words {
        out[i] = vec4<u32>(params.value, i, params.value ^ i, params.value + i);
    }
}
