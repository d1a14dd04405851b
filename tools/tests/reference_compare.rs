//! `hce reference` and `hce compare` from the command line: known answers, determinism and the
//! documented exit statuses (3 invalid input, 4 I/O).

mod common;

use std::path::Path;

use common::hce;

fn write_exr(path: &Path, w: usize, h: usize, rgb: &[[f32; 3]]) {
    exr::prelude::write_rgba_file(path, w, h, |x, y| {
        let p = rgb[y * w + x];
        (p[0], p[1], p[2], 1.0)
    })
    .unwrap();
}

fn read_exr(path: &Path) -> (usize, usize, Vec<[f32; 4]>) {
    let image = exr::prelude::read_first_rgba_layer_from_file(
        path,
        |size, _| {
            (
                size.width(),
                size.height(),
                vec![[0f32; 4]; size.width() * size.height()],
            )
        },
        |(w, _, px): &mut (usize, usize, Vec<[f32; 4]>),
         pos,
         (r, g, b, a): (f32, f32, f32, f32)| { px[pos.y() * *w + pos.x()] = [r, g, b, a] },
    )
    .unwrap();
    image.layer_data.channel_data.pixels
}

fn s(p: &Path) -> &str {
    p.to_str().unwrap()
}

#[test]
fn compare_gives_the_known_answer_and_explains_bad_input() {
    let dir = tempfile::tempdir().unwrap();
    let (a, b) = (dir.path().join("a.exr"), dir.path().join("b.exr"));
    // Reference (1, 2, 2) everywhere; the image is equal on pixel 0 and off by (+1, 0, 0) on
    // pixel 1: sqrt(1 / 18) and bias 1 / 10.
    write_exr(&a, 2, 1, &[[1.0, 2.0, 2.0], [2.0, 2.0, 2.0]]);
    write_exr(&b, 2, 1, &[[1.0, 2.0, 2.0]; 2]);
    let (code, out, err) = common::hce(&["compare", s(&a), s(&b), "--json"]);
    assert_eq!(code, 0, "{err}");
    let v: serde_json::Value = serde_json::from_str(&out).unwrap();
    assert_eq!(v["pixels"], 2);
    assert!((v["relative_rms"].as_f64().unwrap() - (1.0f64 / 18.0).sqrt()).abs() < 1e-9);
    assert!((v["relative_bias"].as_f64().unwrap() - 0.1).abs() < 1e-9);
    let (code, out, _) = common::hce(&["compare", s(&a), s(&b)]);
    assert_eq!(code, 0);
    assert!(out.contains("relative RMS: 0.23570"), "{out}");
    // Pixel 1 sums 6 against 5.
    assert!(out.contains("worst pixel: 0.20000 at (1, 0)"), "{out}");

    // Against a constant (a closed furnace's 0.8): pixel 0 sums 5 against 6, pixel 1 6.
    let (code, out, err) = common::hce(&["compare", s(&a), "--constant", "2", "--json"]);
    assert_eq!(code, 0, "{err}");
    let v: serde_json::Value = serde_json::from_str(&out).unwrap();
    assert!((v["relative_bias"].as_f64().unwrap() + 1.0 / 12.0).abs() < 1e-9);
    assert!((v["worst_pixel"].as_f64().unwrap() - 1.0 / 6.0).abs() < 1e-9);
    assert_eq!(v["worst_at"], serde_json::json!([0, 0]));
    for bad in ["--constant=0", "--constant=-1", "--constant=nan"] {
        let (code, _, err) = common::hce(&["compare", s(&a), bad]);
        assert_eq!(code, 3, "{bad}: {err}");
        assert!(err.contains("--constant"), "{err}");
    }
    let (code, _, err) = common::hce(&["compare", s(&a)]);
    assert_ne!(code, 0, "no reference: {err}");

    // Sizes that differ, a mask of the wrong size, garbage and a missing file.
    let small = dir.path().join("small.exr");
    write_exr(&small, 1, 1, &[[1.0; 3]]);
    let (code, _, err) = common::hce(&["compare", s(&a), s(&small)]);
    assert_eq!(code, 3, "{err}");
    assert!(err.contains("2x1") && err.contains("1x1"), "{err}");
    let mask = dir.path().join("mask.png");
    let mut enc = png::Encoder::new(std::fs::File::create(&mask).unwrap(), 1, 1);
    enc.set_color(png::ColorType::Grayscale);
    enc.write_header()
        .unwrap()
        .write_image_data(&[255])
        .unwrap();
    let (code, _, err) = common::hce(&["compare", s(&a), s(&b), "--mask", s(&mask)]);
    assert_eq!(code, 3, "{err}");
    assert!(err.contains("mask"), "{err}");
    let garbage = dir.path().join("garbage.exr");
    std::fs::write(&garbage, b"not an exr").unwrap();
    let (code, _, err) = common::hce(&["compare", s(&garbage), s(&b)]);
    assert_eq!(code, 3, "{err}");
    assert!(err.contains("garbage.exr"), "{err}");
    let (code, _, err) = common::hce(&["compare", s(&a), s(&dir.path().join("missing.exr"))]);
    assert_eq!(code, 4, "{err}");
    assert!(err.contains("missing.exr"), "{err}");
}

#[test]
fn reference_of_the_baked_cornell_box_is_deterministic_and_lit() {
    let dir = tempfile::tempdir().unwrap();
    let input = Path::new(env!("CARGO_MANIFEST_DIR")).join("../samples/cornell-box.glb");
    let baked = dir.path().join("baked.glb");
    let (code, _, err) = common::hce(&["bake", s(&input), "-o", s(&baked), "-q"]);
    assert_eq!(code, 0, "{err}");
    let run = |out: &Path, threads: &str| {
        let mask = out.with_extension("png");
        let (code, stdout, err) = common::hce(&[
            "reference",
            s(&baked),
            "--level",
            "0",
            "--size",
            "24x18",
            "--samples",
            "4",
            // One ray per pixel centre: at 24 x 18 pixels the light covers no pixel's four
            // multisample positions, and it must show at full strength below.
            "--msaa",
            "1",
            "--threads",
            threads,
            "-o",
            s(out),
            "--mask",
            s(&mask),
            "-q",
        ]);
        assert_eq!(code, 0, "{err}");
        assert!(stdout.contains("24x18"), "{stdout}");
        (read_exr(out), std::fs::read(&mask).unwrap())
    };
    let (one, mask) = run(&dir.path().join("one.exr"), "1");
    let (two, _) = run(&dir.path().join("two.exr"), "2");
    assert_eq!(one, two, "the image depends on the thread count");
    let (w, h, px) = one;
    assert_eq!((w, h), (24, 18));
    assert!(px
        .iter()
        .all(|p| p[3] == 1.0 && p.iter().all(|c| c.is_finite() && *c >= 0.0)));
    // The published camera sees the box fill the frame; the light (17, 12, 4) is visible.
    assert!(px.iter().filter(|p| p[0] > 0.0).count() > w * h / 2);
    assert!(px.iter().any(|p| p[0] >= 17.0));
    // No multiresolution object in the Cornell box: the mask is black.
    let dec = png::Decoder::new(std::io::Cursor::new(mask));
    let mut reader = dec.read_info().unwrap();
    let mut buf = vec![0; reader.output_buffer_size().unwrap()];
    reader.next_frame(&mut buf).unwrap();
    assert!(buf.chunks_exact(4).all(|p| p[0] == 0));
}

#[test]
fn reference_explains_bad_input() {
    let dir = tempfile::tempdir().unwrap();
    let plain = Path::new(env!("CARGO_MANIFEST_DIR")).join("../samples/cornell-box.glb");
    let out = dir.path().join("out.exr");
    // Not baked: says to bake it first.
    let (code, _, err) = common::hce(&["reference", s(&plain), "--level", "0", "-o", s(&out)]);
    assert_eq!(code, 3, "{err}");
    assert!(err.contains("hce bake"), "{err}");
    let (code, _, err) = common::hce(&[
        "reference",
        s(&dir.path().join("missing.glb")),
        "--level",
        "0",
        "-o",
        s(&out),
    ]);
    assert_eq!(code, 4, "{err}");
    let (code, _, err) = common::hce(&["reference", s(&plain), "--level", "9", "-o", s(&out)]);
    // Out of range: clap's usage error (2), naming the flag and the range.
    assert_eq!(code, 2, "{err}");
    assert!(
        err.contains("'9' for '--level") && err.contains("0..=6"),
        "{err}"
    );
    let (code, _, err) = common::hce(&["reference", s(&plain), "--level", "0", "-o", "out.jpg"]);
    assert_eq!(code, 2, "{err}");
    assert!(err.contains(".exr"), "{err}");
    // Every multisample position needs a path; the counts are those with standard positions.
    let (code, _, err) = hce(&[
        "reference",
        s(&plain),
        "--level",
        "0",
        "--samples",
        "2",
        "--msaa",
        "4",
        "-o",
        s(&out),
    ]);
    assert_ne!(code, 0);
    assert!(err.contains("--msaa 4"), "{err}");
    let (code, _, err) = hce(&[
        "reference",
        s(&plain),
        "--level",
        "0",
        "--msaa",
        "3",
        "-o",
        s(&out),
    ]);
    assert_eq!(code, 2, "{err}");
    assert!(err.contains("1, 2, 4, 8 or 16"), "{err}");
    // --level is required.
    let (code, _, _) = common::hce(&["reference", s(&plain), "-o", s(&out)]);
    assert_eq!(code, 2);
    assert!(!out.exists());
}

#[test]
fn a_reader_closing_the_pipe_early_is_not_a_crash() {
    // `hce compare a.exr b.exr | head -1`: the reader goes away before hce has printed
    // everything; Rust's `println!` would panic on the broken pipe. hce ends quietly, with the
    // status of an output it could not write (4), not success.
    use std::process::Stdio;
    let dir = tempfile::tempdir().unwrap();
    let (a, b) = (dir.path().join("a.exr"), dir.path().join("b.exr"));
    write_exr(&a, 2, 1, &[[1.0, 2.0, 2.0], [2.0, 2.0, 2.0]]);
    write_exr(&b, 2, 1, &[[1.0, 2.0, 2.0]; 2]);
    let mut child = common::command()
        .args(["compare", s(&a), s(&b)])
        .stdout(Stdio::piped())
        .stderr(Stdio::piped())
        .spawn()
        .unwrap();
    drop(child.stdout.take());
    let out = child.wait_with_output().unwrap();
    let stderr = String::from_utf8_lossy(&out.stderr);
    assert!(!stderr.contains("panicked"), "{stderr}");
    assert_eq!(out.status.code(), Some(4), "{stderr}");
}
