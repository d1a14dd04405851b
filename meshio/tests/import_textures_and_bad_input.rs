//! glTF base colour textures (external PNG, sampler wrap modes) through import, and malformed
//! glTF content that must become warnings, not panics. (The baked output of a textured scene is
//! tested in `bake/tests/output_textures.rs`, on the same quad.)

mod common;

use common::quad::quad_scene;
use hce_meshio::scene::{import_scene, ImportOptions};
use std::path::Path;

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
