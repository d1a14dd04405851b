//! End-to-end tests of `hce bake` (`hce_bake::bake_file`) on the sample scenes, at low
//! settings so that each bake takes a moment in the dev profile: the outputs validate, every
//! primitive links to its object with the right hash and triangle count, the bytes do not depend
//! on the thread count, and multiresolution objects keep several normals where they curve.

use std::path::{Path, PathBuf};

use hce_bake::BakeParams;
use hce_bake::{bake_file, BakeOutcome, PipelineOptions};
use hce_format::ObjectKind;
use hce_format::{container_bytes, linked_geometries, primitive_links, GltfAsset as Asset};
use hce_geometry::Creases;
use hce_meshio::scene::ImportOptions;

fn sample(name: &str) -> PathBuf {
    Path::new(env!("CARGO_MANIFEST_DIR"))
        .join("../samples")
        .join(name)
}

fn options(output: &Path, multires: &[&str]) -> PipelineOptions {
    PipelineOptions {
        import: ImportOptions {
            multires: multires.iter().map(|s| s.to_string()).collect(),
        },
        levels: 2,
        creases: Creases::Auto,
        bake: BakeParams {
            bf_epsilon: 1e-2,
            visibility_rays: 4,
            ..BakeParams::default()
        },
        output: output.to_path_buf(),
        ..PipelineOptions::default()
    }
}

fn bake_with_threads(input: &Path, o: &PipelineOptions, threads: usize) -> BakeOutcome {
    let pool = rayon::ThreadPoolBuilder::new()
        .num_threads(threads)
        .build()
        .unwrap();
    pool.install(|| bake_file(input, o, &|_: &str, _: usize, _: usize| {}))
        .unwrap()
}

/// Checks a baked GLB: the embedded container validates, and every primitive's link names an
/// object whose triangle count and geometry hash match the primitive. Returns the link count.
fn check_glb(path: &Path) -> usize {
    let bytes = std::fs::read(path).unwrap();
    let asset = Asset::from_glb(&bytes).unwrap();
    let buffers = vec![asset.bin.clone().unwrap()];
    let container = container_bytes(&asset.json, &buffers).unwrap().unwrap();
    let problems = hce_format::validate_bytes(container);
    assert!(problems.is_empty(), "{problems:?}");
    let c = hce_format::read(container).unwrap();
    let links = primitive_links(&asset.json).unwrap();
    assert!(!links.is_empty());
    for (l, g) in links
        .iter()
        .zip(linked_geometries(&asset.json, &buffers, &links))
    {
        let (hash, triangles) = g.unwrap();
        let o = &c.objects[l.object as usize];
        assert_eq!(l.first_triangle, 0);
        assert_eq!(triangles, o.triangles.len());
        assert_eq!(triangles, o.mesh.triangle_count());
        assert_eq!(hash, l.geometry_hash);
        assert_eq!(hash, o.geometry_hash);
    }
    // Every primitive got a COLOR_0 fallback.
    let meshes = asset.json["meshes"].as_array().unwrap();
    for m in meshes {
        for p in m["primitives"].as_array().unwrap() {
            assert!(p["attributes"].get("COLOR_0").is_some(), "{p}");
        }
    }
    links.len()
}

#[test]
fn cornell_box_bakes_to_a_valid_linked_glb_whatever_the_thread_count() {
    let dir = tempfile::tempdir().unwrap();
    let a = dir.path().join("one.glb");
    let b = dir.path().join("two.glb");
    let input = sample("cornell-box.glb");
    let out1 = bake_with_threads(&input, &options(&a, &["short_block"]), 1);
    bake_with_threads(&input, &options(&b, &["short_block"]), 2);
    assert_eq!(std::fs::read(&a).unwrap(), std::fs::read(&b).unwrap());
    assert_eq!(check_glb(&a), 8);
    assert_eq!(out1.coarse_triangles, 32);
    assert_eq!(out1.objects.len(), 8);
    let block = out1
        .objects
        .iter()
        .find(|o| o.name.contains("short_block"))
        .unwrap();
    // Split normals make the box's edges creases: its faces stay flat, one normal each.
    assert_eq!(block.kind, ObjectKind::Multiresolution);
    assert_eq!(block.normal_histogram.get(1), Some(&10));
    assert!(block.worst_angle_deg < 1.0, "{}", block.worst_angle_deg);
    // The light is white in the fallback, the rest is exposed to mostly within [0, 1].
    assert!(out1.exposure > 0.0 && out1.exposure.is_finite());
    let written = std::fs::metadata(&a).unwrap().len();
    assert_eq!(out1.output_bytes, written);
}

#[test]
fn hce_output_is_the_container_alone_and_reads_back() {
    let dir = tempfile::tempdir().unwrap();
    let out = dir.path().join("cornell.hce");
    let outcome = bake_with_threads(&sample("cornell-box.glb"), &options(&out, &[]), 2);
    let bytes = std::fs::read(&out).unwrap();
    assert!(hce_format::validate_bytes(&bytes).is_empty());
    let c = hce_format::read(&bytes).unwrap();
    assert_eq!(c, outcome.container);
    assert!(c.metadata.generator.starts_with("hce "));
    let params: serde_json::Value = serde_json::from_str(&c.metadata.bake_parameters).unwrap();
    assert_eq!(params["levels"], 2);
    assert_eq!(params["max_normals"], 7);
    assert_eq!(params["creases"], "auto");
    assert!(c.objects.iter().all(|o| o.kind == ObjectKind::Flat));
    // Every flat node has one colour per node: normal_count 1.
    assert!(c
        .objects
        .iter()
        .flat_map(|o| &o.triangles)
        .all(|t| t.normal_count == 1));
    // Some elements were refined below the coarse triangles.
    assert!(outcome.elements > outcome.coarse_triangles);
}

#[test]
fn curved_multiresolution_objects_keep_several_normals() {
    let dir = tempfile::tempdir().unwrap();
    let out = dir.path().join("teatime.glb");
    let mut o = options(&out, &[]);
    o.creases = Creases::None;
    let outcome = bake_with_threads(&sample("teatime.glb"), &o, 2);
    check_glb(&out);
    // Multiresolution objects too: one thread gives the same bytes.
    let one = dir.path().join("teatime-1.glb");
    let mut o1 = o.clone();
    o1.output = one.clone();
    bake_with_threads(&sample("teatime.glb"), &o1, 1);
    assert_eq!(std::fs::read(&out).unwrap(), std::fs::read(&one).unwrap());
    let multires: Vec<_> = outcome
        .objects
        .iter()
        .filter(|o| o.kind == ObjectKind::Multiresolution)
        .collect();
    assert!(!multires.is_empty());
    for m in &multires {
        let several: usize = m.normal_histogram.iter().skip(2).sum();
        assert!(several > 0, "{}: {:?}", m.name, m.normal_histogram);
    }
    // Stored normals are unit vectors.
    for obj in &outcome.container.objects {
        for n in &obj.normals {
            let l = (n[0] * n[0] + n[1] * n[1] + n[2] * n[2]).sqrt();
            assert!((l - 1.0).abs() < 1e-4, "{n:?}");
        }
    }
}

#[test]
fn gltf_output_writes_json_and_bin_beside_it() {
    let dir = tempfile::tempdir().unwrap();
    let out = dir.path().join("cornell.gltf");
    let outcome = bake_with_threads(&sample("cornell-box.glb"), &options(&out, &[]), 2);
    let bin = dir.path().join("cornell.bin");
    let json: serde_json::Value = serde_json::from_slice(&std::fs::read(&out).unwrap()).unwrap();
    assert_eq!(json["buffers"][0]["uri"], "cornell.bin");
    let size = std::fs::metadata(&out).unwrap().len() + std::fs::metadata(&bin).unwrap().len();
    assert_eq!(outcome.output_bytes, size);
    // Nothing but the two outputs is left in the directory (writes are atomic renames).
    let mut names: Vec<String> = std::fs::read_dir(dir.path())
        .unwrap()
        .map(|e| e.unwrap().file_name().to_string_lossy().into_owned())
        .collect();
    names.sort();
    assert_eq!(names, vec!["cornell.bin", "cornell.gltf"]);
}

#[test]
fn bad_output_extension_is_refused_before_baking() {
    let dir = tempfile::tempdir().unwrap();
    let out = dir.path().join("cornell.png");
    let e = bake_file(
        &sample("cornell-box.glb"),
        &options(&out, &[]),
        &|_: &str, _: usize, _: usize| {},
    )
    .unwrap_err()
    .to_string();
    assert!(e.contains(".glb, .gltf or .hce"), "{e}");
    assert!(!out.exists());
}

#[test]
fn inconsistently_wound_multires_object_falls_back_to_flat_with_a_warning() {
    let dir = tempfile::tempdir().unwrap();
    std::fs::write(
        dir.path().join("s.mtl"),
        "newmtl white\nKd 0.8 0.8 0.8\nnewmtl lamp\nKd 0 0 0\nKe 5 5 5\n",
    )
    .unwrap();
    // The floor's second triangle runs its shared edge 1-3 the same way as the first, so the
    // orientation pass would flip it: the control mesh would not keep the primitive's corners.
    let obj = "mtllib s.mtl\n\
        o floor\nv 0 0 0\nv 1 0 0\nv 1 0 1\nv 0 0 1\nusemtl white\nf 1 3 2\nf 1 3 4\n\
        o lamp\nv 0 1 0\nv 1 1 0\nv 1 1 1\nv 0 1 1\nusemtl lamp\nf 5 6 7\nf 5 7 8\n";
    let input = dir.path().join("s.obj");
    std::fs::write(&input, obj).unwrap();
    let out = dir.path().join("s.glb");
    let outcome = bake_with_threads(&input, &options(&out, &["all"]), 2);
    assert!(
        outcome.warnings.iter().any(|w| w.contains("floor")),
        "{:?}",
        outcome.warnings
    );
    let c = &outcome.container;
    let floor = c.objects.iter().find(|o| o.name.contains("floor")).unwrap();
    assert_eq!(floor.kind, ObjectKind::Flat);
    // Unwelded: three control vertices per triangle, corners exactly the primitive's.
    assert_eq!(floor.mesh.vertex_count(), 6);
    assert_eq!(
        floor.mesh.position(floor.mesh.triangle(1)[2]),
        [0.0, 0.0, 1.0]
    );
    let lamp = c.objects.iter().find(|o| o.name.contains("lamp")).unwrap();
    assert_eq!(lamp.kind, ObjectKind::Multiresolution);
    assert_eq!(lamp.mesh.vertex_count(), 4);
    assert_eq!(check_glb(&out), 2);
}
