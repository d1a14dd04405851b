// The storage buffers of the kernels that refine and colour objects, one numbering for all:
// flat.wgsl, loop.wgsl (and loop_workgroup.wgsl) and decode.wgsl import these declarations, and
// bindings.rs is their Rust twin (a test compares the two by name). Binding 0 and bindings from
// 14 on are each kernel's own (its uniform, flat.wgsl's batch table, decode.wgsl's queries and
// results); an entry point's layout holds only the bindings it uses.

// One per coarse triangle: where its tree, colours and normals start in the arrays below.
struct TriRecord {
    bits_start: u32,
    colour_start: u32,
    normal_start: u32,
    normal_count: u32,
}

// The object: its coarse positions, x y z packed (no vec3 padding), and its tables packed into
// one word array (where each section starts is in the kernel's uniform).
@group(0) @binding(1) var<storage, read> coarse_positions: array<f32>;
@group(0) @binding(2) var<storage, read> topo: array<u32>;

// Its baked lighting (hce_tree.wgsl): the records, the HCE bitstream (least significant bit
// first), the representative normals (x y z packed) and the RGB9E5 colours, [node][normal] per
// triangle.
@group(0) @binding(3) var<storage, read> hce_records: array<TriRecord>;
@group(0) @binding(4) var<storage, read> hce_bits: array<u32>;
@group(0) @binding(5) var<storage, read> hce_normals: array<f32>;
@group(0) @binding(6) var<storage, read> hce_colours: array<u32>;

// The refined mesh: positions (x y z packed), indices (three per fine triangle), per fine
// triangle its colour and, in w, its area, and the vertex colours (linear RGBA).
@group(0) @binding(7) var<storage, read_write> out_positions: array<f32>;
@group(0) @binding(8) var<storage, read_write> out_indices: array<u32>;
@group(0) @binding(9) var<storage, read_write> out_faces: array<vec4<f32>>;
@group(0) @binding(10) var<storage, read_write> out_colours: array<vec4<f32>>;

// The lighting table of the smooth reconstruction (hce_light.wgsl).
@group(0) @binding(11) var<storage, read> hce_light: array<u32>;

// The Loop kernel's: unit vertex normals (x y z packed), and the scratch patches of patch_main.
@group(0) @binding(12) var<storage, read_write> out_normals: array<f32>;
@group(0) @binding(13) var<storage, read_write> scratch: array<f32>;
