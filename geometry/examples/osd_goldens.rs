//! Writes the OpenSubdiv golden files that `tests/goldens.rs` checks against: the small meshes
//! of `tests/data/` at levels 1 to 3 (`tests/data/golden/NAME.L<level>.obj`) and, when
//! HCE_EXTRA_MESHES names the folder of the shared real meshes, sampled points of those at
//! levels 1 and 2 (`tests/data/golden/extra_meshes_osd.txt`).
//!
//! ```text
//! HCE_OSD_LOOP_CREASE=/path/osd_loop_crease HCE_EXTRA_MESHES=/work/shared/meshes \
//!     cargo run -p hce-geometry --example osd_goldens
//! ```
//!
//! `osd_loop_crease` is /work/shared/tools/osd_loop.cpp (OpenSubdiv 3.5, Loop,
//! VTX_BOUNDARY_EDGE_AND_CORNER) with `c A B` lines read as infinitely sharp crease edges.

#[path = "../tests/common/mod.rs"]
mod common;
#[path = "../tests/common/osd.rs"]
mod osd;

use std::fmt::Write as _;
use std::path::Path;
use std::process::Command;

use osd::{data, oracle_input, topology, CASES, LEVELS, SAMPLES};

fn run_oracle(osd: &str, input: &str, level: u32) -> Vec<[f32; 3]> {
    let tmp = tempfile::tempdir().unwrap();
    let (i, o) = (tmp.path().join("in.obj"), tmp.path().join("out.obj"));
    std::fs::write(&i, input).unwrap();
    let r = Command::new(osd)
        .arg(&i)
        .arg(level.to_string())
        .arg(&o)
        .output()
        .unwrap();
    assert!(r.status.success(), "{}", String::from_utf8_lossy(&r.stderr));
    common::obj_points(&std::fs::read_to_string(&o).unwrap())
}

fn main() {
    let Ok(osd) = std::env::var("HCE_OSD_LOOP_CREASE") else {
        eprintln!("set HCE_OSD_LOOP_CREASE to the osd_loop_crease oracle (see this file's header)");
        std::process::exit(2);
    };
    std::fs::create_dir_all(data().join("golden")).unwrap();
    for &(name, creases) in CASES {
        let t = topology(name, creases);
        let input = oracle_input(&t);
        for level in 1..=LEVELS {
            let pts = run_oracle(&osd, &input, level);
            let mut s = format!("# OpenSubdiv 3.5 Loop level {level} of {name}.obj\n");
            for p in pts {
                let _ = writeln!(s, "v {:.9e} {:.9e} {:.9e}", p[0], p[1], p[2]);
            }
            std::fs::write(data().join(format!("golden/{name}.L{level}.obj")), s).unwrap();
        }
    }
    // Sampled goldens for the shared real meshes (manifold after welding).
    if let Ok(dir) = std::env::var("HCE_EXTRA_MESHES") {
        let mut s = String::from(
            "# mesh level count, then sampled OpenSubdiv points (every count/200-th)\n",
        );
        for name in ["spot", "fandisk", "teapot", "stanford-bunny"] {
            let t = common::control_mesh(
                &Path::new(&dir).join(format!("{name}.obj")),
                &Default::default(),
            );
            let input = oracle_input(&t);
            for level in 1..=2 {
                let pts = run_oracle(&osd, &input, level);
                let _ = writeln!(s, "mesh {name} {level} {}", pts.len());
                let step = pts.len().div_ceil(SAMPLES);
                for p in pts.iter().step_by(step) {
                    let _ = writeln!(s, "v {:.9e} {:.9e} {:.9e}", p[0], p[1], p[2]);
                }
            }
        }
        std::fs::write(data().join("golden/extra_meshes_osd.txt"), s).unwrap();
    }
}
