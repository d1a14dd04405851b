//! Writes the sample scenes (`teatime.glb`, `chesstime.glb`, `cornell-box.glb`) into a folder,
//! `samples/` of the repository by default, and prints their triangle counts.
//!
//! Usage: `cargo run -p hce-samples --bin gen-samples [-- OUT_DIR]`

use std::io::Write;
use std::path::{Path, PathBuf};

use anyhow::{Context, Result};

/// Writes `bytes` to `path` through a temporary file in the same folder and a rename, so that a
/// reader never sees a half-written sample.
fn write_atomically(path: &Path, bytes: &[u8]) -> Result<()> {
    let dir = path.parent().unwrap_or(Path::new("."));
    let name = path
        .file_name()
        .with_context(|| format!("{}: not a file path", path.display()))?;
    let tmp = dir.join(format!(
        ".{}.tmp-{}",
        name.to_string_lossy(),
        std::process::id()
    ));
    let result = (|| -> Result<()> {
        let mut f = std::fs::File::create(&tmp)
            .with_context(|| format!("{}: cannot create", tmp.display()))?;
        f.write_all(bytes)
            .with_context(|| format!("{}: cannot write", tmp.display()))?;
        f.sync_all()
            .with_context(|| format!("{}: cannot flush to disk", tmp.display()))?;
        std::fs::rename(&tmp, path)
            .with_context(|| format!("{}: cannot move into place", path.display()))
    })();
    if result.is_err() {
        let _ = std::fs::remove_file(&tmp);
    }
    result
}

fn main() -> Result<()> {
    let out: PathBuf = match std::env::args_os().nth(1) {
        Some(dir) => dir.into(),
        None => Path::new(env!("CARGO_MANIFEST_DIR"))
            .parent()
            .context("the generator crate has no parent folder")?
            .to_path_buf(),
    };
    std::fs::create_dir_all(&out)
        .with_context(|| format!("{}: cannot create the output folder", out.display()))?;
    for (file, scene) in hce_samples::scenes::all() {
        let bytes = hce_samples::glb::write_glb(&scene)
            .with_context(|| format!("{file}: cannot build the GLB"))?;
        let path = out.join(file);
        write_atomically(&path, &bytes)?;
        println!(
            "{}: {} bytes, {} triangles",
            path.display(),
            bytes.len(),
            scene.triangle_count()
        );
        for o in &scene.objects {
            println!(
                "  {:<16} {:>5} triangles{}",
                o.name,
                o.triangle_count(),
                if o.multires { "  (multires)" } else { "" }
            );
        }
    }
    Ok(())
}
