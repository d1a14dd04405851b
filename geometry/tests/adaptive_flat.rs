//! The adaptive flat refinement (SPEC.md F.7.1): no cracks and no T-junctions, every coarse
//! triangle covered once, and at every vertex the position and colour of the uniform refinement
//! to the deepest leaf at the same point (F.7.2), on grids with folds and random trees.
use std::collections::HashMap;

use hce_format::{rgb9e5, BitWriter, Object, ObjectKind, TriangleRecord, NO_NEIGHBOUR};
use hce_geometry::adaptive_flat::{refine_adaptive_flat, tile, AdaptiveFlatError};
use hce_geometry::lattice::fine_corners;
use hce_geometry::lighting::triangle_lighting;
use hce_geometry::normal::{face_normal, unit_or_up};
use hce_geometry::refine::{refine_object_as, FlatRefinement};
use hce_geometry::Reconstruction;

/// `object` with random breadth-first trees up to `max_depth` (one geometric normal each,
/// random colours), from a fixed seed.
fn with_random_trees(mut object: Object, seed: u64, max_depth: u32) -> Object {
    let mut state = seed;
    let mut unit = move || {
        state = state
            .wrapping_mul(6364136223846793005)
            .wrapping_add(1442695040888963407);
        (state >> 40) as f32 / (1u64 << 24) as f32
    };
    let mut bits = BitWriter::new();
    let (mut records, mut normals, mut colours) = (Vec::new(), Vec::new(), Vec::new());
    for t in 0..object.mesh.triangle_count() {
        let p = object.mesh.triangle(t).map(|v| object.mesh.position(v));
        normals.push(unit_or_up(face_normal(p)));
        let mut queue = std::collections::VecDeque::from([0u32]);
        let mut flags = Vec::new();
        while let Some(depth) = queue.pop_front() {
            let split = depth < max_depth && unit() < 0.45;
            flags.push(split);
            if split {
                queue.extend([depth + 1; 4]);
            }
        }
        records.push(TriangleRecord {
            bits_start: bits.push_tree(&flags).unwrap() as u32,
            colour_start: colours.len() as u32,
            normal_start: t as u32,
            normal_count: 1,
        });
        colours.extend(
            flags
                .iter()
                .map(|_| rgb9e5::encode([unit(), unit(), unit()])),
        );
    }
    (object.bits, object.bit_len) = bits.finish();
    object.triangles = records;
    object.normals = normals;
    object.colours = colours;
    object.kind = ObjectKind::Flat;
    object
}

/// A bumpy grid (folds above and below 10 degrees, a boundary) with random trees, and the
/// example grid's own trees (deep on every other triangle).
fn objects() -> Vec<Object> {
    let mut own = hce_format::example::grid(4, 5).objects.remove(0);
    own.kind = ObjectKind::Flat;
    let base = hce_format::example::grid(4, 0).objects.remove(0);
    vec![
        own,
        with_random_trees(base.clone(), 1, 5),
        with_random_trees(base, 7, 6),
    ]
}

fn lattice_area(t: [[u32; 2]; 3]) -> i64 {
    let [a, b, c] = t.map(|p| p.map(i64::from));
    (b[0] - a[0]) * (c[1] - a[1]) - (b[1] - a[1]) * (c[0] - a[0])
}

#[test]
fn tiling_a_leaf_adds_one_triangle_per_hanging_point() {
    let (a, b, c) = ([0, 0], [8, 0], [0, 8]);
    let run = |points: &[[i32; 2]]| {
        let mut out = Vec::new();
        tile(a, b, c, &|p| points.contains(&p), &mut out);
        out
    };
    assert_eq!(run(&[]), vec![[a, b, c]]);
    // One midpoint: a bisection towards the opposite corner.
    assert_eq!(run(&[[4, 0]]), vec![[a, [4, 0], c], [[4, 0], b, c]]);
    // Three: the 1-to-4 split in the child order of SPEC.md 2.2.
    assert_eq!(
        run(&[[4, 0], [4, 4], [0, 4]]),
        vec![
            [a, [4, 0], [0, 4]],
            [[4, 0], b, [4, 4]],
            [[4, 4], [0, 4], [4, 0]],
            [[0, 4], [4, 4], c]
        ]
    );
    // Two, a quarter point and points off the leaf's edges (ignored).
    for points in [
        vec![[4, 4], [0, 4]],
        vec![[4, 0], [2, 0], [6, 2], [4, 4], [1, 1]],
        vec![[0, 4], [0, 2], [0, 6], [0, 1], [4, 4], [2, 6]],
    ] {
        let out = run(&points);
        let hanging = points
            .iter()
            .filter(|p| p[0] == 0 || p[1] == 0 || p[0] + p[1] == 8)
            .count();
        assert_eq!(out.len(), hanging + 1, "{points:?}");
        let area: i64 = out
            .iter()
            .map(|t| lattice_area(t.map(|p| p.map(|x| x as u32))))
            .sum();
        assert_eq!(area, 64, "{points:?}");
        assert!(out
            .iter()
            .all(|t| lattice_area(t.map(|p| p.map(|x| x as u32))) > 0));
    }
}

/// Every triangle side is used once each way, by index and by position, except sides on a
/// coarse boundary edge (once) and on a split edge (once by index; both ways by position,
/// the two sides' copies sitting on the same points).
#[test]
fn no_cracks_and_no_t_junctions() {
    for object in objects() {
        let r = refine_adaptive_flat(&object).unwrap();
        let mesh = &object.mesh;
        let joined = hce_geometry::split::joined_sides(mesh, object.kind);
        let mut by_index = HashMap::new();
        let mut by_position = HashMap::new();
        let bits = |i: u32| r.positions[i as usize].map(f32::to_bits);
        for (f, tri) in r.indices.iter().enumerate() {
            assert!(
                lattice_area(r.points[f]) > 0,
                "{}: triangle {f}",
                object.name
            );
            for e in 0..3 {
                let (a, b) = (tri[e], tri[(e + 1) % 3]);
                *by_index.entry((a, b)).or_insert(0) += 1;
                *by_position.entry((bits(a), bits(b))).or_insert(0) += 1;
            }
        }
        let mut split_sides = 0;
        for (f, tri) in r.indices.iter().enumerate() {
            let t = r.coarse_triangle(f);
            for e in 0..3 {
                let (a, b) = (tri[e], tri[(e + 1) % 3]);
                let (p, q) = (r.points[f][e], r.points[f][(e + 1) % 3]);
                // The coarse edge both ends lie on, if any.
                let side = (0..3).find(|&ce| {
                    let on = |[x, y]: [u32; 2]| match ce {
                        0 => y == 0,
                        1 => x + y == 4096,
                        _ => x == 0,
                    };
                    on(p) && on(q)
                });
                let what = format!("{}: triangle {f} side {e}", object.name);
                assert_eq!(by_index[&(a, b)], 1, "{what}");
                match side.map(|ce| 3 * t + ce) {
                    Some(s) if mesh.neighbours[s] == NO_NEIGHBOUR => {
                        assert_eq!(by_position.get(&(bits(b), bits(a))), None, "{what}")
                    }
                    Some(s) if !joined[s] => {
                        split_sides += 1;
                        assert_eq!(by_index.get(&(b, a)), None, "{what}");
                        assert_eq!(by_position.get(&(bits(b), bits(a))), Some(&1), "{what}");
                    }
                    _ => assert_eq!(by_index.get(&(b, a)), Some(&1), "{what}"),
                }
            }
        }
        assert!(split_sides > 0, "{}: the grid has folds", object.name);
    }
}

#[test]
fn the_triangles_cover_each_coarse_triangle_once() {
    for object in objects() {
        let r = refine_adaptive_flat(&object).unwrap();
        for t in 0..object.triangles.len() {
            let range = r.triangle_start[t] as usize..r.triangle_start[t + 1] as usize;
            let lattice: i64 = r.points[range.clone()]
                .iter()
                .map(|&p| lattice_area(p))
                .sum();
            assert_eq!(lattice, 4096 * 4096, "{} triangle {t}", object.name);
            let area = |p: [[f32; 3]; 3]| {
                let n = face_normal(p).map(f64::from);
                0.5 * (n[0] * n[0] + n[1] * n[1] + n[2] * n[2]).sqrt()
            };
            let coarse = area(object.mesh.triangle(t).map(|v| object.mesh.position(v)));
            let fine: f64 = r.indices[range]
                .iter()
                .map(|tri| area(tri.map(|i| r.positions[i as usize])))
                .sum();
            assert!(
                (fine - coarse).abs() <= 1e-5 * coarse,
                "{} triangle {t}: {fine} against {coarse}",
                object.name
            );
        }
    }
}

/// At every vertex, the uniform refinement to the deepest leaf (SPEC.md F.7.2) has a vertex
/// at the same point with the same position bits and the same colour.
#[test]
fn vertices_are_the_uniform_refinements_at_the_same_points() {
    for object in objects() {
        let r = refine_adaptive_flat(&object).unwrap();
        let depth = (0..object.triangles.len())
            .flat_map(|t| triangle_lighting(&object, t).unwrap().tree.nodes())
            .map(|node| node.depth)
            .max()
            .unwrap();
        let smooth = Reconstruction::Smooth;
        let uniform = refine_object_as(&object, depth, smooth, FlatRefinement::Uniform).unwrap();
        let adaptive = refine_object_as(&object, 0, smooth, FlatRefinement::Adaptive).unwrap();
        assert_eq!(adaptive.mesh.positions, r.positions);
        assert_eq!(adaptive.mesh.indices, r.indices);
        let per = 1usize << (2 * depth);
        let mut at: HashMap<(usize, [u32; 2]), u32> = HashMap::new();
        for (g, tri) in uniform.mesh.indices.iter().enumerate() {
            let corners = fine_corners(depth, (g % per) as u32);
            for (&i, q) in tri.iter().zip(corners) {
                at.insert((g / per, q.map(|x| x as u32)), i);
            }
        }
        assert!(
            r.vertex_count() * 4 < uniform.mesh.positions.len(),
            "{}: {} adaptive vertices, {} uniform",
            object.name,
            r.vertex_count(),
            uniform.mesh.positions.len()
        );
        let shift = 12 - depth;
        for (f, tri) in r.indices.iter().enumerate() {
            let t = r.coarse_triangle(f);
            for (&i, p) in tri.iter().zip(r.points[f]) {
                let u = at[&(t, p.map(|x| x >> shift))] as usize;
                let (i, what) = (i as usize, format!("{} vertex {i}", object.name));
                assert_eq!(
                    r.positions[i].map(f32::to_bits),
                    uniform.mesh.positions[u].map(f32::to_bits),
                    "{what}"
                );
                let (a, b) = (adaptive.colours[i], uniform.colours[u]);
                let scale = a.iter().chain(&b).fold(1e-3f32, |m, &x| m.max(x));
                assert!(
                    (0..3).all(|k| (a[k] - b[k]).abs() <= 1e-5 * scale),
                    "{what}: {a:?} against {b:?}"
                );
            }
        }
    }
}

/// Each vertex's source is the coarse triangle and point of its first use, and its position is
/// computed there: the lists a GPU kernel evaluates (SPEC.md F.7.1, `sources`).
#[test]
fn each_vertex_comes_from_its_first_use() {
    for object in objects() {
        let r = refine_adaptive_flat(&object).unwrap();
        assert_eq!(r.sources.len(), r.vertex_count(), "{}", object.name);
        let mut seen = vec![false; r.vertex_count()];
        let mut shared = 0;
        for (f, tri) in r.indices.iter().enumerate() {
            let t = r.coarse_triangle(f) as u32;
            for (&i, p) in tri.iter().zip(r.points[f]) {
                let i = i as usize;
                if !seen[i] {
                    seen[i] = true;
                    assert_eq!(r.sources[i], (t, p), "{} vertex {i}", object.name);
                } else if r.sources[i].0 != t {
                    shared += 1;
                }
            }
        }
        assert!(seen.iter().all(|&s| s), "{}: an unused vertex", object.name);
        let (offsets, uses) = r.incidence();
        assert_eq!(offsets.len(), r.vertex_count() + 1);
        assert_eq!(uses.len(), 3 * r.triangle_count());
        for v in 0..r.vertex_count() {
            let list = &uses[offsets[v] as usize..offsets[v + 1] as usize];
            assert!(list.windows(2).all(|w| w[0] < w[1]), "{}", object.name);
            for &u in list {
                assert_eq!(r.indices[u as usize / 3][u as usize % 3], v as u32);
            }
        }
        assert!(
            shared > 0,
            "{}: no vertex shared across a coarse edge",
            object.name
        );
    }
}

#[test]
fn the_refinement_is_deterministic_and_rejects_bad_trees() {
    for object in objects() {
        assert_eq!(
            refine_adaptive_flat(&object).unwrap(),
            refine_adaptive_flat(&object).unwrap()
        );
        let mut bad = object.clone();
        bad.triangles[1].bits_start = u32::MAX;
        assert!(matches!(
            refine_adaptive_flat(&bad),
            Err(AdaptiveFlatError::Lighting(_))
        ));
    }
}
