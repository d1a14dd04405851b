//! A minimal loader for plain (not yet baked) meshes, so `hce render` can preview any OBJ or
//! glTF: positions, triangle indices and `COLOR_0` when present, read by the same reader as
//! [`crate::load_mesh`] (the guards of [`crate::gltf_guard`], meshes placed by their nodes'
//! world transforms through [`crate::scene_graph`]), then welded on exactly equal positions and
//! turned into a flat object whose single-node trees carry one colour per triangle, which the
//! runtime's flat kernel draws.

use std::path::Path;

use hce_format::{rgb9e5, ControlMesh, Object, ObjectKind, TriangleRecord};

use hce_geometry::flat::{edge_ids, normal_and_area};

use crate::import::{read_triangles, ImportError, Wanted};

/// Triangles with optional linear per-vertex colours.
#[derive(Clone, Debug, Default, PartialEq)]
pub struct PlainMesh {
    pub positions: Vec<f32>,
    pub indices: Vec<u32>,
    /// Linear `r, g, b` per vertex, from glTF `COLOR_0` or OBJ vertex colours.
    pub colours: Option<Vec<f32>>,
}

/// Grey for the vertices without colours of a partly coloured file.
const NO_COLOUR: [f32; 3] = [0.5; 3];

/// Loads every triangle primitive of every mesh instance of an OBJ, glTF or GLB file into one
/// mesh, in world space.
pub fn load_plain_mesh(path: &Path) -> Result<PlainMesh, ImportError> {
    let read = read_triangles(
        path,
        Wanted {
            normals: false,
            colours: true,
        },
    )?;
    Ok(PlainMesh {
        positions: read.positions.iter().flatten().copied().collect(),
        indices: read.triangles.iter().flatten().copied().collect(),
        colours: read
            .colours
            .map(|c| c.iter().flat_map(|c| c.unwrap_or(NO_COLOUR)).collect()),
    })
}

/// Direction of the preview light used for meshes without colours.
const PREVIEW_LIGHT: [f32; 3] = [0.408_248_3, 0.816_496_6, 0.408_248_3];

/// A flat object for the flat-refinement kernel: vertices welded on exactly equal positions,
/// degenerate triangles dropped, one single-node tree and one colour per triangle: the mean of
/// its corners' `COLOR_0`, or (no colours) a neutral grey `0.6 × (0.2 + 0.8 max(0, n·l))` lit by
/// a fixed preview light, clearly not baked lighting. Returns the object and the number of
/// triangles dropped.
pub fn to_flat_object(name: &str, mesh: &PlainMesh) -> (Object, usize) {
    let mut map = std::collections::HashMap::new();
    let mut positions = Vec::new();
    let mut remap = Vec::with_capacity(mesh.positions.len() / 3);
    for p in mesh.positions.chunks_exact(3) {
        let key = [p[0].to_bits(), p[1].to_bits(), p[2].to_bits()];
        let next = (positions.len() / 3) as u32;
        let id = *map.entry(key).or_insert_with(|| {
            positions.extend_from_slice(p);
            next
        });
        remap.push(id);
    }
    let mut triangles = Vec::new();
    let mut tri_colours = Vec::new();
    let mut dropped = 0;
    for tri in mesh.indices.chunks_exact(3) {
        let w = [tri[0], tri[1], tri[2]].map(|i| remap[i as usize]);
        if w[0] == w[1] || w[1] == w[2] || w[0] == w[2] {
            dropped += 1;
            continue;
        }
        let colour = match &mesh.colours {
            Some(c) => {
                let mut s = [0f32; 3];
                for &i in tri {
                    for k in 0..3 {
                        s[k] += c[3 * i as usize + k] / 3.0;
                    }
                }
                s
            }
            None => {
                let p = w.map(|v| {
                    let v = v as usize * 3;
                    [positions[v], positions[v + 1], positions[v + 2]]
                });
                let (n, _) = normal_and_area(p);
                let d =
                    (n[0] * PREVIEW_LIGHT[0] + n[1] * PREVIEW_LIGHT[1] + n[2] * PREVIEW_LIGHT[2])
                        .max(0.0);
                [0.6 * (0.2 + 0.8 * d); 3]
            }
        };
        triangles.extend(w);
        tri_colours.push(rgb9e5::encode(colour));
    }
    let f = tri_colours.len();
    let mut normals = Vec::with_capacity(f);
    for tri in triangles.chunks_exact(3) {
        let p = [tri[0], tri[1], tri[2]].map(|v| {
            let v = v as usize * 3;
            [positions[v], positions[v + 1], positions[v + 2]]
        });
        normals.push(normal_and_area(p).0);
    }
    let edges = edge_ids(&triangles);
    let object = Object {
        name: name.to_string(),
        kind: ObjectKind::Flat,
        geometry_hash: 0,
        mesh: ControlMesh {
            positions,
            triangles,
            edges,
            ..Default::default()
        },
        triangles: (0..f as u32)
            .map(|t| TriangleRecord {
                bits_start: t,
                colour_start: t,
                normal_start: t,
                normal_count: 1,
            })
            .collect(),
        normals,
        // Every tree is a single leaf: all start bits zero.
        bits: vec![0; f.div_ceil(32)],
        bit_len: f as u64,
        colours: tri_colours,
    };
    (object, dropped)
}

#[cfg(test)]
mod tests {
    use super::*;

    /// A one-triangle glTF (with `COLOR_0`) whose mesh sits under a translated, mirrored node.
    fn translated_gltf(dir: &Path) -> std::path::PathBuf {
        let mut bin = Vec::new();
        for p in [[0.0f32, 0.0, 0.0], [1.0, 0.0, 0.0], [0.0, 1.0, 0.0]] {
            bin.extend(p.iter().flat_map(|c| c.to_le_bytes()));
        }
        for c in [[1.0f32, 0.0, 0.0], [0.0, 1.0, 0.0], [0.0, 0.0, 1.0]] {
            bin.extend(c.iter().flat_map(|c| c.to_le_bytes()));
        }
        std::fs::write(dir.join("translated.bin"), &bin).unwrap();
        let json = r#"{"asset":{"version":"2.0"},"scene":0,"scenes":[{"nodes":[0]}],
            "nodes":[{"translation":[0,5,0],"children":[1]},{"mesh":0,"scale":[-1,1,1]}],
            "meshes":[{"primitives":[{"attributes":{"POSITION":0,"COLOR_0":1}}]}],
            "buffers":[{"byteLength":72,"uri":"translated.bin"}],
            "bufferViews":[{"buffer":0,"byteOffset":0,"byteLength":36},
                {"buffer":0,"byteOffset":36,"byteLength":36}],
            "accessors":[{"bufferView":0,"componentType":5126,"count":3,"type":"VEC3","min":[0,0,0],"max":[1,1,0]},
                {"bufferView":1,"componentType":5126,"count":3,"type":"VEC3"}]}"#;
        let path = dir.join("translated.gltf");
        std::fs::write(&path, json).unwrap();
        path
    }

    #[test]
    fn a_mesh_under_a_translated_node_previews_where_the_node_puts_it() {
        let dir = tempfile::tempdir().unwrap();
        let mesh = load_plain_mesh(&translated_gltf(dir.path())).unwrap();
        // Moved up 5 by the parent, mirrored in x by the child.
        assert_eq!(
            mesh.positions,
            vec![0.0, 5.0, 0.0, -1.0, 5.0, 0.0, 0.0, 6.0, 0.0]
        );
        // The mirror reverses the winding, so the triangle still faces +z.
        assert_eq!(mesh.indices, vec![0, 2, 1]);
        let (object, dropped) = to_flat_object("t", &mesh);
        assert_eq!(dropped, 0);
        assert_eq!(object.normals, vec![[0.0, 0.0, 1.0]]);
        // The triangle's colour is the mean of its corners' COLOR_0.
        let c = rgb9e5::decode(object.colours[0]);
        for k in 0..3 {
            assert!((c[k] - 1.0 / 3.0).abs() < 0.01, "{c:?}");
        }
    }

    #[test]
    fn hostile_buffers_are_errors_not_panics() {
        let dir = tempfile::tempdir().unwrap();
        let path = translated_gltf(dir.path());
        // COLOR_0 claims more elements than its view holds.
        let text = std::fs::read_to_string(&path).unwrap().replace(
            r#""count":3,"type":"VEC3"}]"#,
            r#""count":3000,"type":"VEC3"}]"#,
        );
        std::fs::write(&path, text).unwrap();
        let e = load_plain_mesh(&path).unwrap_err().to_string();
        assert!(e.contains("do not fit in bufferViews[1]"), "{e}");
    }
}
