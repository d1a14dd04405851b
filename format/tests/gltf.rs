//! The glTF extension helpers: embed a container into a GLB, read it back, recompute hashes.

use hce_format::GltfAsset as Asset;
use hce_format::*;

use serde_json::json;

fn triangle_glb() -> Vec<u8> {
    example::triangle_glb()
}

#[test]
fn embedded_container_reads_back_with_matching_hash() {
    let glb = triangle_glb();
    assert_eq!(glb.len() % 4, 0);
    let asset = Asset::parse(&glb).unwrap();
    assert_eq!(asset.json["extensionsUsed"], json!([EXTENSION_NAME]));
    assert!(asset.json.get("extensionsRequired").is_none());
    assert_eq!(asset.json["bufferViews"][2]["byteOffset"], json!(256));
    let buffers = asset.buffers(|_| Err("no external files".into())).unwrap();
    let bytes = container_bytes(&asset.json, &buffers).unwrap().unwrap();
    let c = read(bytes).unwrap();
    assert_eq!(c, example::single_triangle());
    let links = primitive_links(&asset.json).unwrap();
    assert_eq!(links.len(), 1);
    let (hash, triangles) = primitive_geometry(&asset.json, &buffers, 0, 0).unwrap();
    assert_eq!(triangles, 1);
    assert_eq!(hash, links[0].geometry_hash);
    assert_eq!(hash, c.objects[0].geometry_hash);
}

#[test]
fn gltf_with_data_uri_is_read() {
    let glb = triangle_glb();
    let asset = Asset::parse(&glb).unwrap();
    let bin = asset.bin.clone().unwrap();
    let mut json = asset.json.clone();
    let b64 = encode_base64(&bin);
    json["buffers"][0]["uri"] = json!(format!("data:application/octet-stream;base64,{b64}"));
    let text = serde_json::to_vec(&json).unwrap();
    let asset = Asset::parse(&text).unwrap();
    let buffers = asset.buffers(|_| Err("no external files".into())).unwrap();
    let bytes = container_bytes(&asset.json, &buffers).unwrap().unwrap();
    assert_eq!(read(bytes).unwrap(), example::single_triangle());
}

fn encode_base64(b: &[u8]) -> String {
    const A: &[u8; 64] = b"ABCDEFGHIJKLMNOPQRSTUVWXYZabcdefghijklmnopqrstuvwxyz0123456789+/";
    let mut s = String::new();
    for chunk in b.chunks(3) {
        let n = chunk
            .iter()
            .enumerate()
            .fold(0u32, |acc, (i, &x)| acc | u32::from(x) << (16 - 8 * i));
        for i in 0..=chunk.len() {
            s.push(A[(n >> (18 - 6 * i) & 63) as usize] as char);
        }
    }
    while s.len() % 4 != 0 {
        s.push('=');
    }
    s
}

#[test]
fn truncated_and_corrupted_glb_are_errors() {
    let glb = triangle_glb();
    for n in 0..glb.len() {
        assert!(
            Asset::from_glb(&glb[..n]).is_err(),
            "prefix of {n} bytes accepted"
        );
    }
    let asset = Asset::parse(&glb).unwrap();
    let mut json = asset.json.clone();
    json["meshes"][0]["primitives"][0]["extensions"][EXTENSION_NAME]["geometryHash"] = json!("XYZ");
    let e = primitive_links(&json).unwrap_err().to_string();
    assert!(e.contains("meshes[0].primitives[0].extensions.EXT_hce_baked_lighting.geometryHash: must be 16 lowercase hexadecimal digits, found \"XYZ\""), "{e}");
    let mut json = asset.json.clone();
    json["bufferViews"][2]["byteLength"] = json!(1u64 << 40);
    let buffers = asset.buffers(|_| Err("none".into())).unwrap();
    assert!(container_bytes(&json, &buffers)
        .unwrap_err()
        .to_string()
        .contains("run past buffer 0"));
}

/// `HCE_WRITE_SAMPLES=DIR cargo test -p hce-format --test gltf` writes the example files, to
/// seed the fuzzer and to run the Khronos glTF-Validator on (see fuzz/README.md).
#[test]
fn sample_files_can_be_written_for_external_tools() {
    let glb = triangle_glb();
    assert_eq!(&glb[..4], b"glTF");
    if let Some(dir) = std::env::var_os("HCE_WRITE_SAMPLES") {
        let dir = std::path::PathBuf::from(dir);
        std::fs::create_dir_all(&dir).unwrap();
        std::fs::write(dir.join("triangle.glb"), &glb).unwrap();
        for (name, c) in [
            ("single_triangle.hce", example::single_triangle()),
            ("two_triangles.hce", example::two_triangles()),
            ("grid.hce", example::grid(3, 3)),
        ] {
            std::fs::write(dir.join(name), hce_format::write(&c).unwrap()).unwrap();
        }
        println!("wrote samples to {}", dir.display());
    }
}

/// Replays the glTF inputs of `tests/regressions/` (found by `cargo fuzz run gltf`) through the
/// whole extension pipeline: each must give errors or results, never a panic.
#[test]
fn gltf_regression_inputs_are_handled() {
    let dir = std::path::Path::new(env!("CARGO_MANIFEST_DIR")).join("tests/regressions");
    let mut n = 0;
    for e in std::fs::read_dir(&dir).unwrap() {
        let path = e.unwrap().path();
        if !path.extension().is_some_and(|x| x == "glb" || x == "gltf") {
            continue;
        }
        let asset = Asset::parse(&std::fs::read(&path).unwrap()).unwrap();
        let buffers = asset.buffers(|_| Err("none".into())).unwrap();
        let links = primitive_links(&asset.json).unwrap();
        let geometries = linked_geometries(&asset.json, &buffers, &links);
        if path.file_name().unwrap() == "gltf_position_accessor_scalar.glb" {
            // The fuzzer made POSITION a SCALAR accessor; indexing it as VEC3 used to panic.
            assert_eq!(
                geometries[0].as_ref().unwrap_err().to_string(),
                "glTF JSON: meshes[0].primitives[0]: the POSITION accessor is not VEC3"
            );
        }
        n += 1;
    }
    assert!(n >= 1);
}
