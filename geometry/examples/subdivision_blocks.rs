//! Writes `tests/data/subdivision_blocks.txt`: for every case pinned by
//! `tests/subdivision_bits.rs`, the FNV-1a hash of each run of 32 vertices and 32 triangles of
//! its CPU Loop output, which that test uses to say where a change of bits begins. Rewrite it
//! only together with a deliberate change of the pinned hashes:
//!
//! ```text
//! cargo run -p hce-geometry --example subdivision_blocks
//! ```

#[path = "../tests/common/bits.rs"]
mod bits;
#[path = "../tests/common/mod.rs"]
mod common;

use std::fmt::Write as _;

use bits::{block_hashes, blocks_file, key, sections, subdivide, whole_hash, BLOCK, PINNED};

fn main() {
    let mut s = format!(
        "# Written by examples/subdivision_blocks.rs: per case, per section, the element count\n\
         # and the FNV-1a hash of each run of {BLOCK} elements.\n"
    );
    for &(name, creases, level, want) in PINNED {
        let r = subdivide(name, creases, level);
        let h = whole_hash(&r);
        if h != want {
            eprintln!(
                "{name} {creases:?} level {level}: {h:016x}, pinned {want:016x}; not written"
            );
            std::process::exit(1);
        }
        let _ = writeln!(s, "case {}", key(name, creases, level));
        for (section, words) in sections(&r) {
            let _ = write!(s, "{section} {}", words.len());
            for b in block_hashes(&words) {
                let _ = write!(s, " {b:016x}");
            }
            s.push('\n');
        }
    }
    std::fs::write(blocks_file(), s).unwrap();
    println!("wrote {}", blocks_file().display());
}
