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
//! `--mesh` may be given several times, each followed by its own `--triangles`: the meshes
//! then stand in a row ([`hce_samples::room::room_with_meshes`]), each named by its file.
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

/// `room --mesh PATH [--triangles N] [--mesh PATH [--triangles N] ...] -o OUT.glb [--name NAME]
/// [--turn DEG] [--furnace]`.
fn room(args: &[String]) -> Result<()> {
    let usage = "usage: gen-samples room --mesh MESH.obj [--triangles N] [--mesh MESH.obj \
                 [--triangles N] ...] -o ROOM.glb [--name NAME] [--turn DEG] [--furnace]";
    // Each mesh with the triangle count it is simplified to, if one.
    let mut meshes: Vec<(PathBuf, Option<usize>)> = Vec::new();
    let (mut out, mut name, mut turn) = (None, None, 0.0);
    // A `--triangles` given before any `--mesh` (one mesh only, as the single-mesh room always
    // took it in any order).
    let mut early_triangles: Option<usize> = None;
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
            "--mesh" => meshes.push((PathBuf::from(value?), None)),
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
                let n = value?
                    .parse::<usize>()
                    .ok()
                    .filter(|&n| n >= 4)
                    .ok_or_else(|| {
                        usage_error(format!("--triangles takes a count of 4 or more; {usage}"))
                    })?;
                match meshes.last_mut() {
                    Some(m) if m.1.is_none() => m.1 = Some(n),
                    Some(_) => {
                        return Err(usage_error(format!(
                            "--triangles given twice for one --mesh; {usage}"
                        )))
                    }
                    None => early_triangles = Some(n),
                }
            }
            _ => return Err(usage_error(format!("unknown argument {a:?}; {usage}"))),
        }
    }
    let Some(out) = out else {
        return Err(usage_error(usage.to_string()));
    };
    if meshes.is_empty() {
        return Err(usage_error(usage.to_string()));
    }
    if let Some(n) = early_triangles {
        match meshes.as_mut_slice() {
            [(_, t @ None)] => *t = Some(n),
            _ => {
                return Err(usage_error(format!(
                    "with several meshes, --triangles follows the --mesh it is for; {usage}"
                )))
            }
        }
    }
    if name.is_some() && meshes.len() > 1 {
        return Err(usage_error(format!(
            "--name names the one mesh; with several, each is named by its file; {usage}"
        )));
    }
    let mut loaded = Vec::new();
    let mut described = Vec::new();
    for (i, (path, triangles)) in meshes.iter().enumerate() {
        let stem = path
            .file_stem()
            .map_or("mesh".into(), |s| s.to_string_lossy().into_owned());
        // Two copies of one file are two objects, named apart.
        let mut object = name.clone().unwrap_or(stem);
        if meshes[..i]
            .iter()
            .any(|(p, _)| p.file_stem() == path.file_stem())
        {
            object = format!("{object}-{i}");
        }
        let text = std::fs::read_to_string(path)
            .with_context(|| format!("{}: cannot read", path.display()))?;
        let mut mesh = hce_samples::room::parse_obj(&text)
            .with_context(|| format!("{}: not a usable OBJ", path.display()))?;
        let input_triangles = mesh.triangles.len();
        if let Some(n) = *triangles {
            mesh = hce_samples::simplify::simplify(&mesh, n);
        }
        let simplified = match triangles {
            Some(_) => format!(", simplified from {input_triangles}"),
            None => String::new(),
        };
        described.push(format!(
            "'{object}' {} triangles (multires{simplified})",
            mesh.triangles.len()
        ));
        loaded.push((object, mesh));
    }
    let mut scene = match loaded.as_slice() {
        [(object, mesh)] => hce_samples::room::room_with_mesh(object, mesh, turn),
        _ => {
            let refs: Vec<(&str, &hce_samples::mesh::Mesh)> =
                loaded.iter().map(|(n, m)| (n.as_str(), m)).collect();
            hce_samples::room::room_with_meshes(&refs, turn)
        }
    };
    if furnace {
        hce_samples::room::furnace(&mut scene);
    }
    let bytes = hce_samples::glb::write_glb(&scene).context("cannot build the GLB")?;
    write_atomically(&out, &bytes)?;
    println!(
        "{}: {} bytes, {} triangles, {}{}",
        out.display(),
        bytes.len(),
        scene.triangle_count(),
        described.join(", "),
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

/// What `--help` prints.
const USAGE: &str = "\
usage: gen-samples [OUT_DIR]
       gen-samples room --mesh MESH.obj [--triangles N] [--mesh ...] -o ROOM.glb [--name NAME]
                        [--turn DEG] [--furnace]

Writes teatime.glb, chesstime.glb and cornell-box.glb into OUT_DIR (default: samples/ of the
repository), or with `room` a closed lit test room around one or more meshes.";

fn run() -> Result<()> {
    let args: Vec<String> = std::env::args().skip(1).collect();
    if args.first().map(String::as_str) == Some("room") {
        return room(&args[1..]);
    }
    match args.first().map(String::as_str) {
        Some("-h" | "--help") => {
            println!("{USAGE}");
            return Ok(());
        }
        // An option is never a folder name: a mistyped flag must not write the samples into it.
        Some(a) if a.starts_with('-') => {
            return Err(usage_error(format!("unknown option {a}\n\n{USAGE}")));
        }
        _ => {}
    }
    if args.len() > 1 {
        return Err(usage_error(format!(
            "one output folder at most, got {}\n\n{USAGE}",
            args.len()
        )));
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
