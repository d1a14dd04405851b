//! A plain (not yet baked) mesh as a flat object, so `hce render` can preview any OBJ or glTF
//! read by `hce_meshio::plain::load_plain_mesh`, and the browser a glTF whose baked lighting
//! is gone ([`gltf_plain_mesh`], read by hce-format's own accessor reader, which `hce.wasm`
//! carries): welded on exactly equal positions, one single-node tree and one colour per
//! triangle, which the flat kernel draws.

use glam::DVec3;
use hce_format::{rgb9e5, ControlMesh, GltfError, Object, ObjectKind, TriangleRecord};
use hce_geometry::flat::{edge_ids, normal_and_area};
use hce_meshio::plain::PlainMesh;
use hce_meshio::scene_graph::SceneWalk;
use serde_json::Value;

/// The colour of the vertices of a primitive without `COLOR_0` in a file where others have it.
const NO_COLOUR: [f32; 3] = [0.5; 3];

/// The triangle primitives of the meshes `walk` visits, as one plain mesh in world space: each
/// primitive's positions decoded and dequantized ([`hce_format::read_primitive`]) and moved
/// by its node's world transform, its indices, and, when any primitive has `COLOR_0`, the
/// colour a glTF viewer draws without lighting: `COLOR_0` (`VEC3` or `VEC4`, any component type
/// glTF allows, normalized values as fractions; the alpha dropped) times the material's
/// `baseColorFactor`, plus its emissive colour (`emissiveFactor` times
/// `KHR_materials_emissive_strength`). A baked file's `COLOR_0` is the light arriving at each
/// vertex (SPEC.md F.9), so that product is the baked look that survives an optimiser. A
/// primitive that cannot be read (Draco-compressed, not triangles) is skipped with a warning in
/// `warnings`.
pub fn gltf_plain_mesh(
    json: &Value,
    buffers: &[Vec<u8>],
    walk: &SceneWalk,
    warnings: &mut Vec<String>,
) -> Result<PlainMesh, GltfError> {
    let mut positions = Vec::new();
    let mut indices = Vec::new();
    let mut colours: Vec<Option<[f32; 3]>> = Vec::new();
    for visit in &walk.visits {
        let Some(m) = visit.mesh else { continue };
        let count = json["meshes"][m]["primitives"]
            .as_array()
            .map_or(0, Vec::len);
        let world = visit.world.as_dmat4();
        for p in 0..count {
            let prim = match hce_format::read_primitive(json, buffers, m, p) {
                Ok(prim) => prim,
                Err(e) => {
                    warnings.push(format!("{e}; not drawn"));
                    continue;
                }
            };
            let base = u32::try_from(positions.len() / 3)
                .ok()
                .filter(|b| b.checked_add(prim.positions.len() as u32).is_some())
                .ok_or_else(|| GltfError::Json("the meshes have too many vertices".into()))?;
            for q in &prim.positions {
                let w = world.transform_point3(DVec3::from_array(*q));
                positions.extend(w.to_array().map(|x| x as f32));
            }
            indices.extend(prim.triangles.iter().flatten().map(|&v| base + v));
            let colour = json["meshes"][m]["primitives"][p]["attributes"]["COLOR_0"].as_u64();
            let read = match colour {
                Some(a) => {
                    let c = hce_format::read_accessor(json, buffers, a as usize)?;
                    if !(3..=4).contains(&c.components) || c.count() != prim.positions.len() {
                        return Err(GltfError::Json(format!(
                            "meshes[{m}].primitives[{p}]: COLOR_0 is not a VEC3 or VEC4 per vertex"
                        )));
                    }
                    let (base, emitted) = material_colours(json, m, p);
                    c.values
                        .chunks_exact(c.components)
                        .map(|v| {
                            Some(std::array::from_fn(|k| {
                                (v[k] * base[k] + emitted[k]) as f32
                            }))
                        })
                        .collect()
                }
                None => vec![None; prim.positions.len()],
            };
            colours.extend(read);
        }
    }
    let any = colours.iter().any(Option::is_some);
    Ok(PlainMesh {
        positions,
        indices,
        colours: any.then(|| {
            colours
                .iter()
                .flat_map(|c| c.unwrap_or(NO_COLOUR))
                .collect()
        }),
    })
}

/// Direction of the preview light used for meshes without colours.
const PREVIEW_LIGHT: [f32; 3] = [0.408_248_3, 0.816_496_6, 0.408_248_3];

/// The `baseColorFactor` (RGB; white by default) and emissive colour (black by default) of
/// primitive `p` of mesh `m`'s material, as glTF viewers read them (textures aside).
fn material_colours(json: &Value, m: usize, p: usize) -> ([f64; 3], [f64; 3]) {
    let material = json["meshes"][m]["primitives"][p]["material"]
        .as_u64()
        .and_then(|i| json.get("materials")?.get(i as usize));
    let rgb = |v: Option<&Value>, default: f64| -> [f64; 3] {
        let a = v.and_then(Value::as_array);
        std::array::from_fn(|k| {
            a.and_then(|a| a.get(k))
                .and_then(Value::as_f64)
                .filter(|x| x.is_finite())
                .unwrap_or(default)
        })
    };
    let Some(material) = material else {
        return ([1.0; 3], [0.0; 3]);
    };
    let base = rgb(
        material.pointer("/pbrMetallicRoughness/baseColorFactor"),
        1.0,
    );
    let strength = material
        .pointer("/extensions/KHR_materials_emissive_strength/emissiveStrength")
        .and_then(Value::as_f64)
        .filter(|x| x.is_finite())
        .unwrap_or(1.0);
    let emissive = rgb(material.get("emissiveFactor"), 0.0).map(|e| e * strength);
    (base, emissive)
}

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
        corner_colours: Vec::new(),
    };
    (object, dropped)
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn a_coloured_triangle_takes_its_corners_mean_colour_and_its_face_normal() {
        // Four corners, two of them at one position: welded, and the triangle repeating it
        // dropped.
        let mesh = PlainMesh {
            positions: vec![0.0, 0.0, 0.0, 1.0, 0.0, 0.0, 0.0, 1.0, 0.0, 1.0, 0.0, 0.0],
            indices: vec![0, 1, 2, 0, 1, 3],
            colours: Some(vec![
                1.0, 0.0, 0.0, 0.0, 1.0, 0.0, 0.0, 0.0, 1.0, 0.5, 0.5, 0.5,
            ]),
        };
        let (object, dropped) = to_flat_object("t", &mesh);
        assert_eq!(dropped, 1);
        assert_eq!(object.mesh.positions.len(), 9);
        assert_eq!(object.mesh.triangles, vec![0, 1, 2]);
        assert_eq!(object.normals, vec![[0.0, 0.0, 1.0]]);
        let c = rgb9e5::decode(object.colours[0]);
        for k in 0..3 {
            assert!((c[k] - 1.0 / 3.0).abs() < 0.01, "{c:?}");
        }
        assert!(hce_geometry::flat::FlatTopology::new("t", &object.mesh).is_ok());
    }

    #[test]
    fn an_uncoloured_triangle_is_grey_lit_by_the_preview_light() {
        let mesh = PlainMesh {
            positions: vec![0.0, 0.0, 0.0, 1.0, 0.0, 0.0, 0.0, 1.0, 0.0],
            indices: vec![0, 1, 2],
            colours: None,
        };
        let (object, _) = to_flat_object("t", &mesh);
        // Facing +z: n·l = 0.408.
        let want = 0.6 * (0.2 + 0.8 * PREVIEW_LIGHT[2]);
        let c = rgb9e5::decode(object.colours[0]);
        assert!(
            (c[0] - want).abs() < 0.01 && c[0] == c[1] && c[1] == c[2],
            "{c:?}"
        );
    }
}
