//! Enrichment on real Loop subdivision.
//!
//! A bumpy multiresolution object (an icosphere whose twelve original vertices stand out, so
//! that its Loop limit surface has twelve smooth bumps) stands on a flat floor and is lit from
//! one side by a directional light. It is baked through the whole pipeline (`bake_file`: glTF
//! import, control mesh, the runtime's CPU Loop subdivision, normal sets, enriched hierarchical
//! radiosity, HCE encoding), and then:
//!
//! * (a) in the file, the colours of representative normals facing the light are brighter than
//!   those of normals facing away;
//! * (b) the colours that `hce_geometry::colour::apply_baked_colours` puts on the vertices of the
//!   level-`levels` Loop subdivision are closer (RMS) to a reference, a flat bake of that
//!   already-subdivided mesh, than the same bake with `max_normals 0` gets.
//!
//! `HCE_ENRICHMENT_LEVELS=N` runs the comparison at level N instead of `hce bake`'s default 3
//! (BENCHMARKS.md records the figures).

use std::path::Path;

use glam::{Quat, Vec3};
use hce_bake::NormalSetParams;
use hce_bake::{bake, BakeParams, SolverObject};
use hce_bake::{bake_file, PipelineOptions};
use hce_format::{rgb9e5, Object, ObjectKind};
use hce_geometry::colour::apply_baked_colours;
use hce_geometry::{subdivide, Creases, Refined};
use hce_meshio::scene::{import_scene, ImportOptions, ToSolver};
use serde_json::json;

/// The direction the sunlight travels.
const SUN: [f32; 3] = [-1.0, -0.6, 0.3];
const CENTRE: Vec3 = Vec3::new(0.0, 1.2, 0.0);
const RHO_BUMPY: f32 = 0.8;
/// Illuminance of the sun (lux).
const SUN_LUX: f32 = 3.0;

/// Icosphere refined once (42 vertices, 80 triangles, counter-clockwise from outside) with the
/// icosahedron's twelve vertices pushed out to 1.45 times the radius.
fn bumpy_icosphere() -> (Vec<Vec3>, Vec<[u32; 3]>) {
    let phi = (1.0 + 5f32.sqrt()) / 2.0;
    let mut v: Vec<Vec3> = [
        (-1.0, phi, 0.0),
        (1.0, phi, 0.0),
        (-1.0, -phi, 0.0),
        (1.0, -phi, 0.0),
        (0.0, -1.0, phi),
        (0.0, 1.0, phi),
        (0.0, -1.0, -phi),
        (0.0, 1.0, -phi),
        (phi, 0.0, -1.0),
        (phi, 0.0, 1.0),
        (-phi, 0.0, -1.0),
        (-phi, 0.0, 1.0),
    ]
    .iter()
    .map(|&(x, y, z)| Vec3::new(x, y, z).normalize())
    .collect();
    let faces: [[u32; 3]; 20] = [
        [0, 11, 5],
        [0, 5, 1],
        [0, 1, 7],
        [0, 7, 10],
        [0, 10, 11],
        [1, 5, 9],
        [5, 11, 4],
        [11, 10, 2],
        [10, 7, 6],
        [7, 1, 8],
        [3, 9, 4],
        [3, 4, 2],
        [3, 2, 6],
        [3, 6, 8],
        [3, 8, 9],
        [4, 9, 5],
        [2, 4, 11],
        [6, 2, 10],
        [8, 6, 7],
        [9, 8, 1],
    ];
    let mut mid = std::collections::HashMap::new();
    let mut midpoint = |a: u32, b: u32, v: &mut Vec<Vec3>| -> u32 {
        *mid.entry((a.min(b), a.max(b))).or_insert_with(|| {
            v.push(((v[a as usize] + v[b as usize]) * 0.5).normalize());
            v.len() as u32 - 1
        })
    };
    let mut tris = Vec::new();
    for [a, b, c] in faces {
        let (ab, bc, ca) = (
            midpoint(a, b, &mut v),
            midpoint(b, c, &mut v),
            midpoint(c, a, &mut v),
        );
        tris.extend([[a, ab, ca], [ab, b, bc], [bc, ca, ab], [ca, bc, c]]);
    }
    for t in &tris {
        let [a, b, c] = t.map(|i| v[i as usize]);
        assert!((b - a).cross(c - a).dot(a + b + c) > 0.0, "outward winding");
    }
    let pos = v
        .iter()
        .enumerate()
        .map(|(i, &p)| CENTRE + p * 0.6 * if i < 12 { 1.45 } else { 1.0 })
        .collect();
    (pos, tris)
}

/// Appends a mesh to the BIN buffer and returns its glTF mesh JSON (POSITION and u32 indices).
fn add_mesh(
    json: &mut serde_json::Value,
    bin: &mut Vec<u8>,
    name: &str,
    pos: &[Vec3],
    tris: &[[u32; 3]],
    material: usize,
) {
    let (mut lo, mut hi) = (Vec3::splat(f32::MAX), Vec3::splat(f32::MIN));
    let view = json["bufferViews"].as_array().unwrap().len();
    let start = bin.len();
    for p in pos {
        lo = lo.min(*p);
        hi = hi.max(*p);
        bin.extend(p.to_array().iter().flat_map(|c| c.to_le_bytes()));
    }
    let mid = bin.len();
    bin.extend(tris.iter().flatten().flat_map(|i| i.to_le_bytes()));
    let end = bin.len();
    json["bufferViews"].as_array_mut().unwrap().extend([
        json!({"buffer": 0, "byteOffset": start, "byteLength": mid - start}),
        json!({"buffer": 0, "byteOffset": mid, "byteLength": end - mid}),
    ]);
    let acc = json["accessors"].as_array().unwrap().len();
    json["accessors"].as_array_mut().unwrap().extend([
        json!({"bufferView": view, "componentType": 5126, "count": pos.len(), "type": "VEC3",
               "min": lo.to_array(), "max": hi.to_array()}),
        json!({"bufferView": view + 1, "componentType": 5125, "count": 3 * tris.len(),
               "type": "SCALAR"}),
    ]);
    json["meshes"]
        .as_array_mut()
        .unwrap()
        .push(json!({"name": name, "primitives": [
        {"attributes": {"POSITION": acc}, "indices": acc + 1, "material": material}]}));
}

/// The test scene as a GLB: the bumpy object, a 4 m floor (reflectance 0.5) and the sun.
fn write_scene(path: &Path) {
    let mut json = json!({
        "asset": {"version": "2.0"},
        "extensionsUsed": ["KHR_lights_punctual"],
        "extensions": {"KHR_lights_punctual": {"lights": [
            {"type": "directional", "color": [1, 1, 1], "intensity": SUN_LUX}]}},
        "scene": 0,
        "scenes": [{"nodes": [0, 1, 2]}],
        "materials": [
            {"pbrMetallicRoughness": {"baseColorFactor": [RHO_BUMPY, RHO_BUMPY, RHO_BUMPY, 1]}},
            {"pbrMetallicRoughness": {"baseColorFactor": [0.5, 0.5, 0.5, 1]}}
        ],
        "buffers": [], "bufferViews": [], "accessors": [], "meshes": []
    });
    let mut bin = Vec::new();
    let (pos, tris) = bumpy_icosphere();
    add_mesh(&mut json, &mut bin, "bumpy", &pos, &tris, 0);
    let floor: Vec<Vec3> = [(-2.0, -2.0), (2.0, -2.0), (2.0, 2.0), (-2.0, 2.0)]
        .iter()
        .map(|&(x, z)| Vec3::new(x, 0.0, z))
        .collect();
    // Counter-clockwise seen from above (+Y).
    add_mesh(
        &mut json,
        &mut bin,
        "floor",
        &floor,
        &[[0, 2, 1], [0, 3, 2]],
        1,
    );
    let q = Quat::from_rotation_arc(Vec3::NEG_Z, Vec3::from(SUN).normalize());
    json["nodes"] = json!([
        {"name": "bumpy", "mesh": 0},
        {"name": "floor", "mesh": 1},
        {"name": "sun", "rotation": q.to_array(),
         "extensions": {"KHR_lights_punctual": {"light": 0}}}
    ]);
    json["buffers"] = json!([{"byteLength": bin.len()}]);
    let glb = hce_format::write_glb(&json, &bin).unwrap();
    std::fs::write(path, glb).unwrap();
}

/// Bakes the scene with `max_normals` and returns the bumpy object's container object.
fn bake_bumpy(scene: &Path, out: &Path, levels: u32, max_normals: usize) -> Object {
    let options = PipelineOptions {
        import: ImportOptions {
            multires: vec!["bumpy".into()],
        },
        levels,
        normal_sets: NormalSetParams {
            max_normals,
            ..NormalSetParams::default()
        },
        creases: Creases::None,
        bake: BakeParams::default(),
        output: out.to_path_buf(),
    };
    let outcome = bake_file(scene, &options, &|_: &str, _: usize, _: usize| {}).unwrap();
    let o = outcome
        .container
        .objects
        .into_iter()
        .find(|o| o.name == "bumpy")
        .unwrap();
    assert_eq!(o.kind, ObjectKind::Multiresolution);
    o
}

/// Per vertex of `refined`: the area-weighted average of its incident triangles' colours (the
/// same vertex rule as `apply_baked_colours`).
fn vertex_average(refined: &Refined, per_triangle: &[[f32; 3]]) -> Vec<[f32; 3]> {
    let mut sum = vec![[0.0f64; 4]; refined.positions.len()];
    for (tri, c) in refined.indices.iter().zip(per_triangle) {
        let p = tri.map(|i| Vec3::from(refined.positions[i as usize]));
        let area = f64::from((p[1] - p[0]).cross(p[2] - p[0]).length() * 0.5);
        for &i in tri {
            let s = &mut sum[i as usize];
            for k in 0..3 {
                s[k] += area * f64::from(c[k]);
            }
            s[3] += area;
        }
    }
    sum.iter()
        .map(|s| [0, 1, 2].map(|k| (s[k] / s[3]) as f32))
        .collect()
}

fn rms(a: &[[f32; 3]], b: &[[f32; 3]]) -> f64 {
    let se: f64 = a
        .iter()
        .zip(b)
        .flat_map(|(x, y)| (0..3).map(move |k| f64::from(x[k] - y[k]).powi(2)))
        .sum();
    (se / (3 * a.len()) as f64).sqrt()
}

#[test]
fn enrichment_on_loop_subdivision_beats_one_normal_per_triangle() {
    let levels: u32 = std::env::var("HCE_ENRICHMENT_LEVELS")
        .ok()
        .and_then(|v| v.parse().ok())
        .unwrap_or(3);
    let dir = tempfile::tempdir().unwrap();
    let scene_path = dir.path().join("bumpy.glb");
    write_scene(&scene_path);
    let enriched = bake_bumpy(&scene_path, &dir.path().join("7.hce"), levels, 7);
    let plain = bake_bumpy(&scene_path, &dir.path().join("0.hce"), levels, 0);
    assert!(plain.triangles.iter().all(|t| t.normal_count == 1));
    let several = enriched
        .triangles
        .iter()
        .filter(|t| t.normal_count > 2)
        .count();
    assert!(
        several > 40,
        "{several} of 80 triangles have more than 2 normals"
    );

    // (a) Root colours of each coarse triangle that faces the light and is lit (its geometric
    // normal's colour is at least half the unshadowed direct light, so that the bumps do not
    // shadow it): a normal facing the light clearly more than another gets the brighter colour.
    let towards = -Vec3::from(SUN).normalize();
    let (mut pairs, mut ratio_sum) = (0usize, 0.0f64);
    for (t, rec) in enriched.triangles.iter().enumerate() {
        let ns = &enriched.normals[rec.normal_start as usize..][..rec.normal_count as usize];
        let cos0 = Vec3::from(ns[0]).dot(towards);
        let cs = &enriched.colours[rec.colour_start as usize..][..rec.normal_count as usize];
        let unshadowed = 3.0 * RHO_BUMPY * SUN_LUX * cos0 / std::f32::consts::PI;
        if cos0 < 0.2 || Vec3::from(rgb9e5::decode(cs[0])).element_sum() < 0.5 * unshadowed {
            continue;
        }
        for i in 0..ns.len() {
            for j in 0..ns.len() {
                let (ci, cj) = (
                    Vec3::from(ns[i]).dot(towards),
                    Vec3::from(ns[j]).dot(towards),
                );
                if ci > 0.2 && ci > cj + 0.3 {
                    let (li, lj) = (
                        Vec3::from(rgb9e5::decode(cs[i])).element_sum(),
                        Vec3::from(rgb9e5::decode(cs[j])).element_sum(),
                    );
                    assert!(
                        li > lj,
                        "triangle {t}: normal {i} (cos {ci:.2}) has {li}, normal {j} (cos {cj:.2}) \
                         has {lj}"
                    );
                    pairs += 1;
                    ratio_sum += f64::from(li / lj.max(1e-6));
                }
            }
        }
    }
    assert!(pairs > 30, "only {pairs} pairs of normals compared");

    // (b) Reference: a flat bake of the level-`levels` Loop subdivision itself, in the same scene.
    let refined = subdivide(&enriched.mesh, levels).unwrap();
    assert_eq!(refined.indices.len(), 80 << (2 * levels));
    let imported = import_scene(&scene_path, &ImportOptions::default()).unwrap();
    let mut scene = imported.solver_scene();
    let bi = scene
        .objects
        .iter()
        .position(|o| o.name == "bumpy")
        .unwrap();
    scene.objects[bi] = SolverObject::new(
        "fine",
        refined.positions.clone(),
        refined.indices.clone(),
        [RHO_BUMPY; 3],
    );
    let reference = bake(&scene, &BakeParams::default()).unwrap();
    let per_fine: Vec<[f32; 3]> = reference.objects[bi]
        .triangles
        .iter()
        .map(|t| t.colours[0])
        .collect();
    let want = vertex_average(&refined, &per_fine);
    let got_enriched = apply_baked_colours(&enriched, &refined, levels).unwrap();
    let plain_refined = subdivide(&plain.mesh, levels).unwrap();
    assert_eq!(plain_refined.positions, refined.positions);
    let got_plain = apply_baked_colours(&plain, &plain_refined, levels).unwrap();
    let scale = (want
        .iter()
        .flat_map(|c| c.iter().map(|&x| f64::from(x).powi(2)))
        .sum::<f64>()
        / (3 * want.len()) as f64)
        .sqrt();
    let (e7, e0) = (rms(&got_enriched, &want), rms(&got_plain, &want));
    println!(
        "enrichment on Loop level {levels} ({} vertices): RMS error against the flat bake of the \
         subdivided mesh: max_normals 7 -> {e7:.5} ({:.1}% of the reference RMS {scale:.4}), \
         max_normals 0 -> {e0:.5} ({:.1}%); {pairs} normal pairs, brighter towards the light \
         by {:.2}x on average",
        want.len(),
        100.0 * e7 / scale,
        100.0 * e0 / scale,
        ratio_sum / pairs as f64
    );
    assert!(e7 < 0.6 * e0, "enriched {e7} vs plain {e0}");
}
