//! The pinned cases of `tests/subdivision_bits.rs` and the hashes of their output, shared with
//! `examples/subdivision_blocks.rs`, which writes the per-block hashes that localise a change.
#![allow(dead_code)]

use std::path::{Path, PathBuf};

use hce_geometry::subdivide::Refined;
use hce_geometry::topology::{Creases, TopologyConfig};

use crate::common;

/// Elements (vertices or triangles) per block of `tests/data/subdivision_blocks.txt`.
pub const BLOCK: usize = 32;

pub const PINNED: &[(&str, Creases, u32, u64)] = &[
    ("bifan7", Creases::None, 1, 0x306ed235986f577a),
    ("bifan7", Creases::None, 2, 0xb42c51c790eea629),
    ("bifan7", Creases::None, 3, 0x65b5ae673c0f64bb),
    ("bifan7", Creases::None, 4, 0x259008c96af1439f),
    ("bifan7", Creases::Angle(30.0), 1, 0xcd46918cb2d0684b),
    ("bifan7", Creases::Angle(30.0), 2, 0x74958f8c8cf6e88f),
    ("bifan7", Creases::Angle(30.0), 3, 0xfc0e6dfb65859948),
    ("bifan7", Creases::Angle(30.0), 4, 0x7b978cfa6e165388),
    ("bipyramid9", Creases::None, 1, 0xc505ea22a25bd15c),
    ("bipyramid9", Creases::None, 2, 0x01f1098e39d42ede),
    ("bipyramid9", Creases::None, 3, 0xa0f38b3de263518b),
    ("bipyramid9", Creases::None, 4, 0x3942f79f44879409),
    ("bipyramid9", Creases::Angle(30.0), 1, 0xbab1f8e2a2bd18d0),
    ("bipyramid9", Creases::Angle(30.0), 2, 0x03be61725c1d3f96),
    ("bipyramid9", Creases::Angle(30.0), 3, 0x992ed77d5f8ad4c4),
    ("bipyramid9", Creases::Angle(30.0), 4, 0xb7f9ee0ef8e70b00),
    ("cube_creased", Creases::None, 1, 0x0b470679390958d8),
    ("cube_creased", Creases::None, 2, 0xc5a58b6242d3ca6c),
    ("cube_creased", Creases::None, 3, 0x29f2ab5b3af8fe80),
    ("cube_creased", Creases::None, 4, 0x700ce984af5023f4),
    ("cube_creased", Creases::Angle(30.0), 1, 0x1957a5b349efec68),
    ("cube_creased", Creases::Angle(30.0), 2, 0xa4f554256ac79884),
    ("cube_creased", Creases::Angle(30.0), 3, 0x04ab7c07470c1e08),
    ("cube_creased", Creases::Angle(30.0), 4, 0x17fb0ce3cd7267a8),
    ("fan7_open", Creases::None, 1, 0x4d5b3b230344b98d),
    ("fan7_open", Creases::None, 2, 0x391a273950a92e57),
    ("fan7_open", Creases::None, 3, 0x9d0d785ce9afe3e8),
    ("fan7_open", Creases::None, 4, 0xdc7fee5706eaed26),
    ("fan7_open", Creases::Angle(30.0), 1, 0x4d5b3b230344b98d),
    ("fan7_open", Creases::Angle(30.0), 2, 0x391a273950a92e57),
    ("fan7_open", Creases::Angle(30.0), 3, 0x9d0d785ce9afe3e8),
    ("fan7_open", Creases::Angle(30.0), 4, 0xdc7fee5706eaed26),
    ("grid_open", Creases::None, 1, 0x5475a22bcf199973),
    ("grid_open", Creases::None, 2, 0x681d7eeb1fc03140),
    ("grid_open", Creases::None, 3, 0x62d0620a72c9de2e),
    ("grid_open", Creases::None, 4, 0x79ef7787f64d6ce8),
    ("grid_open", Creases::Angle(30.0), 1, 0x3eae6426467d4538),
    ("grid_open", Creases::Angle(30.0), 2, 0xeb25ade1819b34e9),
    ("grid_open", Creases::Angle(30.0), 3, 0xd35b84e1d7a361dc),
    ("grid_open", Creases::Angle(30.0), 4, 0x9007942d5cf672c6),
    ("icosahedron", Creases::None, 1, 0x512392d2aff61d71),
    ("icosahedron", Creases::None, 2, 0x4d024fa5ac18f1da),
    ("icosahedron", Creases::None, 3, 0x8adcaaadc375e89b),
    ("icosahedron", Creases::None, 4, 0xedeeeec9fa7a2117),
    ("icosahedron", Creases::Angle(30.0), 1, 0xe01845be7fbca6bd),
    ("icosahedron", Creases::Angle(30.0), 2, 0xf69b769678f2ea5d),
    ("icosahedron", Creases::Angle(30.0), 3, 0x68759be900dcb639),
    ("icosahedron", Creases::Angle(30.0), 4, 0xbbe896960b51e1e1),
    ("octahedron", Creases::None, 1, 0xda7d410a52336605),
    ("octahedron", Creases::None, 2, 0x68fe14a001e38239),
    ("octahedron", Creases::None, 3, 0xe2b89af54dbfb4e1),
    ("octahedron", Creases::None, 4, 0x2b78cc1a80e77651),
    ("octahedron", Creases::Angle(30.0), 1, 0x78c851504a0f4245),
    ("octahedron", Creases::Angle(30.0), 2, 0x509ff70e84da5575),
    ("octahedron", Creases::Angle(30.0), 3, 0x3becbf897814cae1),
    ("octahedron", Creases::Angle(30.0), 4, 0xf9ca75a626b04ce5),
    ("tetrahedron", Creases::None, 1, 0x3be594bc0643b005),
    ("tetrahedron", Creases::None, 2, 0x4585d7384e7b797b),
    ("tetrahedron", Creases::None, 3, 0x51de5be23acb3060),
    ("tetrahedron", Creases::None, 4, 0x7edd150e8cf48283),
    ("tetrahedron", Creases::Angle(30.0), 1, 0xb7051181e2960425),
    ("tetrahedron", Creases::Angle(30.0), 2, 0xbb58dba07de08f8b),
    ("tetrahedron", Creases::Angle(30.0), 3, 0xf43530c3eb49cac8),
    ("tetrahedron", Creases::Angle(30.0), 4, 0x85c5e5275ab3711d),
];

pub fn blocks_file() -> PathBuf {
    Path::new(env!("CARGO_MANIFEST_DIR")).join("tests/data/subdivision_blocks.txt")
}

/// The key of a case in the blocks file.
pub fn key(name: &str, creases: Creases, level: u32) -> String {
    format!("{name} {creases:?} {level}")
}

pub fn subdivide(name: &str, creases: Creases, level: u32) -> Refined {
    let data = Path::new(env!("CARGO_MANIFEST_DIR")).join("tests/data");
    let t = common::control_mesh(
        &data.join(format!("{name}.obj")),
        &TopologyConfig {
            creases,
            ..Default::default()
        },
    );
    hce_geometry::subdivide::subdivide(&t.mesh, level).unwrap()
}

pub const FNV_START: u64 = 0xcbf29ce484222325;

pub fn fnv(h: &mut u64, x: u32) {
    for b in x.to_le_bytes() {
        *h ^= b as u64;
        *h = h.wrapping_mul(0x100000001b3);
    }
}

/// The words of the two sections: positions as `f32` bits, three per vertex, and indices,
/// three per triangle.
pub fn sections(r: &Refined) -> [(&'static str, Vec<[u32; 3]>); 2] {
    [
        (
            "positions",
            r.positions.iter().map(|p| p.map(f32::to_bits)).collect(),
        ),
        ("indices", r.indices.clone()),
    ]
}

/// The pinned hash: FNV-1a over the positions, then the indices.
pub fn whole_hash(r: &Refined) -> u64 {
    let mut h = FNV_START;
    for (_, words) in sections(r) {
        for e in &words {
            for &w in e {
                fnv(&mut h, w);
            }
        }
    }
    h
}

/// FNV-1a of each run of [`BLOCK`] elements.
pub fn block_hashes(words: &[[u32; 3]]) -> Vec<u64> {
    words
        .chunks(BLOCK)
        .map(|c| {
            let mut h = FNV_START;
            for e in c {
                for &w in e {
                    fnv(&mut h, w);
                }
            }
            h
        })
        .collect()
}
