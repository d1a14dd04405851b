//! `hce validate FILE`: deep validation of a `.hce` container or of the container embedded in a
//! `.glb` / `.gltf` asset (SPEC.md Appendix C), plus the asset's links: object indices in range,
//! triangle ranges inside their object and geometry hashes that still match the mesh.
//! Prints one line per problem; the exit status says valid (0), invalid (3) or unreadable (4).

use super::inspect::LoadError;
use clap::Args;
use hce_format::{validate_asset_report, validate_bytes, AssetReport, GltfError};
use hce_runtime::asset::{buffer_files, GltfSource};
use std::path::{Path, PathBuf};

#[derive(Args, Debug)]
pub struct ValidateArgs {
    /// A `.hce` container, or a `.glb` / `.gltf` asset that embeds one.
    pub file: PathBuf,
}

/// Every problem of the file, as `location: message` lines: the container's (SPEC.md
/// Appendix C) and, for glTF assets, the extension's and every primitive link's
/// ([`hce_format::validate_asset_report`]), with the warnings that do not make it invalid (a
/// primitive that cannot be checked, SPEC.md 2.6). `Err` only when the file cannot be read or
/// parsed at all.
pub fn report(args: &ValidateArgs) -> Result<AssetReport, LoadError> {
    let path = &args.file;
    let bytes =
        std::fs::read(path).map_err(|e| LoadError::Io(format!("{}: {e}", path.display())))?;
    let is_gltf = bytes.starts_with(b"glTF")
        || path
            .extension()
            .is_some_and(|e| e.eq_ignore_ascii_case("gltf") || e.eq_ignore_ascii_case("glb"));
    Ok(if is_gltf {
        let invalid = |e: GltfError| LoadError::Invalid(format!("{}: {e}", path.display()));
        let dir = path.parent().map(Path::to_path_buf).unwrap_or_default();
        let source = GltfSource::parse(&bytes, buffer_files(&dir)).map_err(invalid)?;
        validate_asset_report(&source.json, &source.buffers)
    } else {
        AssetReport {
            problems: validate_bytes(&bytes),
            warnings: Vec::new(),
        }
    })
}

/// The problems of [`report`] as `location: message` lines.
pub fn problems(args: &ValidateArgs) -> Result<Vec<String>, LoadError> {
    Ok(report(args)?
        .problems
        .iter()
        .map(ToString::to_string)
        .collect())
}

/// Runs the command: prints every warning on stderr and every problem, and fails (status 3)
/// when there is a problem.
pub fn run(args: ValidateArgs) -> anyhow::Result<()> {
    let r = report(&args)?;
    for w in &r.warnings {
        eprintln!("warning: {w}");
    }
    let p: Vec<String> = r.problems.iter().map(ToString::to_string).collect();
    if p.is_empty() {
        super::inspect::emit(&format!("{}: valid\n", args.file.display()));
        return Ok(());
    }
    super::inspect::emit(&p.iter().map(|l| format!("{l}\n")).collect::<String>());
    Err(crate::exit::Invalid(format!("{}: {} problem(s)", args.file.display(), p.len())).into())
}
