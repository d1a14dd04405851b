//! The closed furnace on a multiresolution object: one Loop-subdivided cube seen from
//! inside, every face emitting `E = 0.4` with reflectance `ρ = 0.5`. Whatever the geometry, the
//! outgoing radiance is `E / (1 − ρ) = 0.8` everywhere, so every refined vertex at every level
//! must read 0.8: per-normal colours that lose the light below a coarse triangle's plane, or a
//! reconstruction that extrapolates badly over normals, shows up here as a drift near the
//! cube's corners, where the refined normals turn furthest from the coarse ones. The same for
//! a multiresolution object inside a closed room of flat faces.

use std::path::Path;

use hce_bake::BakeParams;
use hce_bake::NormalSetParams;
use hce_bake::{bake_file, PipelineOptions};
use hce_format::{Object, ObjectKind};
use hce_geometry::colour::{apply_baked_colours_with, Reconstruction};
use hce_geometry::{subdivide, Creases};
use hce_meshio::scene::ImportOptions;
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

/// A named mesh: positions and triangles.
type Mesh<'a> = (&'a str, Vec<[f32; 3]>, Vec<[u32; 3]>);

/// An outward octahedron of radius `r` centred at `c`: 6 corners, 8 triangles.
fn octahedron(c: [f32; 3], r: f32) -> (Vec<[f32; 3]>, Vec<[u32; 3]>) {
    let axes = [
        [1.0, 0.0, 0.0],
        [-1.0, 0.0, 0.0],
        [0.0, 1.0, 0.0],
        [0.0, -1.0, 0.0],
        [0.0, 0.0, 1.0],
        [0.0, 0.0, -1.0],
    ];
    let p = axes
        .iter()
        .map(|a: &[f32; 3]| [c[0] + r * a[0], c[1] + r * a[1], c[2] + r * a[2]])
        .collect();
    let mut tris = Vec::new();
    for x in [0u32, 1] {
        for y in [2u32, 3] {
            for z in [4u32, 5] {
                // Counter-clockwise seen from outside: the corner's axes in right-handed order.
                let odd = (x + y + z) % 2 == 1;
                tris.push(if odd { [x, y, z] } else { [x, z, y] });
            }
        }
    }
    (p, tris)
}

/// A closed furnace scene of `meshes` (name, positions, triangles), every one emitting `E` and
/// reflecting `ρ`, as a binary glTF at `path`.
fn write_scene(path: &Path, meshes: &[Mesh]) {
    let mut bin: Vec<u8> = Vec::new();
    let (mut views, mut accessors, mut nodes, mut gltf_meshes) =
        (Vec::new(), Vec::new(), Vec::new(), Vec::new());
    for (m, (name, pos, tris)) in meshes.iter().enumerate() {
        let start = bin.len();
        bin.extend(pos.iter().flatten().flat_map(|c| c.to_le_bytes()));
        let mid = bin.len();
        bin.extend(tris.iter().flatten().flat_map(|i| i.to_le_bytes()));
        views.push(json!({"buffer": 0, "byteOffset": start, "byteLength": mid - start}));
        views.push(json!({"buffer": 0, "byteOffset": mid, "byteLength": bin.len() - mid}));
        let (mut lo, mut hi) = ([f32::MAX; 3], [f32::MIN; 3]);
        for p in pos {
            for k in 0..3 {
                lo[k] = lo[k].min(p[k]);
                hi[k] = hi[k].max(p[k]);
            }
        }
        accessors.push(json!({"bufferView": 2 * m, "componentType": 5126,
            "count": pos.len(), "type": "VEC3", "min": lo, "max": hi}));
        accessors.push(json!({"bufferView": 2 * m + 1, "componentType": 5125,
            "count": 3 * tris.len(), "type": "SCALAR"}));
        nodes.push(json!({"name": name, "mesh": m}));
        gltf_meshes.push(json!({"name": name, "primitives": [
            {"attributes": {"POSITION": 2 * m}, "indices": 2 * m + 1, "material": 0}]}));
    }
    let json = json!({
        "asset": {"version": "2.0"},
        "scene": 0,
        "scenes": [{"nodes": (0..meshes.len()).collect::<Vec<_>>()}],
        "nodes": nodes,
        "materials": [{
            "pbrMetallicRoughness": {"baseColorFactor": [RHO, RHO, RHO, 1.0]},
            "emissiveFactor": [EMISSION, EMISSION, EMISSION]
        }],
        "meshes": gltf_meshes,
        "buffers": [{"byteLength": bin.len()}],
        "bufferViews": views,
        "accessors": accessors
    });
    let glb = hce_format::write_glb(&json, &bin).unwrap();
    std::fs::write(path, glb).unwrap();
}

/// Bakes the furnace scene of `meshes` at `dir` through the pipeline, the objects named in
/// `multires` multiresolution, and returns the baked objects.
fn bake_furnace(dir: &Path, meshes: &[Mesh], multires: &[&str]) -> Vec<Object> {
    let scene = dir.join("furnace.glb");
    write_scene(&scene, meshes);
    let options = PipelineOptions {
        import: ImportOptions {
            multires: multires.iter().map(|m| m.to_string()).collect(),
        },
        levels: 4,
        normal_sets: NormalSetParams::default(),
        creases: Creases::None,
        bake: BakeParams::default(),
        output: dir.join("furnace-baked.hce"),
    };
    let outcome = bake_file(&scene, &options, &|_: &str, _: usize, _: usize| {}).unwrap();
    outcome.container.objects
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
    let (pos, tris) = inward_cube();
    let objects = bake_furnace(dir.path(), &[("furnace", pos, tris)], &["furnace"]);
    let object = &objects[0];
    assert_eq!(object.kind, ObjectKind::Multiresolution);
    check_refined(object);
}

/// A multiresolution object inside a closed furnace room: an octahedron, whose Loop
/// surface is a rounded blob with valence-4 corners, floating in a box of flat faces. Its
/// refined vertices face every way, and the room around them must give `E / (1 − ρ)` at all of
/// them, at every level and with both reconstructions, as it does at every node.
#[test]
fn a_multiresolution_object_in_a_closed_room_is_exact_at_every_level() {
    let dir = tempfile::tempdir().unwrap();
    let (room_pos, room_tris) = inward_cube();
    let room_pos = room_pos
        .iter()
        .map(|p| [p[0] * 2.0, p[1] * 2.0, p[2] * 1.5])
        .collect();
    let (obj_pos, obj_tris) = octahedron([0.9, 1.1, 0.7], 0.45);
    let objects = bake_furnace(
        dir.path(),
        &[("room", room_pos, room_tris), ("blob", obj_pos, obj_tris)],
        &["blob"],
    );
    let blob = objects
        .iter()
        .find(|o| o.kind == ObjectKind::Multiresolution)
        .expect("the blob is multiresolution");
    check_refined(blob);
}

/// Every node of `object`'s trees, and every refined vertex at levels 0 to 4 with the smooth
/// and the nearest-normal reconstruction, within 1% of `E / (1 − ρ)`.
fn check_refined(object: &Object) {
    let sets = object.triangles.iter().map(|r| r.normal_count).max();
    assert!(
        sets > Some(1),
        "the object's triangles should carry several normals, got at most {sets:?}"
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
        let (smooth, at) = worst_error(object, level, Reconstruction::Smooth);
        let (nearest, _) = worst_error(object, level, Reconstruction::NearestNormal);
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
