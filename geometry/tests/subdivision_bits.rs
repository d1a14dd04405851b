//! The bits of the CPU Loop subdivision are a contract: the GPU kernel ports its order of
//! arithmetic, and the goldens were made from it. These FNV-1a hashes of the positions (`f32`
//! bits) and the indices were taken from the reference as of commit 2516a0f (before it was
//! restructured for speed); any change to them is a change of the documented arithmetic or
//! numbering, not an optimisation. Normals are not hashed: only their definition is fixed.
//!
//! A hash alone says nothing about what changed, so `tests/data/subdivision_blocks.txt` keeps
//! the hash of every run of 32 vertices and 32 triangles of each case (written by
//! `examples/subdivision_blocks.rs`, checked here against the pinned hashes): a failure names
//! the case, the section and the first block that differs, with the values it holds now.

#[path = "common/bits.rs"]
mod bits;
mod common;

use std::collections::HashMap;

use bits::{block_hashes, blocks_file, key, sections, subdivide, whole_hash, BLOCK, PINNED};

/// The blocks file: key → section → (element count, block hashes).
fn pinned_blocks() -> HashMap<String, HashMap<String, (usize, Vec<u64>)>> {
    let text = std::fs::read_to_string(blocks_file()).expect("tests/data/subdivision_blocks.txt");
    let mut out: HashMap<String, HashMap<String, (usize, Vec<u64>)>> = HashMap::new();
    let mut case = String::new();
    for line in text.lines().filter(|l| !l.starts_with('#')) {
        if let Some(k) = line.strip_prefix("case ") {
            case = k.to_string();
            continue;
        }
        let mut w = line.split_whitespace();
        let (Some(section), Some(count)) = (w.next(), w.next()) else {
            continue;
        };
        let hashes = w.map(|h| u64::from_str_radix(h, 16).unwrap()).collect();
        out.entry(case.clone())
            .or_default()
            .insert(section.to_string(), (count.parse().unwrap(), hashes));
    }
    out
}

/// Where `words` first departs from the pinned blocks of its section, in words.
fn first_difference(section: &str, words: &[[u32; 3]], pinned: &(usize, Vec<u64>)) -> String {
    let (count, want) = pinned;
    let got = block_hashes(words);
    let unit = if section == "positions" {
        "vertex"
    } else {
        "triangle"
    };
    match got.iter().zip(want).position(|(g, w)| g != w) {
        Some(b) => {
            let range = b * BLOCK..((b + 1) * BLOCK).min(words.len());
            let now: Vec<String> = words[range.clone()]
                .iter()
                .take(4)
                .map(|e| {
                    if section == "positions" {
                        format!("{:?}", e.map(f32::from_bits))
                    } else {
                        format!("{e:?}")
                    }
                })
                .collect();
            format!(
                "{section}: first change in {unit}s {range:?} (of {}), which now begin {}",
                words.len(),
                now.join(", ")
            )
        }
        None if words.len() != *count => {
            format!("{section}: {} {unit}s, pinned {count}", words.len())
        }
        None => format!("{section}: unchanged"),
    }
}

#[test]
fn positions_and_indices_keep_their_pinned_bits() {
    let blocks = pinned_blocks();
    let mut wrong = Vec::new();
    for &(name, creases, level, want) in PINNED {
        let r = subdivide(name, creases, level);
        let h = whole_hash(&r);
        if h != want {
            let k = key(name, creases, level);
            let mut why = Vec::new();
            for (section, words) in sections(&r) {
                match blocks.get(&k).and_then(|s| s.get(section)) {
                    Some(p) => why.push(first_difference(section, &words, p)),
                    None => why.push(format!("{section}: no blocks pinned for {k}")),
                }
            }
            wrong.push(format!(
                "{name} {creases:?} level {level}: {h:016x}, pinned {want:016x}\n    {}",
                why.join("\n    ")
            ));
        }
    }
    assert!(wrong.is_empty(), "changed bits:\n{}", wrong.join("\n"));
}

/// The blocks file must describe the pinned bits, or it would localise a change against the
/// wrong reference: every case is there, and its blocks hash the current (pinned) output.
#[test]
fn block_hashes_describe_the_pinned_output() {
    let blocks = pinned_blocks();
    assert_eq!(
        blocks.len(),
        PINNED.len(),
        "cases in {}",
        blocks_file().display()
    );
    for &(name, creases, level, want) in PINNED {
        let r = subdivide(name, creases, level);
        if whole_hash(&r) != want {
            continue; // reported by the test above
        }
        let k = key(name, creases, level);
        for (section, words) in sections(&r) {
            let (count, hashes) = &blocks[&k][section];
            assert_eq!(*count, words.len(), "{k} {section}");
            assert_eq!(hashes, &block_hashes(&words), "{k} {section}");
        }
    }
}
