//! A textured quad scene written to a folder: the input of meshio's texture import tests and of
//! `bake/tests/output_textures.rs` (which includes this file by path, so that the scene has one
//! home).

use serde_json::json;
use std::path::Path;

/// A unit quad in the XY plane with UVs covering the texture's left half, lit by a point light.
pub fn quad_scene(dir: &Path, accessor_count: u32, image_view: bool) -> std::path::PathBuf {
    let mut bin = Vec::new();
    for p in [[0f32, 0., 0.], [1., 0., 0.], [1., 1., 0.], [0., 1., 0.]] {
        p.iter()
            .for_each(|c| bin.extend_from_slice(&c.to_le_bytes()));
    }
    for uv in [[0f32, 1.], [0.5, 1.], [0.5, 0.], [0., 0.]] {
        uv.iter()
            .for_each(|c| bin.extend_from_slice(&c.to_le_bytes()));
    }
    for i in [0u16, 1, 2, 0, 2, 3] {
        bin.extend_from_slice(&i.to_le_bytes());
    }
    std::fs::write(dir.join("quad.bin"), &bin).unwrap();
    // Left texel red-ish grey (sRGB 188 = linear 0.5), right texel black.
    image::RgbImage::from_raw(2, 1, vec![188, 188, 188, 0, 0, 0])
        .unwrap()
        .save(dir.join("tex.png"))
        .unwrap();
    let image = if image_view {
        json!({"bufferView": 3, "mimeType": "image/png"})
    } else {
        json!({"uri": "tex.png"})
    };
    let doc = json!({
        "asset": {"version": "2.0"},
        "extensionsUsed": ["KHR_lights_punctual"],
        "extensions": {"KHR_lights_punctual": {"lights": [{"type": "point", "intensity": 10}]}},
        "scene": 0,
        "scenes": [{"nodes": [0, 1]}],
        "nodes": [
            {"name": "quad", "mesh": 0},
            {"name": "bulb", "translation": [0.5, 0.5, 1], "extensions": {"KHR_lights_punctual": {"light": 0}}}
        ],
        "meshes": [{"primitives": [{"attributes": {"POSITION": 0, "TEXCOORD_0": 1}, "indices": 2, "material": 0}]}],
        "materials": [{"pbrMetallicRoughness": {"baseColorFactor": [1, 0.5, 1, 1], "baseColorTexture": {"index": 0}}}],
        "textures": [{"source": 0, "sampler": 0}],
        "samplers": [{"wrapS": 33071, "wrapT": 33071}],
        "images": [image],
        "buffers": [{"uri": "quad.bin", "byteLength": bin.len()}],
        "bufferViews": [
            {"buffer": 0, "byteLength": 48, "target": 34962},
            {"buffer": 0, "byteOffset": 48, "byteLength": 32, "target": 34962},
            {"buffer": 0, "byteOffset": 80, "byteLength": 12, "target": 34963},
            {"buffer": 0, "byteOffset": 4096, "byteLength": 100}
        ],
        "accessors": [
            {"bufferView": 0, "componentType": 5126, "count": accessor_count, "type": "VEC3", "min": [0, 0, 0], "max": [1, 1, 0]},
            {"bufferView": 1, "componentType": 5126, "count": 4, "type": "VEC2"},
            {"bufferView": 2, "componentType": 5123, "count": 6, "type": "SCALAR"}
        ]
    });
    let path = dir.join("quad.gltf");
    std::fs::write(&path, serde_json::to_vec_pretty(&doc).unwrap()).unwrap();
    path
}
