//! Imports the three committed sample scenes and checks what was read against their README.

use hce_meshio::scene::{import_scene, ImportError, ImportOptions, LightKind, SourceFormat};
use std::path::PathBuf;

fn sample(name: &str) -> PathBuf {
    PathBuf::from(env!("CARGO_MANIFEST_DIR"))
        .join("../samples")
        .join(name)
}

#[test]
fn teatime_reads_objects_counts_and_multires_flags() {
    let s = import_scene(&sample("teatime.glb"), &ImportOptions::default()).unwrap();
    assert_eq!(s.format, SourceFormat::Glb);
    let names: Vec<&str> = s.objects.iter().map(|o| o.name.as_str()).collect();
    assert_eq!(
        names,
        ["floor", "walls", "ceiling", "light", "table", "teapot", "cup", "spoon"]
    );
    assert_eq!(s.triangle_count(), 1038);
    let multires: Vec<&str> = s
        .objects
        .iter()
        .filter(|o| o.multires)
        .map(|o| o.name.as_str())
        .collect();
    assert_eq!(multires, ["teapot", "cup", "spoon"]);
    assert_eq!(s.objects[5].triangle_count(), 552);
    let light = &s.objects[3];
    assert!(s.material_of(light).is_emissive());
    assert!(s
        .camera
        .as_ref()
        .is_some_and(|c| c.name.as_deref() == Some("view")));
    assert!(s.warnings.is_empty(), "{:?}", s.warnings);
    assert!(s.summary.contains("1038 triangles"), "{}", s.summary);
    assert!(s.summary.contains("metres"), "{}", s.summary);
}

#[test]
fn hashes_match_the_format_crate_recomputation() {
    let path = sample("chesstime.glb");
    let s = import_scene(&path, &ImportOptions::default()).unwrap();
    assert_eq!(s.triangle_count(), 2214);
    let bytes = std::fs::read(&path).unwrap();
    let asset = hce_format::GltfAsset::parse(&bytes).unwrap();
    let buffers = asset.buffers(|_| Err("no external".into())).unwrap();
    for o in &s.objects {
        let (hash, tris) =
            hce_format::primitive_geometry(&asset.json, &buffers, o.mesh, o.primitive).unwrap();
        assert_eq!(hash, o.geometry_hash(), "{}", o.name);
        assert_eq!(tris, o.triangle_count());
        assert_eq!(o.world_positions.len(), o.positions.len());
        assert!(o
            .normals
            .as_ref()
            .is_some_and(|n| n.len() == o.positions.len()));
        // The samples place objects by translation only: world normals equal object normals.
        let wn = o.world_normals().unwrap();
        for (a, b) in wn.iter().zip(o.normals.as_ref().unwrap()) {
            assert!(
                (0..3).all(|k| (a[k] - b[k]).abs() < 1e-5),
                "{}: {a:?} {b:?}",
                o.name
            );
        }
    }
}

#[test]
fn multires_patterns_select_by_name() {
    let opts = ImportOptions {
        multires: vec!["short_*".into(), "light".into(), "teapot".into()],
    };
    let s = import_scene(&sample("cornell-box.glb"), &opts).unwrap();
    assert_eq!(
        s.warnings,
        ["--multires \"teapot\" matches no node or mesh name"]
    );
    let multires: Vec<&str> = s
        .objects
        .iter()
        .filter(|o| o.multires)
        .map(|o| o.name.as_str())
        .collect();
    assert_eq!(multires, ["short_block", "light"]);
    let all = ImportOptions {
        multires: vec!["all".into()],
    };
    let s = import_scene(&sample("cornell-box.glb"), &all).unwrap();
    assert!(s.objects.iter().all(|o| o.multires));
    // The Cornell light emits (17, 12, 4).
    let light = s.objects.iter().find(|o| o.name == "light").unwrap();
    let e = s.material_of(light).emission;
    assert!(
        (e[0] - 17.0).abs() < 1e-3 && (e[1] - 12.0).abs() < 1e-3 && (e[2] - 4.0).abs() < 1e-3,
        "{e:?}"
    );
}

fn write(dir: &std::path::Path, name: &str, text: &str) -> PathBuf {
    let p = dir.join(name);
    std::fs::write(&p, text).unwrap();
    p
}

const QUAD_GLTF: &str = r#"{
 "asset": {"version": "2.0"},
 "extensionsUsed": ["KHR_lights_punctual", "KHR_texture_transform"],
 "extensions": {"KHR_lights_punctual": {"lights": [{"type": "spot", "color": [1, 0.5, 0.25], "intensity": 40,
   "spot": {"innerConeAngle": 0.1, "outerConeAngle": 0.5}}]}},
 "scene": 0,
 "scenes": [{"nodes": [0, 1, 2]}],
 "nodes": [
  {"name": "quad", "mesh": 0, "translation": [0, 0, -2]},
  {"name": "lamp", "translation": [0, 3, 0], "rotation": [-0.7071068, 0, 0, 0.7071068],
   "extensions": {"KHR_lights_punctual": {"light": 0}}},
  {"name": "lines", "mesh": 1}
 ],
 "meshes": [
  {"name": "quadmesh", "primitives": [{"attributes": {"POSITION": 0}, "indices": 1}]},
  {"name": "linemesh", "primitives": [{"attributes": {"POSITION": 0}, "mode": 1}]}
 ],
 "buffers": [{"byteLength": 60, "uri": "quad.bin"}],
 "bufferViews": [{"buffer": 0, "byteLength": 48}, {"buffer": 0, "byteOffset": 48, "byteLength": 12}],
 "accessors": [
  {"bufferView": 0, "componentType": 5126, "count": 4, "type": "VEC3", "min": [0,0,0], "max": [1,1,0]},
  {"bufferView": 1, "componentType": 5121, "count": 6, "type": "SCALAR"}
 ]
}"#;

fn quad_bin() -> Vec<u8> {
    let mut b = Vec::new();
    for p in [[0f32, 0., 0.], [1., 0., 0.], [1., 1., 0.], [0., 1., 0.]] {
        for c in p {
            b.extend_from_slice(&c.to_le_bytes());
        }
    }
    b.extend_from_slice(&[0, 1, 2, 0, 2, 3, 0, 0, 0, 0, 0, 0]);
    b
}

#[test]
fn gltf_lights_transforms_and_warnings() {
    let dir = tempfile::tempdir().unwrap();
    let gltf = write(dir.path(), "quad.gltf", QUAD_GLTF);
    std::fs::write(dir.path().join("quad.bin"), quad_bin()).unwrap();
    let s = import_scene(&gltf, &ImportOptions::default()).unwrap();
    assert_eq!(s.format, SourceFormat::Gltf);
    assert_eq!(s.objects.len(), 1);
    assert_eq!(s.objects[0].world_positions[2], [1.0, 1.0, -2.0]);
    assert!(s.objects[0].world_normals().is_none());
    assert!(!s.objects[0].mirrored());
    assert_eq!(s.lights.len(), 1);
    let l = &s.lights[0];
    assert!(
        matches!(l.kind, LightKind::Spot { outer_cone_angle, .. } if (outer_cone_angle - 0.5).abs() < 1e-6)
    );
    assert_eq!(l.position, [0.0, 3.0, 0.0]);
    // A -90° turn about X points the node's -Z straight down.
    assert!((l.direction[1] + 1.0).abs() < 1e-5, "{:?}", l.direction);
    assert_eq!(l.intensity, 40.0);
    let w = s.warnings.join("\n");
    assert!(w.contains("KHR_texture_transform"), "{w}");
    assert!(w.contains("meshes[1].primitives[0] has mode Lines"), "{w}");
}

#[test]
fn missing_buffer_is_a_warning_and_no_light_is_an_error() {
    let dir = tempfile::tempdir().unwrap();
    // The quad with its buffer missing: no geometry left, an error that lists the warnings.
    let gltf = write(dir.path(), "quad.gltf", QUAD_GLTF);
    let e = import_scene(&gltf, &ImportOptions::default()).unwrap_err();
    assert!(matches!(e, ImportError::NoTriangles { .. }), "{e}");
    assert!(e.to_string().contains("buffers[0] is missing"), "{e}");
    // Without the light: the scene has nothing to bake with.
    let unlit = QUAD_GLTF.replace(
        "\"extensions\": {\"KHR_lights_punctual\": {\"light\": 0}}",
        "\"extras\": {}",
    );
    let gltf = write(dir.path(), "unlit.gltf", &unlit);
    std::fs::write(dir.path().join("quad.bin"), quad_bin()).unwrap();
    let e = import_scene(&gltf, &ImportOptions::default()).unwrap_err();
    assert!(matches!(e, ImportError::NoLightSource { .. }), "{e}");
    assert!(e.to_string().contains("no light source"), "{e}");
}

#[test]
fn obj_with_mtl_emission_and_texture() {
    let dir = tempfile::tempdir().unwrap();
    // A 2 × 1 texture: left pixel sRGB 255 (linear 1), right pixel 0.
    let png_path = dir.path().join("half.png");
    image::RgbImage::from_raw(2, 1, vec![255, 255, 255, 0, 0, 0])
        .unwrap()
        .save(&png_path)
        .unwrap();
    write(
        dir.path(),
        "scene.mtl",
        "newmtl lamp\nKd 0 0 0\nKe 5 4 3\nnewmtl wall\nKd 0.5 0.5 0.5\nmap_Kd half.png\n",
    );
    let obj = write(
        dir.path(),
        "scene.obj",
        "mtllib scene.mtl\no lamp\nv 0 2 0\nv 1 2 0\nv 0 2 1\nusemtl lamp\nf 1 3 2\n\
         o wall\nv 0 0 0\nv 1 0 0\nv 1 1 0\nv 0 1 0\nvt 0 0\nvt 0.5 0\nvt 0.5 1\nvt 0 1\n\
         usemtl wall\nf 4/1 5/2 6/3 7/4\n",
    );
    let opts = ImportOptions {
        multires: vec!["wa*".into()],
    };
    let s = import_scene(&obj, &opts).unwrap();
    assert_eq!(s.format, SourceFormat::Obj);
    assert_eq!(s.objects.len(), 2);
    assert_eq!(s.objects[1].triangle_count(), 2);
    assert!(!s.objects[0].multires && s.objects[1].multires);
    assert_eq!(s.material_of(&s.objects[0]).emission, [5.0, 4.0, 3.0]);
    let wall = &s.objects[1];
    let m = s.material_of(wall);
    // The wall's UVs cover the left half of the texture, whose texels are 1 at x = 0.25 and
    // fade towards the right pixel's centre at 0.75: the average is between 0.5 and 1, times Kd.
    let r = m.reflectance_over(wall.triangle_uvs(0))[0];
    assert!(r > 0.3 && r < 0.5, "{r}");
    assert!(s.summary.contains("assumed metres"), "{}", s.summary);
}
