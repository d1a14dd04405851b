//! Known-answer tests of the CPU Loop subdivision: counts, weights, planarity, invariance
//! under relabeling, watertightness, numbering, determinism and error handling.

#![allow(clippy::needless_range_loop)]

mod common;

use std::collections::HashMap;
use std::path::Path;

use hce_geometry::lattice::subtriangle_cells;
use hce_geometry::subdivide::{subdivide, SubdivError};
use hce_geometry::topology::{build_control_mesh, Topology, TopologyConfig};

fn data_mesh(name: &str) -> Topology {
    common::control_mesh(
        &Path::new(env!("CARGO_MANIFEST_DIR")).join(format!("tests/data/{name}.obj")),
        &TopologyConfig::default(),
    )
}

fn build(p: &[[f32; 3]], t: &[[u32; 3]]) -> Topology {
    build_control_mesh(p, t, None, &TopologyConfig::default()).unwrap()
}

/// A regular (valence 6 inside) triangulated grid of `n x n` quads with heights `z(i, j)`.
fn grid(n: usize, z: impl Fn(usize, usize) -> f32) -> (Vec<[f32; 3]>, Vec<[u32; 3]>) {
    let mut p = Vec::new();
    for j in 0..=n {
        for i in 0..=n {
            p.push([i as f32, j as f32, z(i, j)]);
        }
    }
    let mut t = Vec::new();
    for j in 0..n {
        for i in 0..n {
            let a = (j * (n + 1) + i) as u32;
            let (b, c, d) = (a + 1, a + n as u32 + 2, a + n as u32 + 1);
            t.push([a, b, c]);
            t.push([a, c, d]);
        }
    }
    (p, t)
}

#[test]
fn counts_follow_f4_and_v_plus_e_per_level() {
    for name in ["octahedron", "fan7_open", "grid_open", "bipyramid9"] {
        let t = data_mesh(name);
        let (mut v, mut e, mut f) = (t.report.vertices, t.report.edges, t.report.triangles);
        for level in 1..=4 {
            // One level: every edge adds a vertex and splits in two, every face adds 3 edges.
            (v, e, f) = (v + e, 2 * e + 3 * f, 4 * f);
            let r = subdivide(&t.mesh, level).unwrap();
            assert_eq!(r.positions.len(), v, "{name} level {level}");
            assert_eq!(r.normals.len(), v);
            assert_eq!(r.indices.len(), f, "{name} level {level}");
        }
    }
}

#[test]
fn valence_six_vertex_gets_weights_ten_and_one_sixteenths() {
    let (p, t) = grid(4, |i, j| ((i * 7 + j * 3) % 5) as f32 * 0.1);
    let topo = build(&p, &t);
    let r = subdivide(&topo.mesh, 1).unwrap();
    let v = 12u32; // the centre of the 5 x 5 grid
    let ring = topo.mesh.ring_of(v);
    assert_eq!(ring.len(), 6);
    for k in 0..3 {
        let s: f32 = ring.iter().map(|&n| p[n as usize][k]).sum();
        let expected = 10.0 / 16.0 * p[v as usize][k] + s / 16.0;
        assert!((r.positions[v as usize][k] - expected).abs() < 1e-6);
    }
    // An edge point between v and its first spoke: 3/8, 3/8, 1/8, 1/8.
    let (a, b) = (v as usize, ring[0] as usize);
    let (c, d) = (ring[5] as usize, ring[1] as usize);
    let expected: Vec<f32> = (0..3)
        .map(|k| 0.375 * (p[a][k] + p[b][k]) + 0.125 * (p[c][k] + p[d][k]))
        .collect();
    assert!(
        r.positions
            .iter()
            .any(|q| (0..3).all(|k| (q[k] - expected[k]).abs() < 1e-6)),
        "no edge point at {expected:?}"
    );
}

#[test]
fn planar_regular_patch_stays_planar() {
    let plane = |x: f32, y: f32| 0.3 * x - 0.2 * y + 1.0;
    let (p, t) = grid(6, |i, j| plane(i as f32, j as f32));
    let topo = build(&p, &t);
    let r = subdivide(&topo.mesh, 3).unwrap();
    let worst = r
        .positions
        .iter()
        .map(|q| (q[2] - plane(q[0], q[1])).abs())
        .fold(0.0f32, f32::max);
    assert!(worst < 1e-5, "off the plane by {worst}");
    let n = [-0.3f32, 0.2, 1.0];
    let len = (n[0] * n[0] + n[1] * n[1] + n[2] * n[2]).sqrt();
    for m in &r.normals {
        let dot = (m[0] * n[0] + m[1] * n[1] + m[2] * n[2]) / len;
        assert!(dot > 0.9999, "normal {m:?}");
    }
}

#[test]
fn invariant_under_vertex_relabeling_and_index_rotation() {
    let t = data_mesh("icosahedron");
    let p: Vec<[f32; 3]> = t
        .mesh
        .positions
        .chunks(3)
        .map(|c| [c[0], c[1], c[2]])
        .collect();
    let tris: Vec<[u32; 3]> = t
        .mesh
        .triangles
        .chunks(3)
        .map(|c| [c[0], c[1], c[2]])
        .collect();
    let nv = p.len() as u32;
    let perm: Vec<u32> = (0..nv).map(|i| (i * 5 + 3) % nv).collect(); // 5 is prime to 12
    let mut p2 = vec![[0.0; 3]; p.len()];
    for (i, &j) in perm.iter().enumerate() {
        p2[j as usize] = p[i];
    }
    let mut t2: Vec<[u32; 3]> = tris
        .iter()
        .enumerate()
        .map(|(k, tr)| {
            let r = tr.map(|i| perm[i as usize]);
            match k % 3 {
                0 => r,
                1 => [r[1], r[2], r[0]],
                _ => [r[2], r[0], r[1]],
            }
        })
        .collect();
    t2.reverse();
    let a = subdivide(&t.mesh, 3).unwrap();
    let b = subdivide(&build(&p2, &t2).mesh, 3).unwrap();
    assert_eq!(a.positions.len(), b.positions.len());
    let d = common::relative_hausdorff(&a.positions, &b.positions);
    assert!(d < 1e-6, "relative distance {d:e}");
}

/// Every directed edge of the output appears once and, on a closed mesh, its reverse too; no
/// two output vertices share a position.
#[test]
fn output_is_watertight_and_consistently_oriented() {
    for (name, closed) in [
        ("icosahedron", true),
        ("bifan7", true),
        ("fan7_open", false),
    ] {
        let t = data_mesh(name);
        let r = subdivide(&t.mesh, 3).unwrap();
        let mut directed: HashMap<(u32, u32), usize> = HashMap::new();
        for tri in &r.indices {
            for e in 0..3 {
                *directed.entry((tri[e], tri[(e + 1) % 3])).or_default() += 1;
            }
        }
        assert!(
            directed.values().all(|&c| c == 1),
            "{name}: repeated directed edge"
        );
        let open = directed
            .keys()
            .filter(|(a, b)| !directed.contains_key(&(*b, *a)))
            .count();
        if closed {
            assert_eq!(open, 0, "{name}");
        } else {
            // fan7_open: 6 rim edges + 2 open spokes, less the rim edge the ear covers, plus
            // the ear's two: 9 coarse boundary edges, each split into 8.
            assert_eq!(t.report.boundary_edges, 9);
            assert_eq!(open, 9 * 8, "{name}");
        }
        let mut seen = HashMap::new();
        for (i, p) in r.positions.iter().enumerate() {
            assert!(
                seen.insert(p.map(f32::to_bits), i).is_none(),
                "{name}: duplicate vertex {i}"
            );
        }
    }
}

#[test]
fn normals_are_unit_and_point_outwards_on_a_convex_solid() {
    let t = data_mesh("icosahedron");
    let r = subdivide(&t.mesh, 2).unwrap();
    for (p, n) in r.positions.iter().zip(&r.normals) {
        let len = (n[0] * n[0] + n[1] * n[1] + n[2] * n[2]).sqrt();
        assert!((len - 1.0).abs() < 1e-5);
        assert!(p[0] * n[0] + p[1] * n[1] + p[2] * n[2] > 0.0);
    }
}

#[test]
fn fine_triangles_follow_the_path_numbering() {
    let cells = subtriangle_cells(1);
    assert_eq!(
        cells,
        vec![
            [[0, 0], [1, 0], [0, 1]],
            [[1, 0], [2, 0], [1, 1]],
            [[1, 1], [0, 1], [1, 0]],
            [[0, 1], [1, 1], [0, 2]],
        ]
    );
    // Level 2, path 0b0110 = Left then Center.
    assert_eq!(subtriangle_cells(2)[6], [[3, 1], [2, 1], [3, 0]]);
    let t = data_mesh("tetrahedron");
    let r = subdivide(&t.mesh, 2).unwrap();
    assert_eq!(r.coarse_triangle(37), 2);
    assert_eq!(r.path(37), 5);
    // The Top child at every level keeps the coarse corner v0 (coarse vertices come first).
    for tri in 0..4 {
        assert_eq!(r.indices[tri * 16][0], t.mesh.triangles[3 * tri]);
        assert_eq!(r.indices[tri * 16 + 5][1], t.mesh.triangles[3 * tri + 1]);
        assert_eq!(r.indices[tri * 16 + 15][2], t.mesh.triangles[3 * tri + 2]);
    }
}

#[test]
fn output_is_identical_with_one_or_two_threads() {
    let t = data_mesh("bipyramid9");
    let one = rayon::ThreadPoolBuilder::new()
        .num_threads(1)
        .build()
        .unwrap();
    let two = rayon::ThreadPoolBuilder::new()
        .num_threads(2)
        .build()
        .unwrap();
    let a = one.install(|| subdivide(&t.mesh, 4).unwrap());
    let b = two.install(|| subdivide(&t.mesh, 4).unwrap());
    assert_eq!(a, b);
}

#[test]
fn bad_levels_and_broken_tables_are_errors() {
    let t = data_mesh("octahedron");
    assert_eq!(subdivide(&t.mesh, 7), Err(SubdivError::Level(7)));
    let mut m = t.mesh.clone();
    m.corner_spokes[4] = 99;
    assert!(matches!(subdivide(&m, 2), Err(SubdivError::Tables(_))));
    let mut m = t.mesh.clone();
    m.ring_offsets.pop();
    assert!(matches!(subdivide(&m, 2), Err(SubdivError::Tables(_))));
    let mut m = t.mesh.clone();
    m.edges[5] = 1000;
    assert!(matches!(subdivide(&m, 2), Err(SubdivError::Tables(_))));
    let mut m = t.mesh.clone();
    m.ring[0] = 1 << 30;
    assert!(matches!(subdivide(&m, 1), Err(SubdivError::Tables(_))));
    // An offset past the ring array, caught before the ring is sliced (this used to panic).
    let mut m = t.mesh.clone();
    m.ring_offsets[1] = 10_000;
    assert_eq!(
        subdivide(&m, 1),
        Err(SubdivError::Tables(
            "mesh.ring_offsets[1]: ring offsets decrease".into()
        ))
    );
}
