//! Seeded structural mutations of a sample's glTF JSON (indices, counts, offsets, strides set to
//! extreme values): the importer and the output writer must return a value or an error, never
//! panic or allocate without bound.

use hce_bake::{write_baked_gltf, ObjectLink};
use hce_meshio::scene::{import_scene, ImportOptions};
use serde_json::Value;
use std::path::Path;

/// Paths to every number in the JSON, in document order.
fn number_paths(v: &Value, path: &mut Vec<Step>, out: &mut Vec<Vec<Step>>) {
    match v {
        Value::Number(_) => out.push(path.clone()),
        Value::Array(a) => {
            for (i, x) in a.iter().enumerate() {
                path.push(Step::Index(i));
                number_paths(x, path, out);
                path.pop();
            }
        }
        Value::Object(o) => {
            for (k, x) in o {
                path.push(Step::Key(k.clone()));
                number_paths(x, path, out);
                path.pop();
            }
        }
        _ => {}
    }
}

#[derive(Clone, Debug)]
enum Step {
    Key(String),
    Index(usize),
}

fn at<'a>(v: &'a mut Value, path: &[Step]) -> &'a mut Value {
    path.iter().fold(v, |v, s| match s {
        Step::Key(k) => &mut v[k.as_str()],
        Step::Index(i) => &mut v[*i],
    })
}

#[test]
fn mutated_samples_never_panic() {
    let glb =
        std::fs::read(Path::new(env!("CARGO_MANIFEST_DIR")).join("../samples/cornell-box.glb"))
            .unwrap();
    let asset = hce_format::GltfAsset::parse(&glb).unwrap();
    let bin = asset.bin.clone().unwrap();
    let mut paths = Vec::new();
    number_paths(&asset.json, &mut Vec::new(), &mut paths);
    assert!(paths.len() > 100);
    let container = hce_format::write(&hce_format::example::single_triangle()).unwrap();
    let dir = tempfile::tempdir().unwrap();
    let file = dir.path().join("m.glb");
    let extremes = [
        0.0,
        1.0,
        -1.0,
        3.0,
        255.0,
        4096.0,
        2147483648.0,
        4294967303.0,
        1e30,
    ];
    let mut state: u64 = 0x9e37_79b9_7f4a_7c15;
    let mut next = || {
        state = state
            .wrapping_mul(6364136223846793005)
            .wrapping_add(1442695040888963407);
        (state >> 33) as usize
    };
    let (mut ok, mut err) = (0, 0);
    // HCE_MUTATIONS=N runs a longer campaign than the default 400.
    let runs = std::env::var("HCE_MUTATIONS")
        .ok()
        .and_then(|n| n.parse().ok())
        .unwrap_or(400);
    for _ in 0..runs {
        let mut json = asset.json.clone();
        for _ in 0..1 + next() % 2 {
            let p = &paths[next() % paths.len()];
            let slot = at(&mut json, p);
            let old = slot.as_f64().unwrap_or(0.0);
            let new = match next() % 3 {
                0 => old + 1.0,
                1 => old - 1.0,
                _ => extremes[next() % extremes.len()],
            };
            *slot = if new.fract() == 0.0 && new.abs() < 1e18 {
                Value::from(new as i64)
            } else {
                Value::from(new)
            };
        }
        let bytes = hce_format::write_glb(&json, &bin).unwrap();
        std::fs::write(&file, &bytes).unwrap();
        match import_scene(&file, &ImportOptions::default()) {
            Ok(scene) => {
                ok += 1;
                for o in &scene.objects {
                    assert!(o.indices.iter().all(|&i| (i as usize) < o.positions.len()));
                    assert!(o.world_positions.iter().flatten().all(|c| c.is_finite()));
                }
                // The writer re-reads the same file: it must cope as well. Only the
                // single-triangle objects can link to the example container's one triangle.
                let colours: Vec<Vec<[f32; 3]>> = scene
                    .objects
                    .iter()
                    .map(|o| vec![[0.5; 3]; o.vertex_count()])
                    .collect();
                let links: Vec<Option<ObjectLink>> = scene
                    .objects
                    .iter()
                    .map(|o| {
                        (o.triangle_count() == 1).then_some(ObjectLink {
                            object: 0,
                            first_triangle: 0,
                        })
                    })
                    .collect();
                let _ = write_baked_gltf(&scene, &colours, &container, &links);
            }
            Err(_) => err += 1,
        }
    }
    // Both outcomes occur: the mutations reach past the JSON parser.
    assert!(ok > 0 && err > 0, "ok {ok}, err {err}");
}
