//! A finely tessellated ball beside a bright patch on a large floor (the darkening of
//! curved objects): a lamp tilted away from the ball lights a patch of the floor about a metre
//! across, so the floor's radiance runs from that patch to dim far corners, and the ball, which
//! sees only the floor and the lamp's black back, gathers all its light from it while each of
//! its coarse triangles is tiny. The refinement oracle weighed a source's radiance variation
//! against the receiving coarse triangle alone, so the floor stayed one source for every ball
//! triangle and the ball gathered the floor's mean radiance instead of the bright patch it
//! faces: 63% too little on the sides facing the patch (the sides of the multiresolution
//! objects in `gen-samples room` were 5% too dark that way). (With a ball of half the size,
//! this scene also showed a cluster seen from behind sending light: the lamp's two triangles,
//! one cluster, gave the ball 2.4 times what the floor gives it; `cluster.rs` tests that.)
//!
//! The check is on transport alone, so it is exact whatever the floor's own solution: the ball
//! is convex and nothing else stands in the scene, so what a point of a ball triangle gathers
//! is the sum, over the baked leaf elements of the floor and the lamp, of the analytic
//! point-to-polygon form factor (zero from behind) times the leaf's radiance. Averaged over
//! each ball triangle and compared with the triangle's baked radiance over its reflectance.

mod common;

use glam::Vec3;
use hce_bake::{bake, BakeParams, Scene, SolverObject};
use hce_bake::{point_to_polygon, stratified_points};

const RHO: f32 = 0.5;

/// A UV sphere of `rings` rings and `2 rings` segments (`4 rings² − 4 rings` triangles),
/// counter-clockwise seen from outside.
fn ball(c: Vec3, r: f32, rings: u32) -> SolverObject {
    let segs = rings * 2;
    let mut pos = Vec::new();
    let mut tris = Vec::new();
    for j in 0..=rings {
        let th = std::f32::consts::PI * j as f32 / rings as f32;
        for i in 0..segs {
            let ph = std::f32::consts::TAU * i as f32 / segs as f32;
            let d = Vec3::new(th.sin() * ph.cos(), th.cos(), th.sin() * ph.sin());
            pos.push((c + d * r).to_array());
        }
    }
    for j in 0..rings {
        for i in 0..segs {
            let a = j * segs + i;
            let b = j * segs + (i + 1) % segs;
            let (a2, b2) = (a + segs, b + segs);
            if j != 0 {
                tris.push([a, b, a2]);
            }
            if j != rings - 1 {
                tris.push([b, b2, a2]);
            }
        }
    }
    let mut o = SolverObject::new("ball", pos, tris, [RHO; 3]);
    o.multires = true;
    o
}

fn scene() -> Scene {
    // An 8 m floor facing up, two triangles.
    let h = 4.0;
    let floor = SolverObject::new(
        "floor",
        vec![[-h, 0.0, -h], [-h, 0.0, h], [h, 0.0, h], [h, 0.0, -h]],
        vec![[0, 1, 2], [0, 2, 3]],
        [RHO; 3],
    );
    // A 0.5 m lamp 1 m above the floor and 1.5 m to the side of the ball, facing down and
    // tilted 30 degrees away from the ball (which sees only its black back): it lights a patch
    // of the floor about a metre across, far brighter than the floor's mean.
    let (c, e) = (Vec3::new(1.5, 1.0, 0.0), 0.25);
    let (s30, c30) = (0.5, 0.75f32.sqrt());
    // In the lamp's plane: along z, and along x tilted up by 30 degrees.
    let (u, w) = (Vec3::new(c30, s30, 0.0) * e, Vec3::Z * e);
    let lamp = SolverObject::new(
        "lamp",
        [c - u - w, c - u + w, c + u + w, c + u - w]
            .map(|p| p.to_array())
            .to_vec(),
        vec![[0, 2, 1], [0, 3, 2]],
        [0.0; 3],
    )
    .with_emission([10.0; 3]);
    // A ball of 0.1 m radius, its triangles under a square centimetre each.
    let ball = ball(Vec3::new(0.0, 0.5, 0.0), 0.2, 24);
    Scene {
        objects: vec![floor, lamp, ball],
        lights: Vec::new(),
    }
}

#[test]
fn a_finely_tessellated_ball_gathers_the_bright_patch_it_faces() {
    let scene = scene();
    let res = bake(&scene, &BakeParams::default()).unwrap();
    // Everything in the scene but the ball (the lamp's back sends nothing).
    let mut sources = common::leaves(&scene, &res, 0);
    sources.extend(common::leaves(&scene, &res, 1));
    let ball = &scene.objects[2];
    // Ball triangles facing the bright patch (sideways, towards +x): baked against exact.
    let (mut baked, mut exact, mut area) = (0.0f64, 0.0f64, 0.0f64);
    let mut worst = 0.0f64;
    for t in 0..ball.triangles.len() {
        let tri = ball.corners(t);
        let cross = (tri[1] - tri[0]).cross(tri[2] - tri[0]);
        let n = cross.normalize();
        if n.x < 0.7 || n.y.abs() > 0.5 {
            continue;
        }
        let a = f64::from(cross.length() * 0.5);
        let pts = stratified_points(tri, 3);
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
        let got = f64::from(res.objects[2].triangles[t].colours[0][0] / RHO);
        worst = worst.max(((got - q) / q).abs());
        baked += a * got;
        exact += a * q;
        area += a;
    }
    let err = (baked - exact) / exact;
    println!(
        "ball sides facing the patch: {area:.4} m2, gathered {:.5} baked against {:.5} exact \
         ({:+.2}%), worst triangle {:.1}%; {} links",
        baked / area,
        exact / area,
        100.0 * err,
        100.0 * worst,
        res.stats.links
    );
    assert!(area > 0.01, "too few triangles face the patch: {area}");
    assert!(err.abs() < 0.03, "gathered {:+.2}% off", 100.0 * err);
}
