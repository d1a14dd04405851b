//! `hce inspect` and `hce validate` on valid and damaged files: output and exit statuses.

mod common;

use hce_format::{example, write};
use std::path::Path;

fn write_example(dir: &Path, name: &str, f: impl FnOnce(&mut Vec<u8>)) -> String {
    let mut bytes = write(&example::two_triangles()).unwrap();
    f(&mut bytes);
    let path = dir.join(name);
    std::fs::write(&path, bytes).unwrap();
    path.to_str().unwrap().to_owned()
}

#[test]
fn valid_file_validates_and_inspects() {
    let dir = tempfile::tempdir().unwrap();
    let path = write_example(dir.path(), "ok.hce", |_| {});
    let (code, out, _) = common::hce(&["validate", &path]);
    assert_eq!(code, 0);
    assert!(out.ends_with(": valid\n"), "{out}");
    let (code, out, _) = common::hce(&["inspect", "--json", &path]);
    assert_eq!(code, 0);
    let v: serde_json::Value = serde_json::from_str(&out).unwrap();
    assert_eq!(v["version"]["major"], 1);
    assert_eq!(v["sections"].as_array().unwrap().len(), 15);
    assert_eq!(v["objects"][0]["triangles"], 2);
    assert_eq!(v["objects"][0]["nodes"], 6);
    assert_eq!(
        v["objects"][0]["tree_depth"],
        serde_json::json!({ "0": 1, "1": 1 })
    );
    assert_eq!(
        v["objects"][0]["normals_per_triangle"],
        serde_json::json!({ "1": 1, "2": 1 })
    );
    let (code, out, _) = common::hce(&["inspect", &path]);
    assert_eq!(code, 0);
    assert!(out.contains("tree depth: 0: 1, 1: 1"), "{out}");
}

#[test]
fn damaged_files_get_distinct_exit_statuses() {
    let dir = tempfile::tempdir().unwrap();
    // A triangle index changed inside TRIS (0x500): checksum and content problems, all listed.
    let bad = write_example(dir.path(), "bad.hce", |b| b[0x500] = 7);
    let (code, out, _) = common::hce(&["validate", &bad]);
    assert_eq!(code, 3);
    let lines: Vec<&str> = out.lines().collect();
    assert!(
        lines[0].starts_with("sections[3] (TRIS of object 0): checksum mismatch"),
        "{out}"
    );
    assert!(
        lines
            .contains(&"objects[0].mesh.triangles[0]: vertex index 7 is out of range (4 vertices)"),
        "{out}"
    );
    let (code, out, _) = common::hce(&["inspect", "--json", &bad]);
    assert_eq!(code, 0, "inspect shows a file whose structure is readable");
    let v: serde_json::Value = serde_json::from_str(&out).unwrap();
    assert_eq!(v["sections"][3]["checksum_ok"], false);
    assert_eq!(v["sections"][2]["checksum_ok"], true);

    let truncated = write_example(dir.path(), "short.hce", |b| b.truncate(100));
    let (code, out, _) = common::hce(&["validate", &truncated]);
    assert_eq!(code, 3);
    assert!(out.contains("truncated"), "{out}");
    let (code, out, _) = common::hce(&["inspect", "--json", &truncated]);
    assert_eq!(code, 3);
    let v: serde_json::Value = serde_json::from_str(&out).unwrap();
    assert!(v["error"].as_str().unwrap().contains("truncated"));

    let missing = dir.path().join("missing.hce");
    let (code, _, err) = common::hce(&["validate", missing.to_str().unwrap()]);
    assert_eq!(code, 4);
    assert!(err.contains("missing.hce"), "{err}");
    let (code, _, _) = common::hce(&["validate"]);
    assert_eq!(code, 2);
    let (code, out, _) = common::hce(&["--help"]);
    assert_eq!(code, 0);
    assert!(
        out.contains("3  invalid input") && out.contains("4  I/O error"),
        "{out}"
    );
}

#[test]
fn glb_links_are_checked_against_the_mesh() {
    use hce_format::{write_glb, GltfAsset as Asset};
    let dir = tempfile::tempdir().unwrap();
    let glb = example::triangle_glb();
    let ok = dir.path().join("ok.glb");
    std::fs::write(&ok, &glb).unwrap();
    let (code, out, _) = common::hce(&["validate", ok.to_str().unwrap()]);
    assert_eq!(code, 0, "{out}");
    // Move the second vertex: the hash differs and no placement pairs the triangle (SPEC.md 2.6).
    let asset = Asset::from_glb(&glb).unwrap();
    let mut bin = asset.bin.clone().unwrap();
    bin[12..16].copy_from_slice(&2f32.to_le_bytes());
    let edited = dir.path().join("edited.glb");
    std::fs::write(&edited, write_glb(&asset.json, &bin).unwrap()).unwrap();
    let (code, out, _) = common::hce(&["validate", edited.to_str().unwrap()]);
    assert_eq!(code, 3);
    assert!(
        out.starts_with(
            "meshes[0].primitives[0]: not the same geometry as object 0 'tri' triangles 0..1 (SPEC.md 2.6)"
        ) && out.contains("the mesh was edited after baking"),
        "{out}"
    );
    let (code, out, _) = common::hce(&["inspect", "--json", edited.to_str().unwrap()]);
    assert_eq!(code, 0);
    let v: serde_json::Value = serde_json::from_str(&out).unwrap();
    assert_eq!(v["format"], "glb");
    assert_eq!(v["primitives"][0]["hash_ok"], false);
}
