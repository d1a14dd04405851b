//! `hce demo`: the whole toolchain on a bundled sample in one command, for a first look.
//!
//! It writes the sample (embedded in the binary, so it works from any directory), bakes it with
//! [`hce_bake::bake_file`], validates the result as `hce validate` does, then draws it
//! with its baked colours at levels 0 to 3 ([`hce_runtime::gpu::render_asset`]) and writes one
//! PNG per level, the levels side by side in one PNG, and the finest level as a linear EXR.
//! Every file is written atomically, and each step prints how long it took.
//!
//! Without a GPU adapter it still bakes and writes the baked file, then says what to install and
//! exits with a non-zero status, so that a script never mistakes a half-finished demo for a
//! finished one.

use std::path::{Path, PathBuf};
use std::time::Instant;

use anyhow::{bail, Context, Result};
use clap::{Args, ValueEnum};
use hce_bake::{bake_file, PipelineOptions};
use hce_geometry::Creases;
use hce_meshio::scene::ImportOptions;

use super::render::{parse_size, write_exr, write_png};
use super::validate::{problems, ValidateArgs};

/// The levels drawn side by side; the bake serves them all.
const LEVELS: std::ops::RangeInclusive<u32> = 0..=3;

#[derive(Args, Debug)]
pub struct DemoArgs {
    /// Folder for the outputs, created when missing. Default: `hce-demo` in the current
    /// directory.
    #[arg(short, long, value_name = "DIR")]
    pub output: Option<PathBuf>,
    /// Size of each level's image: small (240x180), medium (480x360), large (800x600) or
    /// WIDTHxHEIGHT. The side-by-side image is four of them wide.
    #[arg(long, default_value = "medium")]
    pub size: String,
    /// Which bundled sample to bake and draw.
    #[arg(long, value_enum, default_value_t = DemoScene::Teatime)]
    pub scene: DemoScene,
    /// Use a software adapter even if a GPU is present.
    #[arg(long)]
    pub software: bool,
}

#[derive(Clone, Copy, Debug, PartialEq, Eq, ValueEnum)]
pub enum DemoScene {
    /// The Utah teapot, a cup and a spoon on a table (three multiresolution objects).
    Teatime,
    /// Six chess pieces with hard edges on a board (six multiresolution objects).
    Chesstime,
    /// The Cornell box, its short block made multiresolution (a subdivided box that must stay a
    /// box).
    Cornell,
}

impl DemoScene {
    fn file_stem(self) -> &'static str {
        match self {
            DemoScene::Teatime => "teatime",
            DemoScene::Chesstime => "chesstime",
            DemoScene::Cornell => "cornell-box",
        }
    }

    fn title(self) -> &'static str {
        match self {
            DemoScene::Teatime => "Teatime (the Utah teapot, a cup and a spoon in a lit room)",
            DemoScene::Chesstime => "Chesstime (two kings, two queens, a pawn and a bishop)",
            DemoScene::Cornell => "the Cornell box (short block multiresolution)",
        }
    }

    fn bytes(self) -> &'static [u8] {
        use hce_samples::embedded;
        match self {
            DemoScene::Teatime => embedded::TEATIME_GLB,
            DemoScene::Chesstime => embedded::CHESSTIME_GLB,
            DemoScene::Cornell => embedded::CORNELL_BOX_GLB,
        }
    }

    /// The samples' hard edges are split normals, which `--creases auto` keeps sharp; the
    /// Cornell box has no multiresolution object of its own, so its short block is made one.
    fn import(self) -> ImportOptions {
        ImportOptions {
            multires: match self {
                DemoScene::Cornell => vec!["short_block".to_string()],
                _ => Vec::new(),
            },
        }
    }

    /// The equivalent `hce bake` flags, printed so that the user can repeat the step.
    fn bake_flags(self) -> &'static str {
        match self {
            DemoScene::Cornell => "--multires short_block --creases auto",
            _ => "--creases auto",
        }
    }
}

/// Parses `small`, `medium`, `large` or `WIDTHxHEIGHT`.
pub fn parse_demo_size(s: &str) -> Result<(u32, u32)> {
    match s {
        "small" => Ok((240, 180)),
        "medium" => Ok((480, 360)),
        "large" => Ok((800, 600)),
        // Four panels side by side must stay a writable PNG row.
        _ => match parse_size(s)? {
            (w, _) if w > 4096 => bail!("--size {s:?}: each level's image is at most 4096 wide"),
            wh => Ok(wh),
        },
    }
}

/// Prints one step: its duration and what it produced.
fn step(started: Instant, what: impl std::fmt::Display) {
    println!("  {:>6.2} s  {what}", started.elapsed().as_secs_f64());
}

pub fn run(args: DemoArgs) -> Result<()> {
    let total = Instant::now();
    let (width, height) = parse_demo_size(&args.size).map_err(crate::exit::usage)?;
    let scene = args.scene;
    let (dir, default_dir) = match &args.output {
        Some(d) => (d.clone(), false),
        None => (PathBuf::from("hce-demo"), true),
    };
    let existed = dir.is_dir();
    std::fs::create_dir_all(&dir)
        .with_context(|| format!("creating the output folder {}", dir.display()))?;
    println!("hce demo: {}", scene.title());
    println!(
        "writing into {}/ ({}{})",
        dir.display(),
        if existed {
            "existing folder, files replaced"
        } else {
            "created"
        },
        if default_dir {
            "; -o DIR chooses another folder"
        } else {
            ""
        }
    );

    let stem = scene.file_stem();
    let input = dir.join(format!("{stem}.glb"));
    let baked = dir.join(format!("{stem}-baked.glb"));

    let t = Instant::now();
    hce_meshio::write_atomic(&input, scene.bytes())
        .with_context(|| format!("writing the sample to {}", input.display()))?;
    step(t, format_args!("sample scene: {}", input.display()));

    let t = Instant::now();
    let options = PipelineOptions {
        import: scene.import(),
        creases: Creases::Auto,
        output: baked.clone(),
        ..PipelineOptions::default()
    };
    let outcome = bake_file(&input, &options, &|_: &str, _: usize, _: usize| {})
        .with_context(|| format!("baking {}", input.display()))?;
    for w in &outcome.warnings {
        eprintln!("warning: {w}");
    }
    let phases: Vec<String> = outcome
        .phase_seconds
        .iter()
        .map(|(p, s)| format!("{p} {s:.2}s"))
        .collect();
    step(
        t,
        format_args!(
            "baked: {} ({} bytes; {} coarse triangles, {} links; {})",
            baked.display(),
            outcome.output_bytes,
            outcome.coarse_triangles,
            outcome.links,
            phases.join(", ")
        ),
    );
    println!(
        "            (the same as `hce bake {} -o {} {}`)",
        input.display(),
        baked.display(),
        scene.bake_flags()
    );

    let t = Instant::now();
    let found = problems(&ValidateArgs {
        file: baked.clone(),
    })
    .map_err(|e| anyhow::anyhow!("validating {}: {}", baked.display(), e.message()))?;
    if !found.is_empty() {
        for p in &found {
            eprintln!("{}: {p}", baked.display());
        }
        bail!(
            "{}: the baked file has {} problems (a bug in hce bake; please report it)",
            baked.display(),
            found.len()
        );
    }
    step(t, "validated: no problems (as `hce validate`)");

    render_levels(&args, &dir, stem, &baked, (width, height))?;
    println!(
        "done in {:.1} s. Look at {}, or draw it yourself:",
        total.elapsed().as_secs_f64(),
        dir.join(format!("{stem}-levels.png")).display()
    );
    println!(
        "  hce render {} -o view.png --level 2 --size 800x600",
        baked.display()
    );
    Ok(())
}

#[cfg(feature = "gpu")]
fn render_levels(
    args: &DemoArgs,
    dir: &Path,
    stem: &str,
    baked: &Path,
    (width, height): (u32, u32),
) -> Result<()> {
    use hce_runtime::asset::Asset;
    use hce_runtime::gpu::{
        render_asset, AdapterKind, AssetRenderOptions, ContextOptions, GpuContext,
    };

    let t = Instant::now();
    let ctx = match GpuContext::new(&ContextOptions {
        force_software: args.software,
    }) {
        Ok(ctx) => ctx,
        Err(e) => {
            eprintln!("cannot render: {e}");
            eprintln!("the baked scene is written: {}", baked.display());
            eprintln!(
                "to render it on a machine without a GPU, install Mesa's software Vulkan \
                 driver (Debian/Ubuntu: `sudo apt-get install mesa-vulkan-drivers`) and run \
                 `hce demo` again"
            );
            bail!("no GPU adapter: the images were not rendered");
        }
    };
    step(t, format_args!("GPU adapter: {}", ctx.description));
    if ctx.description.kind == AdapterKind::Software {
        println!("            (a software rasteriser: slower than a GPU, same images)");
    }

    let asset = Asset::open(baked).with_context(|| format!("opening {}", baked.display()))?;
    let mut panels = Vec::new();
    let mut finest = None;
    for level in LEVELS {
        let t = Instant::now();
        let result = render_asset(
            &ctx,
            &asset,
            &AssetRenderOptions {
                width,
                height,
                level: Some(level),
                ..Default::default()
            },
        )
        .with_context(|| format!("rendering {} at level {level}", baked.display()))?;
        for n in &result.notes {
            eprintln!("note: {n}");
        }
        let srgb = result.image.to_srgb8(0.0);
        let path = dir.join(format!("{stem}-level{level}.png"));
        write_png(&path, width, height, &srgb)?;
        step(
            t,
            format_args!(
                "level {level}: {} ({} triangles)",
                path.display(),
                result.triangles
            ),
        );
        panels.push((level, srgb));
        finest = Some((level, result.image));
    }

    let t = Instant::now();
    let (sheet_w, sheet_h, sheet) = side_by_side(width, height, &panels);
    let path = dir.join(format!("{stem}-levels.png"));
    write_png(&path, sheet_w, sheet_h, &sheet)?;
    step(
        t,
        format_args!(
            "levels {}-{} side by side: {}",
            LEVELS.start(),
            LEVELS.end(),
            path.display()
        ),
    );

    if let Some((level, image)) = finest {
        let t = Instant::now();
        let path = dir.join(format!("{stem}-level{level}.exr"));
        write_exr(&path, image.width, image.height, &image.pixels)?;
        step(
            t,
            format_args!("level {level}, linear radiance: {}", path.display()),
        );
    }
    Ok(())
}

/// Pixels between two panels of the side-by-side image.
const GAP: u32 = 4;

/// Lays the panels (8-bit RGBA, `width` × `height` each) out in a row on a dark grey sheet,
/// each labelled with its level in the top-left corner.
fn side_by_side(width: u32, height: u32, panels: &[(u32, Vec<u8>)]) -> (u32, u32, Vec<u8>) {
    let n = panels.len() as u32;
    let sheet_w = n * width + n.saturating_sub(1) * GAP;
    let (w, sw) = (width as usize, sheet_w as usize);
    let mut sheet: Vec<u8> = [40, 40, 40, 255].repeat(sw * height as usize);
    for (i, (level, rgba)) in panels.iter().enumerate() {
        let x0 = i * (w + GAP as usize);
        for y in 0..height as usize {
            let src = &rgba[4 * y * w..4 * (y + 1) * w];
            sheet[4 * (y * sw + x0)..4 * (y * sw + x0 + w)].copy_from_slice(src);
        }
        // Labels scale with the image so that they stay readable but small.
        let scale = (height as usize / 120).clamp(1, 4);
        let margin = 3 * scale;
        draw_text(
            &mut sheet,
            sw,
            height as usize,
            x0 + margin,
            margin,
            scale,
            &format!("LEVEL {level}"),
        );
    }
    (sheet_w, height, sheet)
}

/// 5 × 7 glyphs, one row per byte, the leftmost pixel in bit 4.
fn glyph(c: char) -> [u8; 7] {
    match c {
        '0' => [0x0E, 0x11, 0x13, 0x15, 0x19, 0x11, 0x0E],
        '1' => [0x04, 0x0C, 0x04, 0x04, 0x04, 0x04, 0x0E],
        '2' => [0x0E, 0x11, 0x01, 0x02, 0x04, 0x08, 0x1F],
        '3' => [0x1F, 0x02, 0x04, 0x02, 0x01, 0x11, 0x0E],
        '4' => [0x02, 0x06, 0x0A, 0x12, 0x1F, 0x02, 0x02],
        '5' => [0x1F, 0x10, 0x1E, 0x01, 0x01, 0x11, 0x0E],
        '6' => [0x06, 0x08, 0x10, 0x1E, 0x11, 0x11, 0x0E],
        '7' => [0x1F, 0x01, 0x02, 0x04, 0x08, 0x08, 0x08],
        '8' => [0x0E, 0x11, 0x11, 0x0E, 0x11, 0x11, 0x0E],
        '9' => [0x0E, 0x11, 0x11, 0x0F, 0x01, 0x02, 0x0C],
        'E' => [0x1F, 0x10, 0x10, 0x1E, 0x10, 0x10, 0x1F],
        'L' => [0x10, 0x10, 0x10, 0x10, 0x10, 0x10, 0x1F],
        'V' => [0x11, 0x11, 0x11, 0x11, 0x11, 0x0A, 0x04],
        _ => [0; 7],
    }
}

/// Draws `text` in white with a black outline one pixel wide (scaled), clipped to the image.
fn draw_text(rgba: &mut [u8], w: usize, h: usize, x: usize, y: usize, scale: usize, text: &str) {
    let set = |rgba: &mut [u8], px: usize, py: usize, v: u8| {
        if px < w && py < h {
            rgba[4 * (py * w + px)..4 * (py * w + px) + 3].fill(v);
        }
    };
    // Outline first, then the glyphs, so that the white is never overdrawn.
    for pass in [0u8, 255] {
        for (k, c) in text.chars().enumerate() {
            let gx = x + k * 6 * scale;
            for (row, bits) in glyph(c).iter().enumerate() {
                for col in 0..5 {
                    if bits & (0x10 >> col) == 0 {
                        continue;
                    }
                    let (px, py) = (gx + col * scale, y + row * scale);
                    let reach = if pass == 0 { scale } else { 0 };
                    for dy in 0..scale + 2 * reach {
                        for dx in 0..scale + 2 * reach {
                            if let (Some(qx), Some(qy)) =
                                ((px + dx).checked_sub(reach), (py + dy).checked_sub(reach))
                            {
                                set(rgba, qx, qy, pass);
                            }
                        }
                    }
                }
            }
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn sizes_name_presets_or_dimensions() {
        assert_eq!(parse_demo_size("small").unwrap(), (240, 180));
        assert_eq!(parse_demo_size("medium").unwrap(), (480, 360));
        assert_eq!(parse_demo_size("large").unwrap(), (800, 600));
        assert_eq!(parse_demo_size("320x200").unwrap(), (320, 200));
        assert!(parse_demo_size("huge").is_err());
        assert!(parse_demo_size("5000x10").is_err());
    }

    #[test]
    fn panels_are_placed_in_order_with_labels_inside_them() {
        let (w, h) = (40u32, 30u32);
        let panels: Vec<(u32, Vec<u8>)> = (0..4u32)
            .map(|l| (l, [10 * l as u8 + 50, 0, 0, 255].repeat((w * h) as usize)))
            .collect();
        let (sw, sh, sheet) = side_by_side(w, h, &panels);
        assert_eq!((sw, sh), (4 * w + 3 * GAP, h));
        assert_eq!(sheet.len(), (4 * sw * sh) as usize);
        let px = |x: u32, y: u32| &sheet[4 * (y * sw + x) as usize..4 * (y * sw + x) as usize + 4];
        // Bottom-right corner of each panel keeps the panel's colour; the gaps are grey.
        for l in 0..4 {
            let x = l * (w + GAP) + w - 1;
            assert_eq!(px(x, h - 1), &[10 * l as u8 + 50, 0, 0, 255], "panel {l}");
        }
        assert_eq!(px(w, 0), &[40, 40, 40, 255]);
        // The label's first stroke (the L's stem at the margin) is white.
        assert_eq!(px(3, 3 + 2), &[255, 255, 255, 255]);
    }
}
