//! `hce view` in a real window: scripted runs under a virtual X server (`xvfb-run`) on the
//! software adapter, checked against `hce render` and for level changes along a camera path;
//! and its errors (no display, missing or bad file) as messages with their exit statuses.
//!
//! Without `xvfb-run` or a Vulkan adapter the window tests print why they skipped, unless
//! `HCE_REQUIRE_GPU=1` (CI), which makes that a failure. `.ci/run` installs `xvfb`.

use std::path::{Path, PathBuf};
use std::process::{Command, Output};
use std::sync::OnceLock;

use hce_runtime::gpu::testing::{try_context, Unavailable};

const W: u32 = 320;
const H: u32 = 240;
/// Close to the Teatime sample's own camera, looking at the table.
const CAMERA: &str = "0.35,1.08,0.85:-0.79,0.11,-1.88:40";

fn hce() -> Command {
    Command::new(env!("CARGO_BIN_EXE_hce"))
}

fn text(out: &Output) -> String {
    format!(
        "status {:?}\nstdout:\n{}\nstderr:\n{}",
        out.status,
        String::from_utf8_lossy(&out.stdout),
        String::from_utf8_lossy(&out.stderr)
    )
}

fn required() -> bool {
    std::env::var("HCE_REQUIRE_GPU").is_ok_and(|v| matches!(v.trim(), "1" | "true" | "yes"))
}

/// `xvfb-run` with a 24-bit screen larger than the windows, or `None` after printing why the
/// test skips (a failure under `HCE_REQUIRE_GPU=1`).
fn xvfb(test: &str) -> Option<Command> {
    match try_context(test) {
        Ok(_) => {}
        Err(Unavailable::Fail(m)) => panic!("{m}"),
        Err(Unavailable::Skip(_)) => return None,
    }
    let found = Command::new("xvfb-run").arg("--help").output().is_ok();
    if !found {
        let m = format!("{test}: xvfb-run is not installed (apt-get install xvfb)");
        assert!(!required(), "HCE_REQUIRE_GPU=1 but {m}");
        eprintln!("SKIPPED {m}");
        return None;
    }
    let mut cmd = Command::new("xvfb-run");
    cmd.args(["-a", "-s", "-screen 0 1280x1024x24"])
        .arg(env!("CARGO_BIN_EXE_hce"));
    Some(cmd)
}

/// The Teatime sample baked once for every test of this file.
fn baked() -> &'static Path {
    static BAKED: OnceLock<(tempfile::TempDir, PathBuf)> = OnceLock::new();
    &BAKED
        .get_or_init(|| {
            let dir = tempfile::tempdir().unwrap();
            let out = dir.path().join("teatime-baked.glb");
            let sample = Path::new(env!("CARGO_MANIFEST_DIR")).join("../samples/teatime.glb");
            let run = hce()
                .arg("bake")
                .arg(&sample)
                .arg("-o")
                .arg(&out)
                .args(["--creases", "auto"])
                .output()
                .unwrap();
            assert!(run.status.success(), "{}", text(&run));
            (dir, out)
        })
        .1
}

fn read_png(path: &Path) -> (u32, u32, Vec<u8>) {
    let file = std::fs::File::open(path).unwrap_or_else(|e| panic!("{}: {e}", path.display()));
    let mut reader = png::Decoder::new(std::io::BufReader::new(file))
        .read_info()
        .unwrap();
    let mut buf = vec![0; reader.output_buffer_size().unwrap()];
    let info = reader.next_frame(&mut buf).unwrap();
    assert_eq!(info.color_type, png::ColorType::Rgba, "{}", path.display());
    buf.truncate(info.buffer_size());
    (info.width, info.height, buf)
}

/// Mean absolute difference of the RGB channels (8-bit sRGB values), and the fraction of
/// pixels where some channel differs by more than `tolerance`.
fn difference(a: &[u8], b: &[u8], tolerance: u8) -> (f64, f64) {
    assert_eq!(a.len(), b.len());
    let mut sum = 0u64;
    let mut off = 0usize;
    for (p, q) in a.chunks_exact(4).zip(b.chunks_exact(4)) {
        let d: Vec<u8> = (0..3).map(|k| p[k].abs_diff(q[k])).collect();
        sum += d.iter().map(|&x| u64::from(x)).sum::<u64>();
        if d.iter().any(|&x| x > tolerance) {
            off += 1;
        }
    }
    let pixels = a.len() / 4;
    (sum as f64 / (3 * pixels) as f64, off as f64 / pixels as f64)
}

/// Mean luma of 8-bit RGBA pixels.
fn mean_luma(rgba: &[u8]) -> f64 {
    rgba.chunks_exact(4)
        .map(|p| 0.2126 * f64::from(p[0]) + 0.7152 * f64::from(p[1]) + 0.0722 * f64::from(p[2]))
        .sum::<f64>()
        / (rgba.len() / 4) as f64
}

/// A window screenshot equals `hce render` of the same file, camera, size and level (both
/// draw with the runtime's pipeline; the window tone-maps on the GPU, `hce render` on the
/// CPU). Metric: mean absolute difference of 8-bit sRGB channels at most 0.25, and at most
/// 0.1% of pixels with a channel more than 2 apart. Checked for a forced level, for levels
/// chosen from the view with another reconstruction, and for a plain mesh's flat preview.
#[test]
fn screenshot_matches_hce_render() {
    let Some(_) = xvfb("screenshot_matches_hce_render") else {
        return;
    };
    let plain = Path::new(env!("CARGO_MANIFEST_DIR")).join("../samples/teatime.glb");
    let dir = tempfile::tempdir().unwrap();
    let size = format!("{W}x{H}");
    for (name, file, extra) in [
        ("level2", baked(), &["--level", "2"][..]),
        (
            "auto-nearest",
            baked(),
            &["--reconstruction", "nearest"][..],
        ),
        // Not baked: previewed flat, as `hce render` previews it.
        ("plain", plain.as_path(), &["--level", "1"][..]),
    ] {
        let shot = dir.path().join(format!("{name}-view.png"));
        let still = dir.path().join(format!("{name}-render.png"));
        let out = xvfb("screenshot_matches_hce_render")
            .unwrap()
            .arg("view")
            .arg(file)
            .args([
                "--frames",
                "3",
                "--no-panel",
                "--size",
                &size,
                "--camera",
                CAMERA,
            ])
            .args(extra)
            .arg("--screenshot")
            .arg(&shot)
            .output()
            .unwrap();
        assert!(out.status.success(), "{}", text(&out));
        let stdout = String::from_utf8_lossy(&out.stdout);
        assert!(stdout.contains("adapter: "), "{}", text(&out));
        // One sample per pixel, as the window draws (hce render multisamples by default).
        let out = hce()
            .arg("render")
            .arg(file)
            .args(["--size", &size, "--camera", CAMERA, "--msaa", "1"])
            .args(extra)
            .arg("-o")
            .arg(&still)
            .output()
            .unwrap();
        assert!(out.status.success(), "{}", text(&out));
        let (w, h, a) = read_png(&shot);
        assert_eq!(
            (w, h),
            (W, H),
            "{name}: the screenshot has the window's size"
        );
        let (_, _, b) = read_png(&still);
        let luma = mean_luma(&b);
        assert!(luma > 20.0, "{name}: hce render drew a dark image ({luma})");
        let (mean, off) = difference(&a, &b, 2);
        eprintln!(
            "{name}: mean |difference| {mean:.4}, pixels off by > 2: {:.4}%",
            off * 100.0
        );
        assert!(
            mean <= 0.25 && off <= 0.001,
            "{name}: window and hce render differ: mean {mean}, {:.3}% of pixels",
            off * 100.0
        );
    }
}

#[derive(serde::Deserialize)]
struct Frame {
    levels: Vec<u32>,
    refined: Vec<String>,
    working: Vec<String>,
    pending: usize,
    triangles: u64,
}

#[derive(serde::Deserialize)]
struct Stats {
    software: bool,
    frames: Vec<Frame>,
    objects: Vec<Object>,
}

#[derive(serde::Deserialize)]
struct Object {
    name: String,
    kind: String,
    instances: usize,
    level: u32,
    triangles: u64,
}

/// Walking into the scene raises the levels: every frame is drawn, the levels change along the
/// way, and each frame refines exactly the objects whose level changed, and nothing in part.
#[test]
fn camera_path_changes_levels_and_draws_every_frame() {
    let Some(mut cmd) = xvfb("camera_path_changes_levels_and_draws_every_frame") else {
        return;
    };
    let dir = tempfile::tempdir().unwrap();
    let stats = dir.path().join("stats.json");
    let frames = 10;
    let out = cmd
        .arg("view")
        .arg(baked())
        .args([
            "--frames",
            &frames.to_string(),
            "--size",
            &format!("{W}x{H}"),
        ])
        .args([
            "--camera",
            "1.2,1.6,2.6:-0.6,0.7,-1.2:40",
            "--camera-path",
            "approach:0.8",
            // Every change refined whole in its frame, so that the levels follow the walk
            // within its ten frames however loaded the machine is (the budget's pieces are
            // checked by the next test, in frames rather than milliseconds).
            "--refine-budget",
            "0",
        ])
        .arg("--stats")
        .arg(&stats)
        .output()
        .unwrap();
    assert!(out.status.success(), "{}", text(&out));
    let s: Stats = serde_json::from_slice(&std::fs::read(&stats).unwrap()).unwrap();
    assert!(s.software, "CI draws on lavapipe");
    assert_eq!(s.frames.len(), frames, "{}", text(&out));
    let drawn: Vec<&str> = s
        .objects
        .iter()
        .filter(|o| o.instances > 0)
        .map(|o| o.name.as_str())
        .collect();
    for (i, f) in s.frames.iter().enumerate() {
        assert!(f.triangles > 0, "frame {i} drew nothing");
        assert_eq!(f.levels.len(), drawn.len());
        let changed: Vec<&str> = match i {
            0 => drawn.clone(),
            _ => drawn
                .iter()
                .zip(f.levels.iter().zip(&s.frames[i - 1].levels))
                .filter(|(_, (a, b))| a != b)
                .map(|(n, _)| *n)
                .collect(),
        };
        assert_eq!(
            f.refined, changed,
            "frame {i} refined other objects than changed level"
        );
        assert!(f.working.is_empty() && f.pending == 0, "frame {i}");
    }
    let first = &s.frames[0].levels;
    let raised = s
        .frames
        .iter()
        .any(|f| f.levels.iter().zip(first).any(|(l, l0)| l > l0));
    assert!(raised, "walking in raised no level:\n{}", text(&out));
    let changes = s
        .frames
        .windows(2)
        .filter(|w| w[0].levels != w[1].levels)
        .count();
    assert!(
        changes >= 2,
        "levels changed only {changes} times:\n{}",
        text(&out)
    );
}

/// A scripted run of `frames` frames along `path` with `budget` ms of refinement per frame:
/// its statistics and its last frame.
fn flight(path: &str, frames: usize, budget: &str, shot: &Path) -> (Stats, Vec<u8>) {
    let stats = shot.with_extension("json");
    let out = xvfb("flight")
        .unwrap()
        .arg("view")
        .arg(baked())
        .args(["--frames", &frames.to_string(), "--no-panel"])
        .args(["--size", &format!("{W}x{H}")])
        .args(["--camera-path", path, "--refine-budget", budget])
        .arg("--stats")
        .arg(&stats)
        .arg("--screenshot")
        .arg(shot)
        .output()
        .unwrap();
    assert!(out.status.success(), "{}", text(&out));
    let s: Stats = serde_json::from_slice(&std::fs::read(&stats).unwrap()).unwrap();
    assert_eq!(s.frames.len(), frames, "{}", text(&out));
    (s, read_png(shot).2)
}

/// A level change under a small refine budget is refined in pieces over several frames while
/// the object keeps drawing its old level: the triangles drawn are always those of whole
/// objects at the levels reported, a level changes only in the frame its refinement finishes,
/// and the run ends at the levels and with the image of the same path refined all at once.
#[test]
fn a_level_change_is_spread_over_frames_and_never_drawn_in_part() {
    let Some(_) = xvfb("a_level_change_is_spread_over_frames_and_never_drawn_in_part") else {
        return;
    };
    // Ten frames towards the teapot, then the camera holds still while the pieces land.
    let near = "-0.24,0.88,-0.44:-0.6,0.7,-1.2:40";
    let mut keys = vec!["1.2,1.6,2.6:-0.6,0.7,-1.2:40"];
    keys.extend([near; 12]);
    let path = keys.join(";");
    let frames = 130;
    let dir = tempfile::tempdir().unwrap();
    let (whole, whole_png) = flight(&path, frames, "0", &dir.path().join("whole.png"));
    let (pieces, pieces_png) = flight(&path, frames, "0.01", &dir.path().join("pieces.png"));
    let drawn: Vec<&Object> = pieces.objects.iter().filter(|o| o.instances > 0).collect();
    // Coarse triangles per object, from the last frame's level and fine triangles; a flat
    // object is drawn from its trees (SPEC.md F.7.1), the same triangles at every level.
    let coarse: Vec<u64> = drawn.iter().map(|o| o.triangles >> (2 * o.level)).collect();
    let at = |k: usize, level: u32| match drawn[k].kind.as_str() {
        "flat" => drawn[k].triangles,
        _ => coarse[k] << (2 * level),
    };
    assert!(whole.frames.iter().all(|f| f.working.is_empty()));
    let mut spread = Vec::new();
    for (i, f) in pieces.frames.iter().enumerate() {
        // Whole objects only: the triangles drawn are those of the levels reported.
        let expected: u64 = (0..drawn.len())
            .map(|k| at(k, f.levels[k]) * drawn[k].instances as u64)
            .sum();
        assert_eq!(f.triangles, expected, "frame {i} drew part of an object");
        if i > 0 {
            let prev = &pieces.frames[i - 1];
            for (k, o) in drawn.iter().enumerate() {
                let changed = f.levels[k] != prev.levels[k];
                assert_eq!(
                    changed,
                    f.refined.contains(&o.name),
                    "frame {i}, {}: a level changes exactly when its refinement finishes",
                    o.name
                );
                // Pieces in earlier frames, then the refinement finished here.
                if changed && prev.working.contains(&o.name) {
                    spread.push((i, o.name.clone()));
                }
            }
        }
        assert!(
            f.refined.iter().all(|n| !f.working.contains(n)),
            "frame {i}: an object both finished and in part"
        );
    }
    assert!(
        !spread.is_empty(),
        "no level change was spread over frames with a budget of 0.01 ms"
    );
    eprintln!("level changes finished after pieces in earlier frames: {spread:?}");
    let (last, last_whole) = (pieces.frames.last().unwrap(), whole.frames.last().unwrap());
    assert_eq!(last.pending, 0, "the refinements did not all land");
    assert_eq!(last.levels, last_whole.levels);
    assert!(
        last.levels
            .iter()
            .zip(&pieces.frames[0].levels)
            .any(|(a, b)| a > b),
        "the path raised no level"
    );
    let (mean, off) = difference(&pieces_png, &whole_png, 0);
    assert_eq!(
        (mean, off),
        (0.0, 0.0),
        "the last frames of the two runs differ"
    );
}

/// `--offscreen` draws the same frames without a window or a display: along a camera path
/// that changes levels, every frame's levels and refined objects are those of the windowed run,
/// and its last frame is the very pixels of the window's (both on lavapipe, no panel).
#[test]
fn offscreen_runs_draw_what_the_window_draws() {
    let Some(window) = xvfb("offscreen_runs_draw_what_the_window_draws") else {
        return;
    };
    let dir = tempfile::tempdir().unwrap();
    let path = "1.2,1.6,2.6:-0.6,0.7,-1.2:40;-0.24,0.88,-0.44:-0.6,0.7,-1.2:40";
    let run = |mut cmd: Command, name: &str, extra: &[&str]| {
        let shot = dir.path().join(format!("{name}.png"));
        let stats = dir.path().join(format!("{name}.json"));
        let out = cmd
            .arg("view")
            .arg(baked())
            .args(["--frames", "8", "--no-panel", "--size", &format!("{W}x{H}")])
            .args(["--camera-path", path, "--refine-budget", "0"])
            .args(extra)
            .arg("--stats")
            .arg(&stats)
            .arg("--screenshot")
            .arg(&shot)
            .output()
            .unwrap();
        assert!(out.status.success(), "{}", text(&out));
        let s: Stats = serde_json::from_slice(&std::fs::read(&stats).unwrap()).unwrap();
        (s, read_png(&shot), text(&out))
    };
    let (windowed, windowed_png, _) = run(window, "window", &[]);
    let mut offscreen = hce();
    // No display at all.
    offscreen
        .env_remove("DISPLAY")
        .env_remove("WAYLAND_DISPLAY");
    let (off, off_png, log) = run(offscreen, "offscreen", &["--offscreen"]);
    assert_eq!(off.frames.len(), 8, "{log}");
    let levels = |s: &Stats| -> Vec<(Vec<u32>, Vec<String>)> {
        s.frames
            .iter()
            .map(|f| (f.levels.clone(), f.refined.clone()))
            .collect()
    };
    assert_eq!(levels(&off), levels(&windowed), "{log}");
    assert!(
        off.frames.windows(2).any(|w| w[0].levels != w[1].levels),
        "the path changed no level:\n{log}"
    );
    assert_eq!((off_png.0, off_png.1), (W, H));
    assert!(
        off_png.2 == windowed_png.2,
        "the offscreen frame differs from the window's: {:?}",
        difference(&off_png.2, &windowed_png.2, 0)
    );
}

/// A missing file and a bad file are reported with their exit statuses (4, 3) before any
/// window opens; no display is status 1 with what to do. None of them panics.
#[test]
fn errors_are_messages_with_their_exit_status() {
    let dir = tempfile::tempdir().unwrap();
    let missing = dir.path().join("missing.glb");
    let bad = dir.path().join("bad.glb");
    std::fs::write(&bad, b"glTF not really").unwrap();
    let check = |out: Output, status: i32, needle: &str| {
        let all = text(&out);
        assert_eq!(out.status.code(), Some(status), "{all}");
        assert!(all.contains(needle), "expected {needle:?} in\n{all}");
        assert!(!all.contains("panicked"), "{all}");
    };
    for (file, status, needle) in [(&missing, 4, "missing.glb"), (&bad, 3, "bad.glb")] {
        let out = hce().arg("view").arg(file).output().unwrap();
        check(out, status, needle);
    }
    let out = hce()
        .arg("view")
        .arg(baked())
        .args(["--frames", "1"])
        .env_remove("DISPLAY")
        .env_remove("WAYLAND_DISPLAY")
        .env_remove("WAYLAND_SOCKET")
        .output()
        .unwrap();
    check(out, 1, "needs a display");
}

/// Without a Vulkan driver the window opens but no adapter can draw into it: status 1 and what
/// to install, no panic.
#[test]
fn no_adapter_is_a_message() {
    let Some(mut cmd) = xvfb("no_adapter_is_a_message") else {
        return;
    };
    let missing = "/nonexistent/hce-no-icd.json";
    let out = cmd
        .arg("view")
        .arg(baked())
        .args(["--frames", "1", "--size", "64x48"])
        .env("VK_ICD_FILENAMES", missing)
        .env("VK_DRIVER_FILES", missing)
        .output()
        .unwrap();
    let all = text(&out);
    assert_eq!(out.status.code(), Some(1), "{all}");
    assert!(all.contains("mesa-vulkan-drivers"), "{all}");
    assert!(!all.contains("panicked"), "{all}");
}
