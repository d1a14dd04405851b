//! The baked Cornell box against an independent path-traced reference
//! ([`hce_bake::reference`]), surface by surface: every wall, the floor, the ceiling, every
//! block face and the light, each as the area average of the outgoing radiance.
//!
//! `HCE_REFERENCE_PATHS=N` sets the paths per surface (default 16384, which keeps the test
//! within the CI budget); BENCHMARKS.md records a run with many more.

use std::path::Path;

use glam::Vec3;
use hce_bake::import::{import_scene, ImportOptions};
use hce_bake::reference::PathTracer;
use hce_bake::{bake, BakeParams};

/// A planar surface: an object's triangles that share one normal.
struct Surface {
    name: String,
    object: usize,
    triangles: Vec<usize>,
    area: f64,
}

fn surfaces(scene: &hce_bake::Scene) -> Vec<Surface> {
    let mut out: Vec<(Surface, Vec3)> = Vec::new();
    for (oi, o) in scene.objects.iter().enumerate() {
        let first = out.len();
        for t in 0..o.triangles.len() {
            let [a, b, c] = o.corners(t);
            let cr = (b - a).cross(c - a);
            let n = cr.normalize();
            let area = f64::from(cr.length() * 0.5);
            match out[first..].iter_mut().find(|(_, m)| m.dot(n) > 0.9999) {
                Some((s, _)) => {
                    s.triangles.push(t);
                    s.area += area;
                }
                None => {
                    let k = out.len() - first;
                    out.push((
                        Surface {
                            name: format!("{} {k}", o.name),
                            object: oi,
                            triangles: vec![t],
                            area,
                        },
                        n,
                    ));
                }
            }
        }
    }
    out.into_iter().map(|(s, _)| s).collect()
}

#[test]
fn cornell_box_agrees_with_a_path_traced_reference() {
    let path = Path::new(env!("CARGO_MANIFEST_DIR")).join("../samples/cornell-box.glb");
    let imported = import_scene(&path, &ImportOptions::default()).unwrap();
    let mut scene = imported.solver_scene();
    if let Ok(d) = std::env::var("XLOWER") {
        let d: f32 = d.parse().unwrap();
        for o in scene.objects.iter_mut().filter(|o| o.name == "light") {
            for p in &mut o.positions {
                p[1] -= d;
            }
        }
    }
    if std::env::var("XNOBLOCKS").is_ok() {
        scene.objects.retain(|o| !o.name.contains("block"));
    }
    let paths: u64 = std::env::var("HCE_REFERENCE_PATHS")
        .ok()
        .and_then(|v| v.parse().ok())
        .unwrap_or(16384);
    let t0 = std::time::Instant::now();
    let env = |k: &str| std::env::var(k).ok().and_then(|v| v.parse::<f32>().ok());
    let mut params = BakeParams::default();
    if let Some(v) = env("XBF") {
        params.bf_epsilon = v;
    }
    if let Some(v) = env("XCO") {
        params.cluster_opening = v;
    }
    if let Some(v) = env("XVR") {
        params.visibility_rays = v as u32;
    }
    if let Some(v) = env("XML") {
        params.max_level = v as u32;
    }
    if let Some(v) = env("XMA") {
        params.min_area_fraction = v;
    }
    let baked = bake(&scene, &params).unwrap();
    println!("{:?}", baked.stats);
    let bake_s = t0.elapsed().as_secs_f64();
    let t0 = std::time::Instant::now();
    let tracer = PathTracer::new(&scene);
    let surfaces = surfaces(&scene);
    if std::env::var("XNOBLOCKS").is_err() {
        assert_eq!(surfaces.len(), 5 + 2 * 5 + 1);
    }
    let mut worst_large = 0.0f64;
    let mut worst_small = 0.0f64;
    let mut worst_channel = 0.0f64;
    println!(
        "{:<22} {:>8}  {:>26}  {:>26}  {:>7} {:>6}",
        "surface", "area m2", "baked radiance (RGB)", "path-traced (RGB)", "err %", "sigma %"
    );
    for (si, s) in surfaces.iter().enumerate() {
        let o = &baked.objects[s.object];
        let mut sum = [0.0f64; 3];
        for &t in &s.triangles {
            let [a, b, c] = scene.objects[s.object].corners(t);
            let area = f64::from((b - a).cross(c - a).length() * 0.5);
            let root = o.triangles[t].colours[0];
            for k in 0..3 {
                sum[k] += area * f64::from(root[k]);
            }
        }
        let got = sum.map(|x| x / s.area);
        let want = tracer.surface_radiance(s.object, &s.triangles, paths, 0x5eed + si as u64);
        // Relative error of the channel sum (a luminance-like figure that no dark channel
        // dominates), and the reference's own standard error on the same scale.
        let (g, w) = (got.iter().sum::<f64>(), want.mean.iter().sum::<f64>());
        let sigma = want.std_error.iter().map(|e| e * e).sum::<f64>().sqrt() / w;
        let err = (g - w).abs() / w;
        println!(
            "{:<22} {:>8.4}  {:>8.4} {:>8.4} {:>8.4}  {:>8.4} {:>8.4} {:>8.4}  {:>7.2} {:>6.2}",
            s.name,
            s.area,
            got[0],
            got[1],
            got[2],
            want.mean[0],
            want.mean[1],
            want.mean[2],
            100.0 * err,
            100.0 * sigma
        );
        // Per channel as well, where the channel carries at least a tenth of the brightest.
        let top = want.mean.iter().cloned().fold(0.0, f64::max);
        for k in 0..3 {
            if want.mean[k] >= 0.1 * top {
                worst_channel = worst_channel.max((got[k] - want.mean[k]).abs() / want.mean[k]);
            }
        }
        if s.area > 0.1 {
            worst_large = worst_large.max(err);
        } else {
            worst_small = worst_small.max(err);
        }
    }
    println!(
        "worst relative error: large surfaces {:.2}%, block faces and light {:.2}%; \
         {paths} paths per surface; bake {bake_s:.2}s, reference {:.2}s",
        100.0 * worst_large,
        100.0 * worst_small,
        t0.elapsed().as_secs_f64()
    );
    assert!(worst_channel < 0.08, "a channel is off by {worst_channel}");
    assert!(worst_large < 0.03, "large surfaces: {worst_large}");
    assert!(worst_small < 0.06, "small surfaces: {worst_small}");
}
