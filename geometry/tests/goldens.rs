//! Exactness against OpenSubdiv 3.5 (Loop, VTX_BOUNDARY_EDGE_AND_CORNER, infinitely sharp
//! creases) through golden files made with its `osd_loop` oracle, so that these tests do not
//! need OpenSubdiv. Point sets are compared (OpenSubdiv numbers vertices differently): every
//! point must have a partner within 1e-5 of the bounding-box diagonal, and the counts agree.
//!
//! The goldens are written by `examples/osd_goldens.rs` (its header has the command).

mod common;
#[path = "common/osd.rs"]
mod osd;

use std::path::Path;

use hce_geometry::topology::Creases;
use osd::{data, topology, CASES, LEVELS};

#[test]
fn small_meshes_match_opensubdiv_goldens() {
    for &(name, creases) in CASES {
        let t = topology(name, creases);
        for level in 1..=LEVELS {
            let path = data().join(format!("golden/{name}.L{level}.obj"));
            let theirs = common::obj_points(&std::fs::read_to_string(&path).unwrap());
            let ours = hce_geometry::subdivide::subdivide(&t.mesh, level).unwrap();
            assert_eq!(ours.positions.len(), theirs.len(), "{name} level {level}");
            let d = common::relative_hausdorff(&ours.positions, &theirs);
            assert!(d < 1e-5, "{name} level {level}: relative distance {d:e}");
        }
    }
}

#[test]
fn cube_creases_are_tagged_as_the_golden_expects() {
    let t = topology("cube_creased", Creases::Angle(45.0));
    // 12 cube edges, each split in two by the 2x2 face grid.
    assert_eq!(t.report.crease_edges, 24);
    let rules: Vec<u32> = (0..t.mesh.vertex_count() as u32)
        .map(|v| t.mesh.rule(v))
        .collect();
    assert_eq!(
        rules
            .iter()
            .filter(|&&r| r == hce_format::RULE_CORNER)
            .count(),
        8
    );
    assert_eq!(
        rules
            .iter()
            .filter(|&&r| r == hce_format::RULE_CREASE)
            .count(),
        12
    );
}

#[test]
fn extra_meshes_match_sampled_opensubdiv_goldens() {
    let Ok(dir) = std::env::var("HCE_EXTRA_MESHES") else {
        eprintln!(
            "HCE_EXTRA_MESHES is not set: skipping the comparison with OpenSubdiv on the shared real meshes (point it at the folder of spot.obj, fandisk.obj, teapot.obj, stanford-bunny.obj)"
        );
        return;
    };
    let text = std::fs::read_to_string(data().join("golden/extra_meshes_osd.txt")).unwrap();
    let mut blocks: Vec<(String, u32, usize, Vec<[f32; 3]>)> = Vec::new();
    for line in text.lines() {
        if let Some(rest) = line.strip_prefix("mesh ") {
            let w: Vec<&str> = rest.split_whitespace().collect();
            blocks.push((
                w[0].to_string(),
                w[1].parse().unwrap(),
                w[2].parse().unwrap(),
                vec![],
            ));
        } else if line.starts_with("v ") {
            blocks
                .last_mut()
                .unwrap()
                .3
                .extend(common::obj_points(line));
        }
    }
    assert_eq!(blocks.len(), 8);
    for (name, level, count, sample) in blocks {
        let t = common::control_mesh(
            &Path::new(&dir).join(format!("{name}.obj")),
            &Default::default(),
        );
        let ours = hce_geometry::subdivide::subdivide(&t.mesh, level).unwrap();
        assert_eq!(ours.positions.len(), count, "{name} level {level}");
        let d = common::relative_directed(&sample, &ours.positions);
        assert!(d < 1e-5, "{name} level {level}: relative distance {d:e}");
    }
}
