//! `EXT_mesh_gpu_instancing` input (KhronosGroup/glTF `extensions/2.0/Vendor/
//! EXT_mesh_gpu_instancing`): a node whose mesh is drawn once per instance, each instance placed
//! by its `TRANSLATION`, `ROTATION` and `SCALE` in node space.
//!
//! Baked light differs from one copy to the next (one copy stands in another's shadow), so the
//! baker cannot share one bake between instances. [`expand`] rewrites such a node, in the JSON,
//! into one child node per instance holding that instance's transform and the node's mesh: the
//! importer then bakes each copy as its own object, and the baked output, which re-reads the
//! source through the same function, gives each its own mesh copy (as for a mesh used by several
//! nodes). Both sides expand the same JSON the same way, so their node indices agree.
//!
//! Instance `i` of node `n` becomes node `N + k` (after every node of the file, in node order
//! and then instance order), named `"<node name>#<i>"` (`"node<n>#<i>"` without a name), the
//! first children of `n`. Its local transform is `T · R · S` of the instance, as glTF's nodes
//! read (scene_graph), so its world transform is the node's times the instance's, as the
//! extension specifies.

use serde_json::{json, Value};

/// The extension's name.
pub const EXTENSION: &str = "EXT_mesh_gpu_instancing";

/// The most instances one file may expand into. Each one becomes an object with its own bake,
/// so a grass field of a million blades would be a million bakes: refused, with a message,
/// rather than allocated.
pub const MAX_INSTANCES: usize = 16_384;

/// Whether any node of `json` uses the extension.
pub fn used(json: &Value) -> bool {
    nodes(json).iter().any(|n| instancing(n).is_some())
}

fn nodes(json: &Value) -> &[Value] {
    json.get("nodes")
        .and_then(Value::as_array)
        .map_or(&[], Vec::as_slice)
}

fn instancing(node: &Value) -> Option<&Value> {
    node.get("extensions")?.get(EXTENSION)
}

/// Rewrites every instanced node of `json` as described in the module documentation, reading
/// the instance accessors from `buffers` (by index; a buffer that could not be loaded is empty
/// and its accessors fail to read). Returns how many instances were expanded. Removes the
/// extension from `extensionsUsed` and `extensionsRequired`. Errors name the JSON location.
pub fn expand(json: &mut Value, buffers: &[Vec<u8>]) -> Result<usize, String> {
    let count = nodes(json).len();
    let mut new_nodes = Vec::new();
    let mut children_of = Vec::new();
    for n in 0..count {
        let node = &nodes(json)[n];
        let Some(ext) = instancing(node) else {
            continue;
        };
        let loc = format!("nodes[{n}].extensions.{EXTENSION}");
        let mesh = node
            .get("mesh")
            .cloned()
            .ok_or_else(|| format!("{loc}: the node has no mesh to instance"))?;
        let attributes = ext
            .get("attributes")
            .and_then(Value::as_object)
            .ok_or_else(|| format!("{loc}.attributes is missing or not an object"))?;
        let read = |name: &str, components: usize| -> Result<Option<Vec<f32>>, String> {
            let Some(a) = attributes.get(name) else {
                return Ok(None);
            };
            let at = format!("{loc}.attributes.{name}");
            let index = a
                .as_u64()
                .ok_or_else(|| format!("{at} is not an accessor index"))?;
            let values = hce_format::read_accessor(json, buffers, index as usize)
                .map_err(|e| format!("{at}: {e}"))?;
            if values.components != components {
                return Err(format!(
                    "{at}: accessors[{index}] has {} components, not {components}",
                    values.components
                ));
            }
            let v: Vec<f32> = values.values.iter().map(|&x| x as f32).collect();
            if v.iter().any(|x| !x.is_finite()) {
                return Err(format!("{at}: accessors[{index}] holds a non-finite value"));
            }
            Ok(Some(v))
        };
        let translation = read("TRANSLATION", 3)?;
        let rotation = read("ROTATION", 4)?;
        let scale = read("SCALE", 3)?;
        let counts: Vec<usize> = [(&translation, 3), (&rotation, 4), (&scale, 3)]
            .iter()
            .filter_map(|(v, c)| v.as_ref().map(|v| v.len() / c))
            .collect();
        let Some(&instances) = counts.first() else {
            return Err(format!(
                "{loc}.attributes has none of TRANSLATION, ROTATION and SCALE"
            ));
        };
        if counts.iter().any(|&c| c != instances) {
            return Err(format!(
                "{loc}.attributes: the accessors have different counts ({counts:?})"
            ));
        }
        if new_nodes.len() + instances > MAX_INSTANCES {
            return Err(format!(
                "{loc}: more than {MAX_INSTANCES} instances in the file; each instance is baked \
                 as an object of its own, so bake the instanced mesh once in a file of its own"
            ));
        }
        let base = node
            .get("name")
            .and_then(Value::as_str)
            .map_or_else(|| format!("node{n}"), str::to_owned);
        let mut children = Vec::with_capacity(instances);
        for i in 0..instances {
            let mut child = json!({ "name": format!("{base}#{i}"), "mesh": mesh });
            if let Some(t) = &translation {
                child["translation"] = json!(t[3 * i..3 * i + 3]);
            }
            if let Some(r) = &rotation {
                child["rotation"] = json!(r[4 * i..4 * i + 4]);
            }
            if let Some(s) = &scale {
                child["scale"] = json!(s[3 * i..3 * i + 3]);
            }
            children.push(json!(count + new_nodes.len()));
            new_nodes.push(child);
        }
        children_of.push((n, children));
    }
    let expanded = new_nodes.len();
    if children_of.is_empty() {
        return Ok(0);
    }
    let all = json["nodes"].as_array_mut().expect("nodes were read above");
    for (n, mut children) in children_of {
        let node = &mut all[n];
        if let Some(old) = node.get("children").and_then(Value::as_array) {
            children.extend(old.iter().cloned());
        }
        node["children"] = Value::Array(children);
        if let Some(o) = node.as_object_mut() {
            o.remove("mesh");
        }
        if let Some(exts) = node.get_mut("extensions").and_then(Value::as_object_mut) {
            exts.remove(EXTENSION);
            if exts.is_empty() {
                node.as_object_mut().map(|o| o.remove("extensions"));
            }
        }
    }
    all.extend(new_nodes);
    for list in ["extensionsUsed", "extensionsRequired"] {
        if let Some(a) = json.get_mut(list).and_then(Value::as_array_mut) {
            a.retain(|e| e != EXTENSION);
        }
    }
    Ok(expanded)
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::scene_graph::walk;
    use glam::{Mat4, Quat, Vec3};

    /// A node with a parent transform, two instances, and an ordinary child.
    fn asset() -> (Value, Vec<Vec<u8>>) {
        let mut bin = Vec::new();
        for x in [1.0f32, 0.0, 0.0, 0.0, 2.0, 0.0] {
            bin.extend_from_slice(&x.to_le_bytes());
        }
        // A quarter turn about z for instance 1, none for instance 0.
        let h = std::f32::consts::FRAC_1_SQRT_2;
        for x in [0.0f32, 0.0, 0.0, 1.0, 0.0, 0.0, h, h] {
            bin.extend_from_slice(&x.to_le_bytes());
        }
        let json = json!({
            "extensionsUsed": [EXTENSION],
            "scenes": [{ "nodes": [0] }],
            "nodes": [
                { "name": "trees", "mesh": 0, "translation": [0.0, 0.0, 5.0], "children": [1],
                  "extensions": { EXTENSION: { "attributes": { "TRANSLATION": 0, "ROTATION": 1 } } } },
                { "name": "child" }
            ],
            "meshes": [{ "primitives": [] }],
            "accessors": [
                { "bufferView": 0, "componentType": 5126, "count": 2, "type": "VEC3" },
                { "bufferView": 1, "componentType": 5126, "count": 2, "type": "VEC4" }
            ],
            "bufferViews": [
                { "buffer": 0, "byteOffset": 0, "byteLength": 24 },
                { "buffer": 0, "byteOffset": 24, "byteLength": 32 }
            ],
            "buffers": [{ "byteLength": bin.len() }]
        });
        (json, vec![bin])
    }

    #[test]
    fn each_instance_becomes_a_child_node_placed_by_the_node_then_the_instance() {
        let (mut json, buffers) = asset();
        assert!(used(&json));
        assert_eq!(expand(&mut json, &buffers), Ok(2));
        assert!(!used(&json));
        assert_eq!(json["extensionsUsed"], json!([]));
        assert_eq!(json["nodes"][0].get("mesh"), None);
        assert_eq!(json["nodes"][0]["children"], json!([2, 3, 1]));
        assert_eq!(json["nodes"][2]["name"], "trees#0");
        assert_eq!(json["nodes"][3]["name"], "trees#1");
        let w = walk(&json).unwrap();
        let meshes: Vec<_> = w.mesh_instances().collect();
        assert_eq!(meshes.len(), 2);
        let parent = Mat4::from_translation(Vec3::new(0.0, 0.0, 5.0));
        let second = parent
            * Mat4::from_rotation_translation(
                Quat::from_xyzw(
                    0.0,
                    0.0,
                    std::f32::consts::FRAC_1_SQRT_2,
                    std::f32::consts::FRAC_1_SQRT_2,
                ),
                Vec3::new(0.0, 2.0, 0.0),
            );
        let p = meshes[1].0.world.transform_point3(Vec3::X);
        assert!(
            (p - second.transform_point3(Vec3::X)).length() < 1e-6,
            "{p}"
        );
        assert!((p - Vec3::new(0.0, 3.0, 5.0)).length() < 1e-6, "{p}");
        let q = meshes[0].0.world.transform_point3(Vec3::ZERO);
        assert!((q - Vec3::new(1.0, 0.0, 5.0)).length() < 1e-6, "{q}");
    }

    #[test]
    fn bad_instancing_is_an_error_naming_its_location() {
        let (json, buffers) = asset();
        let mut no_mesh = json.clone();
        no_mesh["nodes"][0].as_object_mut().unwrap().remove("mesh");
        assert!(expand(&mut no_mesh, &buffers)
            .unwrap_err()
            .starts_with("nodes[0].extensions.EXT_mesh_gpu_instancing: the node has no mesh"));
        let mut uneven = json.clone();
        uneven["accessors"][1]["count"] = json!(1);
        assert!(expand(&mut uneven, &buffers)
            .unwrap_err()
            .contains("different counts"));
        let mut short = json.clone();
        assert!(expand(&mut short, &[vec![0; 8]])
            .unwrap_err()
            .starts_with("nodes[0].extensions.EXT_mesh_gpu_instancing.attributes.TRANSLATION: "));
        let mut empty = json;
        empty["nodes"][0]["extensions"][EXTENSION]["attributes"] = json!({});
        assert!(expand(&mut empty, &buffers)
            .unwrap_err()
            .contains("has none of"));
    }

    #[test]
    fn too_many_instances_are_refused_before_any_node_is_made() {
        let count = MAX_INSTANCES + 1;
        let bin = vec![0u8; 12 * count];
        let mut json = json!({
            "nodes": [{ "mesh": 0,
                        "extensions": { EXTENSION: { "attributes": { "TRANSLATION": 0 } } } }],
            "accessors": [{ "bufferView": 0, "componentType": 5126, "count": count, "type": "VEC3" }],
            "bufferViews": [{ "buffer": 0, "byteLength": bin.len() }],
            "buffers": [{ "byteLength": bin.len() }]
        });
        let e = expand(&mut json, &[bin]).unwrap_err();
        assert!(e.contains("more than 16384 instances"), "{e}");
        assert_eq!(json["nodes"].as_array().unwrap().len(), 1);
    }
}
