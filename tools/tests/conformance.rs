//! Runs the real `hce` binary over the conformance suite (`conformance/`, see its README): every
//! file's `hce validate` exit status and problem lines, and for valid files the refined
//! positions and normals (bitwise) and smooth colours of the probe vertices at levels 1 to 3
//! (through `hce subdivide --merge` to OBJ), and both reconstructions' colours through the
//! library; the scene `hce subdivide` writes for baked glTF files (`NORMAL`, `COLOR_0`).
//! Also checks that the suite is what its generator writes today.

mod common;

use serde_json::Value;
use std::path::{Path, PathBuf};

fn suite() -> PathBuf {
    Path::new(env!("CARGO_MANIFEST_DIR")).join("../conformance")
}

fn manifest() -> Value {
    serde_json::from_slice(&std::fs::read(suite().join("manifest.json")).unwrap()).unwrap()
}

#[test]
fn hce_validate_gives_every_expected_outcome() {
    let m = manifest();
    let cases = m["cases"].as_array().unwrap();
    assert!(cases.len() >= 15, "{} cases", cases.len());
    for c in cases {
        let file = suite().join(c["file"].as_str().unwrap());
        let out = common::command()
            .arg("validate")
            .arg(&file)
            .output()
            .unwrap();
        let stdout = String::from_utf8_lossy(&out.stdout);
        assert_eq!(
            out.status.code(),
            c["exit_status"].as_i64().map(|s| s as i32),
            "{}: {stdout}{}",
            c["file"],
            String::from_utf8_lossy(&out.stderr)
        );
        let expected: Vec<String> = if c["valid"] == true {
            vec![format!("{}: valid", file.display())]
        } else {
            located_lines(&c["problems"])
        };
        let got: Vec<&str> = stdout.lines().collect();
        assert_eq!(got, expected, "{}", c["file"]);
        let stderr = String::from_utf8_lossy(&out.stderr);
        let warned: Vec<&str> = stderr
            .lines()
            .filter_map(|l| l.strip_prefix("warning: "))
            .collect();
        let expected = located_lines(c.get("warnings").unwrap_or(&Value::Null));
        assert_eq!(warned, expected, "{}: warnings", c["file"]);
    }
}

/// A manifest list of `{location, message}` (absent: none) as `hce validate` prints its lines.
fn located_lines(list: &Value) -> Vec<String> {
    list.as_array()
        .map_or(&[][..], Vec::as_slice)
        .iter()
        .map(|p| {
            format!(
                "{}: {}",
                p["location"].as_str().unwrap(),
                p["message"].as_str().unwrap()
            )
        })
        .collect()
}

/// Per vertex of an OBJ written by `hce subdivide --merge`: position, colour (`v x y z r g b`)
/// and normal (`vn`, one per vertex, in vertex order).
struct Obj {
    positions: Vec<[f32; 3]>,
    colours: Vec<[f32; 3]>,
    normals: Vec<[f32; 3]>,
}

fn read_obj(path: &Path) -> Obj {
    let text = std::fs::read_to_string(path).unwrap();
    let floats = |l: &str| -> Vec<f32> { l.split(' ').map(|t| t.parse().unwrap()).collect() };
    let mut obj = Obj {
        positions: Vec::new(),
        colours: Vec::new(),
        normals: Vec::new(),
    };
    for line in text.lines() {
        if let Some(l) = line.strip_prefix("v ") {
            let x = floats(l);
            assert_eq!(x.len(), 6, "{line}: expected x y z r g b");
            obj.positions.push([x[0], x[1], x[2]]);
            obj.colours.push([x[3], x[4], x[5]]);
        } else if let Some(l) = line.strip_prefix("vn ") {
            let x = floats(l);
            obj.normals.push([x[0], x[1], x[2]]);
        }
    }
    obj
}

/// The `f32` bits of a probe field (`{"xyz": …, "bits": [hex, hex, hex]}`).
fn bits(field: &Value) -> [u32; 3] {
    let b = field["bits"].as_array().unwrap();
    std::array::from_fn(|k| u32::from_str_radix(b[k].as_str().unwrap(), 16).unwrap())
}

fn value(field: &Value) -> [f32; 3] {
    bits(field).map(f32::from_bits)
}

/// The colour tolerance of conformance/README.md: every channel within 1e-5 of the largest
/// channel of the expected colour.
fn colour_close(got: [f32; 3], expected: [f32; 3]) -> bool {
    let scale = expected.iter().fold(1e-6f32, |m, &x| m.max(x.abs()));
    (0..3).all(|k| (got[k] - expected[k]).abs() <= 1e-5 * scale)
}

#[test]
fn probes_match_hce_subdivide_at_levels_1_to_3() {
    let m = manifest();
    let dir = tempfile::tempdir().unwrap();
    let mut checked = 0;
    for c in m["cases"]
        .as_array()
        .unwrap()
        .iter()
        .filter(|c| c["valid"] == true)
    {
        let file = suite().join(c["file"].as_str().unwrap());
        let refined = c["refined"].as_array().unwrap();
        for level in m["probe_levels"].as_array().unwrap() {
            let level = level.as_u64().unwrap();
            let out = dir.path().join(format!("l{level}.obj"));
            let status = common::command()
                // The suite records the uniform refinement of flat objects (SPEC.md F.7.2).
                .args([
                    "subdivide",
                    "--merge",
                    "--flat",
                    "uniform",
                    "-l",
                    &level.to_string(),
                    "-o",
                ])
                .arg(&out)
                .arg(&file)
                .output()
                .unwrap();
            if c.get("warnings").is_some() {
                // A primitive that cannot be checked: `hce subdivide` will not apply its
                // lighting, and says why (its probes are the container's, read below).
                let stderr = String::from_utf8_lossy(&status.stderr);
                assert_eq!(status.status.code(), Some(3), "{}: {stderr}", c["file"]);
                assert!(stderr.contains("cannot check"), "{}: {stderr}", c["file"]);
                continue;
            }
            assert!(
                status.status.success(),
                "{}",
                String::from_utf8_lossy(&status.stderr)
            );
            let obj = read_obj(&out);
            assert_eq!(obj.normals.len(), obj.positions.len());
            // The merged mesh concatenates the objects in container order.
            let mut offset = 0;
            for r in refined.iter().filter(|r| r["level"] == level) {
                for p in r["probes"].as_array().unwrap() {
                    let v = offset + p["vertex"].as_u64().unwrap() as usize;
                    let at = format!(
                        "{} object {} level {level} vertex {}",
                        c["file"], r["object"], p["vertex"]
                    );
                    assert_eq!(
                        obj.positions[v].map(f32::to_bits),
                        bits(&p["position"]),
                        "position of {at}"
                    );
                    assert_eq!(
                        obj.normals[v].map(f32::to_bits),
                        bits(&p["normal"]),
                        "normal of {at}"
                    );
                    // The OBJ's colours are the smooth reconstruction clamped to [0, 1].
                    let expected = value(&p["colour_smooth"]).map(|x| x.clamp(0.0, 1.0));
                    assert!(
                        colour_close(obj.colours[v], expected),
                        "colour of {at}: {:?}, expected {expected:?}",
                        obj.colours[v]
                    );
                    checked += 1;
                }
                offset += r["vertex_count"].as_u64().unwrap() as usize;
            }
            assert_eq!(offset, obj.positions.len(), "{} level {level}", c["file"]);
        }
    }
    assert!(checked > 50, "{checked} probes");
}

/// Both reconstructions, unclamped, from the library `hce` calls (`hce subdivide` writes only
/// the smooth one, clamped): the file read through `hce_format`, refined by
/// `hce_geometry::refine::refine_object`, coloured by `apply_baked_colours_with`.
#[test]
fn probe_colours_match_both_reconstructions() {
    use hce_geometry::colour::{apply_baked_colours_with, Reconstruction};
    let m = manifest();
    let mut checked = 0;
    for c in m["cases"]
        .as_array()
        .unwrap()
        .iter()
        .filter(|c| c["valid"] == true)
    {
        let name = c["file"].as_str().unwrap();
        let bytes = std::fs::read(suite().join(name)).unwrap();
        let objects = hce_tests::conformance::objects(name, &bytes);
        for r in c["refined"].as_array().unwrap() {
            let object = &objects[r["object"].as_u64().unwrap() as usize];
            let level = r["level"].as_u64().unwrap() as u32;
            let refined = hce_geometry::refine::refine_object(object, level).unwrap();
            for (field, reconstruction) in [
                ("colour_smooth", Reconstruction::Smooth),
                ("colour_nearest", Reconstruction::NearestNormal),
            ] {
                let colours =
                    apply_baked_colours_with(object, &refined.mesh, level, reconstruction).unwrap();
                for p in r["probes"].as_array().unwrap() {
                    let v = p["vertex"].as_u64().unwrap() as usize;
                    let expected = value(&p[field]);
                    assert!(
                        colour_close(colours[v], expected),
                        "{field} of {name} object {} level {level} vertex {v}: {:?}, expected \
                         {expected:?}",
                        r["object"],
                        colours[v]
                    );
                    checked += 1;
                }
            }
        }
    }
    assert!(checked > 100, "{checked} probe colours");
}

/// The `scene` entries (SPEC.md F.10): what `hce subdivide FILE -l 1` writes as a scene, read
/// back, per primitive: vertex count, `NORMAL` and `COLOR_0` (after the exposure) bitwise, and
/// the output vertex order: each output vertex at the position of the refined vertex that
/// `refined_vertices` names, and the primitive's indices, read through that list, the refined
/// mesh's fine triangles of the primitive's coarse triangles.
/// The suite's valid files have no link faults.
struct NoFault;

impl hce_format::LinkSink for NoFault {
    fn fault(
        &mut self,
        _: &hce_format::PrimitiveLink,
        at: &str,
        fault: hce_format::LinkFault,
    ) -> hce_format::LinkNext {
        panic!("{at}: {fault:?}")
    }
}

#[test]
fn scene_entries_match_hce_subdivide() {
    let m = manifest();
    let dir = tempfile::tempdir().unwrap();
    let mut checked = 0;
    for c in m["cases"].as_array().unwrap() {
        let Some(scene) = c.get("scene") else {
            continue;
        };
        let name = c["file"].as_str().unwrap();
        let file = suite().join(name);
        let bytes = std::fs::read(&file).unwrap();
        let objects = hce_tests::conformance::objects(name, &bytes);
        let input = hce_format::GltfAsset::parse(&bytes).unwrap();
        let input_buffers = input.buffers(|_| Err("none".into())).unwrap();
        let links = hce_format::primitive_links(&input.json).unwrap();
        // Each link's placement (SPEC.md 2.6): hce subdivide writes the object through M⁻¹.
        let placements =
            hce_format::check_links(&objects, &input.json, &input_buffers, &links, &mut NoFault)
                .unwrap();
        let out = dir.path().join(format!("scene{checked}.glb"));
        let level = scene["level"].to_string();
        common::hce_ok(&[
            "subdivide",
            file.to_str().unwrap(),
            "--flat",
            "uniform",
            "-l",
            &level,
            "-o",
            out.to_str().unwrap(),
        ]);
        let (doc, buffers, _) = gltf::import_slice(std::fs::read(&out).unwrap()).unwrap();
        for p in scene["primitives"].as_array().unwrap() {
            let mesh = doc
                .meshes()
                .nth(p["mesh"].as_u64().unwrap() as usize)
                .unwrap();
            let prim = mesh
                .primitives()
                .nth(p["primitive"].as_u64().unwrap() as usize)
                .unwrap();
            let reader = prim.reader(|b| Some(&buffers[b.index()][..]));
            let normals: Vec<[f32; 3]> = reader.read_normals().unwrap().collect();
            let colours: Vec<[f32; 3]> = reader.read_colors(0).unwrap().into_rgb_f32().collect();
            assert_eq!(normals.len() as u64, p["vertex_count"].as_u64().unwrap());
            let order: Vec<u32> = p["refined_vertices"]
                .as_array()
                .unwrap()
                .iter()
                .map(|v| v.as_u64().unwrap() as u32)
                .collect();
            let (m, q) = (mesh.index(), prim.index());
            let link = links
                .iter()
                .find(|l| l.mesh == m && l.primitive == q)
                .unwrap();
            assert_eq!(p["object"].as_u64(), Some(u64::from(link.object)));
            let level = scene["level"].as_u64().unwrap() as u32;
            let refined =
                hce_geometry::refine::refine_object(&objects[link.object as usize], level).unwrap();
            let positions: Vec<[f32; 3]> = reader.read_positions().unwrap().collect();
            assert_eq!(positions.len(), order.len(), "{name} mesh {m}");
            let placement = placements
                .links
                .iter()
                .find(|c| std::ptr::eq(&links[c.index], link))
                .unwrap()
                .placement;
            for (v, &r) in order.iter().enumerate() {
                let expected = refined.mesh.positions[r as usize];
                if placement.is_identity() {
                    assert_eq!(
                        positions[v].map(f32::to_bits),
                        expected.map(f32::to_bits),
                        "{name} mesh {m} output vertex {v}"
                    );
                } else {
                    // Placed back by M: the f32 rounding of M⁻¹, a thousandth of τ at most.
                    let back = placement.apply(positions[v].map(f64::from));
                    for a in 0..3 {
                        assert!(
                            (back[a] - f64::from(expected[a])).abs() <= 1e-3 * placement.tolerance,
                            "{name} mesh {m} output vertex {v}: {back:?} vs {expected:?}"
                        );
                    }
                }
            }
            let (_, coarse) =
                hce_format::primitive_geometry(&input.json, &input_buffers, m, q).unwrap();
            let per = 1usize << (2 * level);
            let first = link.first_triangle as usize * per;
            let fine = &refined.mesh.indices[first..first + coarse * per];
            let indices: Vec<u32> = reader.read_indices().unwrap().into_u32().collect();
            let through: Vec<[u32; 3]> = indices
                .chunks_exact(3)
                .map(|t| [0, 1, 2].map(|k| order[t[k] as usize]))
                .collect();
            assert_eq!(through, fine, "{name} mesh {m}: fine triangles");
            for probe in p["probes"].as_array().unwrap() {
                let v = probe["vertex"].as_u64().unwrap() as usize;
                let at = format!("{} mesh {} vertex {v}", c["file"], p["mesh"]);
                assert_eq!(normals[v].map(f32::to_bits), bits(&probe["normal"]), "{at}");
                assert_eq!(colours[v].map(f32::to_bits), bits(&probe["colour"]), "{at}");
            }
        }
        checked += 1;
    }
    assert!(checked >= 2, "{checked} scene entries");
}

/// The container a GLB of the suite carries.
fn container_of(glb: &[u8]) -> Vec<u8> {
    let a = hce_format::GltfAsset::parse(glb).unwrap();
    let buffers = a.buffers(|_| Err("none".into())).unwrap();
    hce_format::container_bytes(&a.json, &buffers)
        .unwrap()
        .unwrap()
        .to_vec()
}

#[test]
fn suite_is_what_the_generator_writes() {
    use hce_tests::conformance::{cases, generate, tool_cases};
    let dir = tempfile::tempdir().unwrap();
    // The baked sample is taken as it is: its bytes follow the baker, which may change; its
    // expectations (validity, probes of its control meshes) are regenerated from it.
    let cornell = std::fs::read(suite().join("valid/cornell-box.glb")).unwrap();
    let mut all = cases(cornell);
    let made = tool_cases(|f| std::fs::read(suite().join(f))).unwrap();
    // What the tools wrote still carries the container of the grid they were given.
    let grid = container_of(&std::fs::read(suite().join("valid/grid.glb")).unwrap());
    for c in &made {
        assert!(
            container_of(&c.bytes) == grid,
            "{}: not valid/grid.glb's container; remake it with the command in TOOL_CASES",
            c.file
        );
    }
    all.extend(made);
    generate(dir.path(), &all).unwrap();
    for c in all.iter().filter(|c| c.generated_by.is_none()) {
        let committed = std::fs::read(suite().join(&c.file)).unwrap();
        assert!(
            committed == c.bytes,
            "{} differs from the generator's; run `cargo run -p hce-tests --bin gen-conformance`",
            c.file
        );
    }
    let fresh = std::fs::read_to_string(dir.path().join("manifest.json")).unwrap();
    let committed = std::fs::read_to_string(suite().join("manifest.json")).unwrap();
    assert!(
        fresh == committed,
        "manifest.json is stale; run `cargo run -p hce-tests --bin gen-conformance`"
    );
    let size: u64 = std::fs::read_dir(suite().join("valid"))
        .unwrap()
        .chain(std::fs::read_dir(suite().join("invalid")).unwrap())
        .map(|e| e.unwrap().metadata().unwrap().len())
        .sum();
    assert!(size < 2 << 20, "the suite holds {size} bytes");
}
