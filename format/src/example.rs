//! The example container of SPEC.md Appendix D: one triangle, one normal, the 9-node tree of
//! SPEC.md B.2. Tests (ours and other crates') use it as a small valid file.

use crate::gltf::{embed_container, link_primitive, write_glb, PrimitiveLink};
use crate::model::*;
use crate::tree::encode_tree;
use serde_json::json;

/// The SPEC.md Appendix D container.
pub fn single_triangle() -> Container {
    let corners = [[0.0, 0.0, 0.0], [1.0, 0.0, 0.0], [0.0, 1.0, 0.0]];
    let hash = geometry_hash(corners);
    let flags = [1, 0, 0, 1, 0, 0, 0, 0, 0].map(|b| b == 1);
    // The flags are a complete tree of depth 2, so encoding cannot fail.
    let (bits, bit_len) = encode_tree(&flags).unwrap_or_default();
    // Node k gets the colour (k / 8, 1/2, 1/4): exact in RGB9E5.
    let colours = (0..9u8)
        .map(|k| rgb9e5::encode([f32::from(k) / 8.0, 0.5, 0.25]))
        .collect();
    let boundary_corner = VERTEX_BOUNDARY | (RULE_CORNER << VERTEX_RULE_SHIFT);
    Container {
        metadata: Metadata {
            generator: "hce".into(),
            bake_parameters: String::new(),
            source_hash: hash,
        },
        objects: vec![Object {
            name: "tri".into(),
            kind: ObjectKind::Multiresolution,
            geometry_hash: hash,
            mesh: ControlMesh {
                positions: corners.iter().flatten().copied().collect(),
                triangles: vec![0, 1, 2],
                ring_offsets: vec![0, 2, 4, 6],
                ring: vec![1, 2, 2, 0, 0, 1],
                vertex_flags: vec![boundary_corner; 3],
                spoke_flags: vec![SPOKE_SHARP | SPOKE_BOUNDARY; 6],
                corner_spokes: vec![0, 0, 0],
                neighbours: vec![NO_NEIGHBOUR; 3],
                edges: vec![0, 1, 2],
            },
            triangles: vec![TriangleRecord {
                bits_start: 0,
                colour_start: 0,
                normal_start: 0,
                normal_count: 1,
            }],
            normals: vec![[0.0, 0.0, 1.0]],
            bits,
            bit_len,
            colours,
        }],
    }
}

/// Two triangles sharing an edge (a unit square split along its diagonal), with different
/// trees and normal-set sizes: exercises interior edges, neighbours and crease vertices.
pub fn two_triangles() -> Container {
    let corners = [
        [0.0, 0.0, 0.0],
        [1.0, 0.0, 0.0],
        [1.0, 1.0, 0.0],
        [0.0, 1.0, 0.0],
    ];
    let triangles = vec![0, 1, 2, 0, 2, 3];
    let hash = geometry_hash(triangles.iter().map(|&v: &u32| corners[v as usize]));
    let mut w = crate::tree::BitWriter::new();
    // Both trees are complete and shallow, so pushing cannot fail.
    let s0 = w
        .push_tree(&[true, false, false, false, false])
        .unwrap_or(0) as u32;
    let s1 = w.push_tree(&[false]).unwrap_or(0) as u32;
    let (bits, bit_len) = w.finish();
    let crease = VERTEX_BOUNDARY | (RULE_CREASE << VERTEX_RULE_SHIFT);
    let corner = VERTEX_BOUNDARY | (RULE_CORNER << VERTEX_RULE_SHIFT);
    let b = SPOKE_SHARP | SPOKE_BOUNDARY;
    Container {
        metadata: Metadata {
            generator: "hce example".into(),
            bake_parameters: "{\"levels\":1}".into(),
            source_hash: hash,
        },
        objects: vec![Object {
            name: "square".into(),
            kind: ObjectKind::Multiresolution,
            geometry_hash: hash,
            mesh: ControlMesh {
                positions: corners.iter().flatten().copied().collect(),
                triangles,
                ring_offsets: vec![0, 3, 5, 8, 10],
                ring: vec![1, 2, 3, 2, 0, 3, 0, 1, 0, 2],
                vertex_flags: vec![crease, corner, crease, corner],
                spoke_flags: vec![b, 0, b, b, b, b, 0, b, b, b],
                corner_spokes: vec![0, 0, 1, 1, 0, 0],
                neighbours: vec![NO_NEIGHBOUR, NO_NEIGHBOUR, 1, 0, NO_NEIGHBOUR, NO_NEIGHBOUR],
                edges: vec![0, 1, 2, 2, 3, 4],
            },
            triangles: vec![
                TriangleRecord {
                    bits_start: s0,
                    colour_start: 0,
                    normal_start: 0,
                    normal_count: 2,
                },
                TriangleRecord {
                    bits_start: s1,
                    colour_start: 10,
                    normal_start: 2,
                    normal_count: 1,
                },
            ],
            normals: vec![[0.0, 0.0, 1.0], [0.0, 0.6, 0.8], [0.0, 0.0, 1.0]],
            bits,
            bit_len,
            colours: (0..11u8)
                .map(|k| rgb9e5::encode([1.0, f32::from(k), 0.5]))
                .collect(),
        }],
    }
}

/// A GLB with one triangle primitive (positions and u16 indices) carrying [`single_triangle`]
/// through `EXT_hce_baked_lighting`; passes the Khronos glTF-Validator without errors or warnings.
pub fn triangle_glb() -> Vec<u8> {
    let mut bin = Vec::new();
    for p in [[0f32, 0.0, 0.0], [1.0, 0.0, 0.0], [0.0, 1.0, 0.0]] {
        for c in p {
            bin.extend_from_slice(&c.to_le_bytes());
        }
    }
    for i in [0u16, 1, 2, 0] {
        bin.extend_from_slice(&i.to_le_bytes()); // the last one is padding
    }
    let mut json = json!({
        "asset": { "version": "2.0", "generator": "hce tests" },
        "scene": 0,
        "scenes": [{ "nodes": [0] }],
        "nodes": [{ "mesh": 0 }],
        "meshes": [{ "primitives": [{ "attributes": { "POSITION": 0 }, "indices": 1 }] }],
        "accessors": [
            { "bufferView": 0, "componentType": 5126, "count": 3, "type": "VEC3",
              "min": [0.0, 0.0, 0.0], "max": [1.0, 1.0, 0.0] },
            { "bufferView": 1, "componentType": 5123, "count": 3, "type": "SCALAR" }
        ],
        "bufferViews": [
            { "buffer": 0, "byteOffset": 0, "byteLength": 36, "target": 34962 },
            { "buffer": 0, "byteOffset": 36, "byteLength": 6, "target": 34963 }
        ],
        "buffers": [{ "byteLength": 44 }]
    });
    // The example's arrays have consistent shapes, so writing cannot fail.
    let container = crate::write(&single_triangle()).unwrap_or_default();
    // A fresh JSON object with buffers[0] without uri: embedding cannot fail.
    let _ = embed_container(&mut json, &mut bin, &container);
    link_primitive(
        &mut json,
        &PrimitiveLink {
            mesh: 0,
            primitive: 0,
            object: 0,
            geometry_hash: single_triangle().objects[0].geometry_hash,
            first_triangle: 0,
        },
    )
    .ok();
    write_glb(&json, &bin).unwrap_or_default()
}
