//! Runs the real `hce` binary over the conformance suite (`conformance/`, see its README): every
//! file's `hce validate` exit status and problem lines, and for valid files the refined
//! positions of the probe vertices at levels 1 to 3 (through `hce subdivide --merge` to OBJ).
//! Also checks that the suite is what its generator writes today.

use serde_json::Value;
use std::path::{Path, PathBuf};
use std::process::Command;

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
        let out = Command::new(env!("CARGO_BIN_EXE_hce"))
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
            c["problems"]
                .as_array()
                .unwrap()
                .iter()
                .map(|p| {
                    format!(
                        "{}: {}",
                        p["location"].as_str().unwrap(),
                        p["message"].as_str().unwrap()
                    )
                })
                .collect()
        };
        let got: Vec<&str> = stdout.lines().collect();
        assert_eq!(got, expected, "{}", c["file"]);
    }
}

/// `v` positions of an OBJ.
fn obj_positions(path: &Path) -> Vec<[f32; 3]> {
    std::fs::read_to_string(path)
        .unwrap()
        .lines()
        .filter_map(|l| l.strip_prefix("v "))
        .map(|l| {
            let x: Vec<f32> = l.split(' ').take(3).map(|t| t.parse().unwrap()).collect();
            [x[0], x[1], x[2]]
        })
        .collect()
}

#[test]
fn probe_positions_match_at_levels_1_to_3() {
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
            let status = Command::new(env!("CARGO_BIN_EXE_hce"))
                .args(["subdivide", "--merge", "-l", &level.to_string(), "-o"])
                .arg(&out)
                .arg(&file)
                .output()
                .unwrap();
            assert!(
                status.status.success(),
                "{}",
                String::from_utf8_lossy(&status.stderr)
            );
            let positions = obj_positions(&out);
            // The merged mesh concatenates the objects in container order.
            let mut offset = 0;
            for r in refined.iter().filter(|r| r["level"] == level) {
                for p in r["probes"].as_array().unwrap() {
                    let v = offset + p["vertex"].as_u64().unwrap() as usize;
                    let bits: Vec<u32> = p["position"]["bits"]
                        .as_array()
                        .unwrap()
                        .iter()
                        .map(|b| u32::from_str_radix(b.as_str().unwrap(), 16).unwrap())
                        .collect();
                    assert_eq!(
                        positions[v].map(f32::to_bits).to_vec(),
                        bits,
                        "{} object {} level {level} vertex {}",
                        c["file"],
                        r["object"],
                        p["vertex"]
                    );
                    checked += 1;
                }
                offset += r["vertex_count"].as_u64().unwrap() as usize;
            }
            assert_eq!(offset, positions.len(), "{} level {level}", c["file"]);
        }
    }
    assert!(checked > 50, "{checked} probes");
}

#[test]
fn suite_is_what_the_generator_writes() {
    use hce_tests::conformance::{cases, generate};
    let dir = tempfile::tempdir().unwrap();
    // The baked sample is taken as it is: its bytes follow the baker, which may change; its
    // expectations (validity, probes of its control meshes) are regenerated from it.
    let cornell = std::fs::read(suite().join("valid/cornell-box.glb")).unwrap();
    let all = cases(cornell);
    generate(dir.path(), &all).unwrap();
    for c in all.iter().filter(|c| !c.baked) {
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
