//! One test per MUST of SPEC.md that `validate_bytes` / `gltf::validate_asset` enforce beyond
//! the byte-level reader: each breaks exactly one rule of a valid file and asserts the located
//! problem it must give.

mod common;

use hce_format::{example, validate_bytes, write, Container, Problem, SPOKE_SHARP};
use hce_format::{validate_asset, GltfAsset as Asset, EXTENSION_NAME};
use serde_json::{json, Value};

fn problems_of(c: &Container) -> Vec<Problem> {
    validate_bytes(&write(c).unwrap())
}

/// Asserts that some problem sits at `location` and its message contains `needle`.
fn assert_problem(problems: &[Problem], location: &str, needle: &str) {
    assert!(
        problems
            .iter()
            .any(|p| p.location == location && p.message.contains(needle)),
        "no problem at {location} containing {needle:?} in {problems:#?}"
    );
}

#[test]
fn examples_are_valid() {
    for c in [
        example::single_triangle(),
        example::two_triangles(),
        example::grid(3, 2),
    ] {
        assert_eq!(problems_of(&c), vec![]);
    }
    let glb = Asset::from_glb(&example::triangle_glb()).unwrap();
    let buffers = glb.buffers(|_| Err("none".into())).unwrap();
    assert_eq!(validate_asset(&glb.json, &buffers), vec![]);
}

#[test]
fn object_geometry_hash_must_match_its_control_triangles() {
    let mut c = example::two_triangles();
    c.objects[0].mesh.positions[0] = 0.25;
    let p = problems_of(&c);
    assert_problem(&p, "objects[0].geometry_hash", "POSN or TRIS was edited");
}

#[test]
fn sharp_bit_must_be_on_both_ends_of_an_edge() {
    let mut c = example::two_triangles();
    let m = &mut c.objects[0].mesh;
    // The interior edge: the first spoke of some vertex that is not a boundary spoke.
    let s = (0..m.ring.len())
        .find(|&s| m.spoke_flags[s] == 0)
        .expect("an interior spoke");
    m.spoke_flags[s] |= SPOKE_SHARP;
    let p = problems_of(&c);
    assert_problem(
        &p,
        &format!("objects[0].mesh.spoke_flags[{s}]"),
        "the sharp bit must be set on both ends or neither",
    );
}

#[test]
fn bytes_after_the_last_section_are_an_error() {
    let mut b = write(&example::single_triangle()).unwrap();
    let end = b.len();
    b.extend_from_slice(&[0u8; 256]);
    let len = b.len() as u64;
    common::put_u64(&mut b, 16, len);
    common::reseal(&mut b);
    let p = validate_bytes(&b);
    assert_problem(
        &p,
        &format!("file[{end}]"),
        "256 bytes after the last section",
    );
}

#[test]
fn bake_parameters_must_be_a_json_object_or_empty() {
    let mut c = example::single_triangle();
    c.metadata.bake_parameters = "levels=3".into();
    assert_problem(&problems_of(&c), "metadata.bake_parameters", "is not JSON");
    c.metadata.bake_parameters = "[1, 2]".into();
    assert_problem(
        &problems_of(&c),
        "metadata.bake_parameters",
        "not an object",
    );
}

/// The example GLB with its JSON edited, validated.
fn glb_problems(edit: impl FnOnce(&mut Value)) -> Vec<Problem> {
    let a = Asset::from_glb(&example::triangle_glb()).unwrap();
    let mut json = a.json.clone();
    edit(&mut json);
    let buffers = a.buffers(|_| Err("none".into())).unwrap();
    validate_asset(&json, &buffers)
}

const ROOT: &str = "extensions.EXT_hce_baked_lighting";
const PRIM: &str = "meshes[0].primitives[0].extensions.EXT_hce_baked_lighting";

#[test]
fn extension_must_be_used_and_not_required() {
    let p = glb_problems(|j| j["extensionsUsed"] = json!([]));
    assert_problem(&p, "extensionsUsed", "MUST list it");
    let p = glb_problems(|j| j["extensionsRequired"] = json!([EXTENSION_NAME]));
    assert_problem(&p, "extensionsRequired", "MUST NOT be required");
}

#[test]
fn container_buffer_view_has_no_stride_or_target_and_is_4_aligned() {
    let view = |j: &Value| {
        j["extensions"][EXTENSION_NAME]["bufferView"]
            .as_u64()
            .unwrap() as usize
    };
    let p = glb_problems(|j| {
        let v = view(j);
        j["bufferViews"][v]["byteStride"] = json!(4);
        j["bufferViews"][v]["target"] = json!(34962);
    });
    let v = view(&Asset::from_glb(&example::triangle_glb()).unwrap().json);
    assert_problem(&p, &format!("bufferViews[{v}].byteStride"), "MUST NOT");
    assert_problem(&p, &format!("bufferViews[{v}].target"), "MUST NOT");
    let p = glb_problems(|j| {
        let v = view(j);
        let off = j["bufferViews"][v]["byteOffset"].as_u64().unwrap();
        j["bufferViews"][v]["byteOffset"] = json!(off + 2);
    });
    assert_problem(
        &p,
        &format!("bufferViews[{v}].byteOffset"),
        "is not a multiple of 4",
    );
}

#[test]
fn version_must_match_the_schema_pattern() {
    for bad in [json!("1"), json!("1.0.0"), json!("v1.0"), json!(1.0)] {
        let p = glb_problems(|j| j["extensions"][EXTENSION_NAME]["version"] = bad.clone());
        assert_problem(&p, &format!("{ROOT}.version"), "does not match");
    }
    assert_eq!(
        glb_problems(|j| j["extensions"][EXTENSION_NAME]["version"] = json!("1.7")),
        vec![]
    );
}

#[test]
fn malformed_geometry_hash_is_one_located_problem() {
    let upper = example::single_triangle().objects[0].geometry_hash;
    let text = format!("{upper:016X}");
    let p = glb_problems(|j| {
        j["meshes"][0]["primitives"][0]["extensions"][EXTENSION_NAME]["geometryHash"] =
            json!(text.clone())
    });
    assert_eq!(p.len(), 1, "{p:#?}");
    assert_problem(
        &p,
        &format!("{PRIM}.geometryHash"),
        "must be 16 lowercase hexadecimal digits",
    );
}

#[test]
fn primitive_hash_object_range_and_mesh_rules() {
    // A stale hash alone is no edit: the triangles are the object's (SPEC.md 2.6).
    let stale = |j: &mut Value| {
        j["meshes"][0]["primitives"][0]["extensions"][EXTENSION_NAME]["geometryHash"] =
            json!("0123456789abcdef")
    };
    assert_eq!(glb_problems(stale), vec![]);
    // A vertex moved off the plane by half the triangle's size is.
    let a = Asset::from_glb(&example::triangle_glb()).unwrap();
    let mut json = a.json.clone();
    stale(&mut json);
    let mut buffers = a.buffers(|_| Err("none".into())).unwrap();
    buffers[0][32..36].copy_from_slice(&0.5f32.to_le_bytes());
    assert_problem(
        &validate_asset(&json, &buffers),
        "meshes[0].primitives[0]",
        "not the same geometry as object 0 'tri' triangles 0..1 (SPEC.md 2.6): container triangle 0 has no primitive triangle within",
    );
    let p = glb_problems(|j| {
        j["meshes"][0]["primitives"][0]["extensions"][EXTENSION_NAME]["object"] = json!(4)
    });
    assert_problem(&p, &format!("{PRIM}.object"), "out of range");
    // A second mesh linking the same object: objects are shared within one mesh only.
    let p = glb_problems(|j| {
        let m = j["meshes"][0].clone();
        j["meshes"].as_array_mut().unwrap().push(m);
        j["nodes"]
            .as_array_mut()
            .unwrap()
            .push(json!({ "mesh": 1 }));
        j["scenes"][0]["nodes"] = json!([0, 1]);
    });
    assert_problem(
        &p,
        "meshes[1].primitives[0].extensions.EXT_hce_baked_lighting.object",
        "primitives of one mesh only",
    );
}

/// The example GLB with its JSON and its embedded container's bytes edited, validated.
fn glb_problems_with(
    edit: impl FnOnce(&mut Value),
    damage: impl FnOnce(&mut [u8]),
) -> Vec<Problem> {
    let a = Asset::from_glb(&example::triangle_glb()).unwrap();
    let mut json = a.json.clone();
    edit(&mut json);
    let mut buffers = a.buffers(|_| Err("none".into())).unwrap();
    let view = &json["bufferViews"][json["extensions"][EXTENSION_NAME]["bufferView"]
        .as_u64()
        .unwrap() as usize];
    let at = view["byteOffset"].as_u64().unwrap() as usize;
    let len = view["byteLength"].as_u64().unwrap() as usize;
    damage(&mut buffers[0][at..at + len]);
    validate_asset(&json, &buffers)
}

/// A stale hash and an object out of range, on the example's only primitive.
fn stale_link_to_object_4(j: &mut Value) {
    let link = &mut j["meshes"][0]["primitives"][0]["extensions"][EXTENSION_NAME];
    link["geometryHash"] = json!("0123456789abcdef");
    link["object"] = json!(4);
}

/// `edge_count` of object 0 made one too large, every checksum resealed: a decoding failure.
fn wrong_edge_count(b: &mut [u8]) {
    let objs = common::u64_at(b, common::entry(1) + 8) as usize;
    let e = common::u32_at(b, objs + 8 + 36);
    common::put_u32(b, objs + 8 + 36, e + 1);
    common::reseal(b);
}

#[test]
fn an_unreadable_container_hides_only_the_link_checks_that_need_it() {
    // Stage 1 (the header checksum): one problem at `file`; the stale hash is still found, the
    // object's range is not judged (the container's objects are unknown).
    let p = glb_problems_with(stale_link_to_object_4, |b| b[28] ^= 1);
    assert_eq!(p.len(), 2, "{p:#?}");
    assert_problem(&p, "file", "header checksum");
    assert_problem(&p, "meshes[0].primitives[0]", "edited after baking");
    // Stage 2's decoding (edge_count): the same.
    let p = glb_problems_with(stale_link_to_object_4, wrong_edge_count);
    assert_eq!(p.len(), 2, "{p:#?}");
    assert_problem(&p, "file", "edge_count");
    assert_problem(&p, "meshes[0].primitives[0]", "edited after baking");
    // A readable container: the range is judged too.
    let p = glb_problems_with(stale_link_to_object_4, |_| {});
    assert_problem(&p, &format!("{PRIM}.object"), "out of range");
}

#[test]
fn a_decoding_failure_skips_the_content_rules_but_not_the_checksums() {
    let mut c = example::two_triangles();
    // Rule 11 broken: not reported once the decoding fails.
    c.objects[0].mesh.positions[0] = 0.25;
    let mut b = write(&c).unwrap();
    wrong_edge_count(&mut b);
    let last = b.len() - 1;
    b[last] ^= 1;
    let p = validate_bytes(&b);
    assert_eq!(p.len(), 2, "{p:#?}");
    assert_problem(&p, "sections[14] (COLR of object 0)", "checksum mismatch");
    assert_problem(&p, "file", "edge_count");
}
