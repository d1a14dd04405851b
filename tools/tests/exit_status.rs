//! The exit statuses documented in `hce --help` (and SPEC.md Appendix E) for commands that read
//! meshes: 4 for a file that cannot be read, 3 for bytes that are not a usable mesh.

use std::process::Command;

fn hce(args: &[&str]) -> (i32, String) {
    let out = Command::new(env!("CARGO_BIN_EXE_hce"))
        .args(args)
        .output()
        .expect("the hce binary runs");
    (
        out.status.code().expect("exited normally"),
        String::from_utf8_lossy(&out.stderr).into_owned(),
    )
}

#[test]
fn subdivide_reports_a_missing_file_as_io_error() {
    let dir = tempfile::tempdir().unwrap();
    let missing = dir.path().join("missing.obj");
    let out = dir.path().join("out.obj");
    let (code, stderr) = hce(&[
        "subdivide",
        missing.to_str().unwrap(),
        "--level",
        "1",
        "-o",
        out.to_str().unwrap(),
    ]);
    assert_eq!(code, 4, "{stderr}");
    assert!(stderr.contains("missing.obj"), "{stderr}");
    assert!(!out.exists());
}

#[test]
fn subdivide_reports_garbage_as_invalid_input() {
    let dir = tempfile::tempdir().unwrap();
    let bad = dir.path().join("bad.glb");
    std::fs::write(&bad, b"this is not a GLB file").unwrap();
    let out = dir.path().join("out.obj");
    let (code, stderr) = hce(&[
        "subdivide",
        bad.to_str().unwrap(),
        "--level",
        "1",
        "-o",
        out.to_str().unwrap(),
    ]);
    assert_eq!(code, 3, "{stderr}");
    assert!(stderr.contains("bad.glb"), "{stderr}");
    assert!(!out.exists());
}

#[test]
fn usage_errors_exit_with_two() {
    let (code, _) = hce(&["subdivide", "--level", "not-a-number"]);
    assert_eq!(code, 2);
}

#[test]
fn old_level_spellings_still_work_with_a_warning() {
    // `subdivide --levels N` became `--level N`; the old spelling still refines, and says so.
    let dir = tempfile::tempdir().unwrap();
    let input = dir.path().join("tri.obj");
    std::fs::write(&input, "v 0 0 0\nv 1 0 0\nv 0 1 0\nf 1 2 3\n").unwrap();
    let out = dir.path().join("out.obj");
    let (code, stderr) = hce(&[
        "subdivide",
        input.to_str().unwrap(),
        "--levels",
        "1",
        "-o",
        out.to_str().unwrap(),
    ]);
    assert_eq!(code, 0, "{stderr}");
    assert!(
        stderr.contains("--levels is deprecated; use --level"),
        "{stderr}"
    );
    let obj = std::fs::read_to_string(&out).unwrap();
    assert_eq!(obj.lines().filter(|l| l.starts_with("f ")).count(), 4);
    // Both spellings at once is a usage error.
    let (code, _) = hce(&[
        "subdivide",
        "x.obj",
        "--level",
        "1",
        "--levels",
        "1",
        "-o",
        "y.obj",
    ]);
    assert_eq!(code, 2);
}
