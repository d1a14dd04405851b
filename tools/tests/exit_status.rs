//! The exit statuses documented in `hce --help`, README.md and SPEC.md Appendix E.1, one test
//! (at least) per status: 0 success, 2 usage, 3 invalid input, 4 I/O. Status 1 (other errors)
//! has no input that reliably provokes it; its classification is unit-tested in
//! `tools/src/exit.rs`.

mod common;

use hce_format::{example, write};

#[test]
fn subdivide_reports_a_missing_file_as_io_error() {
    let dir = tempfile::tempdir().unwrap();
    let missing = dir.path().join("missing.obj");
    let out = dir.path().join("out.obj");
    let (code, _, stderr) = common::hce(&[
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
    let (code, _, stderr) = common::hce(&[
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
    let (code, _, _) = common::hce(&["subdivide", "--level", "not-a-number"]);
    assert_eq!(code, 2);
}

#[test]
fn old_level_spellings_still_work_with_a_warning() {
    // `subdivide --levels N` became `--level N`; the old spelling still refines, and says so.
    let dir = tempfile::tempdir().unwrap();
    let input = dir.path().join("tri.obj");
    std::fs::write(&input, "v 0 0 0\nv 1 0 0\nv 0 1 0\nf 1 2 3\n").unwrap();
    let out = dir.path().join("out.obj");
    let (code, _, stderr) = common::hce(&[
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
    let (code, _, _) = common::hce(&[
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

#[test]
fn success_exits_with_zero() {
    let dir = tempfile::tempdir().unwrap();
    let file = dir.path().join("ok.hce");
    std::fs::write(&file, write(&example::two_triangles()).unwrap()).unwrap();
    let (code, stdout, stderr) = common::hce(&["validate", file.to_str().unwrap()]);
    assert_eq!(code, 0, "{stderr}");
    assert!(stdout.ends_with(": valid\n"), "{stdout}");
    let (code, stdout, _) = common::hce(&["--help"]);
    assert_eq!(code, 0);
    assert!(stdout.contains("4  I/O error"), "{stdout}");
}

/// `hce bake` arguments out of range are usage errors found by clap, before any file is read.
#[test]
fn bake_ranges_are_usage_errors() {
    for (flag, value) in [
        ("--threads", "0"),
        // Once accepted: `max_normals + 1` wrapped to 0 and the bake went on.
        ("--max-normals", "18446744073709551615"),
        ("--max-normals", "64"),
        ("--max-level", "7"),
        ("--normal-tolerance=-1", ""),
        ("--normal-tolerance", "NaN"),
    ] {
        let mut args = vec!["bake", "no-such-scene.obj", "-o", "out.glb", flag];
        if !value.is_empty() {
            args.push(value);
        }
        let (code, _, stderr) = common::hce(&args);
        assert_eq!(code, 2, "{flag} {value}: {stderr}");
        let name = flag.split('=').next().unwrap();
        assert!(stderr.contains(name), "{flag} {value}: {stderr}");
    }
}

/// `--level 7` is out of range whatever the input: a plain mesh and a baked file both exit 2
/// (once 3 and 1).
#[test]
fn subdivide_level_out_of_range_is_a_usage_error_for_every_input() {
    let dir = tempfile::tempdir().unwrap();
    let plain = dir.path().join("tri.obj");
    std::fs::write(&plain, "v 0 0 0\nv 1 0 0\nv 0 1 0\nf 1 2 3\n").unwrap();
    let baked = dir.path().join("tri.hce");
    std::fs::write(&baked, write(&example::single_triangle()).unwrap()).unwrap();
    let out = dir.path().join("out.glb");
    for input in [&plain, &baked] {
        let (code, _, stderr) = common::hce(&[
            "subdivide",
            input.to_str().unwrap(),
            "--level",
            "7",
            "-o",
            out.to_str().unwrap(),
        ]);
        assert_eq!(code, 2, "{}: {stderr}", input.display());
        assert!(stderr.contains("--level"), "{stderr}");
        assert!(!out.exists());
    }
}

#[test]
fn validate_statuses_follow_the_table() {
    let dir = tempfile::tempdir().unwrap();
    // A container whose header is damaged: read, but invalid (3).
    let bad = dir.path().join("bad.hce");
    let mut bytes = write(&example::two_triangles()).unwrap();
    bytes[0] ^= 0xff;
    std::fs::write(&bad, bytes).unwrap();
    let (code, stdout, stderr) = common::hce(&["validate", bad.to_str().unwrap()]);
    assert_eq!(code, 3, "{stdout}{stderr}");
    assert!(stdout.starts_with("file: bad file identifier"), "{stdout}");
    // A file that is not there (4), for `validate` and `inspect` alike.
    let missing = dir.path().join("missing.hce");
    for command in ["validate", "inspect"] {
        let (code, _, stderr) = common::hce(&[command, missing.to_str().unwrap()]);
        assert_eq!(code, 4, "{command}: {stderr}");
        assert!(stderr.contains("missing.hce"), "{stderr}");
    }
}

#[test]
fn bake_reports_a_missing_scene_as_io_error() {
    let dir = tempfile::tempdir().unwrap();
    let missing = dir.path().join("missing.obj");
    let out = dir.path().join("out.glb");
    let (code, _, stderr) = common::hce(&[
        "bake",
        missing.to_str().unwrap(),
        "-o",
        out.to_str().unwrap(),
    ]);
    assert_eq!(code, 4, "{stderr}");
    assert!(stderr.contains("missing.obj"), "{stderr}");
    assert!(!out.exists());
}

/// Values that clap cannot check alone (sizes, output kinds) are usage errors too.
#[test]
fn values_parsed_after_clap_are_usage_errors() {
    let dir = tempfile::tempdir().unwrap();
    let (code, _, stderr) =
        common::hce(&["demo", "--size", "huge", "-o", dir.path().to_str().unwrap()]);
    assert_eq!(code, 2, "{stderr}");
    assert!(stderr.contains("huge"), "{stderr}");
}

/// `hce render`'s own arguments: a bad `--size`, `--level` or `--camera` is a usage error (2),
/// found before any file is read or GPU opened, whatever the input.
#[test]
fn render_argument_errors_are_usage_errors() {
    let dir = tempfile::tempdir().unwrap();
    let input = dir.path().join("tri.hce");
    std::fs::write(&input, write(&example::single_triangle()).unwrap()).unwrap();
    let out = dir.path().join("out.png");
    let (input, out) = (input.to_str().unwrap(), out.to_str().unwrap());
    for bad in [
        &["--size", "0x600"][..],
        &["--size", "wide"],
        &["--level", "16"],
        &["--camera", "1,2:3"],
        &["--camera", "0,0,1:0,0,1"],
    ] {
        let mut args = vec!["render", input, "-o", out];
        args.extend_from_slice(bad);
        let (code, _, stderr) = common::hce(&args);
        assert_eq!(code, 2, "{bad:?}: {stderr}");
        assert!(
            stderr.contains(bad[0]) || stderr.contains("camera"),
            "{bad:?}: {stderr}"
        );
    }
}

/// A level the flat kernel takes but Loop subdivision does not (7 to 15) is a usage error on an
/// asset with a multiresolution object, found when the object is refined.
#[test]
fn render_level_past_loop_subdivision_is_a_usage_error() {
    use hce_runtime::gpu::testing::{try_context, Unavailable};
    let dir = tempfile::tempdir().unwrap();
    let input = dir.path().join("tri.hce");
    std::fs::write(&input, write(&example::single_triangle()).unwrap()).unwrap();
    let out = dir.path().join("out.png");
    let (code, _, stderr) = common::hce(&[
        "render",
        input.to_str().unwrap(),
        "-o",
        out.to_str().unwrap(),
        "--size",
        "16x16",
        "--level",
        "7",
        "--software",
    ]);
    match try_context("render_level_past_loop_subdivision_is_a_usage_error") {
        Ok(_) => {}
        Err(Unavailable::Skip(_)) => return,
        Err(Unavailable::Fail(m)) => panic!("{m}"),
    }
    assert_eq!(code, 2, "{stderr}");
    assert!(stderr.contains('7'), "{stderr}");
    assert!(!std::path::Path::new(&out).exists());
}
