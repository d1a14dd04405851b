//! `subdivide_streamed` and `output_shape`, which `hce subdivide` uses to write a GLB while it
//! subdivides: the streamed output is the plain one, every finished range reaches the sink once,
//! and the predicted size and position bounds are the output's, bit for bit.

mod common;

use std::path::Path;
use std::sync::Mutex;

use hce_geometry::subdivide::{output_shape, subdivide, subdivide_streamed, Written};
use hce_geometry::Refined;

/// The test meshes, and those of the folder `HCE_EXTRA_MESHES` names, if set.
fn meshes() -> Vec<std::path::PathBuf> {
    let objs = |dir: &Path| {
        let mut m: Vec<_> = std::fs::read_dir(dir)
            .unwrap()
            .map(|e| e.unwrap().path())
            .filter(|p| p.extension().is_some_and(|e| e == "obj"))
            .collect();
        m.sort();
        m
    };
    let mut m = objs(&Path::new(env!("CARGO_MANIFEST_DIR")).join("tests/data"));
    assert!(m.len() >= 5);
    if let Ok(extra) = std::env::var("HCE_EXTRA_MESHES") {
        m.extend(objs(Path::new(&extra)));
    }
    m
}

fn bounds(p: &[[f32; 3]]) -> ([u32; 3], [u32; 3]) {
    let (mut lo, mut hi) = ([f32::INFINITY; 3], [f32::NEG_INFINITY; 3]);
    for q in p {
        for k in 0..3 {
            lo[k] = lo[k].min(q[k]);
            hi[k] = hi[k].max(q[k]);
        }
    }
    (lo.map(f32::to_bits), hi.map(f32::to_bits))
}

#[test]
fn output_shape_predicts_the_size_and_bounds_of_the_output() {
    for path in meshes() {
        let topo = common::control_mesh(&path, &Default::default());
        for level in 0..=4 {
            let shape = output_shape(&topo.mesh, level).unwrap();
            let r = subdivide(&topo.mesh, level).unwrap();
            assert_eq!(shape.vertices, r.positions.len(), "{path:?} {level}");
            assert_eq!(shape.triangles, r.indices.len(), "{path:?} {level}");
            let (lo, hi) = shape.bounds.unwrap();
            assert_eq!(
                (lo.map(f32::to_bits), hi.map(f32::to_bits)),
                bounds(&r.positions),
                "{path:?} level {level}"
            );
        }
    }
    let topo = common::control_mesh(&meshes()[0], &Default::default());
    assert!(output_shape(&topo.mesh, 7).is_err());
}

#[test]
fn streamed_output_is_the_plain_output_and_reaches_the_sink_once() {
    for path in meshes() {
        let topo = common::control_mesh(&path, &Default::default());
        for level in [1, 3] {
            let plain = subdivide(&topo.mesh, level).unwrap();
            let n = plain.positions.len();
            // What the sink saw: positions and normals by vertex, indices by triangle.
            let seen = Mutex::new((
                vec![None; n],
                vec![None; n],
                vec![None; plain.indices.len()],
            ));
            let sink = |w: Written<'_>| {
                let mut s = seen.lock().unwrap();
                let s = &mut *s;
                for (first, p, q) in [
                    (w.first_edge_point, w.edge_positions, w.edge_normals),
                    (
                        w.first_interior_point,
                        w.interior_positions,
                        w.interior_normals,
                    ),
                ] {
                    for (k, (p, q)) in p.iter().zip(q).enumerate() {
                        assert!(s.0[first + k].replace(*p).is_none());
                        assert!(s.1[first + k].replace(*q).is_none());
                    }
                }
                for (k, t) in w.indices.iter().enumerate() {
                    assert!(s.2[w.first_triangle + k].replace(*t).is_none());
                }
            };
            let mut streamed = Refined::default();
            subdivide_streamed(&topo.mesh, level, &mut streamed, Some(&sink)).unwrap();
            assert_eq!(streamed, plain, "{path:?} {level}");
            let (p, q, t) = seen.into_inner().unwrap();
            let coarse = plain.coarse_vertices;
            for v in 0..n {
                let want = (v >= coarse).then(|| (plain.positions[v], plain.normals[v]));
                assert_eq!(p[v].zip(q[v]), want, "{path:?} {level} vertex {v}");
            }
            assert!(t.iter().zip(&plain.indices).all(|(a, b)| *a == Some(*b)));
        }
    }
}
