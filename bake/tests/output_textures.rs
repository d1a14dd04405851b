//! A textured glTF scene through the baked output: external images embedded in the GLB, and the
//! baked file still importing with its texture wherever it is moved.

#[path = "../../meshio/tests/common/quad.rs"]
mod quad;

use hce_bake::{write_baked_gltf, ObjectLink};
use hce_meshio::scene::{import_scene, ImportOptions};
use quad::quad_scene;
use std::path::Path;

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
    let asset = hce_format::GltfAsset::parse(&glb).unwrap();
    let img = &asset.json["images"][0];
    assert!(img.get("uri").is_none());
    assert_eq!(img["mimeType"], "image/png");
    let buffers = asset.buffers(|_| Err("none".into())).unwrap();
    let view = img["bufferView"].as_u64().unwrap() as usize;
    let png = hce_format::buffer_view_bytes(&asset.json, &buffers, view).unwrap();
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
