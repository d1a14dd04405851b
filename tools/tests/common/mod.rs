//! The `hce` binary for the tools' integration tests: one helper, shared by every test file
//! (`mod common;`). Not every file uses every function.
#![allow(dead_code)]

use std::ffi::OsStr;
use std::process::Command;

/// Coarse `hce bake` settings for tests about the command rather than the solution.
pub const COARSE_BAKE: [&str; 6] = [
    "--bf-epsilon",
    "1e-2",
    "--visibility-rays",
    "2",
    "--max-level",
    "1",
];

/// A command for the `hce` binary built with these tests, to add arguments and environment to.
pub fn command() -> Command {
    Command::new(env!("CARGO_BIN_EXE_hce"))
}

/// Runs `hce ARGS` to its end: (exit status, stdout, stderr). A run killed by a signal has
/// status -1.
pub fn hce<S: AsRef<OsStr>>(args: &[S]) -> (i32, String, String) {
    let out = command().args(args).output().expect("the hce binary runs");
    (
        out.status.code().unwrap_or(-1),
        String::from_utf8_lossy(&out.stdout).into_owned(),
        String::from_utf8_lossy(&out.stderr).into_owned(),
    )
}

/// Runs `hce ARGS`, asserts that it succeeded and returns its stdout.
pub fn hce_ok<S: AsRef<OsStr>>(args: &[S]) -> String {
    let (code, stdout, stderr) = hce(args);
    let shown: Vec<_> = args.iter().map(|a| a.as_ref().to_string_lossy()).collect();
    assert_eq!(code, 0, "hce {shown:?}: {stderr}");
    stdout
}
