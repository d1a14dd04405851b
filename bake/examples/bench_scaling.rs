//! Scaling benchmark of the baker: bakes a closed room holding a finely tessellated sphere at
//! several sizes and prints time, elements and links against the number of input triangles.
//! Run with `cargo run --release -p hce-bake --example bench_scaling [sizes...]`.

use std::sync::atomic::{AtomicBool, Ordering};
use std::sync::Mutex;
use std::time::{Duration, Instant};

use glam::Vec3;
use hce_bake::{bake_with_progress, BakeParams, LightKind, PunctualLight, Scene, SolverObject};

/// An `n × n` grid of quads over the parallelogram `o, o+u, o+u+v, o+v`, facing `u × v`.
fn grid(o: Vec3, u: Vec3, v: Vec3, n: u32, pos: &mut Vec<[f32; 3]>, tris: &mut Vec<[u32; 3]>) {
    let base = pos.len() as u32;
    for j in 0..=n {
        for i in 0..=n {
            let p = o + u * (i as f32 / n as f32) + v * (j as f32 / n as f32);
            pos.push(p.to_array());
        }
    }
    for j in 0..n {
        for i in 0..n {
            let a = base + j * (n + 1) + i;
            tris.push([a, a + 1, a + n + 2]);
            tris.push([a, a + n + 2, a + n + 1]);
        }
    }
}

/// A UV sphere with `rings × 2 rings` triangles, centred at `c`.
fn sphere(c: Vec3, r: f32, rings: u32) -> (Vec<[f32; 3]>, Vec<[u32; 3]>) {
    let segs = rings * 2;
    let mut pos = Vec::new();
    let mut tris = Vec::new();
    for j in 0..=rings {
        let th = std::f32::consts::PI * j as f32 / rings as f32;
        for i in 0..segs {
            let ph = 2.0 * std::f32::consts::PI * i as f32 / segs as f32;
            pos.push(
                (c + r * Vec3::new(th.sin() * ph.cos(), th.sin() * ph.sin(), th.cos())).to_array(),
            );
        }
    }
    for j in 0..rings {
        for i in 0..segs {
            let a = j * segs + i;
            let b = j * segs + (i + 1) % segs;
            let (c2, d) = (a + segs, b + segs);
            if j != 0 {
                tris.push([a, c2, b]);
            }
            if j != rings - 1 {
                tris.push([b, c2, d]);
            }
        }
    }
    (pos, tris)
}

/// Gives every triangle of `obj` a set of `count` normals: its own and tilted copies (what a
/// bumpy multiresolution surface produces), so that the cost of enrichment shows.
fn synthetic_normal_sets(obj: &mut SolverObject, count: usize) {
    obj.normal_sets = (0..obj.triangles.len())
        .map(|t| {
            let [a, b, c] = obj.corners(t);
            let n = (b - a).cross(c - a).normalize();
            let u = n.any_orthonormal_vector();
            let v = n.cross(u);
            (0..count)
                .map(|k| {
                    if k == 0 {
                        return n.to_array();
                    }
                    let phi = k as f32 * std::f32::consts::TAU / (count - 1) as f32;
                    let tilt = 20f32.to_radians();
                    (n * tilt.cos() + (u * phi.cos() + v * phi.sin()) * tilt.sin()).to_array()
                })
                .collect()
        })
        .collect();
}

fn room(target: usize, normals: usize) -> Scene {
    // Walls take about a fifth of the triangles, the sphere the rest.
    let wall_n = (((target / 5) as f32 / 12.0).sqrt().round() as u32).max(1);
    let rings = ((((target * 4 / 5) as f32) / 4.0).sqrt().round() as u32).max(3);
    let (mut pos, mut tris) = (Vec::new(), Vec::new());
    let s = 4.0;
    let (x, y, z) = (Vec3::X * s, Vec3::Y * s, Vec3::Z * s);
    grid(Vec3::ZERO, x, y, wall_n, &mut pos, &mut tris);
    grid(z, y, x, wall_n, &mut pos, &mut tris);
    grid(Vec3::ZERO, y, z, wall_n, &mut pos, &mut tris);
    grid(x, z, y, wall_n, &mut pos, &mut tris);
    grid(Vec3::ZERO, z, x, wall_n, &mut pos, &mut tris);
    grid(y, x, z, wall_n, &mut pos, &mut tris);
    let walls = SolverObject::new("room", pos, tris, [0.6; 3]);
    let (sp, st) = sphere(Vec3::new(2.0, 2.0, 1.2), 1.0, rings);
    let mut ball = SolverObject::new("ball", sp, st, [0.7, 0.5, 0.3]);
    ball.multires = true;
    if normals > 1 {
        synthetic_normal_sets(&mut ball, normals);
    }
    Scene {
        objects: vec![walls, ball],
        lights: vec![PunctualLight {
            name: "lamp".into(),
            kind: LightKind::Point,
            position: [2.0, 2.0, 3.6],
            direction: [0.0, 0.0, -1.0],
            color: [1.0; 3],
            intensity: 20.0,
            range: None,
        }],
    }
}

fn main() {
    // Arguments: triangle counts, and optionally `normals=N` (normals per sphere triangle).
    let args: Vec<String> = std::env::args().skip(1).collect();
    let normals = args
        .iter()
        .find_map(|a| a.strip_prefix("normals=")?.parse().ok())
        .unwrap_or(1);
    let sizes: Vec<usize> = args.iter().filter_map(|a| a.parse().ok()).collect();
    let sizes = if sizes.is_empty() {
        vec![1_000, 5_000, 20_000]
    } else {
        sizes
    };
    println!(
        "threads: {}, normals per sphere triangle: {normals}",
        rayon::current_num_threads()
    );
    println!("| triangles | elements | links | iterations | seconds | phases |");
    println!("|---|---|---|---|---|---|");
    for n in sizes {
        let scene = room(n, normals);
        let t = Instant::now();
        let peaks = PhasePeaks::default();
        let done = AtomicBool::new(false);
        let res = std::thread::scope(|s| {
            s.spawn(|| peaks.sample_until(&done));
            let res = bake_with_progress(&scene, &BakeParams::default(), &|phase, _, _| {
                peaks.enter(phase)
            })
            .expect("bake");
            done.store(true, Ordering::Relaxed);
            res
        });
        let secs = t.elapsed().as_secs_f64();
        let phases: Vec<String> = res
            .stats
            .phase_seconds
            .iter()
            .map(|(k, v)| format!("{k} {v:.2}"))
            .collect();
        println!(
            "| {} | {} | {} | {} | {secs:.2} | {} |",
            res.stats.coarse_triangles,
            res.stats.elements,
            res.stats.links,
            res.stats.iterations,
            phases.join(", ")
        );
        println!("resident memory, peak by phase: {}", peaks.report());
    }
}

/// The process's resident memory sampled every 20 ms, its peak kept per bake phase (the phase
/// the progress callback last named), to show which phase sets the bake's memory peak. Linux
/// only (`/proc/self/statm`); elsewhere it reports nothing.
#[derive(Default)]
struct PhasePeaks {
    phase: Mutex<String>,
    peaks: Mutex<Vec<(String, u64)>>,
}

impl PhasePeaks {
    fn enter(&self, phase: &str) {
        if let Ok(mut p) = self.phase.lock() {
            if *p != phase {
                *p = phase.to_string();
            }
        }
    }

    fn sample_until(&self, done: &AtomicBool) {
        // statm gives pages; 4 KiB pages on the machines this runs on.
        let page = 4096u64;
        while !done.load(Ordering::Relaxed) {
            let rss = std::fs::read_to_string("/proc/self/statm")
                .ok()
                .and_then(|s| s.split_whitespace().nth(1)?.parse::<u64>().ok())
                .map_or(0, |p| p * page);
            let phase = self.phase.lock().map(|p| p.clone()).unwrap_or_default();
            if let Ok(mut peaks) = self.peaks.lock() {
                match peaks.iter_mut().find(|(p, _)| *p == phase) {
                    Some((_, m)) => *m = (*m).max(rss),
                    None => peaks.push((phase, rss)),
                }
            }
            std::thread::sleep(Duration::from_millis(20));
        }
    }

    fn report(&self) -> String {
        let peaks = self.peaks.lock().map(|p| p.clone()).unwrap_or_default();
        peaks
            .iter()
            .map(|(p, m)| {
                let name = if p.is_empty() { "setup" } else { p };
                format!("{name} {:.2} GB", *m as f64 / 1e9)
            })
            .collect::<Vec<_>>()
            .join(", ")
    }
}
