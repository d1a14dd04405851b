//! `hce subdivide BAKED` writes the scene: nodes, names, transforms, shared meshes, materials and
//! cameras kept; multiresolution objects Loop-subdivided, flat ones split linearly (their
//! geometry does not move), each baked primitive with NORMAL and COLOR_0.

mod common;

use hce_format::{GltfAsset as Asset, EXTENSION_NAME};
use serde_json::{json, Value};
use std::path::Path;

fn json_of(path: &Path) -> Value {
    Asset::parse(&std::fs::read(path).unwrap()).unwrap().json
}

/// POSITION bounds of the first primitive of the mesh of the node named `name`.
fn bounds(j: &Value, name: &str) -> (Value, Value) {
    let node = j["nodes"]
        .as_array()
        .unwrap()
        .iter()
        .find(|n| n["name"] == name)
        .unwrap();
    let mesh = &j["meshes"][node["mesh"].as_u64().unwrap() as usize];
    let a = &j["accessors"][mesh["primitives"][0]["attributes"]["POSITION"]
        .as_u64()
        .unwrap() as usize];
    (a["min"].clone(), a["max"].clone())
}

#[test]
fn baked_cornell_box_keeps_its_scene_and_flat_blocks_stay_boxes() {
    let dir = tempfile::tempdir().unwrap();
    let sample = Path::new(env!("CARGO_MANIFEST_DIR")).join("../samples/cornell-box.glb");
    let baked = dir.path().join("cornell.glb");
    let out = dir.path().join("cornell-l2.glb");
    common::hce_ok(&[
        "bake",
        sample.to_str().unwrap(),
        "-o",
        baked.to_str().unwrap(),
        "--bf-epsilon",
        "0.05",
    ]);
    common::hce_ok(&[
        "subdivide",
        baked.to_str().unwrap(),
        "-l",
        "2",
        "-o",
        out.to_str().unwrap(),
    ]);
    let (input, output) = (json_of(&baked), json_of(&out));
    // Every node as it was (names, transforms, cameras); the materials and cameras copied.
    for (a, b) in input["nodes"]
        .as_array()
        .unwrap()
        .iter()
        .zip(output["nodes"].as_array().unwrap())
    {
        for key in [
            "name",
            "translation",
            "rotation",
            "scale",
            "matrix",
            "camera",
            "mesh",
        ] {
            assert_eq!(a.get(key), b.get(key), "{key} of {a}");
        }
    }
    assert_eq!(input["nodes"].as_array().unwrap().len(), 9);
    assert_eq!(input["materials"], output["materials"]);
    assert_eq!(input["cameras"], output["cameras"]);
    // No container any more: the extension is gone from the output.
    assert!(output
        .get("extensions")
        .is_none_or(|e| e.get(EXTENSION_NAME).is_none()));
    assert!(!output["extensionsUsed"]
        .as_array()
        .unwrap()
        .contains(&json!(EXTENSION_NAME)));
    // Flat blocks are split linearly: their bounds do not shrink as Loop smoothing would.
    for name in ["short_block", "tall_block", "floor"] {
        assert_eq!(bounds(&input, name), bounds(&output, name), "{name}");
    }
    let prim = &output["meshes"][0]["primitives"][0]["attributes"];
    for attr in ["POSITION", "NORMAL", "COLOR_0"] {
        assert!(prim.get(attr).is_some(), "{attr} in {prim}");
    }
}

#[test]
fn nodes_sharing_a_mesh_still_share_the_refined_mesh() {
    let dir = tempfile::tempdir().unwrap();
    let a = Asset::from_glb(&hce_format::example::triangle_glb()).unwrap();
    let mut json = a.json.clone();
    json["nodes"] = json!([
        { "name": "left", "mesh": 0, "translation": [-1.0, 0.0, 0.0] },
        { "name": "right", "mesh": 0, "matrix": [1.0,0.0,0.0,0.0, 0.0,1.0,0.0,0.0, 0.0,0.0,1.0,0.0, 1.0,0.0,0.0,1.0] }
    ]);
    json["scenes"] = json!([{ "nodes": [0, 1] }]);
    let input = dir.path().join("two.glb");
    std::fs::write(
        &input,
        hce_format::write_glb(&json, a.bin.as_deref().unwrap()).unwrap(),
    )
    .unwrap();
    let out = dir.path().join("two-l1.gltf");
    common::hce_ok(&[
        "subdivide",
        input.to_str().unwrap(),
        "--flat",
        "uniform",
        "-l",
        "1",
        "-o",
        out.to_str().unwrap(),
    ]);
    let j = json_of(&out);
    assert_eq!(j["meshes"].as_array().unwrap().len(), 1);
    assert_eq!(j["nodes"][0]["mesh"], 0);
    assert_eq!(j["nodes"][1]["mesh"], 0);
    assert_eq!(j["nodes"][0]["translation"], json!([-1.0, 0.0, 0.0]));
    assert_eq!(j["nodes"][1]["matrix"], json["nodes"][1]["matrix"]);
    // Level 1 of one triangle: 4 triangles, 6 vertices.
    let prim = &j["meshes"][0]["primitives"][0];
    let count = |k: &Value| j["accessors"][k.as_u64().unwrap() as usize]["count"].clone();
    assert_eq!(count(&prim["indices"]), 12);
    assert_eq!(count(&prim["attributes"]["POSITION"]), 6);
    assert_eq!(count(&prim["attributes"]["COLOR_0"]), 6);
}

/// `NORMAL` of a multiresolution object in the scene output is the F.6 normal bit for bit (as
/// `--merge` writes it and the conformance probes list it), not normalised a second time.
#[test]
fn scene_normals_are_the_f6_normals_bit_for_bit() {
    let dir = tempfile::tempdir().unwrap();
    let container = hce_format::example::grid(3, 2);
    let object = &container.objects[0];
    assert_eq!(object.kind, hce_format::ObjectKind::Multiresolution);
    let input = dir.path().join("grid.hce");
    std::fs::write(&input, hce_format::write(&container).unwrap()).unwrap();
    let out = dir.path().join("grid-l2.glb");
    common::hce_ok(&[
        "subdivide",
        input.to_str().unwrap(),
        "-l",
        "2",
        "-o",
        out.to_str().unwrap(),
    ]);
    let (doc, buffers, _) = gltf::import_slice(std::fs::read(&out).unwrap()).unwrap();
    let prim = doc.meshes().next().unwrap().primitives().next().unwrap();
    let reader = prim.reader(|b| Some(&buffers[b.index()][..]));
    let normals: Vec<[f32; 3]> = reader.read_normals().unwrap().collect();
    let f6 = hce_geometry::refine::refine_object(object, 2)
        .unwrap()
        .mesh
        .normals;
    let bits =
        |v: &[[f32; 3]]| -> Vec<[u32; 3]> { v.iter().map(|n| n.map(f32::to_bits)).collect() };
    assert_eq!(bits(&normals), bits(&f6));
    // The bumpy grid has normals that a second normalisation would change: the test can fail.
    let renormalised: Vec<[f32; 3]> = f6
        .iter()
        .map(|&n| {
            let len = (n[0] * n[0] + n[1] * n[1] + n[2] * n[2]).sqrt();
            n.map(|x| x / len)
        })
        .collect();
    assert_ne!(bits(&renormalised), bits(&f6));
}
