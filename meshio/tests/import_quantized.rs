//! KHR_mesh_quantization input (what `gltf-transform quantize` and gltfpack write): integer
//! positions and normals, the dequantization in the node. The scene importer the baker reads
//! with takes them as it takes the same scene in floats: the `gltf` crate alone refuses a file
//! that requires the extension and cannot decode its accessors.

use hce_meshio::scene::{import_scene_bytes, ImportOptions, SceneBytes};
use serde_json::json;

/// A unit quad lit by its own emissive material, in floats, or with positions as normalized
/// SHORTs (`k / 32767` of a unit) and normals as normalized BYTEs, required KHR_mesh_quantization
/// and the node scaled by 2 (so that both are the same surface: the quantized quad is a half
/// unit, scaled back up).
fn quad(quantized: bool) -> Vec<u8> {
    let corners = [
        [0.0f32, 0.0, 0.0],
        [1.0, 0.0, 0.0],
        [1.0, 1.0, 0.0],
        [0.0, 1.0, 0.0],
    ];
    let mut bin = Vec::new();
    if quantized {
        for c in corners {
            for x in c {
                bin.extend_from_slice(&((x * 0.5 * 32767.0).round() as i16).to_le_bytes());
            }
            bin.extend_from_slice(&[0, 0]); // each element padded to 4 bytes
        }
        for _ in 0..4 {
            bin.extend_from_slice(&[0, 0, 127, 0]);
        }
    } else {
        for c in corners {
            for x in c {
                bin.extend_from_slice(&x.to_le_bytes());
            }
        }
        for _ in 0..4 {
            for x in [0.0f32, 0.0, 1.0] {
                bin.extend_from_slice(&x.to_le_bytes());
            }
        }
    }
    let normals_at = bin.len() - 4 * if quantized { 4 } else { 12 };
    let indices_at = bin.len();
    for i in [0u16, 1, 2, 0, 2, 3] {
        bin.extend_from_slice(&i.to_le_bytes());
    }
    let (component, normal_component, stride) = if quantized {
        (5122, 5120, Some(8))
    } else {
        (5126, 5126, None)
    };
    let mut position_view = json!({ "buffer": 0, "byteOffset": 0, "byteLength": normals_at });
    if let Some(s) = stride {
        position_view["byteStride"] = s.into();
    }
    let mut normal_view =
        json!({ "buffer": 0, "byteOffset": normals_at, "byteLength": indices_at - normals_at });
    if quantized {
        // Three bytes an element, each element starting on 4 bytes (glTF 3.6.2.4).
        normal_view["byteStride"] = 4.into();
    }
    let mut json = json!({
        "asset": { "version": "2.0" },
        "scene": 0,
        "scenes": [{ "nodes": [0] }],
        "nodes": [{ "mesh": 0, "scale": if quantized { [2.0, 2.0, 2.0] } else { [1.0, 1.0, 1.0] } }],
        "materials": [{ "emissiveFactor": [1.0, 1.0, 1.0] }],
        "meshes": [{ "primitives": [{
            "attributes": { "POSITION": 0, "NORMAL": 1 }, "indices": 2, "material": 0
        }] }],
        "accessors": [
            { "bufferView": 0, "componentType": component, "normalized": quantized, "count": 4,
              "type": "VEC3", "min": [0.0, 0.0, 0.0],
              "max": if quantized { [0.5, 0.5, 0.0] } else { [1.0, 1.0, 0.0] } },
            { "bufferView": 1, "componentType": normal_component, "normalized": quantized,
              "count": 4, "type": "VEC3" },
            { "bufferView": 2, "componentType": 5123, "count": 6, "type": "SCALAR" }
        ],
        "bufferViews": [
            position_view,
            normal_view,
            { "buffer": 0, "byteOffset": indices_at, "byteLength": 12 }
        ],
        "buffers": [{ "byteLength": bin.len() }]
    });
    if quantized {
        json["extensionsUsed"] = json!(["KHR_mesh_quantization"]);
        json["extensionsRequired"] = json!(["KHR_mesh_quantization"]);
    }
    while bin.len() % 4 != 0 {
        bin.push(0);
    }
    hce_format::write_glb(&json, &bin).unwrap()
}

#[test]
fn quantized_positions_and_normals_import_as_the_float_scene_does() {
    let options = ImportOptions::default();
    let float = import_scene_bytes(SceneBytes::Gltf(&quad(false)), &options).unwrap();
    let quantized = import_scene_bytes(SceneBytes::Gltf(&quad(true)), &options).unwrap();
    assert!(
        quantized
            .warnings
            .iter()
            .all(|w| !w.contains("KHR_mesh_quantization")),
        "{:?}",
        quantized.warnings
    );
    let (f, q) = (&float.objects[0], &quantized.objects[0]);
    assert_eq!(f.indices, q.indices);
    for (a, b) in f.world_positions.iter().zip(&q.world_positions) {
        for k in 0..3 {
            // Within one step of the 16-bit grid, scaled by 2.
            assert!((a[k] - b[k]).abs() <= 2.0 / 32767.0, "{a:?} {b:?}");
        }
    }
    // A normal of (0, 0, 127) is exactly the unit z.
    assert_eq!(q.normals.as_deref(), Some(&[[0.0, 0.0, 1.0]; 4][..]));
}

#[test]
fn another_required_extension_is_still_refused() {
    let bytes = quad(true);
    let glb = hce_format::GltfAsset::from_glb(&bytes).unwrap();
    let mut json = glb.json;
    json["extensionsRequired"] = json!(["KHR_mesh_quantization", "EXT_unknown"]);
    let bytes = hce_format::write_glb(&json, glb.bin.as_deref().unwrap()).unwrap();
    let e = import_scene_bytes(SceneBytes::Gltf(&bytes), &ImportOptions::default()).unwrap_err();
    assert!(e.to_string().contains("EXT_unknown"), "{e}");
}
