//! Helpers shared by the integration tests: the import-to-control-mesh pipeline, OBJ point
//! reading, and the point-set distance used to compare with OpenSubdiv's output (whose vertex
//! numbering differs from ours).
#![allow(dead_code)]
#![allow(clippy::needless_range_loop)]

use std::collections::HashMap;
use std::path::Path;

use hce_geometry::topology::{Topology, TopologyConfig};

/// Loads, welds (bitwise) and builds the control mesh, as `hce subdivide` does.
pub fn control_mesh(path: &Path, config: &TopologyConfig) -> Topology {
    let input = hce_meshio::load_mesh(path).unwrap();
    let w = hce_geometry::weld(&input.positions, 0.0);
    let tris = w.triangles(&input.triangles);
    hce_geometry::topology::build_control_mesh(
        &w.positions,
        &tris,
        input.corner_normals.as_deref(),
        config,
    )
    .unwrap()
}

/// The `v` lines of an OBJ text.
pub fn obj_points(text: &str) -> Vec<[f32; 3]> {
    text.lines()
        .filter_map(|l| l.strip_prefix("v "))
        .map(|l| {
            let v: Vec<f32> = l.split_whitespace().map(|x| x.parse().unwrap()).collect();
            [v[0], v[1], v[2]]
        })
        .collect()
}

pub fn bbox_diagonal(p: &[[f32; 3]]) -> f64 {
    let mut lo = [f64::INFINITY; 3];
    let mut hi = [f64::NEG_INFINITY; 3];
    for q in p {
        for k in 0..3 {
            lo[k] = lo[k].min(q[k] as f64);
            hi[k] = hi[k].max(q[k] as f64);
        }
    }
    (0..3).map(|k| (hi[k] - lo[k]).powi(2)).sum::<f64>().sqrt()
}

/// Largest distance from a point of `a` to its nearest point of `b` and vice versa, relative
/// to `b`'s bounding-box diagonal, plus the point counts (which must agree too).
pub fn relative_hausdorff(a: &[[f32; 3]], b: &[[f32; 3]]) -> f64 {
    let diag = bbox_diagonal(b);
    directed(a, b, diag).max(directed(b, a, diag)) / diag
}

/// Max over `a` of the distance to the nearest point of `b`, relative to `b`'s bounding-box
/// diagonal (for a sample `a` of a larger set).
pub fn relative_directed(a: &[[f32; 3]], b: &[[f32; 3]]) -> f64 {
    let diag = bbox_diagonal(b);
    directed(a, b, diag) / diag
}

/// Max over `a` of the distance to the nearest point of `b`, via a uniform grid whose cell is
/// far larger than the tolerance we test (so the 27 neighbouring cells always suffice when
/// the sets match; a larger mismatch shows up as a large, still correct, lower bound).
fn directed(a: &[[f32; 3]], b: &[[f32; 3]], diag: f64) -> f64 {
    let cell = diag / (b.len() as f64).cbrt().max(1.0) * 0.5;
    let key = |p: &[f32; 3]| p.map(|c| (c as f64 / cell).floor() as i64);
    let mut grid: HashMap<[i64; 3], Vec<usize>> = HashMap::new();
    for (i, p) in b.iter().enumerate() {
        grid.entry(key(p)).or_default().push(i);
    }
    let mut worst: f64 = 0.0;
    for p in a {
        let k = key(p);
        let mut best = f64::INFINITY;
        for dx in -1..=1 {
            for dy in -1..=1 {
                for dz in -1..=1 {
                    if let Some(list) = grid.get(&[k[0] + dx, k[1] + dy, k[2] + dz]) {
                        for &i in list {
                            let q = b[i];
                            let d = (0..3)
                                .map(|c| (p[c] as f64 - q[c] as f64).powi(2))
                                .sum::<f64>()
                                .sqrt();
                            best = best.min(d);
                        }
                    }
                }
            }
        }
        if !best.is_finite() {
            best = cell;
        }
        worst = worst.max(best);
    }
    worst
}

/// The control mesh as OBJ text (what OpenSubdiv is given: no welding left to do).
pub fn control_obj(t: &Topology) -> String {
    use std::fmt::Write;
    let mut s = String::new();
    for p in t.mesh.positions.chunks_exact(3) {
        let _ = writeln!(s, "v {:.9e} {:.9e} {:.9e}", p[0], p[1], p[2]);
    }
    for f in t.mesh.triangles.chunks_exact(3) {
        let _ = writeln!(s, "f {} {} {}", f[0] + 1, f[1] + 1, f[2] + 1);
    }
    s
}
