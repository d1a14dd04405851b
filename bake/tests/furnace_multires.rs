//! The closed furnace on a multiresolution object (issue 11): one Loop-subdivided cube seen from
//! inside, every face emitting `E = 0.4` with reflectance `ρ = 0.5`. Whatever the geometry, the
//! outgoing radiance is `E / (1 − ρ) = 0.8` everywhere, so every refined vertex at every level
//! must read 0.8: per-normal colours that lose the light below a coarse triangle's plane, or a
//! reconstruction that extrapolates badly over normals, shows up here as a drift near the
//! cube's corners, where the refined normals turn furthest from the coarse ones.

use std::path::Path;

use hce_bake::import::ImportOptions;
use hce_bake::normal_sets::NormalSetParams;
use hce_bake::pipeline::{bake_file, PipelineOptions};
use hce_bake::BakeParams;
use hce_format::{Object, ObjectKind};
use hce_geometry::colour::{apply_baked_colours_with, Reconstruction};
use hce_geometry::{subdivide, Creases};
use serde_json::json;

const EMISSION: f32 = 0.4;
const RHO: f32 = 0.5;

/// The unit cube's 8 corners and 12 triangles, counter-clockwise seen from inside.
fn inward_cube() -> (Vec<[f32; 3]>, Vec<[u32; 3]>) {
    let p = (0..8)
        .map(|i| [(i & 1) as f32, ((i >> 1) & 1) as f32, ((i >> 2) & 1) as f32])
        .collect();
    // Quads counter-clockwise seen from outside, then every triangle reversed.
    let quads: [[u32; 4]; 6] = [
        [0, 2, 3, 1], // z = 0, outward -z
        [4, 5, 7, 6], // z = 1
        [0, 1, 5, 4], // y = 0
        [2, 6, 7, 3], // y = 1
        [0, 4, 6, 2], // x = 0
        [1, 3, 7, 5], // x = 1
    ];
    let tris = quads
        .iter()
        .flat_map(|q| [[q[0], q[2], q[1]], [q[0], q[3], q[2]]])
        .collect();
    (p, tris)
}

fn write_scene(path: &Path) {
    let (pos, tris) = inward_cube();
    let mut bin: Vec<u8> = pos.iter().flatten().flat_map(|c| c.to_le_bytes()).collect();
    let mid = bin.len();
    bin.extend(tris.iter().flatten().flat_map(|i| i.to_le_bytes()));
    let json = json!({
        "asset": {"version": "2.0"},
        "scene": 0,
        "scenes": [{"nodes": [0]}],
        "nodes": [{"name": "furnace", "mesh": 0}],
        "materials": [{
            "pbrMetallicRoughness": {"baseColorFactor": [RHO, RHO, RHO, 1.0]},
            "emissiveFactor": [EMISSION, EMISSION, EMISSION]
        }],
        "meshes": [{"name": "furnace", "primitives": [
            {"attributes": {"POSITION": 0}, "indices": 1, "material": 0}]}],
        "buffers": [{"byteLength": bin.len()}],
        "bufferViews": [
            {"buffer": 0, "byteOffset": 0, "byteLength": mid},
            {"buffer": 0, "byteOffset": mid, "byteLength": bin.len() - mid}
        ],
        "accessors": [
            {"bufferView": 0, "componentType": 5126, "count": 8, "type": "VEC3",
             "min": [0.0, 0.0, 0.0], "max": [1.0, 1.0, 1.0]},
            {"bufferView": 1, "componentType": 5125, "count": 36, "type": "SCALAR"}
        ]
    });
    let glb = hce_format::write_glb(&json, &bin).unwrap();
    std::fs::write(path, glb).unwrap();
}

fn bake_furnace(dir: &Path) -> Object {
    let scene = dir.join("furnace.glb");
    write_scene(&scene);
    let options = PipelineOptions {
        import: ImportOptions {
            multires: vec!["furnace".into()],
        },
        levels: 4,
        normal_sets: NormalSetParams::default(),
        creases: Creases::None,
        bake: BakeParams::default(),
        output: dir.join("furnace-baked.hce"),
    };
    let outcome = bake_file(&scene, &options, &|_: &str, _: usize, _: usize| {}).unwrap();
    let object = outcome.container.objects.into_iter().next().unwrap();
    assert_eq!(object.kind, ObjectKind::Multiresolution);
    object
}

/// Worst relative deviation from `E / (1 − ρ)` over every channel of every refined vertex.
fn worst_error(object: &Object, level: u32, reconstruction: Reconstruction) -> (f32, [f32; 3]) {
    let refined = subdivide(&object.mesh, level).unwrap();
    let colours = apply_baked_colours_with(object, &refined, level, reconstruction).unwrap();
    let expect = EMISSION / (1.0 - RHO);
    let mut worst = (0.0f32, [0.0; 3]);
    for (c, p) in colours.iter().zip(&refined.positions) {
        for &x in c {
            let e = (x - expect).abs() / expect;
            if e > worst.0 {
                worst = (e, *p);
            }
        }
    }
    worst
}

#[test]
fn multiresolution_furnace_is_exact_at_every_level() {
    let dir = tempfile::tempdir().unwrap();
    let object = bake_furnace(dir.path());
    let sets = object.triangles.iter().map(|r| r.normal_count).max();
    assert!(
        sets > Some(1),
        "the cube's triangles should carry several normals, got at most {sets:?}"
    );
    // Every node and leaf of every tree, for every normal of its set.
    let expect = EMISSION / (1.0 - RHO);
    let mut worst_node = 0.0f32;
    for &packed in &object.colours {
        for c in hce_format::rgb9e5::decode(packed) {
            worst_node = worst_node.max((c - expect).abs() / expect);
        }
    }
    println!(
        "furnace nodes: worst relative error {:.3}%",
        100.0 * worst_node
    );
    assert!(worst_node < 0.01, "a tree node is {worst_node} off");
    for level in 0..=4 {
        let (smooth, at) = worst_error(&object, level, Reconstruction::Smooth);
        let (nearest, _) = worst_error(&object, level, Reconstruction::NearestNormal);
        println!(
            "furnace level {level}: worst relative error {:.3}% (smooth, at {at:?}), {:.3}% \
             (nearest normal)",
            100.0 * smooth,
            100.0 * nearest
        );
        assert!(
            smooth < 0.01,
            "level {level}: worst relative error {smooth} at {at:?}"
        );
        assert!(
            nearest < 0.01,
            "level {level}: worst relative error {nearest} (nearest normal)"
        );
    }
}
