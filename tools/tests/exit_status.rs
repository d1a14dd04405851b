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
        "--levels",
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
        "--levels",
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
    let (code, _) = hce(&["subdivide", "--levels", "not-a-number"]);
    assert_eq!(code, 2);
}
