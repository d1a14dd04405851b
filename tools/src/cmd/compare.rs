//! `hce compare`: how far an image is from a reference, over an optional mask.
//!
//! Both images are linear EXRs of the same size (`hce render -o x.exr`, `hce reference -o
//! y.exr`); the second is the reference. Over the pixels the mask selects (all of them without
//! one), with `a` and `b` the RGB of the first and second image:
//!
//! * relative RMS difference `sqrt(Σ |a - b|² / Σ |b|²)`, the sums over pixels and the three
//!   channels (and per channel, the sums over pixels only);
//! * mean relative bias `Σ (a - b) / Σ b`, over pixels and channels: positive when the first
//!   image is brighter on the whole;
//! * the worst pixel: the largest `|Σa − Σb| / Σb` of one pixel's summed RGB, and where it is;
//! * the number of pixels compared.
//!
//! Instead of a reference image, `--constant V` compares against `V` in every channel of every
//! pixel: a closed furnace (`gen-samples room --furnace`) is exactly 0.8 everywhere.
//!
//! A mask is a PNG of the same size (`hce reference --mask`): pixels whose first channel is at
//! least half of full scale are compared.

use std::path::{Path, PathBuf};

use anyhow::{bail, Context, Result};
use clap::Args;
use serde::Serialize;

use crate::exit::Invalid;

#[derive(Args, Debug)]
pub struct CompareArgs {
    /// The image to judge (linear .exr).
    pub image: PathBuf,
    /// The reference (linear .exr); or `--constant`.
    #[arg(required_unless_present = "constant")]
    pub reference: Option<PathBuf>,
    /// Compare against this value in every channel of every pixel instead of a reference
    /// image (a closed furnace: 0.8 for `gen-samples room --furnace`).
    #[arg(long, value_name = "V", conflicts_with = "reference")]
    pub constant: Option<f32>,
    /// Compare only where this PNG (same size) is white.
    #[arg(long, value_name = "PATH.png")]
    pub mask: Option<PathBuf>,
    /// Print one JSON object instead of text.
    #[arg(long)]
    pub json: bool,
    /// Also write a picture of the signed difference: per pixel `(a − b) / mean(b)` of the
    /// summed RGB, red where the image is brighter than the reference, blue where darker, full
    /// colour at ±`--diff-scale`; pixels outside the mask dark grey.
    #[arg(long, value_name = "PATH.png")]
    pub diff: Option<PathBuf>,
    /// The difference that `--diff` draws at full colour, as a fraction of the mean reference.
    #[arg(long, default_value_t = 0.2)]
    pub diff_scale: f32,
    /// Draw in `--diff` the mean difference over blocks of N × N pixels (those inside the
    /// mask), so that a bias of a percent or two shows through a path-traced reference's
    /// noise; 1 draws each pixel's own.
    #[arg(long, value_name = "N", default_value_t = 1, value_parser = clap::value_parser!(u32).range(1..=256))]
    pub diff_block: u32,
}

/// RGBA8 picture of the signed difference of `a` from `b` (see `--diff`), each pixel drawn
/// with the mean difference of its `block` × `block` block (see `--diff-block`).
pub fn diff_picture(a: &Rgb, b: &Rgb, mask: Option<&[bool]>, scale: f32, block: usize) -> Vec<u8> {
    let inside = |i: usize| mask.is_none_or(|m| m[i]);
    let sum = |p: [f32; 3]| f64::from(p[0]) + f64::from(p[1]) + f64::from(p[2]);
    let (mut total, mut count) = (0.0f64, 0u64);
    for (i, p) in b.pixels.iter().enumerate() {
        if inside(i) {
            total += sum(*p);
            count += 1;
        }
    }
    let mean = if count > 0 && total > 0.0 {
        total / count as f64
    } else {
        1.0
    };
    // Mean difference of summed RGB per block, over the pixels inside the mask.
    let block = block.max(1);
    let (bw, bh) = (a.width.div_ceil(block), a.height.div_ceil(block));
    let mut acc = vec![(0.0f64, 0u32); bw * bh];
    for (i, (pa, pb)) in a.pixels.iter().zip(&b.pixels).enumerate() {
        if inside(i) {
            let cell = &mut acc[(i / a.width / block) * bw + (i % a.width) / block];
            cell.0 += sum(*pa) - sum(*pb);
            cell.1 += 1;
        }
    }
    let mut out = Vec::with_capacity(4 * a.pixels.len());
    for i in 0..a.pixels.len() {
        if !inside(i) {
            out.extend([40, 40, 40, 255]);
            continue;
        }
        let (d, n) = acc[(i / a.width / block) * bw + (i % a.width) / block];
        let e = (d / f64::from(n) / mean) as f32 / scale.max(1e-6);
        let t = e.clamp(-1.0, 1.0);
        let fade = |x: f32| (255.0 * (1.0 - x.abs())).round() as u8;
        out.extend(if t >= 0.0 {
            [255, fade(t), fade(t), 255]
        } else {
            [fade(t), fade(t), 255, 255]
        });
    }
    out
}

/// The figures `hce compare` prints.
#[derive(Clone, Debug, PartialEq, Serialize)]
pub struct Comparison {
    pub pixels: u64,
    /// `sqrt(Σ |a - b|² / Σ |b|²)` over pixels and channels.
    pub relative_rms: f64,
    /// The same per channel (R, G, B).
    pub relative_rms_rgb: [f64; 3],
    /// `Σ (a - b) / Σ b` over pixels and channels.
    pub relative_bias: f64,
    /// The largest `|Σa − Σb| / Σb` of one pixel (summed RGB) where `Σb > 0`.
    pub worst_pixel: f64,
    /// That pixel's `[x, y]`.
    pub worst_at: [u32; 2],
}

/// A linear RGB image.
pub struct Rgb {
    pub width: usize,
    pub height: usize,
    pub pixels: Vec<[f32; 3]>,
}

/// Reads the first RGBA layer of an EXR (alpha ignored).
pub fn read_exr(path: &Path) -> Result<Rgb> {
    // A missing or unreadable file is an I/O error (exit status 4), not a bad image.
    std::fs::File::open(path).with_context(|| format!("cannot open {}", path.display()))?;
    let image = exr::prelude::read_first_rgba_layer_from_file(
        path,
        |size, _| Rgb {
            width: size.width(),
            height: size.height(),
            pixels: vec![[0.0; 3]; size.width() * size.height()],
        },
        |img: &mut Rgb, pos, (r, g, b, _a): (f32, f32, f32, f32)| {
            let w = img.width;
            img.pixels[pos.y() * w + pos.x()] = [r, g, b];
        },
    )
    .map_err(|e| {
        Invalid(format!(
            "{}: not a readable RGB(A) EXR: {e}",
            path.display()
        ))
    })?;
    Ok(image.layer_data.channel_data.pixels)
}

/// Reads a PNG mask: `true` where the first channel is at least half of full scale.
pub fn read_mask(path: &Path) -> Result<(usize, usize, Vec<bool>)> {
    let file =
        std::fs::File::open(path).with_context(|| format!("cannot open {}", path.display()))?;
    let bad = |e: &dyn std::fmt::Display| {
        Invalid(format!("{}: not a readable PNG mask: {e}", path.display()))
    };
    let mut decoder = png::Decoder::new(std::io::BufReader::new(file));
    decoder.set_transformations(png::Transformations::normalize_to_color8());
    let mut reader = decoder.read_info().map_err(|e| bad(&e))?;
    let mut buf = vec![
        0;
        reader
            .output_buffer_size()
            .ok_or_else(|| bad(&"too large"))?
    ];
    let info = reader.next_frame(&mut buf).map_err(|e| bad(&e))?;
    let channels = info.color_type.samples();
    let (w, h) = (info.width as usize, info.height as usize);
    let mask = buf[..info.buffer_size()]
        .chunks_exact(info.line_size)
        .flat_map(|row| row.chunks_exact(channels).take(w).map(|p| p[0] >= 128))
        .collect();
    Ok((w, h, mask))
}

/// Compares `a` with the reference `b` over `mask` (every pixel when `None`).
pub fn compare(a: &Rgb, b: &Rgb, mask: Option<&[bool]>) -> Result<Comparison> {
    let (mut d2, mut b2, mut diff, mut sum) = ([0f64; 3], [0f64; 3], 0f64, 0f64);
    let mut pixels = 0u64;
    let (mut worst, mut worst_i) = (0f64, 0usize);
    for (i, (pa, pb)) in a.pixels.iter().zip(&b.pixels).enumerate() {
        if mask.is_some_and(|m| !m[i]) {
            continue;
        }
        pixels += 1;
        let sa: f64 = pa.iter().map(|&x| f64::from(x)).sum();
        let sb: f64 = pb.iter().map(|&x| f64::from(x)).sum();
        if sb > 0.0 && (sa - sb).abs() / sb > worst {
            (worst, worst_i) = ((sa - sb).abs() / sb, i);
        }
        for c in 0..3 {
            let (x, y) = (f64::from(pa[c]), f64::from(pb[c]));
            d2[c] += (x - y) * (x - y);
            b2[c] += y * y;
            diff += x - y;
            sum += y;
        }
    }
    if pixels == 0 {
        bail!(Invalid("the mask selects no pixel".into()));
    }
    let (d2_all, b2_all): (f64, f64) = (d2.iter().sum(), b2.iter().sum());
    if !(b2_all > 0.0 && sum != 0.0) {
        bail!(Invalid(
            "the reference is black where compared: a relative difference is undefined".into()
        ));
    }
    let rel = |d: f64, b: f64| if b > 0.0 { (d / b).sqrt() } else { f64::NAN };
    Ok(Comparison {
        pixels,
        relative_rms: rel(d2_all, b2_all),
        relative_rms_rgb: [0, 1, 2].map(|c| rel(d2[c], b2[c])),
        relative_bias: diff / sum,
        worst_pixel: worst,
        worst_at: [
            (worst_i % a.width.max(1)) as u32,
            (worst_i / a.width.max(1)) as u32,
        ],
    })
}

pub fn run(args: CompareArgs) -> Result<()> {
    let a = read_exr(&args.image)?;
    let b = match (&args.reference, args.constant) {
        (_, Some(v)) => {
            if !(v.is_finite() && v > 0.0) {
                bail!(Invalid(format!(
                    "--constant {v}: a reference value must be positive and finite"
                )));
            }
            Rgb {
                width: a.width,
                height: a.height,
                pixels: vec![[v; 3]; a.pixels.len()],
            }
        }
        (Some(path), None) => {
            let b = read_exr(path)?;
            if (a.width, a.height) != (b.width, b.height) {
                bail!(Invalid(format!(
                    "{} is {}x{} but the reference {} is {}x{}; render both at the same --size",
                    args.image.display(),
                    a.width,
                    a.height,
                    path.display(),
                    b.width,
                    b.height
                )));
            }
            b
        }
        (None, None) => bail!("give a reference image or --constant"),
    };
    let mask = match &args.mask {
        Some(path) => {
            let (w, h, m) = read_mask(path)?;
            if (w, h) != (a.width, a.height) {
                bail!(Invalid(format!(
                    "the mask {} is {w}x{h} but the images are {}x{}",
                    path.display(),
                    a.width,
                    a.height
                )));
            }
            Some(m)
        }
        None => None,
    };
    let c = compare(&a, &b, mask.as_deref())?;
    if let Some(path) = &args.diff {
        let rgba = diff_picture(
            &a,
            &b,
            mask.as_deref(),
            args.diff_scale,
            args.diff_block as usize,
        );
        super::render::write_png(path, a.width as u32, a.height as u32, &rgba)?;
    }
    if args.json {
        println!("{}", serde_json::to_string(&c)?);
    } else {
        println!("pixels: {}", c.pixels);
        println!(
            "relative RMS: {:.5} (R {:.5}, G {:.5}, B {:.5})",
            c.relative_rms, c.relative_rms_rgb[0], c.relative_rms_rgb[1], c.relative_rms_rgb[2]
        );
        println!("relative bias: {:+.5}", c.relative_bias);
        println!(
            "worst pixel: {:.5} at ({}, {})",
            c.worst_pixel, c.worst_at[0], c.worst_at[1]
        );
    }
    Ok(())
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn known_answers_with_and_without_a_mask() {
        // Reference all (1, 2, 2): |b|² = 9 per pixel. Image: pixel 0 equal, pixel 1 off by
        // (+1, 0, 0), pixel 2 off by (0, -2, +2) and masked out in the second comparison.
        let b = Rgb {
            width: 3,
            height: 1,
            pixels: vec![[1.0, 2.0, 2.0]; 3],
        };
        let a = Rgb {
            width: 3,
            height: 1,
            pixels: vec![[1.0, 2.0, 2.0], [2.0, 2.0, 2.0], [1.0, 0.0, 4.0]],
        };
        let all = compare(&a, &b, None).unwrap();
        assert_eq!(all.pixels, 3);
        assert!((all.relative_rms - (9.0f64 / 27.0).sqrt()).abs() < 1e-12);
        assert!((all.relative_rms_rgb[0] - (1.0f64 / 3.0).sqrt()).abs() < 1e-12);
        assert!((all.relative_rms_rgb[1] - (4.0f64 / 12.0).sqrt()).abs() < 1e-12);
        assert!((all.relative_bias - 1.0 / 15.0).abs() < 1e-12);
        // Pixel 1: |6 - 5| / 5; pixel 2: |5 - 5| / 5.
        assert!((all.worst_pixel - 0.2).abs() < 1e-12);
        assert_eq!(all.worst_at, [1, 0]);
        let masked = compare(&a, &b, Some(&[true, true, false])).unwrap();
        assert_eq!(masked.pixels, 2);
        assert!((masked.relative_rms - (1.0f64 / 18.0).sqrt()).abs() < 1e-12);
        assert!((masked.relative_bias - 0.1).abs() < 1e-12);
        assert!(compare(&a, &b, Some(&[false; 3])).is_err());
    }

    #[test]
    fn diff_picture_is_red_where_brighter_blue_where_darker() {
        // Mean reference (summed RGB) 3; pixel 0 equal, pixel 1 brighter by 0.6 (0.2 of the
        // mean: full red at the default scale), pixel 2 darker by 0.45 (three quarters blue), pixel 3
        // outside the mask.
        let b = Rgb {
            width: 4,
            height: 1,
            pixels: vec![[1.0; 3]; 4],
        };
        let a = Rgb {
            width: 4,
            height: 1,
            pixels: vec![[1.0; 3], [1.2; 3], [0.85; 3], [5.0; 3]],
        };
        let rgba = diff_picture(&a, &b, Some(&[true, true, true, false]), 0.2, 1);
        assert_eq!(&rgba[0..4], &[255, 255, 255, 255]);
        assert_eq!(&rgba[4..8], &[255, 0, 0, 255]);
        assert_eq!(&rgba[8..12], &[64, 64, 255, 255]);
        assert_eq!(&rgba[12..16], &[40, 40, 40, 255]);
        // Blocks of two: pixels 0 and 1 share +0.1 of the mean (half red, rounded down: 1.2 is not exact in f32); pixels 2 and 3
        // share pixel 2's -0.15 (pixel 3 is outside the mask, left out of the mean and drawn
        // grey).
        let rgba = diff_picture(&a, &b, Some(&[true, true, true, false]), 0.2, 2);
        assert_eq!(&rgba[0..8], &[255, 127, 127, 255, 255, 127, 127, 255]);
        assert_eq!(&rgba[8..12], &[64, 64, 255, 255]);
        assert_eq!(&rgba[12..16], &[40, 40, 40, 255]);
        // Blocks larger than the image, and blocks over rows: a 3 × 2 image in 2 × 2 blocks.
        let b = Rgb {
            width: 3,
            height: 2,
            pixels: vec![[1.0; 3]; 6],
        };
        let a = Rgb {
            width: 3,
            height: 2,
            pixels: vec![[1.2; 3], [1.0; 3], [0.7; 3], [1.0; 3], [1.0; 3], [1.0; 3]],
        };
        let rgba = diff_picture(&a, &b, None, 0.2, 2);
        // Block (0, 0) holds pixels 0, 1, 3, 4: +0.05; block (1, 0) pixels 2 and 5: -0.15.
        for i in [0, 1, 3, 4] {
            assert_eq!(&rgba[4 * i..4 * i + 4], &[255, 191, 191, 255], "pixel {i}");
        }
        for i in [2, 5] {
            assert_eq!(&rgba[4 * i..4 * i + 4], &[64, 64, 255, 255], "pixel {i}");
        }
        assert_eq!(diff_picture(&a, &b, None, 0.2, 64).len(), 24);
    }
}
