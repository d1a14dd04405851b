//! Converts an imported OBJ scene into glTF JSON and a BIN buffer, so that it can carry the
//! extension like any glTF input: one node and one mesh per OBJ object, positions and indices
//! exactly as read (so the geometry hashes hold), normals normalised, materials from MTL `Kd`
//! and `Ke`. `map_Kd` textures are used by the baker but not carried into the output.

use super::{push, OutputError, ARRAY_BUFFER, FLOAT};
use hce_meshio::scene::ImportedScene;
use serde_json::{json, Value};

const ELEMENT_ARRAY_BUFFER: u32 = 34963;
const UNSIGNED_INT: u32 = 5125;

fn push_view(
    json: &mut Value,
    bin: &mut Vec<u8>,
    bytes: &[u8],
    target: u32,
) -> Result<usize, OutputError> {
    bin.resize(bin.len().next_multiple_of(4), 0);
    let offset = bin.len();
    bin.extend_from_slice(bytes);
    push(
        json,
        "bufferViews",
        json!({ "buffer": 0, "byteOffset": offset, "byteLength": bytes.len(), "target": target }),
    )
}

fn floats(v: &[[f32; 3]]) -> Vec<u8> {
    v.iter().flatten().flat_map(|x| x.to_le_bytes()).collect()
}

/// The glTF JSON (without buffers' final length) and BIN of an OBJ scene.
pub fn obj_to_gltf(scene: &ImportedScene) -> Result<(Value, Vec<u8>), OutputError> {
    let mut json = json!({
        "asset": { "version": "2.0", "generator": concat!("hce-bake ", env!("CARGO_PKG_VERSION")) },
        "scene": 0,
        "scenes": [{ "nodes": (0..scene.objects.len()).collect::<Vec<_>>() }],
        "nodes": [],
        "meshes": [],
        "accessors": [],
        "bufferViews": [],
        "buffers": [{ "byteLength": 0 }],
    });
    let mut strength_used = false;
    let materials: Vec<Value> = scene
        .materials
        .iter()
        .map(|m| {
            let c = m.base_color.map(|x| x.clamp(0.0, 1.0));
            let mut out = json!({
                "pbrMetallicRoughness": {
                    "baseColorFactor": [c[0], c[1], c[2], 1.0],
                    "metallicFactor": 0.0,
                    "roughnessFactor": 1.0
                },
                "doubleSided": m.double_sided
            });
            if let Some(n) = &m.name {
                out["name"] = json!(n);
            }
            // emissiveFactor is limited to [0, 1]; larger emission goes into the strength.
            let max = m.emission.iter().copied().fold(0.0f32, f32::max);
            if max > 0.0 {
                let (factor, strength) = if max > 1.0 {
                    (m.emission.map(|e| e / max), max)
                } else {
                    (m.emission, 1.0)
                };
                out["emissiveFactor"] = json!(factor);
                if strength != 1.0 {
                    strength_used = true;
                    out["extensions"] = json!({
                        "KHR_materials_emissive_strength": { "emissiveStrength": strength }
                    });
                }
            }
            out
        })
        .collect();
    if !materials.is_empty() {
        json["materials"] = json!(materials);
    }
    if strength_used {
        json["extensionsUsed"] = json!(["KHR_materials_emissive_strength"]);
    }
    let mut bin = Vec::new();
    for (i, o) in scene.objects.iter().enumerate() {
        let (mut min, mut max) = ([f32::INFINITY; 3], [f32::NEG_INFINITY; 3]);
        for p in &o.positions {
            for k in 0..3 {
                min[k] = min[k].min(p[k]);
                max[k] = max[k].max(p[k]);
            }
        }
        let view = push_view(&mut json, &mut bin, &floats(&o.positions), ARRAY_BUFFER)?;
        let pos = push(
            &mut json,
            "accessors",
            json!({ "bufferView": view, "componentType": FLOAT, "count": o.positions.len(),
                    "type": "VEC3", "min": min, "max": max }),
        )?;
        let mut attributes = json!({ "POSITION": pos });
        // glTF requires unit normals; OBJ files often have others. A zero normal cannot be
        // fixed, so then the object goes without normals.
        let unit: Option<Vec<[f32; 3]>> = o.normals.as_ref().and_then(|n| {
            n.iter()
                .map(|v| {
                    let l = (v[0] * v[0] + v[1] * v[1] + v[2] * v[2]).sqrt();
                    (l > 1e-12 && l.is_finite()).then(|| v.map(|x| x / l))
                })
                .collect()
        });
        if let Some(n) = unit {
            let view = push_view(&mut json, &mut bin, &floats(&n), ARRAY_BUFFER)?;
            attributes["NORMAL"] = json!(push(
                &mut json,
                "accessors",
                json!({ "bufferView": view, "componentType": FLOAT, "count": n.len(), "type": "VEC3" }),
            )?);
        }
        let idx: Vec<u8> = o.indices.iter().flat_map(|i| i.to_le_bytes()).collect();
        let view = push_view(&mut json, &mut bin, &idx, ELEMENT_ARRAY_BUFFER)?;
        let indices = push(
            &mut json,
            "accessors",
            json!({ "bufferView": view, "componentType": UNSIGNED_INT, "count": o.indices.len(), "type": "SCALAR" }),
        )?;
        let mut prim = json!({ "attributes": attributes, "indices": indices, "mode": 4 });
        if let Some(m) = o.material {
            prim["material"] = json!(m);
        }
        push(
            &mut json,
            "meshes",
            json!({ "name": o.name, "primitives": [prim] }),
        )?;
        let mut node = json!({ "name": o.name, "mesh": i });
        if o.multires {
            node["extras"] = json!({ "hce": { "multires": true } });
        }
        push(&mut json, "nodes", node)?;
    }
    json["buffers"][0]["byteLength"] = json!(bin.len());
    Ok((json, bin))
}
