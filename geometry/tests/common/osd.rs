//! The OpenSubdiv golden cases, shared by `tests/goldens.rs`, which checks against the goldens,
//! and `examples/osd_goldens.rs`, which writes them. Both declare `mod common;` beside this
//! module.
#![allow(dead_code)]

use std::fmt::Write as _;
use std::path::{Path, PathBuf};

use hce_format::{NO_NEIGHBOUR, SPOKE_SHARP};
use hce_geometry::topology::{Creases, Topology, TopologyConfig};

use crate::common;

pub const CASES: &[(&str, Creases)] = &[
    ("tetrahedron", Creases::None),
    ("octahedron", Creases::None),
    ("icosahedron", Creases::None),
    ("bipyramid9", Creases::None),
    ("bifan7", Creases::None),
    ("fan7_open", Creases::None),
    ("grid_open", Creases::None),
    ("cube_creased", Creases::Angle(45.0)),
];
pub const LEVELS: u32 = 3;
/// Sampled points per extra mesh and level in `extra_meshes_osd.txt`.
pub const SAMPLES: usize = 200;

pub fn data() -> PathBuf {
    Path::new(env!("CARGO_MANIFEST_DIR")).join("tests/data")
}

pub fn topology(name: &str, creases: Creases) -> Topology {
    common::control_mesh(
        &data().join(format!("{name}.obj")),
        &TopologyConfig {
            creases,
            ..Default::default()
        },
    )
}

/// The control mesh for OpenSubdiv, with its interior sharp edges as `c A B` lines.
pub fn oracle_input(t: &Topology) -> String {
    let mut s = common::control_obj(t);
    let m = &t.mesh;
    for tri in 0..m.triangle_count() {
        let v = m.triangle(tri);
        for e in 0..3 {
            let nb = m.neighbours[3 * tri + e];
            let k = m.corner_spokes[3 * tri + e] + m.ring_offsets[v[e] as usize];
            if nb != NO_NEIGHBOUR
                && (nb as usize) > tri
                && m.spoke_flags[k as usize] & SPOKE_SHARP != 0
            {
                let _ = writeln!(s, "c {} {}", v[e] + 1, v[(e + 1) % 3] + 1);
            }
        }
    }
    s
}
