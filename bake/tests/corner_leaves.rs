//! The leaves along a room's corners: where two walls meet, the bend rule refines one
//! level below `max_level`, so that the light's fall into the corner is not drawn as a bright
//! line one leaf wide. Alike whether the walls are separate objects or one object whose faces
//! share their edges: a room whose walls were one object beside a separate floor stopped at
//! `max_level` along its vertical corners, where the floor's links had taken the leaves deeper,
//! and those leaves read 6% off in a closed furnace (`furnace_property.rs`, `large_faces`).

use glam::Vec3;
use hce_bake::ElemKey;
use hce_bake::{bake, BakeParams, BakeResult, Scene, SolverObject};

const SIZE: f32 = 2.0;

/// A closed 2 m cube room, each face two triangles facing in, lit by its emitting ceiling: six
/// objects, or one whose faces share their edges. No punctual light and no lamp of its own: a
/// punctual light's direct light refines leaves below `max_level` everywhere (the direct-light
/// edge rule), and a lamp, another object, bends the light of every wall leaf near it.
fn room(separate: bool) -> Scene {
    let centre = Vec3::splat(SIZE / 2.0);
    let mut faces: Vec<[Vec3; 4]> = Vec::new();
    for axis in 0..3 {
        for side in [0.0, SIZE] {
            let (u, v) = ((axis + 1) % 3, (axis + 2) % 3);
            let at = |a: f32, b: f32| {
                let mut p = Vec3::ZERO;
                p[axis] = side;
                p[u] = a;
                p[v] = b;
                p
            };
            let mut q = [at(0.0, 0.0), at(SIZE, 0.0), at(SIZE, SIZE), at(0.0, SIZE)];
            let n = (q[1] - q[0]).cross(q[2] - q[0]);
            if n.dot(centre - q[0]) < 0.0 {
                q.reverse();
            }
            faces.push(q);
        }
    }
    let object = |name: String, faces: &[[Vec3; 4]]| -> SolverObject {
        let mut positions: Vec<[f32; 3]> = Vec::new();
        let mut triangles = Vec::new();
        for q in faces {
            let mut index = |p: Vec3| {
                let p = p.to_array();
                match positions.iter().position(|x| *x == p) {
                    Some(i) => i as u32,
                    None => {
                        positions.push(p);
                        positions.len() as u32 - 1
                    }
                }
            };
            let [a, b, c, d] = q.map(&mut index);
            triangles.push([a, b, c]);
            triangles.push([a, c, d]);
        }
        SolverObject::new(name, positions, triangles, [0.7; 3])
    };
    let mut objects: Vec<SolverObject> = if separate {
        faces
            .iter()
            .enumerate()
            .map(|(i, q)| object(format!("face {i}"), std::slice::from_ref(q)))
            .collect()
    } else {
        vec![object("room".into(), &faces)]
    };
    // The ceiling (y = SIZE) is the fourth face.
    if separate {
        objects[3].emission = vec![[1.0; 3]; 2];
    } else {
        objects[0].emission = (0..12)
            .map(|t| if t / 2 == 3 { [1.0; 3] } else { [0.0; 3] })
            .collect();
    }
    Scene {
        objects,
        lights: Vec::new(),
    }
}

/// How many leaves with a corner on one of the room's edges (two coordinates on the room's
/// faces) lie deeper than `level`.
fn edge_leaves_below(scene: &Scene, result: &BakeResult, level: u32) -> usize {
    let on_face = |x: f32| x.abs() < 1e-4 || (x - SIZE).abs() < 1e-4;
    let mut count = 0;
    for (o, solution) in scene.objects.iter().zip(&result.objects) {
        for (t, tri) in solution.triangles.iter().enumerate() {
            let corners = o.corners(t);
            for (k, &(l, path)) in tri.nodes.iter().enumerate() {
                if tri.subdivided[k] || l <= level {
                    continue;
                }
                let key = ElemKey {
                    root: 0,
                    level: l,
                    path,
                };
                let on_edge = key
                    .corners(corners)
                    .iter()
                    .any(|p| p.to_array().iter().filter(|&&x| on_face(x)).count() >= 2);
                count += usize::from(on_edge);
            }
        }
    }
    count
}

#[test]
fn walls_are_refined_one_level_deeper_along_their_corners() {
    let params = BakeParams {
        max_level: 3,
        ..BakeParams::default()
    };
    let separate = room(true);
    let joined = room(false);
    let deep_separate = edge_leaves_below(&separate, &bake(&separate, &params).unwrap(), 3);
    let deep_joined = edge_leaves_below(&joined, &bake(&joined, &params).unwrap(), 3);
    eprintln!(
        "leaves along the edges below max_level: separate walls {deep_separate}, one object \
         {deep_joined}"
    );
    // Along every edge: each side of each of the 12 edges is 8 leaf edges long at level 3,
    // each at least two leaves at level 4.
    for (name, deep) in [
        ("separate walls", deep_separate),
        ("one object", deep_joined),
    ] {
        assert!(deep >= 12 * 8 * 2 * 2, "{name}: {deep}");
    }
}
