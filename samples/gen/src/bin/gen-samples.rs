//! Writes the sample scenes (`teatime.glb`, `chesstime.glb`, `cornell-box.glb`) into a folder,
//! `samples/` of the repository by default, and prints their triangle counts.
//!
//! Usage: `cargo run -p hce-samples --bin gen-samples [-- OUT_DIR]`
//!
//! `gen-samples room --mesh MESH.obj -o ROOM.glb [--name NAME] [--turn DEG] [--triangles N]
//! [--furnace]` writes
//! instead a test room around one mesh ([`hce_samples::room`]): a closed room lit by a ceiling
//! light, the mesh turned `DEG` degrees about +Y (default 0), scaled to fit, standing on the
//! floor, multiresolution, and a camera looking at it. With `--triangles N` the mesh is first
//! simplified to at most `N` triangles ([`hce_samples::simplify`]), so that a fine scan becomes
//! the coarse control mesh a multiresolution object is meant to be. With `--furnace` every
//! surface, the light included, emits 0.4 and reflects 0.5 ([`hce_samples::room::furnace`]):
//! a closed furnace whose exact radiance is 0.8 everywhere (`hce compare --constant 0.8`).
#![forbid(unsafe_code)]

use std::io::Write;
use std::path::{Path, PathBuf};

use anyhow::{Context, Result};

/// A usage error (a bad or missing argument): printed without a backtrace, exit status 2 as
/// `hce`'s are; any other error exits with 1.
#[derive(Debug)]
struct Usage(String);

impl std::fmt::Display for Usage {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        f.write_str(&self.0)
    }
}

impl std::error::Error for Usage {}

fn usage_error(message: String) -> anyhow::Error {
    anyhow::Error::new(Usage(message))
}

/// Writes `bytes` to `path` through a temporary file in the same folder and a rename, so that a
/// reader never sees a half-written sample. (The one atomic writer of the tools is
/// `hce_meshio::write_atomic`; this crate keeps its own because it depends on no hce crate: the
/// samples are generated independently of the code they test.)
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

/// `room --mesh PATH -o OUT.glb [--name NAME] [--turn DEG] [--triangles N] [--furnace]`.
fn room(args: &[String]) -> Result<()> {
    let usage = "usage: gen-samples room --mesh MESH.obj -o ROOM.glb [--name NAME] [--turn DEG] \
                 [--triangles N] [--furnace]";
    let (mut mesh, mut out, mut name, mut turn) = (None, None, None, 0.0);
    let mut triangles: Option<usize> = None;
    let mut furnace = false;
    let mut it = args.iter();
    while let Some(a) = it.next() {
        if a == "--furnace" {
            furnace = true;
            continue;
        }
        let value = it
            .next()
            .ok_or_else(|| usage_error(format!("{a} needs a value; {usage}")));
        match a.as_str() {
            "--mesh" => mesh = Some(PathBuf::from(value?)),
            "-o" | "--output" => out = Some(PathBuf::from(value?)),
            "--name" => name = Some(value?.clone()),
            "--turn" => {
                turn = value?
                    .parse::<f64>()
                    .ok()
                    .filter(|t| t.is_finite())
                    .ok_or_else(|| usage_error(format!("--turn takes degrees; {usage}")))?
            }
            "--triangles" => {
                triangles = Some(
                    value?
                        .parse::<usize>()
                        .ok()
                        .filter(|&n| n >= 4)
                        .ok_or_else(|| {
                            usage_error(format!("--triangles takes a count of 4 or more; {usage}"))
                        })?,
                )
            }
            _ => return Err(usage_error(format!("unknown argument {a:?}; {usage}"))),
        }
    }
    let (mesh_path, out) = match (mesh, out) {
        (Some(m), Some(o)) => (m, o),
        _ => return Err(usage_error(usage.to_string())),
    };
    let name = name.unwrap_or_else(|| {
        mesh_path
            .file_stem()
            .map_or("mesh".into(), |s| s.to_string_lossy().into_owned())
    });
    let text = std::fs::read_to_string(&mesh_path)
        .with_context(|| format!("{}: cannot read", mesh_path.display()))?;
    let mut mesh = hce_samples::room::parse_obj(&text)
        .with_context(|| format!("{}: not a usable OBJ", mesh_path.display()))?;
    let input_triangles = mesh.triangles.len();
    if let Some(n) = triangles {
        mesh = hce_samples::simplify::simplify(&mesh, n);
    }
    let mut scene = hce_samples::room::room_with_mesh(&name, &mesh, turn);
    if furnace {
        hce_samples::room::furnace(&mut scene);
    }
    let bytes = hce_samples::glb::write_glb(&scene).context("cannot build the GLB")?;
    write_atomically(&out, &bytes)?;
    let simplified = match triangles {
        Some(_) => format!(", simplified from {input_triangles}"),
        None => String::new(),
    };
    println!(
        "{}: {} bytes, {} triangles, '{name}' {} triangles (multires{simplified}){}",
        out.display(),
        bytes.len(),
        scene.triangle_count(),
        mesh.triangles.len(),
        if furnace {
            ", a closed furnace (E 0.4, reflectance 0.5: 0.8 everywhere)"
        } else {
            ""
        }
    );
    Ok(())
}

fn main() -> std::process::ExitCode {
    match run() {
        Ok(()) => std::process::ExitCode::SUCCESS,
        Err(e) => {
            eprintln!("error: {e:#}");
            std::process::ExitCode::from(if e.is::<Usage>() { 2 } else { 1 })
        }
    }
}

fn run() -> Result<()> {
    let args: Vec<String> = std::env::args().skip(1).collect();
    if args.first().map(String::as_str) == Some("room") {
        return room(&args[1..]);
    }
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
