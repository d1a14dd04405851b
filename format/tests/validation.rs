//! The validator finds each kind of content problem, with its location, and reports them all.

use hce_format::{example, validate, validate_bytes, write, Container, ObjectKind, NO_NEIGHBOUR};

fn problems_of(f: impl FnOnce(&mut Container)) -> Vec<String> {
    let mut c = example::two_triangles();
    f(&mut c);
    let from_model: Vec<String> = validate(&c).iter().map(ToString::to_string).collect();
    // The file route finds the same content problems.
    let from_file: Vec<String> = validate_bytes(&write(&c).unwrap())
        .iter()
        .map(ToString::to_string)
        .collect();
    assert_eq!(from_model, from_file);
    from_model
}

fn has(problems: &[String], needle: &str) -> bool {
    problems.iter().any(|p| p.contains(needle))
}

#[test]
fn examples_are_valid() {
    assert_eq!(validate(&example::single_triangle()), vec![]);
    assert_eq!(validate(&example::two_triangles()), vec![]);
}

#[test]
fn out_of_range_vertex_is_located() {
    let p = problems_of(|c| c.objects[0].mesh.triangles[4] = 7);
    assert!(
        has(
            &p,
            "objects[0].mesh.triangles[1]: vertex index 7 is out of range (4 vertices)"
        ),
        "{p:?}"
    );
}

#[test]
fn truncated_bitstream_names_the_node() {
    let p = problems_of(|c| c.objects[0].bit_len = 3);
    assert_eq!(
        p,
        vec![
            "objects[0].triangles[0]: bitstream ends inside node 3 (bit 3 of 3) (SPEC.md B.2)",
            "objects[0].triangles[1]: bitstream ends inside node 0 (bit 5 of 3) (SPEC.md B.2)",
        ]
    );
}

#[test]
fn overlapping_trees_are_reported() {
    let p = problems_of(|c| c.objects[0].triangles[1].bits_start = 2);
    assert_eq!(p.len(), 1, "{p:?}");
    assert!(p[0].starts_with("objects[0].triangles[0]: tree overlaps the tree starting at bit 2"));
}

#[test]
fn non_unit_normals_and_colour_overrun_are_all_reported() {
    let p = problems_of(|c| {
        let o = &mut c.objects[0];
        o.normals[1] = [0.0, 0.5, 0.5];
        o.colours.truncate(10);
        o.mesh.positions[4] = f32::INFINITY;
    });
    assert!(
        has(&p, "objects[0].normals[1]: [0.0, 0.5, 0.5] has length 0.70"),
        "{p:?}"
    );
    assert!(
        has(&p, "objects[0].triangles[1]: colours 10..11 for 1 nodes x 1 normals run past the 10 colours"),
        "{p:?}"
    );
    assert!(
        has(&p, "objects[0].mesh.positions[1]: coordinate is not finite"),
        "{p:?}"
    );
    // Editing a position also breaks the stored geometry hash.
    assert!(has(&p, "objects[0].geometry_hash: stored"), "{p:?}");
    assert_eq!(p.len(), 4, "{p:?}");
}

#[test]
fn adjacency_inconsistencies_are_reported() {
    let p = problems_of(|c| c.objects[0].mesh.neighbours[2] = NO_NEIGHBOUR);
    assert!(
        has(&p, "objects[0].mesh.neighbours[2]: edge (2, 0) has no neighbour but its spoke is not marked boundary"),
        "{p:?}"
    );
    let p = problems_of(|c| c.objects[0].mesh.corner_spokes[3] = 0);
    assert!(has(&p, "objects[0].mesh.corner_spokes[3]: ring of vertex 0 has 1 at position 0, triangle 1 needs 2"), "{p:?}");
    let p = problems_of(|c| c.objects[0].mesh.vertex_flags[0] = 1);
    assert!(
        has(
            &p,
            "objects[0].mesh.vertex_flags[0]: rule 0 but 2 sharp spokes (valence 3) make it 1"
        ),
        "{p:?}"
    );
    let p = problems_of(|c| c.objects[0].mesh.edges[3] = 3);
    assert!(
        has(&p, "objects[0].mesh.edges[3]: id 3 skips ahead of 3")
            || has(&p, "objects[0].mesh.edges[2]: id 2 differs from id 3"),
        "{p:?}"
    );
    let p = problems_of(|c| c.objects[0].mesh.neighbours[3] = 5);
    assert!(
        has(
            &p,
            "objects[0].mesh.neighbours[3]: neighbour 5 is out of range (2 triangles)"
        ),
        "{p:?}"
    );
}

#[test]
fn flat_objects_need_one_normal() {
    let p = problems_of(|c| c.objects[0].kind = ObjectKind::Flat);
    assert_eq!(
        p,
        vec!["objects[0].triangles[0]: flat objects have one normal per triangle, found 2"]
    );
}

#[test]
fn generated_grids_are_valid_and_their_damage_is_found() {
    for n in [1, 2, 5] {
        let c = example::grid(n, 4);
        assert_eq!(validate(&c), vec![], "grid {n}");
        assert_eq!(validate_bytes(&write(&c).unwrap()), vec![], "grid {n}");
    }
    // The reference builder agrees with the hand-written tables of the two-triangle example.
    let two = example::two_triangles();
    let m = &two.objects[0].mesh;
    assert_eq!(
        example::control_mesh(m.positions.clone(), m.triangles.clone()),
        *m
    );
    // An interior vertex of a 3x3 grid: its ring wraps around, valence 6, smooth.
    let c = example::grid(3, 2);
    let m = &c.objects[0].mesh;
    assert_eq!(m.ring_of(5).len(), 6);
    assert_eq!(m.vertex_flags[5], 0);
    let mut damaged = c.clone();
    damaged.objects[0]
        .mesh
        .ring
        .swap(m.ring_offsets[5] as usize, m.ring_offsets[5] as usize + 1);
    let p: Vec<String> = validate(&damaged).iter().map(ToString::to_string).collect();
    assert!(
        p.iter()
            .all(|s| s.starts_with("objects[0].mesh.corner_spokes[")),
        "{p:?}"
    );
    assert!(p.len() >= 2, "{p:?}");
}
