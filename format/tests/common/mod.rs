//! Helpers shared by the format tests: re-sealing checksums after deliberate corruption.

#![allow(dead_code)]

pub fn u32_at(b: &[u8], at: usize) -> u32 {
    u32::from_le_bytes(b[at..at + 4].try_into().unwrap())
}

pub fn u64_at(b: &[u8], at: usize) -> u64 {
    u64::from_le_bytes(b[at..at + 8].try_into().unwrap())
}

pub fn put_u32(b: &mut [u8], at: usize, v: u32) {
    b[at..at + 4].copy_from_slice(&v.to_le_bytes());
}

pub fn put_u64(b: &mut [u8], at: usize, v: u64) {
    b[at..at + 8].copy_from_slice(&v.to_le_bytes());
}

/// Recomputes every section CRC that lies inside the file, then the header CRC, so that a
/// corruption reaches the checks behind the checksums. Tolerates any bytes.
pub fn reseal(b: &mut [u8]) {
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
                put_u32(b, e + 24, crc);
            }
        }
        e += 32;
    }
    let mut h = crc32fast::Hasher::new();
    h.update(&b[..28]);
    h.update(&b[32..dir_end.max(32)]);
    let crc = h.finalize();
    put_u32(b, 28, crc);
}

/// Offset of directory entry `i`.
pub fn entry(i: usize) -> usize {
    32 + 32 * i
}
