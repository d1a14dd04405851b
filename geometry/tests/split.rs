//! Split vertices at sharp edges (SPEC.md F.5, F.6, `hce_geometry::split`) on the creased cube
//! of the shared test data: every face is its own smooth region, so after the split each fine
//! triangle's vertices carry its face's normal, copies sit on their originals bit for bit, and
//! the baked light of each face stays on that face.

mod common;

use std::path::Path;

use hce_format::{rgb9e5, ControlMesh, Object, ObjectKind, TriangleRecord};
use hce_geometry::colour::apply_baked_colours;
use hce_geometry::flat::FlatTopology;
use hce_geometry::refine::{refine_object, subdivide_split};
use hce_geometry::split::{SplitTables, NO_COPY};
use hce_geometry::subdivide::subdivide;
use hce_geometry::topology::{Creases, TopologyConfig};

fn cube(creases: Creases) -> ControlMesh {
    common::control_mesh(
        &Path::new(env!("CARGO_MANIFEST_DIR")).join("tests/data/cube_creased.obj"),
        &TopologyConfig {
            creases,
            ..Default::default()
        },
    )
    .mesh
}

/// The outward unit normal of the cube face coarse triangle `t` lies on.
fn face_normal(mesh: &ControlMesh, t: usize) -> [f32; 3] {
    let p = mesh.triangle(t).map(|v| mesh.position(v));
    let n = hce_geometry::normal::face_normal(p);
    hce_geometry::normal::unit_or_up(n)
}

#[test]
fn the_creased_cube_splits_into_its_six_faces() {
    let mesh = cube(Creases::Angle(45.0));
    let tables = SplitTables::new("cube", &mesh, ObjectKind::Multiresolution).unwrap();
    // 26 control points: 8 cube corners in 3 faces (2 copies each), 12 edge midpoints in 2
    // faces (1 copy each), 6 face centres in 1. 24 crease edges between faces.
    assert_eq!((tables.copies, tables.split_edges), (8 * 2 + 12, 24));
    for level in 0..=3 {
        let plain = subdivide(&mesh, level).unwrap();
        let r = subdivide_split("cube", &mesh, level).unwrap();
        let m = (1usize << level) - 1;
        assert_eq!(
            r.positions.len(),
            plain.positions.len() + 28 + 24 * m,
            "level {level}"
        );
        assert_eq!(r.indices.len(), plain.indices.len());
        // The split moves corners only: the same points, so the same fine triangles.
        for (a, b) in r.indices.iter().zip(&plain.indices) {
            let pa = a.map(|i| r.positions[i as usize].map(f32::to_bits));
            let pb = b.map(|i| plain.positions[i as usize].map(f32::to_bits));
            assert_eq!(pa, pb);
        }
        assert_eq!(r.positions[..plain.positions.len()], plain.positions[..]);
        let per = 1usize << (2 * level);
        let mut faces_of = vec![Vec::new(); r.positions.len()];
        for (f, tri) in r.indices.iter().enumerate() {
            let n = face_normal(&mesh, f / per);
            for &i in tri {
                faces_of[i as usize].push(n);
                let got = r.normals[i as usize];
                assert!(
                    (0..3).all(|k| (got[k] - n[k]).abs() < 1e-6),
                    "level {level}: vertex {i} of fine triangle {f} has normal {got:?}, face {n:?}"
                );
            }
        }
        // Every vertex is used, and by one face only.
        assert!(faces_of
            .iter()
            .all(|l| !l.is_empty() && l.iter().all(|n| n == &l[0])));
    }
}

#[test]
fn a_mesh_without_creases_is_not_split() {
    let mesh = cube(Creases::None);
    let tables = SplitTables::new("cube", &mesh, ObjectKind::Multiresolution).unwrap();
    assert!(tables.is_empty());
    assert!(tables.corner_copy.iter().all(|&c| c == NO_COPY));
    assert_eq!(
        subdivide_split("cube", &mesh, 2).unwrap(),
        subdivide(&mesh, 2).unwrap()
    );
}

/// The cube with single-node trees, one colour per face of the cube (the geometric normal
/// only): what a bake of a box lit differently on each side stores.
fn coloured_cube(mesh: ControlMesh) -> Object {
    let f = mesh.triangle_count();
    let colour = |n: [f32; 3]| {
        [
            0.2 + 0.3 * n[0].abs(),
            0.2 + 0.3 * n[1].abs(),
            0.2 + 0.3 * n[2].abs(),
        ]
    };
    let normals: Vec<[f32; 3]> = (0..f).map(|t| face_normal(&mesh, t)).collect();
    let colours = normals.iter().map(|&n| rgb9e5::encode(colour(n))).collect();
    let triangles = (0..f as u32)
        .map(|t| TriangleRecord {
            bits_start: t,
            colour_start: t,
            normal_start: t,
            normal_count: 1,
        })
        .collect();
    Object {
        name: "cube".into(),
        kind: ObjectKind::Multiresolution,
        mesh,
        triangles,
        normals,
        colours,
        corner_colours: Vec::new(),
        bits: vec![0; f.div_ceil(32)],
        bit_len: f as u64,
        geometry_hash: 0,
    }
}

#[test]
fn each_side_of_a_crease_keeps_its_own_light() {
    let object = coloured_cube(cube(Creases::Angle(45.0)));
    let level = 3;
    let r = subdivide_split("cube", &object.mesh, level).unwrap();
    let colours = apply_baked_colours(&object, &r, level).unwrap();
    let per = 1usize << (2 * level);
    let mut mixed = 0;
    for (f, tri) in r.indices.iter().enumerate() {
        let want = rgb9e5::decode(object.colours[f / per]);
        for &i in tri {
            let got = colours[i as usize];
            assert!(
                (0..3).all(|k| (got[k] - want[k]).abs() <= 1e-5 * want[k]),
                "fine triangle {f}, vertex {i}: {got:?}, its face's light is {want:?}"
            );
        }
    }
    // Without the split, the vertices on the cube's edges blend two or three faces.
    let plain = subdivide(&object.mesh, level).unwrap();
    let blended = apply_baked_colours(&object, &plain, level).unwrap();
    for (f, tri) in plain.indices.iter().enumerate() {
        let want = rgb9e5::decode(object.colours[f / per]);
        mixed += tri
            .iter()
            .filter(|&&i| (0..3).any(|k| (blended[i as usize][k] - want[k]).abs() > 1e-3))
            .count();
    }
    assert!(mixed > 0);
}

/// The uncreased cube as a flat object: every fold between faces is 90 degrees, so it splits
/// exactly as the creased cube does (SPEC.md F.5, G.2: the split edges are the edges with a
/// neighbour that are not joined), and each face's vertices carry that face's light only.
#[test]
fn a_flat_box_splits_at_its_folds_and_each_face_keeps_its_light() {
    let mut object = coloured_cube(cube(Creases::None));
    assert!(
        SplitTables::new("cube", &object.mesh, ObjectKind::Multiresolution)
            .unwrap()
            .is_empty(),
        "without sharp edges a multiresolution cube splits nothing"
    );
    object.kind = ObjectKind::Flat;
    let flat = SplitTables::new("cube", &object.mesh, ObjectKind::Flat).unwrap();
    let creased = SplitTables::new(
        "cube",
        &cube(Creases::Angle(45.0)),
        ObjectKind::Multiresolution,
    )
    .unwrap();
    assert_eq!(flat, creased);
    for level in [0, 1, 3] {
        let r = refine_object(&object, level).unwrap();
        let m = &r.mesh;
        let per = 1usize << (2 * level);
        assert_eq!(
            m.positions.len() as u64,
            FlatTopology::new("cube", &object.mesh)
                .unwrap()
                .refined_vertex_count(level)
                + flat.appended(level)
        );
        for (f, tri) in m.indices.iter().enumerate() {
            let want = rgb9e5::decode(object.colours[f / per]);
            let n = face_normal(&object.mesh, f / per);
            for &i in tri {
                let got = r.colours[i as usize];
                assert!(
                    (0..3).all(|k| (got[k] - want[k]).abs() <= 1e-5 * want[k]),
                    "level {level}, fine triangle {f}, vertex {i}: {got:?}, its face's light \
                     is {want:?}"
                );
                // A flat object's vertex normal sums its own side's fine triangles only.
                let got = m.normals[i as usize];
                assert!(
                    (0..3).all(|k| (got[k] - n[k]).abs() <= 1e-6),
                    "level {level}, vertex {i}: normal {got:?}, face {n:?}"
                );
            }
        }
    }
}

/// Two unit squares (four flat triangles) meeting along `x = 1`, the second rising `degrees`
/// from the first; the first square's light is bright, the second's dark.
fn folded_pair(degrees: f64) -> Object {
    let (s, c) = degrees.to_radians().sin_cos();
    let xz = [[0.0, 0.0], [1.0, 0.0], [1.0 + c, s]];
    let mut positions = Vec::new();
    for y in 0..2 {
        for p in xz {
            positions.extend([p[0] as f32, y as f32, p[1] as f32]);
        }
    }
    let triangles = vec![0, 1, 4, 0, 4, 3, 1, 2, 5, 1, 5, 4];
    let mesh = hce_format::example::control_mesh(positions, triangles);
    let mut object = coloured_cube(mesh);
    object.kind = ObjectKind::Flat;
    object.colours = [
        [0.9f32, 0.8, 0.7],
        [0.9, 0.8, 0.7],
        [0.1, 0.05, 0.02],
        [0.1, 0.05, 0.02],
    ]
    .map(rgb9e5::encode)
    .to_vec();
    object
}

/// A fold under 10 degrees joins its triangles (SPEC.md G.2): the refined vertices on it are
/// shared and blend both sides' light; one over 10 degrees splits them, and each side's
/// vertices carry that side's light alone.
#[test]
fn a_flat_fold_splits_above_ten_degrees_only() {
    let level = 2;
    let per = 1usize << (2 * level);
    let on_fold = |p: [f32; 3]| p[0] == 1.0 && p[2] == 0.0;
    for (degrees, splits) in [(5.0, false), (9.9, false), (10.1, true), (90.0, true)] {
        let object = folded_pair(degrees);
        let tables = SplitTables::new("pair", &object.mesh, ObjectKind::Flat).unwrap();
        // The fold's two end points (one copy each) and its 3 inner points at level 2.
        assert_eq!(
            (tables.copies, tables.split_edges),
            if splits { (2, 1) } else { (0, 0) },
            "{degrees} degrees"
        );
        let r = refine_object(&object, level).unwrap();
        let fold_vertices: Vec<usize> = (0..r.mesh.positions.len())
            .filter(|&i| on_fold(r.mesh.positions[i]))
            .collect();
        assert_eq!(
            fold_vertices.len(),
            if splits { 10 } else { 5 },
            "{degrees}"
        );
        let bright = rgb9e5::decode(object.colours[0]);
        let dark = rgb9e5::decode(object.colours[2]);
        for (f, tri) in r.mesh.indices.iter().enumerate() {
            let side = if f / per < 2 { bright } else { dark };
            for &i in tri
                .iter()
                .filter(|&&i| on_fold(r.mesh.positions[i as usize]))
            {
                let got = r.colours[i as usize];
                if splits {
                    assert!(
                        (0..3).all(|k| (got[k] - side[k]).abs() <= 1e-5 * side[k]),
                        "{degrees} degrees: fold vertex {i} is {got:?}, its side's light \
                         {side:?}"
                    );
                } else {
                    assert!(
                        (0..3).all(|k| got[k] < bright[k] - 0.1 && got[k] > dark[k] + 0.01),
                        "{degrees} degrees: shared fold vertex {i} is {got:?}, not a blend of \
                         {bright:?} and {dark:?}"
                    );
                }
            }
        }
    }
}
