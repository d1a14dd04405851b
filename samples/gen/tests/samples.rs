//! End-to-end checks of the generated sample files: they parse back as glTF, carry what the
//! baker needs (names, multires flags, split normals at hard edges), are deterministic, and the
//! committed copies and the README's triangle counts match the generators.

use std::collections::{BTreeMap, BTreeSet};
use std::path::PathBuf;

use gltf_json::validation::Validate;
use hce_samples::glb::{split_glb, write_glb};
use hce_samples::scenes;

fn samples_dir() -> PathBuf {
    PathBuf::from(env!("CARGO_MANIFEST_DIR"))
        .parent()
        .expect("samples/gen has a parent")
        .to_path_buf()
}

/// One primitive read back from the GLB: positions, normals and indices.
struct Prim {
    positions: Vec<[f32; 3]>,
    normals: Vec<[f32; 3]>,
    indices: Vec<u32>,
}

fn read_accessor(root: &gltf_json::Root, bin: &[u8], index: u32) -> (usize, Vec<u8>, u32) {
    let a = &root.accessors[index as usize];
    let view = &root.buffer_views[a.buffer_view.expect("a buffer view").value()];
    let offset = view.byte_offset.map_or(0, |o| o.0) as usize;
    let len = view.byte_length.0 as usize;
    assert!(
        offset + len <= bin.len(),
        "view past the end of the BIN chunk"
    );
    let component = match a.component_type {
        gltf_json::validation::Checked::Valid(c) => c.0.as_gl_enum(),
        _ => panic!("invalid component type"),
    };
    (
        a.count.0 as usize,
        bin[offset..offset + len].to_vec(),
        component,
    )
}

fn floats3(bytes: &[u8], count: usize) -> Vec<[f32; 3]> {
    assert_eq!(bytes.len(), count * 12);
    bytes
        .chunks_exact(12)
        .map(|c| {
            std::array::from_fn(|k| f32::from_le_bytes(c[4 * k..4 * k + 4].try_into().unwrap()))
        })
        .collect()
}

/// Parses a GLB into its JSON root and primitives per node name.
fn parse(bytes: &[u8]) -> (gltf_json::Root, BTreeMap<String, Vec<Prim>>) {
    let (json, bin) = split_glb(bytes).expect("a well-formed GLB container");
    // Plain JSON first (what any tool sees), then the typed glTF model with its validation.
    let _: serde_json::Value = serde_json::from_slice(json).expect("JSON chunk parses");
    let root = gltf_json::Root::from_slice(json).expect("glTF JSON parses");
    let mut problems = Vec::new();
    root.validate(&root, gltf_json::Path::new, &mut |path, err| {
        problems.push(format!("{}: {err:?}", path()))
    });
    assert!(problems.is_empty(), "{problems:?}");
    let mut out = BTreeMap::new();
    for node in &root.nodes {
        let Some(mesh) = node.mesh else {
            assert!(node.camera.is_some(), "a node with neither mesh nor camera");
            continue;
        };
        let mesh = &root.meshes[mesh.value()];
        let mut prims = Vec::new();
        for p in &mesh.primitives {
            let attr = |s: gltf_json::mesh::Semantic| {
                p.attributes[&gltf_json::validation::Checked::Valid(s)].value() as u32
            };
            let (n, bytes, _) =
                read_accessor(&root, bin, attr(gltf_json::mesh::Semantic::Positions));
            let positions = floats3(&bytes, n);
            let (n, bytes, _) = read_accessor(&root, bin, attr(gltf_json::mesh::Semantic::Normals));
            let normals = floats3(&bytes, n);
            let (n, bytes, component) =
                read_accessor(&root, bin, p.indices.expect("indexed").value() as u32);
            let indices: Vec<u32> = match component {
                5123 => bytes
                    .chunks_exact(2)
                    .map(|c| u16::from_le_bytes([c[0], c[1]]) as u32)
                    .collect(),
                5125 => bytes
                    .chunks_exact(4)
                    .map(|c| u32::from_le_bytes(c.try_into().unwrap()))
                    .collect(),
                other => panic!("unexpected index type {other}"),
            };
            assert_eq!(indices.len(), n);
            prims.push(Prim {
                positions,
                normals,
                indices,
            });
        }
        out.insert(node.name.clone().expect("named nodes"), prims);
    }
    (root, out)
}

#[test]
fn generation_is_deterministic() {
    for ((name, a), (_, b)) in scenes::all().into_iter().zip(scenes::all()) {
        assert_eq!(write_glb(&a).unwrap(), write_glb(&b).unwrap(), "{name}");
    }
}

#[test]
fn committed_samples_match_the_generators() {
    for (name, scene) in scenes::all() {
        let path = samples_dir().join(name);
        let committed = std::fs::read(&path).unwrap_or_else(|e| {
            panic!(
                "{}: {e}; run `cargo run -p hce-samples --bin gen-samples`",
                path.display()
            )
        });
        let fresh = write_glb(&scene).unwrap();
        assert!(
            committed == fresh,
            "{} is stale; run `cargo run -p hce-samples --bin gen-samples` and commit it",
            path.display()
        );
        assert!(
            committed.len() < 1 << 20,
            "{name} is {} bytes",
            committed.len()
        );
    }
}

#[test]
fn embedded_samples_are_the_generated_ones() {
    use hce_samples::embedded::*;
    let generated: Vec<Vec<u8>> = scenes::all()
        .iter()
        .map(|(_, s)| write_glb(s).unwrap())
        .collect();
    assert!(generated[0] == TEATIME_GLB, "teatime.glb is stale");
    assert!(generated[1] == CHESSTIME_GLB, "chesstime.glb is stale");
    assert!(generated[2] == CORNELL_BOX_GLB, "cornell-box.glb is stale");
}

#[test]
fn glbs_parse_back_with_valid_geometry() {
    for (name, scene) in scenes::all() {
        let bytes = write_glb(&scene).unwrap();
        let (root, prims) = parse(&bytes);
        // One node per object, plus the camera.
        assert_eq!(root.nodes.len(), scene.objects.len() + 1, "{name}");
        assert_eq!(root.cameras.len(), 1, "{name}");
        assert_eq!(
            root.meshes.len(),
            scene.objects.len(),
            "{name}: one mesh per node"
        );
        let mut triangles = 0;
        for (node, prims) in &prims {
            for p in prims {
                assert_eq!(p.positions.len(), p.normals.len());
                assert_eq!(p.indices.len() % 3, 0);
                triangles += p.indices.len() / 3;
                assert!(
                    p.indices.iter().all(|&i| (i as usize) < p.positions.len()),
                    "{node}"
                );
                for n in &p.normals {
                    let len = (n[0] * n[0] + n[1] * n[1] + n[2] * n[2]).sqrt();
                    assert!(
                        (len - 1.0).abs() < 1e-5,
                        "{name}/{node}: normal length {len}"
                    );
                }
                for t in p.indices.chunks_exact(3) {
                    assert!(
                        t[0] != t[1] && t[1] != t[2] && t[0] != t[2],
                        "{name}/{node}"
                    );
                }
            }
        }
        assert_eq!(triangles, scene.triangle_count(), "{name}");
    }
}

#[test]
fn multires_flags_are_where_the_issue_asks() {
    let expected: [(&str, &[&str]); 3] = [
        ("teatime.glb", &["cup", "spoon", "teapot"]),
        (
            "chesstime.glb",
            &[
                "bishop_black",
                "king_black",
                "king_white",
                "pawn_white",
                "queen_black",
                "queen_white",
            ],
        ),
        ("cornell-box.glb", &[]),
    ];
    for ((name, scene), (file, flagged)) in scenes::all().into_iter().zip(expected) {
        assert_eq!(name, file);
        let (root, _) = parse(&write_glb(&scene).unwrap());
        let mut got = BTreeSet::new();
        for node in &root.nodes {
            if let Some(extras) = &node.extras {
                let v: serde_json::Value = serde_json::from_str(extras.get()).unwrap();
                assert_eq!(v, serde_json::json!({"hce": {"multires": true}}));
                got.insert(node.name.clone().unwrap());
            }
        }
        let want: BTreeSet<String> = flagged.iter().map(|s| s.to_string()).collect();
        assert_eq!(got, want, "{name}");
    }
}

/// Output vertices per distinct position, and how many positions carry differing normals.
fn split_stats(p: &Prim) -> (usize, usize) {
    let mut by_pos: BTreeMap<[u32; 3], BTreeSet<[u32; 3]>> = BTreeMap::new();
    for (q, n) in p.positions.iter().zip(&p.normals) {
        by_pos
            .entry(q.map(f32::to_bits))
            .or_default()
            .insert(n.map(f32::to_bits));
    }
    let split = by_pos.values().filter(|normals| normals.len() > 1).count();
    (by_pos.len(), split)
}

#[test]
fn hard_edges_are_split_normals_and_smooth_objects_are_not() {
    let (_, chess) = parse(&write_glb(&scenes::chesstime()).unwrap());
    let king = &chess["king_white"][0];
    let (distinct, split) = split_stats(king);
    // The king has 8 hard rings of 12 vertices each.
    assert_eq!(split, 8 * 12);
    assert_eq!(king.positions.len(), distinct + 8 * 12);

    let (_, tea) = parse(&write_glb(&scenes::teatime()).unwrap());
    for smooth in ["teapot", "spoon"] {
        let p = &tea[smooth][0];
        assert_eq!(split_stats(p), (p.positions.len(), 0), "{smooth}");
    }
    // The cup's only hard edge is its foot rim (12 vertices).
    assert_eq!(split_stats(&tea["cup"][0]).1, 12);

    let (_, cornell) = parse(&write_glb(&scenes::cornell_box()).unwrap());
    // Each block corner on top joins three faces, at the bottom two.
    let block = &cornell["short_block"][0];
    assert_eq!(split_stats(block), (8, 8));
    assert_eq!(block.positions.len(), 4 * 3 + 4 * 2);
}

#[test]
fn bounding_boxes_are_sensible() {
    let t = scenes::teatime();
    let teapot = t.object("teapot").unwrap();
    let (lo, hi) = teapot.primitives[0].mesh.bounds().unwrap();
    let size = hi - lo;
    assert!((size.y - 0.1575).abs() < 1e-9, "teapot height {}", size.y);
    assert!(size.x > 0.3 && size.x < 0.33, "teapot length {}", size.x);
    // Everything stands inside the room and on or above the floor.
    for (name, scene) in scenes::all() {
        for o in &scene.objects {
            for p in &o.primitives {
                let (lo, hi) = p.mesh.bounds().unwrap();
                let (lo, hi) = (lo + o.translation, hi + o.translation);
                assert!(lo.y >= 0.0, "{name}/{}: below the floor", o.name);
                assert!(
                    hi.y <= 2.6 && hi.x.abs() <= 2.0 && lo.x.abs() <= 2.0,
                    "{name}/{}",
                    o.name
                );
            }
        }
    }
    let c = scenes::cornell_box();
    let (lo, hi) = c.object("tall_block").unwrap().primitives[0]
        .mesh
        .bounds()
        .unwrap();
    assert!((hi.y - 0.33).abs() < 1e-12 && (lo.x - 0.265).abs() < 1e-12);
}

#[test]
fn readme_triangle_counts_match_the_generators() {
    let readme =
        std::fs::read_to_string(samples_dir().join("README.md")).expect("samples/README.md");
    for (name, scene) in scenes::all() {
        let section = readme
            .split("\n## ")
            .find(|s| s.contains(&format!("`samples/{name}`")))
            .unwrap_or_else(|| panic!("README has no section for {name}"));
        for o in &scene.objects {
            let row = format!("| `{}` | {} |", o.name, o.triangle_count());
            assert!(
                section.contains(&row),
                "README section for {name} lacks the row {row:?}"
            );
        }
        let total = format!("| **total** | **{}** |", scene.triangle_count());
        assert!(
            section.contains(&total),
            "README section for {name} lacks {total:?}"
        );
    }
}

#[test]
fn cameras_look_at_their_targets() {
    for (name, scene) in scenes::all() {
        let camera = scene.camera.as_ref().expect("every sample suggests a view");
        let (root, _) = parse(&write_glb(&scene).unwrap());
        let node = root.nodes.iter().find(|n| n.camera.is_some()).unwrap();
        let q = node.rotation.as_ref().unwrap().0;
        let q = glam::Quat::from_array(q).as_dquat();
        let forward = q * -glam::DVec3::Z;
        let wanted = (camera.target - camera.eye).normalize();
        assert!(
            forward.dot(wanted) > 1.0 - 1e-6,
            "{name}: looks along {forward}"
        );
        // Level: the camera's right vector is horizontal.
        assert!((q * glam::DVec3::X).y.abs() < 1e-6, "{name}");
    }
    // The Cornell camera is the published one: turned half a turn about Y.
    let q = hce_samples::glb::look_rotation(
        glam::DVec3::new(0.278, 0.273, -0.8),
        glam::DVec3::new(0.278, 0.273, 0.0),
    );
    assert!((q.y.abs() - 1.0).abs() < 1e-12 && q.x.abs() < 1e-12 && q.z.abs() < 1e-12);
}

#[test]
fn usage_errors_exit_2_with_the_usage_and_no_backtrace() {
    let run = |args: &[&str]| {
        std::process::Command::new(env!("CARGO_BIN_EXE_gen-samples"))
            .args(args)
            .env("RUST_BACKTRACE", "1")
            .output()
            .unwrap()
    };
    for args in [
        &["room", "--bogus"][..],
        &["room", "--turn"],
        &["room", "--mesh", "x.obj", "--triangles", "2", "-o", "x.glb"],
        &["room", "--mesh", "x.obj"],
        // Several meshes: each --triangles follows its --mesh, once, and --name is for one.
        &[
            "room",
            "--triangles",
            "9",
            "--mesh",
            "a.obj",
            "--mesh",
            "b.obj",
            "-o",
            "x.glb",
        ],
        &[
            "room",
            "--mesh",
            "a.obj",
            "--triangles",
            "9",
            "--triangles",
            "9",
            "-o",
            "x.glb",
        ],
        &[
            "room", "--mesh", "a.obj", "--mesh", "b.obj", "--name", "n", "-o", "x.glb",
        ],
    ] {
        let out = run(args);
        let err = String::from_utf8_lossy(&out.stderr);
        assert_eq!(out.status.code(), Some(2), "{args:?}: {err}");
        assert!(
            err.starts_with("error: ") && err.contains("usage: gen-samples room"),
            "{err}"
        );
        assert!(!err.contains("backtrace"), "{err}");
    }
    // A file that cannot be read is not a usage error.
    let missing = std::env::temp_dir().join("hce-gen-samples-no-such-mesh.obj");
    let out = run(&["room", "--mesh", missing.to_str().unwrap(), "-o", "x.glb"]);
    assert_eq!(out.status.code(), Some(1));
    assert!(String::from_utf8_lossy(&out.stderr).contains("cannot read"));
}

#[test]
fn help_prints_the_usage_and_an_option_is_never_taken_for_a_folder() {
    let dir = tempfile_dir("hce-gen-samples-help");
    let run = |args: &[&str]| {
        std::process::Command::new(env!("CARGO_BIN_EXE_gen-samples"))
            .args(args)
            .current_dir(&dir)
            .output()
            .unwrap()
    };
    for flag in ["--help", "-h"] {
        let out = run(&[flag]);
        assert_eq!(out.status.code(), Some(0));
        assert!(String::from_utf8_lossy(&out.stdout).starts_with("usage: gen-samples [OUT_DIR]"));
    }
    for args in [&["--bogus"][..], &["a", "b"]] {
        let out = run(args);
        let err = String::from_utf8_lossy(&out.stderr);
        assert_eq!(out.status.code(), Some(2), "{args:?}: {err}");
        assert!(err.contains("usage: gen-samples [OUT_DIR]"), "{err}");
    }
    let left: Vec<_> = std::fs::read_dir(&dir).unwrap().collect();
    assert!(left.is_empty(), "wrote {left:?}");
    std::fs::remove_dir_all(&dir).unwrap();
}

/// An empty folder of its own under the system's temporary folder.
fn tempfile_dir(name: &str) -> std::path::PathBuf {
    let dir = std::env::temp_dir().join(format!("{name}-{}", std::process::id()));
    let _ = std::fs::remove_dir_all(&dir);
    std::fs::create_dir_all(&dir).unwrap();
    dir
}
