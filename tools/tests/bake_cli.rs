//! `hce bake` as a user runs it: the summary names every figure issue 4 asks for, progress bars
//! stay silent when stderr is not a terminal, `-q` prints nothing, and `--threads 1` and
//! `--threads 2` write the same bytes.

mod common;

use std::path::Path;

fn bake(input: &Path, out: &Path, extra: &[&str]) -> (i32, String, String) {
    let out = common::command()
        .arg("bake")
        .arg(input)
        .arg("-o")
        .arg(out)
        .args(common::COARSE_BAKE)
        .args(extra)
        .output()
        .expect("the hce binary runs");
    (
        out.status.code().expect("exited normally"),
        String::from_utf8_lossy(&out.stdout).into_owned(),
        String::from_utf8_lossy(&out.stderr).into_owned(),
    )
}

fn cornell() -> std::path::PathBuf {
    Path::new(env!("CARGO_MANIFEST_DIR")).join("../samples/cornell-box.glb")
}

fn field(stdout: &str, name: &str) -> String {
    stdout
        .lines()
        .find_map(|l| l.strip_prefix(name))
        .unwrap_or_else(|| panic!("no {name:?} line in\n{stdout}"))
        .trim()
        .to_string()
}

#[test]
fn summary_lists_every_figure_and_progress_is_silent_without_a_terminal() {
    let dir = tempfile::tempdir().unwrap();
    let out = dir.path().join("one.glb");
    let (code, stdout, stderr) = bake(
        &cornell(),
        &out,
        &[
            "--multires",
            "short_block",
            "--creases",
            "auto",
            "--threads",
            "1",
        ],
    );
    assert_eq!(code, 0, "{stderr}");
    assert_eq!(field(&stdout, "objects:"), "8 (1 multiresolution, 7 flat)");
    assert_eq!(field(&stdout, "coarse triangles:"), "32");
    for name in ["elements:", "links:", "iterations:"] {
        let n: usize = field(&stdout, name).parse().unwrap();
        assert!(n > 0, "{name} {n}");
    }
    // The multiresolution block: its histogram and worst angle, per object and overall.
    let block = stdout.lines().find(|l| l.contains("short_block")).unwrap();
    assert!(
        block.contains("multires") && block.contains("normals 1:10") && block.contains("worst"),
        "{block}"
    );
    assert!(field(&stdout, "normals per triangle:").starts_with("1:10"));
    let time = field(&stdout, "time:");
    for phase in [
        "import", "direct", "refine 1", "solve 1", "encode", "write", "total",
    ] {
        assert!(time.contains(phase), "{phase} missing from {time}");
    }
    let size = std::fs::metadata(&out).unwrap().len();
    assert!(
        field(&stdout, "output:").ends_with(&format!("({size} bytes)")),
        "{stdout}"
    );
    // stderr is a pipe here: no progress bar was drawn.
    assert!(!stderr.contains("[="), "{stderr}");
    assert!(!stderr.contains("refine 1"), "{stderr}");

    // Quiet: nothing on stdout; the same bytes with two threads.
    let two = dir.path().join("two.glb");
    let (code, stdout, stderr) = bake(
        &cornell(),
        &two,
        &[
            "--multires",
            "short_block",
            "--creases",
            "auto",
            "--threads",
            "2",
            "-q",
        ],
    );
    assert_eq!(code, 0, "{stderr}");
    assert!(stdout.is_empty(), "{stdout}");
    assert!(stderr.is_empty(), "{stderr}");
    assert_eq!(std::fs::read(&out).unwrap(), std::fs::read(&two).unwrap());
}

#[test]
fn a_scene_without_light_is_an_invalid_input_error() {
    let dir = tempfile::tempdir().unwrap();
    let obj = dir.path().join("dark.obj");
    std::fs::write(&obj, "v 0 0 0\nv 1 0 0\nv 0 1 0\nf 1 2 3\n").unwrap();
    let out = dir.path().join("dark.glb");
    let (code, stdout, stderr) = bake(&obj, &out, &[]);
    assert_eq!(code, 3, "{stdout}{stderr}");
    assert!(stderr.contains("no light source"), "{stderr}");
    assert!(!out.exists());
}

#[test]
fn a_detail_level_outside_its_range_is_a_usage_error_and_writes_nothing() {
    let dir = tempfile::tempdir().unwrap();
    let out = dir.path().join("never.glb");
    for level in ["2", "13"] {
        let (code, _, stderr) = bake(&cornell(), &out, &["--detail-level", level]);
        assert_eq!(code, 2, "--detail-level {level}: {stderr}");
        assert!(
            stderr.contains(&format!("detail_level {level} must lie between")),
            "{stderr}"
        );
        assert!(!out.exists());
    }
}
