//! A bake is a function of its inputs: the same scene in two folders under two names bakes to
//! the same bytes and the same key; the key changes with every parameter that shapes the output
//! and with any byte of any input file (the external `.bin` and texture of a `.gltf` included),
//! and not with `--threads` or the output's path; `--report` writes valid JSON with the inputs,
//! parameters, key, timings and counts, and on a failed bake the exit status and message.

mod common;

use std::path::{Path, PathBuf};

use serde_json::Value;

/// Coarse settings: the tests are about what a bake depends on, not the solution.
const CHEAP: [&str; 6] = common::COARSE_BAKE;

fn cornell_glb() -> Vec<u8> {
    std::fs::read(Path::new(env!("CARGO_MANIFEST_DIR")).join("../samples/cornell-box.glb")).unwrap()
}

/// The JSON and BIN chunks of a GLB.
fn split_glb(glb: &[u8]) -> (Value, Vec<u8>) {
    let u32_at = |o: usize| u32::from_le_bytes(glb[o..o + 4].try_into().unwrap()) as usize;
    let json_len = u32_at(12);
    let json = serde_json::from_slice(&glb[20..20 + json_len]).unwrap();
    let bin_at = 20 + json_len;
    let bin_len = u32_at(bin_at);
    (json, glb[bin_at + 8..bin_at + 8 + bin_len].to_vec())
}

fn tiny_png(red: u8) -> Vec<u8> {
    let mut out = Vec::new();
    let mut enc = png::Encoder::new(&mut out, 2, 2);
    enc.set_color(png::ColorType::Rgb);
    let mut w = enc.write_header().unwrap();
    w.write_image_data(&[red, 128, 64].repeat(4)).unwrap();
    w.finish().unwrap();
    out
}

/// Writes the Cornell box as `<dir>/<name>.gltf` with its buffer in `bin/box.bin` and an
/// image in `../textures/grain.png` (relative to the scene), as an asset pipeline lays them out.
fn write_gltf_scene(dir: &Path, name: &str) -> PathBuf {
    let (mut json, bin) = split_glb(&cornell_glb());
    json["buffers"][0]["uri"] = "bin/box.bin".into();
    json["images"] = serde_json::json!([{ "uri": "../textures/grain.png" }]);
    let scene = dir.join("scene");
    std::fs::create_dir_all(scene.join("bin")).unwrap();
    std::fs::create_dir_all(dir.join("textures")).unwrap();
    std::fs::write(scene.join("bin/box.bin"), bin).unwrap();
    std::fs::write(dir.join("textures/grain.png"), tiny_png(200)).unwrap();
    let path = scene.join(format!("{name}.gltf"));
    std::fs::write(&path, serde_json::to_vec_pretty(&json).unwrap()).unwrap();
    path
}

fn key(input: &Path, out: &str, extra: &[&str]) -> String {
    let mut args: Vec<String> = vec![
        "bake".into(),
        input.display().to_string(),
        "-o".into(),
        out.into(),
        "--print-key".into(),
    ];
    args.extend(CHEAP.iter().chain(extra).map(|s| s.to_string()));
    let stdout = common::hce_ok(&args);
    let key = stdout.trim().to_string();
    assert_eq!(key.len(), 64, "{stdout}");
    assert!(key.bytes().all(|b| b.is_ascii_hexdigit()), "{stdout}");
    key
}

fn bake(input: &Path, out: &Path, extra: &[&str]) -> (i32, String, String) {
    let mut args: Vec<String> = vec![
        "bake".into(),
        input.display().to_string(),
        "-o".into(),
        out.display().to_string(),
        "-q".into(),
    ];
    args.extend(CHEAP.iter().chain(extra).map(|s| s.to_string()));
    common::hce(&args)
}

#[test]
fn the_same_scene_in_two_folders_bakes_to_the_same_bytes_and_key() {
    let a = tempfile::tempdir().unwrap();
    let b = tempfile::tempdir().unwrap();
    let first = write_gltf_scene(a.path(), "room");
    let second = write_gltf_scene(&b.path().join("elsewhere/deeper"), "other name");
    assert_eq!(key(&first, "x.glb", &[]), key(&second, "y/z.glb", &[]));
    for ext in ["glb", "hce"] {
        let out_a = a.path().join(format!("a.{ext}"));
        let out_b = b.path().join(format!("b.{ext}"));
        for (input, out) in [(&first, &out_a), (&second, &out_b)] {
            let (code, _, stderr) = bake(input, out, &["--threads", "1"]);
            assert_eq!(code, 0, "{stderr}");
        }
        let (bytes_a, bytes_b) = (
            std::fs::read(&out_a).unwrap(),
            std::fs::read(&out_b).unwrap(),
        );
        assert!(bytes_a == bytes_b, "the two .{ext} bakes differ");
        // No path reaches the output: neither folder's name is in it.
        for dir in [a.path(), b.path()] {
            let name = dir.file_name().unwrap().to_string_lossy().into_owned();
            let found = bytes_a.windows(name.len()).any(|w| w == name.as_bytes());
            assert!(!found, "{name} is in the .{ext} output");
        }
    }
}

#[test]
fn the_key_follows_parameters_and_input_bytes_but_not_threads_or_paths() {
    let dir = tempfile::tempdir().unwrap();
    let scene = write_gltf_scene(dir.path(), "room");
    let base = key(&scene, "out.glb", &[]);
    assert_eq!(key(&scene, "out.glb", &["--threads", "1"]), base);
    assert_eq!(
        key(&scene, "/elsewhere/other.glb", &["--threads", "2"]),
        base
    );
    assert_eq!(key(&scene, "out.glb", &["-q"]), base);
    // The defaults filled in: naming a default changes nothing.
    assert_eq!(key(&scene, "out.glb", &["--creases", "none"]), base);
    for changed in [
        &["--normal-tolerance", "10"][..],
        &["--max-normals", "2"],
        &["--multires", "all"],
        &["--creases", "auto"],
        &["--detail-level", "5"],
    ] {
        assert_ne!(key(&scene, "out.glb", changed), base, "{changed:?}");
    }
    assert_ne!(key(&scene, "out.hce", &[]), base, "the output format");

    // One byte of each external file.
    let bin = scene.parent().unwrap().join("bin/box.bin");
    let texture = dir.path().join("textures/grain.png");
    for file in [&bin, &texture, &scene] {
        let original = std::fs::read(file).unwrap();
        let mut changed = original.clone();
        let at = changed.len() / 2;
        changed[at] ^= 1;
        std::fs::write(file, &changed).unwrap();
        assert_ne!(key(&scene, "out.glb", &[]), base, "{}", file.display());
        std::fs::write(file, &original).unwrap();
        assert_eq!(key(&scene, "out.glb", &[]), base);
    }
    // A file the scene names but that is missing is an input too: its absence.
    std::fs::remove_file(&texture).unwrap();
    assert_ne!(key(&scene, "out.glb", &[]), base);
}

#[test]
fn print_inputs_lists_each_file_and_the_document_the_key_is_made_from() {
    let dir = tempfile::tempdir().unwrap();
    let scene = write_gltf_scene(dir.path(), "room");
    let mut args = vec![
        "bake",
        scene.to_str().unwrap(),
        "-o",
        "o.glb",
        "--print-inputs",
    ];
    args.extend(CHEAP);
    let v: Value = serde_json::from_str(&common::hce_ok(&args)).unwrap();
    let names: Vec<&str> = v["inputs"]
        .as_array()
        .unwrap()
        .iter()
        .map(|i| i["name"].as_str().unwrap())
        .collect();
    assert_eq!(
        names,
        ["scene.gltf", "../textures/grain.png", "bin/box.bin"]
    );
    assert_eq!(
        v["inputs"][2]["bytes"].as_u64(),
        Some(
            std::fs::metadata(scene.parent().unwrap().join("bin/box.bin"))
                .unwrap()
                .len()
        )
    );
    assert_eq!(v["parameters"]["visibility_rays"], 2);
    assert_eq!(v["parameters"]["output_format"], "glb");
    assert!(v["parameters"].get("threads").is_none());
    let document = v["document"].as_str().unwrap();
    assert!(
        !document.contains(dir.path().to_str().unwrap()),
        "{document}"
    );
    assert_eq!(v["key"].as_str().unwrap(), key(&scene, "o.glb", &[]));
}

#[test]
fn the_report_of_a_bake_has_its_inputs_key_timings_and_counts() {
    let dir = tempfile::tempdir().unwrap();
    let scene = write_gltf_scene(dir.path(), "room");
    let report = dir.path().join("report.json");
    let out = dir.path().join("baked.glb");
    let (code, _, stderr) = bake(&scene, &out, &["--report", report.to_str().unwrap()]);
    assert_eq!(code, 0, "{stderr}");
    let v: Value = serde_json::from_slice(&std::fs::read(&report).unwrap()).unwrap();
    assert_eq!(v["status"], 0);
    assert_eq!(v["error"], Value::Null);
    assert_eq!(v["key"].as_str().unwrap(), key(&scene, "baked.glb", &[]));
    assert_eq!(v["inputs"].as_array().unwrap().len(), 3);
    assert_eq!(v["parameters"]["levels"], 1);
    assert!(v["inputs"][0]["sha256"].as_str().unwrap().len() == 64);
    let counts = &v["counts"];
    assert_eq!(counts["objects"].as_u64(), Some(8), "{counts}");
    assert!(counts["coarse_triangles"].as_u64().unwrap() >= 32);
    assert!(counts["links"].as_u64().unwrap() > 0);
    assert_eq!(
        counts["output_bytes"].as_u64(),
        Some(std::fs::metadata(&out).unwrap().len())
    );
    let phases = v["timings"]["phases"].as_array().unwrap();
    assert!(phases.iter().any(|p| p["phase"] == "import"), "{phases:?}");
    assert!(v["timings"]["total_seconds"].as_f64().unwrap() > 0.0);
    assert!(v["warnings"].is_array());
}

#[test]
fn a_damaged_file_gets_a_report_with_its_status_and_message() {
    let dir = tempfile::tempdir().unwrap();
    let damaged = dir.path().join("damaged.glb");
    let glb = cornell_glb();
    std::fs::write(&damaged, &glb[..glb.len() / 3]).unwrap();
    let report = dir.path().join("report.json");
    let out = dir.path().join("never.glb");
    let (code, _, stderr) = bake(&damaged, &out, &["--report", report.to_str().unwrap()]);
    assert_eq!(code, 3, "{stderr}");
    assert!(!out.exists());
    let v: Value = serde_json::from_slice(&std::fs::read(&report).unwrap()).unwrap();
    assert_eq!(v["status"], 3);
    let message = v["error"].as_str().unwrap();
    assert!(stderr.contains(message), "{message} / {stderr}");
    assert!(message.contains("damaged.glb"), "{message}");
    // The key is of the bytes that failed, so a cache can remember the failure.
    assert_eq!(v["key"].as_str().unwrap().len(), 64);

    let missing = dir.path().join("missing.glb");
    let (code, _, stderr) = bake(&missing, &out, &["--report", report.to_str().unwrap()]);
    assert_eq!(code, 4, "{stderr}");
    let v: Value = serde_json::from_slice(&std::fs::read(&report).unwrap()).unwrap();
    assert_eq!(v["status"], 4);
    assert_eq!(v["key"], Value::Null);
    assert!(v["error"].as_str().unwrap().contains("missing.glb"));
}
