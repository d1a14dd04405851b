//! `hce demo` end to end, as a new user runs it: the files it promises exist and are right.
//!
//! With a GPU adapter (lavapipe is enough) the demo must bake, render and write every image;
//! without one the test says it skipped the rendering checks, unless `HCE_REQUIRE_GPU=1`, which
//! makes that a failure (CI). Either way the no-adapter path is checked by hiding the Vulkan
//! drivers from the loader: the demo must still write the baked file, name the package to
//! install and exit non-zero.

mod common;

use std::path::Path;
use std::process::Output;

use hce_runtime::gpu::testing::{try_context, Unavailable};

/// Panel size of `--size small`.
const W: u32 = 240;
const H: u32 = 180;

fn demo(dir: &Path, env: &[(&str, &str)]) -> Output {
    let mut cmd = common::command();
    cmd.args(["demo", "--size", "small", "-o"]).arg(dir);
    for (k, v) in env {
        cmd.env(k, v);
    }
    cmd.output().unwrap()
}

fn text(out: &Output) -> String {
    format!(
        "status {:?}\nstdout:\n{}\nstderr:\n{}",
        out.status,
        String::from_utf8_lossy(&out.stdout),
        String::from_utf8_lossy(&out.stderr)
    )
}

/// Decodes an 8-bit RGBA PNG: (width, height, pixels).
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

/// Mean and variance of the luma of 8-bit RGBA pixels.
fn luma_stats(rgba: &[u8]) -> (f64, f64) {
    let l: Vec<f64> = rgba
        .chunks_exact(4)
        .map(|p| 0.2126 * f64::from(p[0]) + 0.7152 * f64::from(p[1]) + 0.0722 * f64::from(p[2]))
        .collect();
    let mean = l.iter().sum::<f64>() / l.len() as f64;
    let var = l.iter().map(|x| (x - mean).powi(2)).sum::<f64>() / l.len() as f64;
    (mean, var)
}

/// The baked file holds a container that passes hce-format's deep validation and links every
/// multiresolution object of the sample.
fn check_baked(path: &Path) {
    let bytes = std::fs::read(path).unwrap();
    let asset = hce_format::GltfAsset::from_glb(&bytes).unwrap();
    let buffers = asset
        .buffers(|uri| Err(format!("unexpected external buffer {uri}")))
        .unwrap();
    let container = hce_format::container_bytes(&asset.json, &buffers)
        .unwrap()
        .expect("the baked file has no EXT_hce_baked_lighting container");
    let problems = hce_format::validate_bytes(container);
    assert!(problems.is_empty(), "{problems:?}");
    let c = hce_format::read(container).unwrap();
    let multires: Vec<&str> = c
        .objects
        .iter()
        .filter(|o| o.kind == hce_format::ObjectKind::Multiresolution)
        .map(|o| o.name.as_str())
        .collect();
    for name in ["teapot", "cup", "spoon"] {
        assert!(
            multires.iter().any(|m| m.contains(name)),
            "{name} is not multiresolution: {multires:?}"
        );
    }
}

#[test]
fn demo_bakes_and_renders_levels_side_by_side() {
    let ctx = match try_context("demo_bakes_and_renders_levels_side_by_side") {
        Ok(ctx) => ctx,
        Err(Unavailable::Skip(_)) => return,
        Err(Unavailable::Fail(m)) => panic!("{m}"),
    };
    // The demo opens its own context; this one only proved that an adapter exists.
    drop(ctx);
    let dir = tempfile::tempdir().unwrap();
    let out = demo(dir.path(), &[]);
    let log = text(&out);
    assert!(out.status.success(), "{log}");
    let stdout = String::from_utf8_lossy(&out.stdout);
    assert!(stdout.contains("teatime-levels.png"), "{log}");
    // Every step reports its time.
    assert!(stdout.contains(" s  baked: "), "{log}");

    let p = |name: &str| dir.path().join(name);
    assert_eq!(
        std::fs::read(p("teatime.glb")).unwrap(),
        hce_samples::embedded::TEATIME_GLB,
        "the sample copy differs from the embedded sample"
    );
    check_baked(&p("teatime-baked.glb"));

    let mut levels = Vec::new();
    for level in 0..=3 {
        let (w, h, px) = read_png(&p(&format!("teatime-level{level}.png")));
        assert_eq!((w, h), (W, H), "level {level}");
        let (mean, var) = luma_stats(&px);
        // A lit room: neither black nor white, and with structure (walls, table, objects).
        assert!(
            mean > 20.0 && mean < 235.0,
            "level {level}: mean luma {mean}"
        );
        assert!(
            var > 100.0,
            "level {level}: luma variance {var}: a blank image"
        );
        levels.push(px);
    }
    // Subdivision changes the silhouettes and colours of the three objects.
    let diff = |a: &[u8], b: &[u8]| -> f64 {
        a.iter()
            .zip(b)
            .map(|(x, y)| f64::from(x.abs_diff(*y)))
            .sum::<f64>()
            / a.len() as f64
    };
    for l in 1..=3 {
        let d = diff(&levels[0], &levels[l]);
        assert!(
            d > 0.05,
            "level {l} looks like level 0 (mean difference {d})"
        );
    }

    let (w, h, sheet) = read_png(&p("teatime-levels.png"));
    assert_eq!((w, h), (4 * W + 3 * 4, H));
    // The last panel of the sheet is the level 3 image, outside its label.
    let row = |img: &[u8], width: u32, x0: u32, y: u32| {
        let s = 4 * (y * width + x0) as usize;
        img[s..s + 4 * W as usize].to_vec()
    };
    for y in [H / 2, H - 1] {
        assert_eq!(
            row(&sheet, w, 3 * (W + 4), y),
            row(&levels[3], W, 0, y),
            "row {y}"
        );
    }

    let exr = exr::prelude::read_first_rgba_layer_from_file(
        p("teatime-level3.exr"),
        |size, _| (size.width(), size.height(), Vec::new()),
        |img: &mut (usize, usize, Vec<[f32; 4]>), _pos, (r, g, b, a): (f32, f32, f32, f32)| {
            img.2.push([r, g, b, a])
        },
    )
    .unwrap();
    let (ew, eh, pixels) = exr.layer_data.channel_data.pixels;
    assert_eq!((ew, eh), (W as usize, H as usize));
    assert!(pixels.iter().flatten().all(|v| v.is_finite() && *v >= 0.0));
    let max = pixels
        .iter()
        .map(|p| p[0].max(p[1]).max(p[2]))
        .fold(0.0, f32::max);
    assert!(max > 0.01, "the linear image is black (max {max})");

    // Atomic writes leave no temporary files behind.
    let mut names: Vec<String> = std::fs::read_dir(dir.path())
        .unwrap()
        .map(|e| e.unwrap().file_name().to_string_lossy().into_owned())
        .collect();
    names.sort();
    assert_eq!(
        names,
        [
            "teatime-baked.glb",
            "teatime-level0.png",
            "teatime-level1.png",
            "teatime-level2.png",
            "teatime-level3.exr",
            "teatime-level3.png",
            "teatime-levels.png",
            "teatime.glb",
        ]
    );
}

#[test]
fn demo_without_an_adapter_still_bakes_and_says_what_to_install() {
    let dir = tempfile::tempdir().unwrap();
    // Point the Vulkan loader at a driver list that does not exist: no adapter at all.
    let missing = dir.path().join("no-such-icd.json");
    let missing = missing.to_str().unwrap();
    let out = demo(
        dir.path(),
        &[("VK_ICD_FILENAMES", missing), ("VK_DRIVER_FILES", missing)],
    );
    let log = text(&out);
    assert!(!out.status.success(), "{log}");
    let stderr = String::from_utf8_lossy(&out.stderr);
    assert!(
        stderr.contains("sudo apt-get install mesa-vulkan-drivers"),
        "{log}"
    );
    check_baked(&dir.path().join("teatime-baked.glb"));
    assert!(
        !dir.path().join("teatime-levels.png").exists(),
        "an image was written without an adapter"
    );
}
