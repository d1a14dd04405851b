//! glTF base colour textures (external PNG, sampler wrap modes) through import and output, and
//! malformed glTF content that must become warnings, not panics.

use hce_bake::import::{import_scene, ImportOptions};
use hce_bake::output::{write_baked_gltf, ObjectLink};
use serde_json::json;
use std::path::Path;

/// A unit quad in the XY plane with UVs covering the texture's left half, lit by a point light.
fn quad_scene(dir: &Path, accessor_count: u32, image_view: bool) -> std::path::PathBuf {
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

#[test]
fn gltf_texture_is_averaged_over_uv_triangles() {
    let dir = tempfile::tempdir().unwrap();
    let path = quad_scene(dir.path(), 4, false);
    let s = import_scene(&path, &ImportOptions::default()).unwrap();
    assert!(s.warnings.is_empty(), "{:?}", s.warnings);
    let o = &s.objects[0];
    let m = s.material_of(o);
    let tex = m.base_color_texture.as_ref().unwrap();
    assert_eq!((tex.width, tex.height), (2, 1));
    assert!(
        (tex.texels[0][0] - 0.5029).abs() < 1e-3,
        "{:?}",
        tex.texels[0]
    );
    // The UVs span u in [0, 0.5]: with clamp-to-edge, texel 0 (0.503) at u <= 0.25, fading
    // bilinearly to texel 1 (0) at u = 0.75. Averaged over the half: between 0.35 and 0.5.
    let r = m.reflectance_over(o.triangle_uvs(0));
    assert!(r[0] > 0.35 && r[0] < 0.5, "{r:?}");
    // baseColorFactor multiplies the texture per channel.
    assert!((r[1] - 0.5 * r[0]).abs() < 1e-6, "{r:?}");
    assert_eq!(s.lights[0].position, [0.5, 0.5, 1.0]);
}

#[test]
fn baked_output_embeds_external_images() {
    let dir = tempfile::tempdir().unwrap();
    let path = quad_scene(dir.path(), 4, false);
    let s = import_scene(&path, &ImportOptions::default()).unwrap();
    let c = hce_format::example::two_triangles();
    let bytes = hce_format::write(&c).unwrap();
    let glb = write_baked_gltf(
        &s,
        &[vec![[0.5, 0.25, 0.125]; 4]],
        &bytes,
        &[Some(ObjectLink {
            object: 0,
            first_triangle: 0,
        })],
    )
    .unwrap();
    let asset = hce_format::gltf::Asset::parse(&glb).unwrap();
    let img = &asset.json["images"][0];
    assert!(img.get("uri").is_none());
    assert_eq!(img["mimeType"], "image/png");
    let buffers = asset.buffers(|_| Err("none".into())).unwrap();
    let view = img["bufferView"].as_u64().unwrap() as usize;
    let png = hce_format::gltf::buffer_view_bytes(&asset.json, &buffers, view).unwrap();
    assert_eq!(png, std::fs::read(dir.path().join("tex.png")).unwrap());
    // The baked file, moved elsewhere, still imports with its texture.
    let other = tempfile::tempdir().unwrap();
    let out = other.path().join("baked.glb");
    std::fs::write(&out, &glb).unwrap();
    let back = import_scene(&out, &ImportOptions::default()).unwrap();
    assert!(back.materials[0].base_color_texture.is_some());
    if let Some(keep) = std::env::var_os("HCE_KEEP_OUTPUT") {
        std::fs::write(Path::new(&keep).join("textured.baked.glb"), &glb).unwrap();
    }
}

#[test]
fn out_of_range_accessors_and_images_are_warnings() {
    let dir = tempfile::tempdir().unwrap();
    // POSITION claims 1000 vertices in a 48-byte view; the image view lies past the buffer.
    let path = quad_scene(dir.path(), 1000, true);
    let e = import_scene(&path, &ImportOptions::default()).unwrap_err();
    let text = e.to_string();
    assert!(text.contains("no triangles"), "{text}");
    assert!(
        text.contains("accessors[0]: 1000 elements do not fit in bufferViews[0]"),
        "{text}"
    );
    assert!(text.contains("images[0] cannot be decoded"), "{text}");
}

#[test]
fn truncated_and_garbage_files_are_errors() {
    let dir = tempfile::tempdir().unwrap();
    let glb =
        std::fs::read(Path::new(env!("CARGO_MANIFEST_DIR")).join("../samples/cornell-box.glb"))
            .unwrap();
    for cut in [0, 11, 20, 100, glb.len() / 2, glb.len() - 1] {
        let p = dir.path().join("cut.glb");
        std::fs::write(&p, &glb[..cut]).unwrap();
        let e = import_scene(&p, &ImportOptions::default());
        assert!(e.is_err(), "a GLB cut at {cut} bytes was accepted");
    }
    let p = dir.path().join("x.stl");
    std::fs::write(&p, b"solid").unwrap();
    let e = import_scene(&p, &ImportOptions::default()).unwrap_err();
    assert!(e.to_string().contains(".gltf, .glb or .obj"), "{e}");
    let e = import_scene(&dir.path().join("absent.glb"), &ImportOptions::default()).unwrap_err();
    assert!(e.to_string().contains("absent.glb"), "{e}");
}

#[test]
fn devices_and_absolute_paths_are_never_read() {
    // A buffer, an image and an MTL library that name /dev/zero would be read forever; each
    // becomes a warning naming the file, and the import ends.
    let dir = tempfile::tempdir().unwrap();
    let gltf = r#"{"asset": {"version": "2.0"},
      "buffers": [{"byteLength": 16, "uri": "/dev/zero"}, {"byteLength": 16, "uri": "zero.bin"}],
      "images": [{"uri": "zero.png"}], "textures": [{"source": 0}],
      "materials": [{"pbrMetallicRoughness": {"baseColorTexture": {"index": 0}}}]}"#;
    std::fs::write(dir.path().join("s.gltf"), gltf).unwrap();
    #[cfg(unix)]
    {
        std::os::unix::fs::symlink("/dev/zero", dir.path().join("zero.bin")).unwrap();
        std::os::unix::fs::symlink("/dev/zero", dir.path().join("zero.png")).unwrap();
    }
    let e = import_scene(&dir.path().join("s.gltf"), &ImportOptions::default())
        .unwrap_err()
        .to_string();
    assert!(e.contains("an absolute path is not a relative URI"), "{e}");
    #[cfg(unix)]
    assert!(e.contains("zero.bin is not a regular file"), "{e}");

    std::fs::write(
        dir.path().join("s.obj"),
        "mtllib zero.mtl\nv 0 0 0\nv 1 0 0\nv 0 1 0\nf 1 2 3\n",
    )
    .unwrap();
    #[cfg(unix)]
    std::os::unix::fs::symlink("/dev/zero", dir.path().join("zero.mtl")).unwrap();
    // No light either: the error lists nothing to bake with, after the MTL was refused.
    let e = import_scene(&dir.path().join("s.obj"), &ImportOptions::default())
        .unwrap_err()
        .to_string();
    assert!(e.contains("no light source"), "{e}");
}
