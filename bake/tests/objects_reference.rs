//! Objects in a lit room against the independent path tracer ([`hce_reference`]), face
//! by face (issue 20: objects came out darker than path tracers showed them). A closed room
//! lit by an emitting panel under its ceiling holds an octahedron floating in the middle and
//! one resting on a vertex on the floor, so that its lower faces look at the floor from close
//! by; one is multiresolution with tilted normal sets. Every face's area-averaged radiance for
//! the geometric normal (the coarse scene both programs see) is compared with the path
//! tracer's.
//!
//! `HCE_REFERENCE_PATHS=N` sets the paths per face (default 16384); BENCHMARKS.md ("Leaves of
//! the bake") records a run with more.

mod common;

use glam::Vec3;
use hce_bake::{bake, BakeParams, Scene, SolverObject};
use hce_reference::PathTracer;

struct Mesh {
    positions: Vec<[f32; 3]>,
    triangles: Vec<[u32; 3]>,
}

impl Mesh {
    fn new() -> Self {
        Mesh {
            positions: Vec::new(),
            triangles: Vec::new(),
        }
    }

    /// The triangle `a, b, c` cut into `n²` triangles, each facing away from `inside` when
    /// `outward`, towards it otherwise.
    fn grid(&mut self, corners: [Vec3; 3], n: u32, inside: Vec3, outward: bool) {
        common::barycentric_grid(corners, n, |x, y, z| {
            let base = self.positions.len() as u32;
            self.positions.extend([x, y, z].map(|v| v.to_array()));
            let faces_in = (y - x).cross(z - x).dot(inside - (x + y + z) / 3.0) > 0.0;
            if faces_in != outward {
                self.triangles.push([base, base + 1, base + 2]);
            } else {
                self.triangles.push([base, base + 2, base + 1]);
            }
        });
    }

    fn quad(&mut self, o: Vec3, u: Vec3, v: Vec3, n: u32, inside: Vec3, outward: bool) {
        self.grid([o, o + u, o + v], n, inside, outward);
        self.grid([o + u + v, o + v, o + u], n, inside, outward);
    }
}

/// An octahedron of radius `r` at `c`, each face a barycentric grid of `n²` triangles, the
/// triangles of face `f` at `8 f * n² ..`.
fn octahedron(c: Vec3, r: f32, n: u32) -> Mesh {
    let mut m = Mesh::new();
    for face in common::octahedron_faces(c, r) {
        m.grid(face, n, c, true);
    }
    m
}

fn tilt(n: Vec3, deg: f32) -> Vec3 {
    let side = if n.x.abs() < 0.9 { Vec3::X } else { Vec3::Y };
    let t = n.cross(side).normalize();
    (n * deg.to_radians().cos() + t * deg.to_radians().sin()).normalize()
}

fn scene() -> Scene {
    // A 3 × 3 × 2.5 room (z up), each face a 3 × 3 grid of quads facing inwards.
    let s = Vec3::new(3.0, 3.0, 2.5);
    let inside = s * 0.5;
    let mut room = Mesh::new();
    for (o, u, v) in common::box_faces(s) {
        for i in 0..3 {
            for j in 0..3 {
                room.quad(
                    o + u * (i as f32 / 3.0) + v * (j as f32 / 3.0),
                    u / 3.0,
                    v / 3.0,
                    1,
                    inside,
                    false,
                );
            }
        }
    }
    // A 0.8 m square panel 5 cm under the ceiling, emitting downwards.
    let mut lamp = Mesh::new();
    let lc = Vec3::new(1.5, 1.5, 2.45);
    lamp.quad(
        lc - Vec3::new(0.4, 0.4, 0.0),
        Vec3::X * 0.8,
        Vec3::Y * 0.8,
        1,
        lc - Vec3::Z,
        false,
    );
    let floating = octahedron(Vec3::new(1.0, 1.6, 1.1), 0.35, 2);
    let resting = octahedron(Vec3::new(2.0, 1.2, 0.4), 0.4, 2);
    let room = SolverObject::new("room", room.positions, room.triangles, [0.6, 0.6, 0.6]);
    let lamp = SolverObject::new("lamp", lamp.positions, lamp.triangles, [0.0; 3])
        .with_emission([10.0; 3]);
    let mut floating = SolverObject::new(
        "floating",
        floating.positions,
        floating.triangles,
        [0.7, 0.5, 0.3],
    );
    floating.multires = true;
    floating.normal_sets = (0..floating.triangles.len())
        .map(|t| {
            let [a, b, c] = floating.corners(t);
            let n = (b - a).cross(c - a).normalize();
            vec![n, tilt(n, 20.0), tilt(n, -20.0)]
                .into_iter()
                .map(|v| v.to_array())
                .collect()
        })
        .collect();
    let resting = SolverObject::new(
        "resting",
        resting.positions,
        resting.triangles,
        [0.5, 0.5, 0.5],
    );
    Scene {
        objects: vec![room, lamp, floating, resting],
        lights: Vec::new(),
    }
}

#[test]
fn objects_in_a_lit_room_agree_with_a_path_tracer() {
    let scene = scene();
    let paths = common::reference_paths();
    let baked = bake(&scene, &BakeParams::default()).expect("bakes");
    let tracer = PathTracer::new(&scene);
    let (mut bias_num, mut bias_den) = (0.0f64, 0.0f64);
    let mut worst = (0.0f64, String::new());
    for oi in [2usize, 3] {
        let object = &scene.objects[oi];
        let per_face = object.triangles.len() / 8;
        for f in 0..8 {
            let tris: Vec<usize> = (f * per_face..(f + 1) * per_face).collect();
            let (mut sum, mut area) = (0.0f64, 0.0f64);
            for &t in &tris {
                let [a, b, c] = object.corners(t);
                let ar = f64::from((b - a).cross(c - a).length() * 0.5);
                let root = baked.objects[oi].triangles[t].colours[0];
                sum += ar * root.iter().map(|&v| f64::from(v)).sum::<f64>();
                area += ar;
            }
            let got = sum / area;
            let want = tracer.surface_radiance(oi, &tris, paths, 0xface + (oi * 8 + f) as u64);
            let w: f64 = want.mean.iter().sum();
            let sigma = want.std_error.iter().map(|e| e * e).sum::<f64>().sqrt() / w;
            let err = (got - w) / w;
            println!(
                "{} face {f}: baked {got:.4}, path-traced {w:.4} ({:+.2}%, sigma {:.2}%)",
                object.name,
                100.0 * err,
                100.0 * sigma
            );
            assert!(sigma < 0.02, "reference too noisy ({sigma})");
            bias_num += got * area;
            bias_den += w * area;
            // Three of the reference's standard errors are allowed on top of the bound.
            let excess = err.abs() - 3.0 * sigma;
            if excess > worst.0 {
                worst = (
                    excess,
                    format!("{} face {f}: {:+.2}%", object.name, 100.0 * err),
                );
            }
        }
    }
    // The room's six faces, 18 triangles each.
    let mut worst_room = (0.0f64, String::new());
    for f in 0..6 {
        let tris: Vec<usize> = (f * 18..(f + 1) * 18).collect();
        let (mut sum, mut area) = (0.0f64, 0.0f64);
        for &t in &tris {
            let [a, b, c] = scene.objects[0].corners(t);
            let ar = f64::from((b - a).cross(c - a).length() * 0.5);
            let root = baked.objects[0].triangles[t].colours[0];
            sum += ar * root.iter().map(|&v| f64::from(v)).sum::<f64>();
            area += ar;
        }
        let got = sum / area;
        let want = tracer.surface_radiance(0, &tris, paths, 0xabc + f as u64);
        let w: f64 = want.mean.iter().sum();
        let sigma = want.std_error.iter().map(|e| e * e).sum::<f64>().sqrt() / w;
        let err = (got - w) / w;
        println!(
            "room face {f}: baked {got:.4}, path-traced {w:.4} ({:+.2}%, sigma {:.2}%)",
            100.0 * err,
            100.0 * sigma
        );
        let excess = err.abs() - 3.0 * sigma;
        if excess > worst_room.0 {
            worst_room = (excess, format!("room face {f}: {:+.2}%", 100.0 * err));
        }
    }
    assert!(
        worst_room.0 < ROOM,
        "{} (beyond three standard errors)",
        worst_room.1
    );
    let bias = bias_num / bias_den - 1.0;
    println!("objects' bias {:+.2}%", 100.0 * bias);
    assert!(bias.abs() < BIAS, "objects' bias {:+.2}%", 100.0 * bias);
    assert!(worst.0 < FACE, "{} (beyond three standard errors)", worst.1);
}

/// Bounds, from what the solver achieves (BENCHMARKS.md): before emitters were kept out of
/// mixed clusters every face was too dark, the objects by 5.8% and the ceiling by 12%.
///
/// Bound on the objects' area-weighted bias against the path tracer.
const BIAS: f64 = 0.02;
/// Bound on any face's error beyond three of the reference's standard errors.
const FACE: f64 = 0.05;
/// Bound on any face of the room's error beyond three of the reference's standard errors.
const ROOM: f64 = 0.03;
