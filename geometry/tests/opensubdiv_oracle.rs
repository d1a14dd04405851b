//! Compares the CPU Loop subdivision with OpenSubdiv 3.5 (`osd_loop`, see
//! /work/shared/tools/README.md) on the meshes of `HCE_EXTRA_MESHES` at levels 1 to 4. Needs
//! the oracle binary (`HCE_OSD_LOOP`), so it is ignored by default:
//! `HCE_OSD_LOOP=/path/osd_loop HCE_EXTRA_MESHES=... cargo test -p hce-geometry --release
//! --test opensubdiv_oracle -- --ignored --nocapture`.

mod common;

use std::path::PathBuf;
use std::process::Command;

#[test]
#[ignore = "needs OpenSubdiv's osd_loop (HCE_OSD_LOOP) and HCE_EXTRA_MESHES"]
fn matches_opensubdiv_on_extra_meshes() {
    let (Ok(osd), Ok(dir)) = (
        std::env::var("HCE_OSD_LOOP"),
        std::env::var("HCE_EXTRA_MESHES"),
    ) else {
        panic!("set HCE_OSD_LOOP to the osd_loop binary and HCE_EXTRA_MESHES to the mesh folder");
    };
    let tmp = tempfile::tempdir().unwrap();
    let mut meshes: Vec<PathBuf> = std::fs::read_dir(&dir)
        .unwrap()
        .map(|e| e.unwrap().path())
        .filter(|p| p.extension().is_some_and(|e| e == "obj"))
        .collect();
    meshes.sort();
    let max_level: u32 = std::env::var("HCE_OSD_MAX_LEVEL")
        .ok()
        .and_then(|s| s.parse().ok())
        .unwrap_or(4);
    let mut worst: f64 = 0.0;
    for path in &meshes {
        let topo = common::control_mesh(path, &Default::default());
        if topo.report.non_manifold_edges > 0 {
            // Cutting an edge shared by more than two triangles leaves two boundary edges
            // between the same pair of vertices, which OpenSubdiv (whose topology is keyed by
            // vertex pairs) merges back into one non-manifold edge: not comparable.
            println!(
                "{}: skipped, {} non-manifold edges were cut",
                path.display(),
                topo.report.non_manifold_edges
            );
            continue;
        }
        let input = tmp.path().join("control.obj");
        std::fs::write(&input, common::control_obj(&topo)).unwrap();
        for level in 1..=max_level {
            let out = tmp.path().join("osd.obj");
            let status = Command::new(&osd)
                .arg(&input)
                .arg(level.to_string())
                .arg(&out)
                .output()
                .unwrap();
            assert!(
                status.status.success(),
                "osd_loop failed on {}",
                path.display()
            );
            let theirs = common::obj_points(&std::fs::read_to_string(&out).unwrap());
            let ours = hce_geometry::subdivide::subdivide(&topo.mesh, level).unwrap();
            assert_eq!(
                ours.positions.len(),
                theirs.len(),
                "{} level {level}",
                path.display()
            );
            let d = common::relative_hausdorff(&ours.positions, &theirs);
            println!(
                "{} level {level}: {} vertices, max nearest-neighbour distance / bbox diagonal = {d:.3e}",
                path.file_name().unwrap().to_string_lossy(),
                theirs.len()
            );
            worst = worst.max(d);
        }
    }
    assert!(worst < 1e-5, "worst relative distance {worst:e}");
}
