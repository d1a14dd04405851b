//! What the receivers of a lit room gather, against the exact transport over the baked leaves
//! (walls and ceilings of lit rooms came out 1-2% darker than a path tracer shows
//! them, and objects 1% darker, while a closed furnace was right to within 1%).
//!
//! A closed 3 × 3 × 2.5 m room, each face a 3 × 3 grid of quads, the middle quad of the
//! ceiling a lamp flush with it. The floor is bright under the lamp and dims towards the walls,
//! so what a wall or the ceiling gathers depends on which part of the floor it sees most of: a
//! link that gathers its source's mean radiance, where its receiver sees the bright part more
//! than the dim, brings too little (the ceiling sees the floor's bright middle best of all).
//! That is what a closed furnace cannot show: there every source is as bright as the next.
//!
//! The check is on transport alone, so it is exact whatever the solution: the room is convex,
//! so what a point of a room triangle gathers is the sum, over the baked leaves of every other
//! face and the lamp, of the analytic point-to-polygon form factor times the leaf's radiance.
//! Averaged over each triangle and compared with its baked radiance over its reflectance, face
//! by face.

mod common;

use glam::Vec3;
use hce_bake::{bake, BakeParams, Scene, SolverObject};
use hce_bake::{point_to_polygon, stratified_points};

const RHO: f32 = 0.6;

fn scene() -> Scene {
    let s = Vec3::new(3.0, 3.0, 2.5);
    let inside = s * 0.5;
    let (mut pos, mut tris) = (Vec::new(), Vec::new());
    let (mut lamp_pos, mut lamp_tris) = (Vec::new(), Vec::new());
    for (f, (o, u, v)) in common::box_faces(s).into_iter().enumerate() {
        for i in 0..3 {
            for j in 0..3 {
                let o = o + u * (i as f32 / 3.0) + v * (j as f32 / 3.0);
                let (u, v) = (u / 3.0, v / 3.0);
                // Face 1 is the ceiling (z = 2.5): its middle quad is the lamp.
                let (p, t): (&mut Vec<[f32; 3]>, &mut Vec<[u32; 3]>) = if f == 1 && i == 1 && j == 1
                {
                    (&mut lamp_pos, &mut lamp_tris)
                } else {
                    (&mut pos, &mut tris)
                };
                for corners in [[o, o + u, o + v], [o + u + v, o + v, o + u]] {
                    let base = p.len() as u32;
                    p.extend(corners.map(|c| c.to_array()));
                    let [a, b, c] = corners;
                    let faces_in = (b - a).cross(c - a).dot(inside - (a + b + c) / 3.0) > 0.0;
                    t.push(if faces_in {
                        [base, base + 1, base + 2]
                    } else {
                        [base, base + 2, base + 1]
                    });
                }
            }
        }
    }
    let room = SolverObject::new("room", pos, tris, [RHO; 3]);
    let lamp = SolverObject::new("lamp", lamp_pos, lamp_tris, [0.0; 3]).with_emission([10.0; 3]);
    Scene {
        objects: vec![room, lamp],
        lights: Vec::new(),
    }
}

#[test]
fn a_lit_rooms_faces_gather_what_their_sources_send() {
    let scene = scene();
    let res = bake(&scene, &BakeParams::default()).unwrap();
    let mut sources = common::leaves(&scene, &res, 0);
    sources.extend(common::leaves(&scene, &res, 1));
    let room = &scene.objects[0];
    // Room triangles in face order, 18 a face but 16 on the ceiling (face 1).
    let mut first = 0;
    let mut worst = (0.0f64, String::new());
    for (f, name) in [
        "floor", "ceiling", "wall x=0", "wall x=3", "wall y=0", "wall y=3",
    ]
    .into_iter()
    .enumerate()
    {
        let count = if f == 1 { 16 } else { 18 };
        let (mut baked, mut exact) = (0.0f64, 0.0f64);
        for t in first..first + count {
            let tri = room.corners(t);
            let cross = (tri[1] - tri[0]).cross(tri[2] - tri[0]);
            let (n, a) = (cross.normalize(), f64::from(cross.length() * 0.5));
            let pts = stratified_points(tri, 2);
            let q: f64 = pts
                .iter()
                .map(|&p| {
                    sources
                        .iter()
                        .map(|(leaf, l)| f64::from(point_to_polygon(p, n, leaf) * l))
                        .sum::<f64>()
                })
                .sum::<f64>()
                / pts.len() as f64;
            baked += a * f64::from(res.objects[0].triangles[t].colours[0][0] / RHO);
            exact += a * q;
        }
        first += count;
        let err = baked / exact - 1.0;
        println!(
            "{name}: gathered {:+.2}% against the exact transport",
            100.0 * err
        );
        if err.abs() > worst.0 {
            worst = (err.abs(), format!("{name}: {:+.2}%", 100.0 * err));
        }
    }
    println!("{} links", res.stats.links);
    assert!(worst.0 < GATHER_TOLERANCE, "{}", worst.1);
}

/// Bound on a face's gathered light against the exact transport : while links gathered their sources' mean radiance the ceiling was 1.27% short and
/// the walls 0.5%; reading it where the receiver looks leaves -0.80% and -0.26% to -0.33%.
const GATHER_TOLERANCE: f64 = 0.01;
