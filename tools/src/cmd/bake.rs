//! `hce bake`: import a glTF or OBJ scene, choose normal sets, solve enriched hierarchical
//! radiosity and write the baked `.glb`/`.gltf` (extension + `COLOR_0` fallback) or the `.hce`
//! container alone. The work is `hce_bake::bake_file`; this module parses flags,
//! draws progress bars and prints the summary. `--print-inputs` and `--print-key` print the
//! bake's cache key (`hce_bake::cache_key`) and what it was made of without baking; `--report`
//! writes what a build system needs to know of a bake, failed or not, as JSON.

use std::io::IsTerminal;
use std::path::{Path, PathBuf};
use std::sync::Mutex;
use std::time::Instant;

use anyhow::{Context, Result};
use clap::Args;
use hce_bake::NormalSetParams;
use hce_bake::{bake_file, BakeOutcome, PipelineOptions};
use hce_bake::{cache_key, CacheKey, KEY_FORMAT};
use hce_format::ObjectKind;
use hce_geometry::Creases;
use hce_meshio::scene::ImportOptions;
use indicatif::{ProgressBar, ProgressStyle};

mod quality;
pub use quality::Quality;

#[derive(Args)]
pub struct BakeArgs {
    /// Input scene (.gltf, .glb or .obj with its .mtl).
    pub input: PathBuf,
    /// Output: .glb or .gltf (scene + extension + COLOR_0) or .hce (container alone); written
    /// atomically.
    #[arg(long, short = 'o')]
    pub output: PathBuf,
    /// Make objects whose node or mesh name matches PATTERN (`*`, `?`) multiresolution;
    /// repeatable; `all` selects every object. Node extras `{"hce": {"multires": true}}` also do.
    #[arg(long, value_name = "PATTERN")]
    pub multires: Vec<String>,
    /// Deepest Loop subdivision level the normal sets serve (0..=6): the finest level a
    /// renderer will draw.
    #[arg(long, default_value_t = 3, value_parser = level_parser())]
    pub max_level: u32,
    /// The old spelling of `--max-level`, accepted with a warning.
    #[arg(long = "levels", hide = true, conflicts_with = "max_level", value_parser = level_parser())]
    pub levels_old: Option<u32>,
    /// Most normals per coarse triangle besides its geometric normal (0..=63).
    #[arg(long, default_value_t = NormalSetParams::default().max_normals, value_parser = max_normals_parser())]
    pub max_normals: usize,
    /// Target angle (degrees) between any subtriangle normal and its representative.
    #[arg(long, default_value_t = NormalSetParams::default().normal_tolerance_deg, value_parser = non_negative_degrees)]
    pub normal_tolerance: f32,
    /// Sharp creases of multiresolution objects: none, auto (split input normals) or angle=DEG.
    #[arg(long, default_value = "none")]
    pub creases: Creases,
    /// Named solver settings, each a point measured on the error/time curve of the Cornell
    /// box against Blender Cycles (tools/scripts/cycles-curve.sh, BENCHMARKS.md). Any of
    /// --bf-epsilon, --detail-level and --visibility-rays given explicitly overrides the
    /// preset's value.
    #[arg(long, value_enum, default_value = "default")]
    pub quality: Quality,
    /// Link refinement threshold (fraction of the scene's reference power) [default: from
    /// --quality; 1e-4 at default].
    #[arg(long)]
    pub bf_epsilon: Option<f32>,
    /// Jittered visibility rays per link (0 disables occlusion); links that bring much of
    /// their receiver's light take up to 4x as many [default: from --quality; 8 at default].
    #[arg(long)]
    pub visibility_rays: Option<u32>,
    /// Deepest element level below a coarse triangle that shadow edges and contacts are
    /// refined to (the power rule stops at level 4); each level halves the finest shadow
    /// detail, for more elements where shadows fall [default: from --quality; 7 at default].
    #[arg(long)]
    pub detail_level: Option<u32>,
    /// Store only the elements' means, not their colours at the corners too (SPEC.md A.10):
    /// files about 3.5 times smaller, drawn with more error where the light changes fast (the
    /// Cornell box against Cycles: 1.84% instead of 1.18%).
    #[arg(long)]
    pub no_corner_colours: bool,
    /// Worker threads (default: all cores). The output is the same whatever the count.
    #[arg(long, value_parser = thread_count_parser())]
    pub threads: Option<usize>,
    /// No progress bars and no summary.
    #[arg(long, short = 'q')]
    pub quiet: bool,
    /// Print the bake's cache key and do not bake: the SHA-256 of a canonical document of the
    /// key format, the hce version, each input file's name within the asset and SHA-256, and
    /// every parameter that can change the output with its defaults filled in (the output
    /// format from -o included; not --threads, not any path). Equal keys, equal bytes.
    #[arg(long)]
    pub print_key: bool,
    /// Print the key's inputs as JSON (files with their paths and hashes, canonical
    /// parameters, the key document and the key) and do not bake.
    #[arg(long)]
    pub print_inputs: bool,
    /// Write a JSON report of the bake to FILE (atomically, also when the bake fails): its
    /// inputs, parameters and key, timings, counts, warnings, and its exit status and error
    /// message.
    #[arg(long, value_name = "FILE")]
    pub report: Option<PathBuf>,
}

/// A subdivision level, 0 to [`hce_geometry::subdivide::MAX_LOOP_LEVEL`].
pub fn level_parser() -> clap::builder::RangedU64ValueParser<u32> {
    clap::builder::RangedU64ValueParser::new()
        .range(0..=hce_geometry::subdivide::MAX_LOOP_LEVEL as u64)
}

/// A worker-thread count, at least 1.
pub fn thread_count_parser() -> clap::builder::RangedU64ValueParser<usize> {
    clap::builder::RangedU64ValueParser::new().range(1..)
}

/// Normals per coarse triangle besides the geometric one: at most
/// `MAX_NORMALS_PER_TRIANGLE - 1`.
fn max_normals_parser() -> clap::builder::RangedU64ValueParser<usize> {
    clap::builder::RangedU64ValueParser::new().range(0..hce_bake::MAX_NORMALS_PER_TRIANGLE as u64)
}

/// A finite, non-negative angle in degrees.
fn non_negative_degrees(s: &str) -> Result<f32, String> {
    match s.parse::<f32>() {
        Ok(v) if v.is_finite() && v >= 0.0 => Ok(v),
        _ => Err(format!("{s:?} is not a non-negative number of degrees")),
    }
}

pub fn run(args: BakeArgs) -> Result<()> {
    let options = pipeline_options(&args);
    if args.print_inputs || args.print_key {
        let key = cache_key(&args.input, &options)
            .with_context(|| format!("reading {}", args.input.display()))?;
        if args.print_inputs {
            let mut v = inputs_json(&key);
            v["document"] = serde_json::json!(key.document);
            v["key"] = serde_json::json!(key.key);
            println!("{}", serde_json::to_string_pretty(&v)?);
        }
        if args.print_key {
            println!("{}", key.key);
        }
        return Ok(());
    }
    let Some(report_path) = args.report.clone() else {
        return bake(&args, &options).map(|_| ());
    };
    let started = Instant::now();
    // The key of what is about to be baked, read before the bake reads the same files.
    let key = cache_key(&args.input, &options);
    let key_seconds = started.elapsed().as_secs_f64();
    let outcome = bake(&args, &options);
    let report = Report {
        args: &args,
        key: key.as_ref().ok(),
        key_seconds,
        total_seconds: started.elapsed().as_secs_f64(),
        outcome: outcome.as_ref(),
    };
    let written = hce_meshio::write_atomic(&report_path, report.to_json().as_bytes());
    match (outcome, written) {
        (Ok(_), written) => Ok(written?),
        (Err(e), Ok(())) => Err(e),
        (Err(e), Err(w)) => {
            // The bake's own error decides the status; the lost report is said beside it.
            eprintln!("warning: {}", crate::exit::message(&w.into()));
            Err(e)
        }
    }
}

/// The pipeline's options from the command line.
fn pipeline_options(args: &BakeArgs) -> PipelineOptions {
    PipelineOptions {
        import: ImportOptions {
            multires: args.multires.clone(),
        },
        levels: crate::cmd::renamed_flag(args.levels_old, "--levels", "--max-level")
            .unwrap_or(args.max_level),
        normal_sets: NormalSetParams {
            max_normals: args.max_normals,
            normal_tolerance_deg: args.normal_tolerance,
        },
        creases: args.creases,
        bake: hce_bake::BakeParams {
            corner_colours: !args.no_corner_colours,
            ..args
                .quality
                .params(args.bf_epsilon, args.detail_level, args.visibility_rays)
        },
        output: args.output.clone(),
    }
}

/// Bakes with progress bars and prints the summary.
fn bake(args: &BakeArgs, options: &PipelineOptions) -> Result<BakeOutcome> {
    let show = !args.quiet && std::io::stderr().is_terminal();
    let bars = Bars {
        enabled: show,
        current: Mutex::new(None),
    };
    let progress = |phase: &str, done: usize, total: usize| bars.update(phase, done, total);
    let mut builder = rayon::ThreadPoolBuilder::new();
    if let Some(n) = args.threads {
        builder = builder.num_threads(n);
    }
    let pool = builder.build().context("cannot start the worker threads")?;
    let outcome = pool.install(|| bake_file(&args.input, options, &progress));
    bars.finish();
    let outcome = outcome.with_context(|| format!("baking {}", args.input.display()))?;
    if !args.quiet {
        print_summary(&outcome, args);
    }
    Ok(outcome)
}

/// The inputs and parameters of a key, as `--print-inputs` and `--report` give them.
fn inputs_json(key: &CacheKey) -> serde_json::Value {
    let inputs: Vec<serde_json::Value> = key
        .inputs
        .iter()
        .map(|i| {
            serde_json::json!({
                "name": i.file.name,
                "path": path_text(&i.file.path),
                "sha256": i.sha256,
                "bytes": i.bytes,
            })
        })
        .collect();
    serde_json::json!({
        "key_format": KEY_FORMAT,
        "inputs": inputs,
        "parameters": key.parameters,
    })
}

fn path_text(p: &Path) -> String {
    p.to_string_lossy().into_owned()
}

/// What `--report` writes.
struct Report<'a> {
    args: &'a BakeArgs,
    /// `None` when the key could not be computed (the bake then fails with the reason).
    key: Option<&'a CacheKey>,
    key_seconds: f64,
    total_seconds: f64,
    outcome: Result<&'a BakeOutcome, &'a anyhow::Error>,
}

impl Report<'_> {
    fn to_json(&self) -> String {
        use serde_json::json;
        let mut v = match self.key {
            Some(k) => inputs_json(k),
            None => json!({ "key_format": KEY_FORMAT, "inputs": [], "parameters": {} }),
        };
        v["report_format"] = json!(1);
        v["hce"] = json!(env!("CARGO_PKG_VERSION"));
        v["input"] = json!(path_text(&self.args.input));
        v["output"] = json!(path_text(&self.args.output));
        v["key"] = json!(self.key.map(|k| &k.key));
        v["threads"] = json!(self.args.threads.unwrap_or_else(rayon::current_num_threads));
        let mut phases = vec![json!({ "phase": "key", "seconds": self.key_seconds })];
        match self.outcome {
            Ok(o) => {
                phases.extend(
                    o.phase_seconds
                        .iter()
                        .map(|(p, s)| json!({ "phase": p, "seconds": s })),
                );
                let multires = o
                    .objects
                    .iter()
                    .filter(|s| s.kind == ObjectKind::Multiresolution)
                    .count();
                v["status"] = json!(0);
                v["error"] = json!(null);
                v["warnings"] = json!(o.warnings);
                v["counts"] = json!({
                    "objects": o.objects.len(),
                    "multiresolution_objects": multires,
                    "coarse_triangles": o.coarse_triangles,
                    "elements": o.elements,
                    "links": o.links,
                    "iterations": o.iterations,
                    "output_bytes": o.output_bytes,
                });
            }
            Err(e) => {
                v["status"] = json!(crate::exit::classify(e) as u8);
                v["error"] = json!(crate::exit::message(e));
                v["warnings"] = json!([]);
                v["counts"] = json!(null);
            }
        }
        v["timings"] = json!({ "phases": phases, "total_seconds": self.total_seconds });
        let mut text = serde_json::to_string_pretty(&v).unwrap_or_else(|_| "{}".into());
        text.push('\n');
        text
    }
}

/// One progress bar per phase, replaced when the phase changes.
struct Bars {
    enabled: bool,
    current: Mutex<Option<(String, ProgressBar)>>,
}

impl Bars {
    fn update(&self, phase: &str, done: usize, total: usize) {
        if !self.enabled {
            return;
        }
        let Ok(mut cur) = self.current.lock() else {
            return;
        };
        if cur.as_ref().is_none_or(|(p, _)| p != phase) {
            if let Some((_, bar)) = cur.take() {
                bar.finish();
            }
            let bar = ProgressBar::new(total as u64);
            // A solve's total is its iteration cap, which it mostly stops short of: no time
            // estimate there. The other phases count coarse triangles, whose cost is even
            // enough for one.
            let template = if phase.starts_with("solve") {
                "{prefix:>26} [{bar:30}] {pos}/{len} {elapsed}"
            } else {
                "{prefix:>26} [{bar:30}] {pos}/{len} {elapsed} (eta {eta})"
            };
            if let Ok(style) = ProgressStyle::with_template(template) {
                bar.set_style(style.progress_chars("=> "));
            }
            bar.set_prefix(phase.to_string());
            *cur = Some((phase.to_string(), bar));
        }
        if let Some((_, bar)) = cur.as_ref() {
            bar.set_length(total as u64);
            bar.set_position(done as u64);
        }
    }

    fn finish(&self) {
        if let Ok(mut cur) = self.current.lock() {
            if let Some((_, bar)) = cur.take() {
                bar.finish();
            }
        }
    }
}

fn print_summary(o: &BakeOutcome, args: &BakeArgs) {
    for w in &o.warnings {
        eprintln!("warning: {w}");
    }
    println!("{}", o.import_summary.trim_end());
    let multires = o
        .objects
        .iter()
        .filter(|s| s.kind == ObjectKind::Multiresolution)
        .count();
    println!(
        "objects: {} ({multires} multiresolution, {} flat)",
        o.objects.len(),
        o.objects.len() - multires
    );
    for s in &o.objects {
        let kind = match s.kind {
            ObjectKind::Multiresolution => "multires",
            ObjectKind::Flat => "flat",
        };
        let mut line = format!(
            "  {:<24} {kind:<8} {:>7} triangles {:>7} control vertices",
            s.name, s.triangles, s.control_vertices
        );
        if s.kind == ObjectKind::Multiresolution {
            line += &format!(
                ", normals {}, worst {:.1} deg",
                histogram(&s.normal_histogram),
                s.worst_angle_deg
            );
        }
        println!("{line}");
    }
    println!("coarse triangles: {}", o.coarse_triangles);
    println!("elements: {}", o.elements);
    println!("links: {}", o.links);
    println!("iterations: {}", o.iterations);
    if multires > 0 {
        println!(
            "normals per triangle: {} (worst remaining angle {:.1} deg)",
            histogram(&o.normal_histogram),
            o.worst_angle_deg
        );
    }
    println!("COLOR_0 exposure: {:.4}", o.exposure);
    print!("time:");
    let mut total = 0.0;
    for (phase, s) in &o.phase_seconds {
        print!(" {phase} {s:.2}s,");
        total += s;
    }
    println!(" total {total:.2}s");
    println!(
        "output: {} ({} bytes)",
        args.output.display(),
        o.output_bytes
    );
}

/// `k:count` pairs for the non-empty bins.
fn histogram(h: &[usize]) -> String {
    let parts: Vec<String> = h
        .iter()
        .enumerate()
        .filter(|(_, &c)| c > 0)
        .map(|(k, c)| format!("{k}:{c}"))
        .collect();
    if parts.is_empty() {
        "-".into()
    } else {
        parts.join(" ")
    }
}
