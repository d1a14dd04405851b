//! `hce validate FILE`: deep validation of a `.hce` container or of the container embedded in a
//! `.glb` / `.gltf` asset (SPEC.md Appendix C), plus the asset's links: object indices in range,
//! triangle ranges inside their object and geometry hashes that still match the mesh.
//! Prints one line per problem; the exit status says valid (0), invalid (3) or unreadable (4).

use super::inspect::{load, EXIT_INVALID};
use clap::Args;
use hce_format::{read_with, validate_bytes, ReadOptions};
use std::path::PathBuf;

#[derive(Args, Debug)]
pub struct ValidateArgs {
    /// A `.hce` container, or a `.glb` / `.gltf` asset that embeds one.
    pub file: PathBuf,
}

/// Every problem of the file, as `location: message` lines.
pub fn problems(args: &ValidateArgs) -> Result<Vec<String>, super::inspect::LoadError> {
    let loaded = load(&args.file)?;
    let mut out: Vec<String> = validate_bytes(&loaded.container)
        .iter()
        .map(ToString::to_string)
        .collect();
    if loaded.primitives.is_empty() {
        return Ok(out);
    }
    let container = read_with(
        &loaded.container,
        &ReadOptions {
            verify_checksums: false,
        },
    )
    .ok();
    let mut ranges: Vec<(u32, u64, u64, String)> = Vec::new();
    for p in &loaded.primitives {
        let l = &p.link;
        let at = format!("meshes[{}].primitives[{}]", l.mesh, l.primitive);
        let object = container
            .as_ref()
            .and_then(|c| c.objects.get(l.object as usize));
        let Some(c) = &container else { continue };
        let Some(object) = object else {
            out.push(format!(
                "{at}: object {} is out of range; the container has {} objects",
                l.object,
                c.objects.len()
            ));
            continue;
        };
        match &p.computed {
            Err(e) => out.push(format!("{at}: {e}")),
            Ok((hash, triangles)) => {
                if *hash != l.geometry_hash {
                    out.push(format!(
                        "{at}: geometry hash {:016x} differs from the baked {:016x}: the mesh was edited after baking; bake it again",
                        hash, l.geometry_hash
                    ));
                }
                let end = u64::from(l.first_triangle) + *triangles as u64;
                if end > object.triangles.len() as u64 {
                    out.push(format!(
                        "{at}: triangles {}..{end} exceed object {}'s {} triangles",
                        l.first_triangle,
                        l.object,
                        object.triangles.len()
                    ));
                }
                ranges.push((l.object, u64::from(l.first_triangle), end, at));
            }
        }
    }
    ranges.sort();
    for w in ranges.windows(2) {
        if w[0].0 == w[1].0 && w[1].1 < w[0].2 {
            out.push(format!(
                "{}: triangle range overlaps that of {} for object {} (SPEC.md 3.3)",
                w[1].3, w[0].3, w[0].0
            ));
        }
    }
    Ok(out)
}

/// Runs the command; exits with a documented status on failure (see `hce --help`).
pub fn run(args: ValidateArgs) -> anyhow::Result<()> {
    match problems(&args) {
        Ok(p) if p.is_empty() => {
            super::inspect::emit(&format!("{}: valid\n", args.file.display()));
            Ok(())
        }
        Ok(p) => {
            super::inspect::emit(&p.iter().map(|l| format!("{l}\n")).collect::<String>());
            eprintln!("{}: {} problem(s)", args.file.display(), p.len());
            std::process::exit(EXIT_INVALID)
        }
        Err(e) => {
            eprintln!("error: {}", e.message());
            std::process::exit(e.exit_code())
        }
    }
}
