//! Fuzz target: any bytes through the container reader and validator. Neither may panic, hang
//! or allocate beyond a small multiple of the input; whatever reads must write back and read
//! to the same bytes. Each input is also tried with its checksums recomputed, so that mutations
//! reach the content checks behind the CRCs instead of stopping at them.
#![no_main]

use libfuzzer_sys::fuzz_target;

fn u32_at(b: &[u8], at: usize) -> u32 {
    u32::from_le_bytes([b[at], b[at + 1], b[at + 2], b[at + 3]])
}

fn u64_at(b: &[u8], at: usize) -> u64 {
    u64::from(u32_at(b, at)) | (u64::from(u32_at(b, at + 4)) << 32)
}

/// Recomputes every in-file section CRC and the header CRC.
fn reseal(b: &mut [u8]) {
    if b.len() < 32 {
        return;
    }
    let n = u32_at(b, 12) as usize;
    let dir_end = 32usize
        .saturating_add(n.saturating_mul(32))
        .min(b.len() / 32 * 32);
    let mut e = 32;
    while e + 32 <= dir_end {
        let off = u64_at(b, e + 8);
        let len = u64_at(b, e + 16);
        if let Some(end) = off.checked_add(len) {
            if end <= b.len() as u64 {
                let crc = crc32fast::hash(&b[off as usize..end as usize]);
                b[e + 24..e + 28].copy_from_slice(&crc.to_le_bytes());
            }
        }
        e += 32;
    }
    let mut h = crc32fast::Hasher::new();
    h.update(&b[..28]);
    h.update(&b[32..dir_end.max(32)]);
    let crc = h.finalize();
    b[28..32].copy_from_slice(&crc.to_le_bytes());
}

fn check(data: &[u8]) {
    let read = hce_format::read(data);
    let problems = hce_format::validate_bytes(data);
    if problems.is_empty() {
        assert!(read.is_ok(), "valid per validator but unreadable: {read:?}");
    }
    if let Ok(c) = read {
        for o in &c.objects {
            let _ = hce_format::triangle_trees(o);
        }
        let bytes = hce_format::write(&c).expect("a read container is writable");
        let again = hce_format::read(&bytes).expect("rewritten file reads");
        assert_eq!(hce_format::write(&again).unwrap(), bytes);
    }
}

fuzz_target!(|data: &[u8]| {
    check(data);
    let mut sealed = data.to_vec();
    reseal(&mut sealed);
    if sealed != data {
        check(&sealed);
    }
});
