//! Bodies of the scene and mesh reader fuzz targets, kept apart from the `fuzz_target!` shells
//! so that `bake/tests/fuzz_bodies.rs` compiles and runs the very same code on stable (it
//! includes this file as a module) over a seeded mutation corpus.
//!
//! Each body asserts what the reader promises beyond not panicking: every index it hands on
//! is in range and every position finite, and whatever it accepts goes on through the next
//! stage (the solver's scene checks; welding, the control mesh and one Loop level) without a
//! panic either.

use hce_geometry::{build_control_mesh, subdivide, weld, TopologyConfig};
use hce_meshio::scene::{import_scene_bytes, ImportOptions, ImportedScene, SceneBytes, ToSolver};

/// Meshes larger than this are not subdivided (the subdivision's cost, not its safety, grows).
const SUBDIVIDE_LIMIT: usize = 4096;

/// A glTF or GLB scene through hce-bake's importer (every object multiresolution, so that
/// the node-name and extras paths run too).
pub fn import_gltf(data: &[u8]) {
    let options = ImportOptions {
        multires: vec!["all".into()],
    };
    if let Ok(scene) = import_scene_bytes(SceneBytes::Gltf(data), &options) {
        check_scene(&scene);
    }
}

/// An OBJ scene through hce-bake's importer: the bytes up to the first NUL are the OBJ, the
/// rest (if any) the MTL library it names.
pub fn import_obj(data: &[u8]) {
    let (obj, mtl) = match data.iter().position(|&b| b == 0) {
        Some(i) => (&data[..i], Some(&data[i + 1..])),
        None => (data, None),
    };
    let options = ImportOptions {
        multires: vec!["*".into()],
    };
    if let Ok(scene) = import_scene_bytes(SceneBytes::Obj { obj, mtl }, &options) {
        check_scene(&scene);
    }
}

fn check_scene(scene: &ImportedScene) {
    for o in &scene.objects {
        assert!(o.indices.len() % 3 == 0 && !o.indices.is_empty());
        assert!(o.indices.iter().all(|&i| (i as usize) < o.positions.len()));
        assert_eq!(o.positions.len(), o.world_positions.len());
        assert!(o.world_positions.iter().flatten().all(|c| c.is_finite()));
        if let Some(n) = &o.normals {
            assert_eq!(n.len(), o.positions.len());
        }
        if let Some(uv) = &o.uv0 {
            assert_eq!(uv.len(), o.positions.len());
        }
        assert!(o.material.is_none_or(|m| m < scene.materials.len()));
        let _ = o.geometry_hash();
    }
    let solver = scene.solver_scene();
    assert_eq!(solver.objects.len(), scene.objects.len());
    let _ = solver.validate();
    for o in &scene.objects {
        let triangles: Vec<[u32; 3]> = o
            .indices
            .chunks_exact(3)
            .map(|c| [c[0], c[1], c[2]])
            .collect();
        topology(&o.positions, &triangles, None);
    }
}

/// Welds, builds the control mesh and subdivides once, as `hce subdivide` and the baker do.
fn topology(positions: &[[f32; 3]], triangles: &[[u32; 3]], corner_normals: Option<&[[f32; 3]]>) {
    let w = weld(positions, 0.0);
    assert_eq!(w.input_to_welded.len(), positions.len());
    let welded: Vec<[u32; 3]> = triangles
        .iter()
        .map(|t| t.map(|v| w.input_to_welded[v as usize]))
        .collect();
    let Ok(top) = build_control_mesh(
        &w.positions,
        &welded,
        corner_normals,
        &TopologyConfig::default(),
    ) else {
        return;
    };
    let mesh = &top.mesh;
    if mesh.triangle_count() == 0 || mesh.triangle_count() > SUBDIVIDE_LIMIT {
        return;
    }
    if let Ok(r) = subdivide(mesh, 1) {
        assert_eq!(r.indices.len(), 4 * mesh.triangle_count());
        assert!(r
            .indices
            .iter()
            .flatten()
            .all(|&i| (i as usize) < r.positions.len()));
    }
}

/// Any bytes through `hce_meshio::load_mesh` (what `hce subdivide` reads), as an `.obj`,
/// `.gltf` or `.glb` chosen by the first byte, then on through welding and the control mesh.
/// The loader reads paths only, so the input goes through a temporary file: this exercises
/// exactly the code the command runs.
pub fn load_mesh(data: &[u8]) {
    use std::sync::atomic::{AtomicU64, Ordering};
    static COUNTER: AtomicU64 = AtomicU64::new(0);
    let Some((&selector, body)) = data.split_first() else {
        return;
    };
    let ext = ["obj", "gltf", "glb"][usize::from(selector % 3)];
    let dir = std::env::temp_dir().join(format!("hce-fuzz-load-mesh-{}", std::process::id()));
    if std::fs::create_dir_all(&dir).is_err() {
        return;
    }
    let path = dir.join(format!("{}.{ext}", COUNTER.fetch_add(1, Ordering::Relaxed)));
    if std::fs::write(&path, body).is_err() {
        return;
    }
    let loaded = hce_meshio::load_mesh(&path);
    let _ = std::fs::remove_file(&path);
    let Ok(mesh) = loaded else {
        return;
    };
    assert!(!mesh.triangles.is_empty());
    assert!(mesh
        .triangles
        .iter()
        .flatten()
        .all(|&i| (i as usize) < mesh.positions.len()));
    if let Some(n) = &mesh.corner_normals {
        assert_eq!(n.len(), 3 * mesh.triangles.len());
    }
    topology(
        &mesh.positions,
        &mesh.triangles,
        mesh.corner_normals.as_deref(),
    );
}
