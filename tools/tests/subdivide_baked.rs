//! `hce subdivide --merge` on a baked `.hce`: every object is refined from its stored control
//! mesh and the objects are merged into one mesh carrying the applied colours as COLOR_0.

mod common;

use hce_format::{example, write};

#[test]
fn baked_hce_subdivides_to_a_glb_with_colours() {
    let dir = tempfile::tempdir().unwrap();
    let input = dir.path().join("grid.hce");
    let mut c = example::grid(2, 1);
    // A second object, so that concatenation is exercised: 2 x 2 grid (8 triangles) + 1.
    c.objects.push(example::single_triangle().objects.remove(0));
    std::fs::write(&input, write(&c).unwrap()).unwrap();
    let output = dir.path().join("out.glb");
    let out = common::command()
        .args([
            "subdivide",
            input.to_str().unwrap(),
            "--merge",
            "--level",
            "2",
            "-o",
        ])
        .arg(&output)
        .output()
        .unwrap();
    assert!(
        out.status.success(),
        "{}",
        String::from_utf8_lossy(&out.stderr)
    );
    let (doc, buffers, _) = gltf::import(&output).unwrap();
    let prim = doc.meshes().next().unwrap().primitives().next().unwrap();
    let reader = prim.reader(|b| Some(&buffers[b.index()]));
    let positions: Vec<_> = reader.read_positions().unwrap().collect();
    let colours: Vec<[f32; 3]> = reader.read_colors(0).unwrap().into_rgb_f32().collect();
    let triangles = reader.read_indices().unwrap().into_u32().count() / 3;
    // Level 2: 16 subtriangles per coarse triangle; vertices: a 2x2 grid refined 4 times per
    // edge is a 9 x 9 lattice (81), the single triangle a 15-vertex triangular lattice.
    assert_eq!(triangles, (8 + 1) * 16);
    assert_eq!(positions.len(), 81 + 15);
    assert_eq!(colours.len(), positions.len());
    // The single triangle's first corner lies only in Top's subtriangles: node 1's colour.
    let last = &colours[81..];
    assert!(last.contains(&[1.0 / 8.0, 0.5, 0.25]), "{last:?}");
    // Grid colours are (k * 0.01, t, 0.5) clamped to [0, 1]: blue is 0.5 everywhere.
    assert!(colours[..81].iter().all(|c| (c[2] - 0.5).abs() < 1e-6));
}

#[test]
fn reconstruction_flag_chooses_the_colour_rule() {
    // The Appendix D tree (leaves of different depths, one normal): the smooth field and the
    // paper's per-subtriangle rule give different vertex colours at level 2; same geometry.
    let dir = tempfile::tempdir().unwrap();
    let input = dir.path().join("triangle.hce");
    std::fs::write(&input, write(&example::single_triangle()).unwrap()).unwrap();
    let run = |rule: &str| {
        let output = dir.path().join(format!("{rule}.glb"));
        let out = common::command()
            .args([
                "subdivide",
                input.to_str().unwrap(),
                "--merge",
                "--level",
                "2",
            ])
            .args(["--reconstruction", rule, "-o"])
            .arg(&output)
            .output()
            .unwrap();
        (
            out.status.code(),
            output,
            String::from_utf8_lossy(&out.stderr).into_owned(),
        )
    };
    let read = |path: &std::path::Path| {
        let (doc, buffers, _) = gltf::import(path).unwrap();
        let prim = doc.meshes().next().unwrap().primitives().next().unwrap();
        let reader = prim.reader(|b| Some(&buffers[b.index()]));
        let positions: Vec<_> = reader.read_positions().unwrap().collect();
        let colours: Vec<[f32; 3]> = reader.read_colors(0).unwrap().into_rgb_f32().collect();
        (positions, colours)
    };
    let (code, smooth, err) = run("smooth");
    assert_eq!(code, Some(0), "{err}");
    let (code, nearest, err) = run("nearest");
    assert_eq!(code, Some(0), "{err}");
    let (ps, cs) = read(&smooth);
    let (pn, cn) = read(&nearest);
    assert_eq!(ps, pn);
    assert_ne!(cs, cn);
    let (code, _, err) = run("bilinear");
    assert_eq!(code, Some(2), "{err}");
    assert!(
        err.contains("expected 'smooth', 'nearest' or 'gouraud'"),
        "{err}"
    );
}
