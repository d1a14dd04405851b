//! Shapes the solver's scene tests share (each test uses some of them).
#![allow(dead_code)]

use glam::Vec3;

/// The faces of an octahedron of radius `r` at `c`, each as its three corners.
pub fn octahedron_faces(c: Vec3, r: f32) -> [[Vec3; 3]; 8] {
    let v = [Vec3::X, -Vec3::X, Vec3::Y, -Vec3::Y, Vec3::Z, -Vec3::Z].map(|d| c + d * r);
    [
        (0, 2, 4),
        (2, 1, 4),
        (1, 3, 4),
        (3, 0, 4),
        (2, 0, 5),
        (1, 2, 5),
        (3, 1, 5),
        (0, 3, 5),
    ]
    .map(|(i, j, k)| [v[i], v[j], v[k]])
}

/// The triangle `a, b, c` cut into `n²` triangles by a barycentric grid, each handed to `add`
/// as its three corners, rows of increasing distance from `a` first.
pub fn barycentric_grid([a, b, c]: [Vec3; 3], n: u32, mut add: impl FnMut(Vec3, Vec3, Vec3)) {
    let p = |i: u32, j: u32| a + (b - a) * (i as f32 / n as f32) + (c - a) * (j as f32 / n as f32);
    for j in 0..n {
        for i in 0..n - j {
            add(p(i, j), p(i + 1, j), p(i, j + 1));
            if i + j + 1 < n {
                add(p(i + 1, j), p(i + 1, j + 1), p(i, j + 1));
            }
        }
    }
}

/// The six faces of the box `[0, s]` as (origin, first side, second side), in the order
/// z = 0, z = s.z, x = 0, x = s.x, y = 0, y = s.y.
pub fn box_faces(s: Vec3) -> [(Vec3, Vec3, Vec3); 6] {
    let (x, y, z) = (Vec3::X * s.x, Vec3::Y * s.y, Vec3::Z * s.z);
    [
        (Vec3::ZERO, x, y),
        (z, x, y),
        (Vec3::ZERO, y, z),
        (x, y, z),
        (Vec3::ZERO, z, x),
        (y, z, x),
    ]
}

/// Every leaf element of object `o`: corners and radiance (first channel).
pub fn leaves(
    scene: &hce_bake::Scene,
    res: &hce_bake::BakeResult,
    o: usize,
) -> Vec<([Vec3; 3], f32)> {
    let mut out = Vec::new();
    for (t, ts) in res.objects[o].triangles.iter().enumerate() {
        let nn = ts.normals.len();
        for (i, &(level, path)) in ts.nodes.iter().enumerate() {
            if !ts.subdivided[i] {
                let key = hce_bake::ElemKey {
                    root: 0,
                    level,
                    path,
                };
                out.push((
                    key.corners(scene.objects[o].corners(t)),
                    ts.colours[i * nn][0],
                ));
            }
        }
    }
    out
}

/// Paths per estimate of the path-traced tests: `HCE_REFERENCE_PATHS`, default 16384.
pub fn reference_paths() -> u64 {
    std::env::var("HCE_REFERENCE_PATHS")
        .ok()
        .and_then(|v| v.parse().ok())
        .unwrap_or(16384)
}
