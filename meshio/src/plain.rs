//! A minimal loader for plain (not yet baked) meshes, so `hce render` can preview any OBJ or
//! glTF: positions, triangle indices and `COLOR_0` when present, welded on exactly equal
//! positions and turned into a flat object whose single-node trees carry one colour per
//! triangle, which the runtime's flat kernel draws.

use std::path::Path;

use hce_format::{rgb9e5, ControlMesh, Object, ObjectKind, TriangleRecord};

use hce_geometry::flat::{edge_ids, normal_and_area};

use crate::import::ImportError;

/// Triangles with optional linear per-vertex colours.
#[derive(Clone, Debug, Default, PartialEq)]
pub struct PlainMesh {
    pub positions: Vec<f32>,
    pub indices: Vec<u32>,
    /// Linear `r, g, b` per vertex, from glTF `COLOR_0` or OBJ vertex colours.
    pub colours: Option<Vec<f32>>,
}

fn load_err(path: &Path, reason: impl std::fmt::Display) -> ImportError {
    ImportError::Invalid {
        path: path.to_path_buf(),
        what: reason.to_string(),
    }
}

/// Loads every triangle primitive of an OBJ, glTF or GLB file into one mesh.
pub fn load_plain_mesh(path: &Path) -> Result<PlainMesh, ImportError> {
    let ext = path
        .extension()
        .and_then(|e| e.to_str())
        .unwrap_or("")
        .to_ascii_lowercase();
    let mut mesh = PlainMesh::default();
    let mut colours = Vec::new();
    let mut any_colour = false;
    match ext.as_str() {
        "obj" => {
            let (models, _) = tobj::load_obj(
                path,
                &tobj::LoadOptions {
                    triangulate: true,
                    single_index: true,
                    ..Default::default()
                },
            )
            .map_err(|e| load_err(path, e))?;
            for m in models {
                let base = (mesh.positions.len() / 3) as u32;
                let n = m.mesh.positions.len() / 3;
                mesh.positions.extend(&m.mesh.positions);
                if m.mesh.vertex_color.len() == 3 * n {
                    any_colour = true;
                    colours.extend(&m.mesh.vertex_color);
                } else {
                    colours.extend(std::iter::repeat_n(-1.0, 3 * n));
                }
                mesh.indices.extend(m.mesh.indices.iter().map(|i| i + base));
            }
        }
        "gltf" | "glb" => {
            let (doc, buffers, _) = gltf::import(path).map_err(|e| load_err(path, e))?;
            for gm in doc.meshes() {
                for prim in gm.primitives() {
                    if prim.mode() != gltf::mesh::Mode::Triangles {
                        continue;
                    }
                    let reader = prim.reader(|b| buffers.get(b.index()).map(|d| &d.0[..]));
                    let Some(pos) = reader.read_positions() else {
                        continue;
                    };
                    let base = (mesh.positions.len() / 3) as u32;
                    let pos: Vec<[f32; 3]> = pos.collect();
                    let n = pos.len() as u32;
                    mesh.positions.extend(pos.iter().flatten());
                    match reader.read_colors(0) {
                        Some(c) => {
                            any_colour = true;
                            colours.extend(c.into_rgb_f32().flatten());
                        }
                        None => colours.extend(std::iter::repeat_n(-1.0, 3 * n as usize)),
                    }
                    match reader.read_indices() {
                        Some(ix) => {
                            for i in ix.into_u32() {
                                if i >= n {
                                    return Err(load_err(
                                        path,
                                        format!(
                                            "mesh {:?}: index {i} >= {n} vertices",
                                            gm.name().unwrap_or("")
                                        ),
                                    ));
                                }
                                mesh.indices.push(base + i);
                            }
                        }
                        None => mesh.indices.extend(base..base + n - n % 3),
                    }
                }
            }
        }
        _ => {
            return Err(load_err(
                path,
                "unsupported extension (expected .obj, .gltf or .glb)",
            ))
        }
    }
    if mesh.indices.is_empty() {
        return Err(load_err(path, "no triangles found"));
    }
    if any_colour {
        // Vertices without colours in a partly coloured file take neutral grey.
        mesh.colours = Some(
            colours
                .iter()
                .map(|&c| if c < 0.0 { 0.5 } else { c })
                .collect(),
        );
    }
    Ok(mesh)
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
