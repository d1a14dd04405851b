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
            corner_colours: Vec::new(),
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
            corner_colours: Vec::new(),
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

/// Builds the adjacency tables of `ControlMesh` from positions and triangles of a manifold mesh
/// (every edge used once or twice, consistently oriented, one fan per vertex). A small
/// reference for tests; `hce-runtime`'s topology module is the production builder.
pub fn control_mesh(positions: Vec<f32>, triangles: Vec<u32>) -> ControlMesh {
    use std::collections::HashMap;
    let nv = positions.len() / 3;
    let nf = triangles.len() / 3;
    let tri = |t: usize| [triangles[3 * t], triangles[3 * t + 1], triangles[3 * t + 2]];
    // Directed edge (a, b) -> (triangle, edge index).
    let mut directed = HashMap::new();
    for t in 0..nf {
        let v = tri(t);
        for e in 0..3 {
            directed.insert((v[e], v[(e + 1) % 3]), (t, e));
        }
    }
    // Around vertex a, triangle (a, b, c) contributes the step b -> c of its ring.
    let mut steps: Vec<HashMap<u32, u32>> = vec![HashMap::new(); nv];
    for t in 0..nf {
        let v = tri(t);
        for c in 0..3 {
            steps[v[c] as usize].insert(v[(c + 1) % 3], v[(c + 2) % 3]);
        }
    }
    let mut ring_offsets = vec![0u32];
    let mut ring = Vec::new();
    let mut boundary = vec![false; nv];
    for (v, s) in steps.iter().enumerate() {
        let targets: std::collections::HashSet<u32> = s.values().copied().collect();
        let mut starts: Vec<u32> = s.keys().copied().filter(|k| !targets.contains(k)).collect();
        starts.sort_unstable();
        let start = match starts.first() {
            Some(&k) => {
                boundary[v] = true;
                k
            }
            None => s.keys().copied().min().unwrap_or(0),
        };
        let mut w = start;
        let before = ring.len();
        loop {
            ring.push(w);
            match s.get(&w) {
                Some(&next) if next != start && ring.len() - before <= s.len() => w = next,
                _ => break,
            }
        }
        ring_offsets.push(ring.len() as u32);
    }
    let is_boundary_edge =
        |a: u32, b: u32| !(directed.contains_key(&(a, b)) && directed.contains_key(&(b, a)));
    let mut spoke_flags = Vec::with_capacity(ring.len());
    let mut vertex_flags = Vec::with_capacity(nv);
    for v in 0..nv {
        let r = &ring[ring_offsets[v] as usize..ring_offsets[v + 1] as usize];
        let flags: Vec<u32> = r
            .iter()
            .map(|&w| {
                if is_boundary_edge(v as u32, w) {
                    SPOKE_SHARP | SPOKE_BOUNDARY
                } else {
                    0
                }
            })
            .collect();
        let sharp = flags.iter().filter(|&&f| f & SPOKE_SHARP != 0).count();
        let rule = if (boundary[v] && r.len() == 2) || sharp >= 3 {
            RULE_CORNER
        } else if sharp == 2 {
            RULE_CREASE
        } else {
            RULE_SMOOTH
        };
        spoke_flags.extend(flags);
        vertex_flags.push((u32::from(boundary[v]) * VERTEX_BOUNDARY) | (rule << VERTEX_RULE_SHIFT));
    }
    let mut corner_spokes = Vec::with_capacity(3 * nf);
    let mut neighbours = Vec::with_capacity(3 * nf);
    let mut edges = Vec::with_capacity(3 * nf);
    let mut next_edge = 0u32;
    for t in 0..nf {
        let v = tri(t);
        for c in 0..3 {
            let (a, b) = (v[c], v[(c + 1) % 3]);
            let r = &ring[ring_offsets[a as usize] as usize..ring_offsets[a as usize + 1] as usize];
            corner_spokes.push(r.iter().position(|&w| w == b).unwrap_or(0) as u32);
            let across = directed.get(&(b, a)).copied();
            neighbours.push(across.map_or(NO_NEIGHBOUR, |(u, _)| u as u32));
            match across {
                Some((u, f)) if u < t => edges.push(edges[3 * u + f]),
                _ => {
                    edges.push(next_edge);
                    next_edge += 1;
                }
            }
        }
    }
    ControlMesh {
        positions,
        triangles,
        ring_offsets,
        ring,
        vertex_flags,
        spoke_flags,
        corner_spokes,
        neighbours,
        edges,
    }
}

/// A valid container with one `n` × `n` grid of quads split into triangles, each triangle with
/// two normals and a tree whose shape depends on the triangle index (depth up to `max_depth`).
pub fn grid(n: u32, max_depth: u32) -> Container {
    let mut positions = Vec::new();
    for y in 0..=n {
        for x in 0..=n {
            positions.extend([x as f32, y as f32, ((x * 7 + y * 3) % 5) as f32 * 0.1]);
        }
    }
    let id = |x: u32, y: u32| y * (n + 1) + x;
    let mut triangles = Vec::new();
    for y in 0..n {
        for x in 0..n {
            triangles.extend([id(x, y), id(x + 1, y), id(x + 1, y + 1)]);
            triangles.extend([id(x, y), id(x + 1, y + 1), id(x, y + 1)]);
        }
    }
    let corners: Vec<[f32; 3]> = triangles
        .iter()
        .map(|&v| {
            let i = v as usize * 3;
            [positions[i], positions[i + 1], positions[i + 2]]
        })
        .collect();
    let hash = geometry_hash(corners.iter().copied());
    let mesh = control_mesh(positions, triangles);
    let mut w = crate::tree::BitWriter::new();
    let mut records = Vec::new();
    let mut normals = Vec::new();
    let mut colours = Vec::new();
    for t in 0..mesh.triangle_count() {
        // Subdivide node k while its depth is below the triangle's depth budget and k is even.
        let depth = (t as u32) % (max_depth.min(crate::MAX_TREE_DEPTH) + 1);
        let mut flags = Vec::new();
        let mut level = vec![true];
        for d in 0..=depth {
            let mut next = 0;
            for (i, _) in level.iter().enumerate() {
                let f = d < depth && i % 2 == 0;
                flags.push(f);
                next += 4 * usize::from(f);
            }
            level = vec![true; next];
        }
        let nodes = flags.len() as u32;
        let bits_start = w.push_tree(&flags).unwrap_or(0) as u32;
        records.push(TriangleRecord {
            bits_start,
            colour_start: colours.len() as u32,
            normal_start: normals.len() as u32,
            normal_count: 2,
        });
        normals.push([0.0, 0.0, 1.0]);
        normals.push([0.6, 0.0, 0.8]);
        for k in 0..2 * nodes {
            colours.push(rgb9e5::encode([k as f32 * 0.01, t as f32, 0.5]));
        }
    }
    let (bits, bit_len) = w.finish();
    Container {
        metadata: Metadata {
            generator: "hce example grid".into(),
            bake_parameters: String::new(),
            source_hash: hash,
        },
        objects: vec![Object {
            name: format!("grid{n}"),
            kind: ObjectKind::Multiresolution,
            geometry_hash: hash,
            mesh,
            triangles: records,
            normals,
            bits,
            bit_len,
            colours,
            corner_colours: Vec::new(),
        }],
    }
}
