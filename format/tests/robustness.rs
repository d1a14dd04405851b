//! Truncation, bit flips and field-by-field corruption of valid files: every damaged file gets a
//! specific error from the reader and at least one problem from the validator, never a panic.

mod common;

use common::*;
use hce_format::{example, read, validate_bytes, write, ReadError, SectionType};

fn example_bytes() -> Vec<u8> {
    write(&example::single_triangle()).unwrap()
}

#[test]
fn truncation_at_every_length_is_reported() {
    for c in [example::single_triangle(), example::two_triangles()] {
        let bytes = write(&c).unwrap();
        for n in 0..bytes.len() {
            let err = read(&bytes[..n]).unwrap_err();
            if n < 32 {
                assert_eq!(
                    err,
                    ReadError::Truncated {
                        what: "header",
                        needed: 32,
                        available: n as u64
                    }
                );
            } else {
                assert_eq!(
                    err,
                    ReadError::LengthMismatch {
                        header: bytes.len() as u64,
                        actual: n as u64
                    }
                );
                assert!(err.to_string().contains("truncated"), "{err}");
            }
            let problems = validate_bytes(&bytes[..n]);
            assert_eq!(problems.len(), 1, "{problems:?}");
        }
    }
}

#[test]
fn appended_bytes_are_reported() {
    let mut bytes = example_bytes();
    bytes.push(0);
    let err = read(&bytes).unwrap_err();
    assert!(
        err.to_string().contains("extended or concatenated"),
        "{err}"
    );
}

/// Which error a flipped bit at `at` must produce.
fn expected_for_flip(bytes: &[u8], at: usize) -> &'static str {
    let n = u32_at(bytes, 12) as usize;
    match at {
        0..=7 => "BadIdentifier",
        8..=9 => "UnsupportedVersion",
        _ if at < 32 + 32 * n => "header",
        _ => "section",
    }
}

#[test]
fn every_single_bit_flip_is_detected() {
    let bytes = example_bytes();
    let layout = hce_format::read_layout(&bytes).unwrap();
    let in_section = |at: usize| {
        layout
            .sections
            .iter()
            .position(|s| (s.offset..s.offset + s.length).contains(&(at as u64)))
    };
    let mut padding_flips = 0;
    for at in 0..bytes.len() {
        for bit in 0..8 {
            let mut b = bytes.clone();
            b[at] ^= 1 << bit;
            let problems = validate_bytes(&b);
            assert!(
                !problems.is_empty(),
                "flip of byte {at} bit {bit} went unnoticed"
            );
            let result = read(&b);
            match expected_for_flip(&bytes, at) {
                "BadIdentifier" => {
                    assert!(
                        matches!(result, Err(ReadError::BadIdentifier { .. })),
                        "{at}: {result:?}"
                    )
                }
                "UnsupportedVersion" => assert!(
                    matches!(result, Err(ReadError::UnsupportedVersion { .. })),
                    "{at}: {result:?}"
                ),
                "header" => assert!(
                    matches!(
                        result,
                        Err(ReadError::HeaderChecksum { .. }
                            | ReadError::DirectoryBeyondFileLength { .. }
                            | ReadError::LengthMismatch { .. })
                    ),
                    "{at}: {result:?}"
                ),
                _ => match in_section(at) {
                    Some(i) => assert!(
                        matches!(result, Err(ReadError::SectionChecksum { index, .. }) if index == i),
                        "{at}: {result:?}"
                    ),
                    None => {
                        // Padding is outside every checksum: the reader accepts it, the
                        // validator names the byte.
                        assert!(result.is_ok());
                        assert_eq!(problems[0].location, format!("file[{at}]"));
                        padding_flips += 1;
                    }
                },
            }
        }
    }
    assert!(padding_flips > 0);
}

#[test]
fn text_mode_corruption_is_explained() {
    let bytes = example_bytes();
    // CR LF -> LF, as a text-mode transfer on Windows would do.
    let mut crlf = bytes[..4].to_vec();
    crlf.extend_from_slice(&bytes[5..]);
    let e = read(&crlf).unwrap_err().to_string();
    assert!(e.contains("line endings were converted"), "{e}");
    // LF -> CR LF, the other direction.
    let mut lf = bytes[..4].to_vec();
    lf.extend_from_slice(b"\r\r\n\x1a\r\n");
    lf.extend_from_slice(&bytes[8..]);
    let e = read(&lf).unwrap_err().to_string();
    assert!(e.contains("line endings were converted"), "{e}");
    let mut stripped = bytes.clone();
    stripped[0] &= 0x7f;
    let e = read(&stripped).unwrap_err().to_string();
    assert!(e.contains("high bit"), "{e}");
    let e = read(b"glTF\x02\0\0\0").unwrap_err().to_string();
    assert!(e.contains("GLB"), "{e}");
}

fn corrupt(f: impl FnOnce(&mut Vec<u8>)) -> Result<hce_format::Container, ReadError> {
    let mut b = example_bytes();
    f(&mut b);
    reseal(&mut b);
    read(&b)
}

#[test]
fn each_header_field_has_its_own_error() {
    assert_eq!(
        corrupt(|b| b[8] = 2).unwrap_err(),
        ReadError::UnsupportedVersion { major: 2, minor: 0 }
    );
    // A newer minor version of major 1 stays readable.
    assert_eq!(corrupt(|b| b[10] = 7).unwrap(), example::single_triangle());
    assert!(matches!(
        corrupt(|b| put_u32(b, 12, 1000)).unwrap_err(),
        ReadError::DirectoryBeyondFileLength {
            section_count: 1000,
            ..
        }
    ));
    assert!(matches!(
        corrupt(|b| put_u32(b, 12, u32::MAX)).unwrap_err(),
        ReadError::DirectoryBeyondFileLength { .. }
    ));
    assert!(matches!(
        corrupt(|b| put_u64(b, 16, 5000)).unwrap_err(),
        ReadError::LengthMismatch { header: 5000, .. }
    ));
    assert!(matches!(
        corrupt(|b| put_u64(b, 16, u64::MAX)).unwrap_err(),
        ReadError::LengthMismatch { .. }
    ));
    // Unknown flags are ignored (SPEC.md A.3).
    assert!(corrupt(|b| put_u32(b, 24, 0x8000_0000)).is_ok());
    let mut b = example_bytes();
    b[28] ^= 1;
    assert!(matches!(
        read(&b).unwrap_err(),
        ReadError::HeaderChecksum { .. }
    ));
}

#[test]
fn each_directory_field_has_its_own_error() {
    let posn = entry(2);
    // type: a required section renamed to an unknown type is skipped, so it is missing.
    assert_eq!(
        corrupt(|b| b[posn..posn + 4].copy_from_slice(b"xyzw")).unwrap_err(),
        ReadError::MissingSection {
            kind: SectionType::POSN,
            object: Some(0)
        }
    );
    assert!(matches!(
        corrupt(|b| b[posn..posn + 4].copy_from_slice(b"TRIS")).unwrap_err(),
        ReadError::DuplicateSection {
            first: 2,
            second: 3,
            ..
        }
    ));
    // object
    assert!(matches!(
        corrupt(|b| put_u32(b, posn + 4, 1)).unwrap_err(),
        ReadError::SectionObjectOutOfRange {
            index: 2,
            object: 1,
            object_count: 1,
            ..
        }
    ));
    assert!(matches!(
        corrupt(|b| put_u32(b, entry(0) + 4, 0)).unwrap_err(),
        ReadError::FileLevelSectionWithObject { index: 0, .. }
    ));
    // offset
    assert!(matches!(
        corrupt(|b| put_u64(b, posn + 8, 0x401)).unwrap_err(),
        ReadError::SectionMisaligned {
            index: 2,
            offset: 0x401,
            ..
        }
    ));
    assert!(matches!(
        corrupt(|b| put_u64(b, posn + 8, 0x100)).unwrap_err(),
        ReadError::SectionInsideDirectory { index: 2, .. }
    ));
    assert!(matches!(
        corrupt(|b| put_u64(b, posn + 8, 0x1_0000)).unwrap_err(),
        ReadError::SectionOutOfBounds { index: 2, .. }
    ));
    assert!(matches!(
        corrupt(|b| put_u64(b, posn + 8, u64::MAX - 255)).unwrap_err(),
        ReadError::SectionOutOfBounds { index: 2, .. }
    ));
    assert!(matches!(
        corrupt(|b| put_u64(b, posn + 8, 0x500)).unwrap_err(),
        ReadError::SectionsOverlap {
            first: 2,
            second: 3
        }
    ));
    // length
    assert!(matches!(
        corrupt(|b| put_u64(b, posn + 16, 0x24 - 4)).unwrap_err(),
        ReadError::SectionLength {
            expected: 0x24,
            actual: 0x20,
            ..
        }
    ));
    assert!(matches!(
        corrupt(|b| put_u64(b, posn + 16, u64::MAX)).unwrap_err(),
        ReadError::SectionOutOfBounds { .. }
    ));
    // crc
    let mut b = example_bytes();
    put_u32(&mut b, posn + 24, 0);
    let mut h = crc32fast::Hasher::new();
    h.update(&b[..28]);
    h.update(&b[32..32 + 32 * 15]);
    let crc = h.finalize();
    put_u32(&mut b, 28, crc);
    assert!(matches!(
        read(&b).unwrap_err(),
        ReadError::SectionChecksum {
            index: 2,
            stored: 0,
            ..
        }
    ));
    let problems = validate_bytes(&b);
    assert_eq!(problems.len(), 1, "{problems:?}");
    assert_eq!(problems[0].location, "sections[2] (POSN of object 0)");
}

#[test]
fn object_table_fields_have_their_own_errors() {
    let rec = 0x300 + 8;
    assert!(matches!(
        corrupt(|b| put_u32(b, rec + 8, 9)).unwrap_err(),
        ReadError::UnknownObjectKind { object: 0, kind: 9 }
    ));
    assert!(matches!(
        corrupt(|b| put_u32(b, rec + 24, 4)).unwrap_err(),
        ReadError::SectionLength { .. }
    ));
    assert!(matches!(
        corrupt(|b| put_u32(b, rec + 36, 7)).unwrap_err(),
        ReadError::EdgeCount {
            stored: 7,
            computed: 3,
            ..
        }
    ));
    assert!(matches!(
        corrupt(|b| put_u32(b, rec + 4, 100)).unwrap_err(),
        ReadError::ObjectTable { .. }
    ));
    assert!(matches!(
        corrupt(|b| put_u32(b, 0x300, u32::MAX)).unwrap_err(),
        ReadError::ObjectTable { .. }
    ));
    assert!(matches!(
        corrupt(|b| put_u32(b, 0x300 + 4, 8)).unwrap_err(),
        ReadError::ObjectTable { .. }
    ));
    assert!(matches!(
        corrupt(|b| put_u32(b, 0x200 + 8, 1000)).unwrap_err(),
        ReadError::Metadata { .. }
    ));
    assert!(matches!(
        corrupt(|b| b[0x210] = 0xff).unwrap_err(),
        ReadError::Metadata { .. }
    ));
}

#[test]
fn unknown_sections_are_skipped() {
    // Append a private section after the others: a v1.0 reader must ignore it.
    let c = example::single_triangle();
    let bytes = write(&c).unwrap();
    let n = u32_at(&bytes, 12) as usize;
    let first = u64_at(&bytes, entry(0) + 8) as usize;
    // Room for one more entry: move every section 256 bytes further.
    let mut b = bytes[..32 + 32 * n].to_vec();
    for i in 0..n {
        let off = u64_at(&b, entry(i) + 8);
        put_u64(&mut b, entry(i) + 8, off + 256);
    }
    let data_offset = (bytes.len() + 256).next_multiple_of(256) as u64;
    b.extend_from_slice(b"priv");
    b.extend_from_slice(&u32::MAX.to_le_bytes());
    b.extend_from_slice(&data_offset.to_le_bytes());
    b.extend_from_slice(&5u64.to_le_bytes());
    b.extend_from_slice(&[0; 8]);
    b.resize(first + 256, 0);
    b.extend_from_slice(&bytes[first..]);
    b.resize(data_offset as usize, 0);
    b.extend_from_slice(b"hello");
    put_u32(&mut b, 12, n as u32 + 1);
    let len = b.len() as u64;
    put_u64(&mut b, 16, len);
    reseal(&mut b);
    assert_eq!(read(&b).unwrap(), c);
    assert_eq!(validate_bytes(&b), vec![]);
}

#[test]
fn corner_colours_are_optional_and_checked_against_the_colours() {
    // With corner colours (SPEC.md A.10) the file is a 1.1 file that reads back the same.
    let mut c = example::single_triangle();
    let o = &mut c.objects[0];
    o.corner_colours = o.colours.iter().flat_map(|&x| [x, x ^ 1, x ^ 2]).collect();
    let mut b = write(&c).unwrap();
    assert_eq!(u16::from_le_bytes([b[10], b[11]]), 1, "minor version");
    assert_eq!(read(&b).unwrap(), c);
    // Without them, a 1.0 file as before.
    assert_eq!(
        u16::from_le_bytes([example_bytes()[10], example_bytes()[11]]),
        0
    );
    // A CCOL one word short is refused, naming it.
    let count = u32::from_le_bytes(b[12..16].try_into().unwrap()) as usize;
    let at = (0..count)
        .map(|i| 32 + 32 * i)
        .find(|&e| b[e..e + 4] == *b"CCOL")
        .expect("a CCOL entry");
    let len = u64::from_le_bytes(b[at + 16..at + 24].try_into().unwrap());
    put_u64(&mut b, at + 16, len - 4);
    reseal(&mut b);
    let err = read(&b).unwrap_err();
    assert!(
        matches!(&err, ReadError::SectionLength { section, .. } if section.contains("CCOL")),
        "{err:?}"
    );
}
