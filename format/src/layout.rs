//! The fixed parts of the container (SPEC.md, Appendix A): file identifier, header and section
//! directory, and the bounds-checked parsing of header and directory.

use crate::error::ReadError;
use crate::section::SectionType;

/// The 8-byte file identifier (SPEC.md A.2), built like PNG's to catch 7-bit and text-mode
/// transfer corruption.
pub const IDENTIFIER: [u8; 8] = [0x89, b'H', b'C', b'E', 0x0D, 0x0A, 0x1A, 0x0A];
/// The major version this crate reads and writes (SPEC.md A.3).
pub const MAJOR_VERSION: u16 = 1;
/// The minor version this crate writes; it reads every minor version of [`MAJOR_VERSION`].
pub const MINOR_VERSION: u16 = 1;
/// Identifier plus header.
pub const HEADER_LEN: u64 = 32;
/// One directory entry (SPEC.md A.4).
pub const DIRECTORY_ENTRY_LEN: u64 = 32;
/// Every section starts at a multiple of this (wgpu's storage-buffer offset alignment).
pub const SECTION_ALIGNMENT: u64 = 256;
/// `object` value of file-level sections.
pub const FILE_LEVEL: u32 = u32::MAX;
/// Object record size written by version 1.0; readers accept larger records (SPEC.md A.7).
pub const OBJECT_RECORD_LEN: u32 = 64;

/// The header fields (SPEC.md A.3).
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub struct Header {
    pub major_version: u16,
    pub minor_version: u16,
    pub section_count: u32,
    pub file_length: u64,
    pub flags: u32,
    pub header_crc32: u32,
}

/// One directory entry (SPEC.md A.4).
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub struct SectionEntry {
    pub kind: SectionType,
    /// Object index, or [`FILE_LEVEL`].
    pub object: u32,
    pub offset: u64,
    pub length: u64,
    pub crc32: u32,
}

impl SectionEntry {
    /// The section's bytes; `bytes` must be the container [`read_layout`] accepted.
    pub fn data<'a>(&self, bytes: &'a [u8]) -> &'a [u8] {
        // read_layout checked offset + length <= file_length == bytes.len().
        let start = self.offset as usize;
        bytes
            .get(start..start + self.length as usize)
            .unwrap_or(&[])
    }

    pub fn computed_crc32(&self, bytes: &[u8]) -> u32 {
        crc32fast::hash(self.data(bytes))
    }

    pub fn checksum_ok(&self, bytes: &[u8]) -> bool {
        self.computed_crc32(bytes) == self.crc32
    }

    /// `"POSN of object 3"` or `"META"`, for messages.
    pub fn describe(&self) -> String {
        if self.object == FILE_LEVEL {
            self.kind.to_string()
        } else {
            format!("{} of object {}", self.kind, self.object)
        }
    }
}

/// Header and directory of a container whose structure has been checked.
#[derive(Clone, Debug, PartialEq, Eq)]
pub struct Layout {
    pub header: Header,
    pub sections: Vec<SectionEntry>,
}

impl Layout {
    /// End of the directory: the first byte a section may use.
    pub fn directory_end(&self) -> u64 {
        HEADER_LEN + DIRECTORY_ENTRY_LEN * u64::from(self.header.section_count)
    }
}

pub(crate) fn u16_at(b: &[u8], at: usize) -> u16 {
    u16::from_le_bytes([b[at], b[at + 1]])
}

pub(crate) fn u32_at(b: &[u8], at: usize) -> u32 {
    u32::from_le_bytes([b[at], b[at + 1], b[at + 2], b[at + 3]])
}

pub(crate) fn u64_at(b: &[u8], at: usize) -> u64 {
    u64::from(u32_at(b, at)) | (u64::from(u32_at(b, at + 4)) << 32)
}

/// Explains a wrong identifier: which transfer corruption the bytes suggest (SPEC.md A.2).
fn identifier_problem(found: &[u8]) -> ReadError {
    let n = found.len().min(8);
    let found_hex = found[..n]
        .iter()
        .map(|b| format!("{b:02x}"))
        .collect::<Vec<_>>()
        .join(" ");
    let hint = if found.starts_with(b"\x09HCE") || found.starts_with(b"HCE") {
        "the high bit of byte 0 was stripped: the file went through a 7-bit channel; transfer it in binary mode"
    } else if found.starts_with(b"\x89HCE\n\x1a") || found.starts_with(b"\x89HCE\r\r\n") {
        "line endings were converted: the file was transferred in text mode; transfer it in binary mode"
    } else if found.starts_with(b"glTF") {
        "this is a GLB file; hce reads the container embedded in it through its EXT_hce_baked_lighting extension"
    } else if found.starts_with(b"\x89HCE") {
        "the identifier is damaged; transfer the file in binary mode"
    } else {
        "this is not an .hce container"
    };
    ReadError::BadIdentifier {
        found: found_hex,
        hint,
    }
}

/// Parses and checks the identifier, header and directory (SPEC.md A.2–A.4). Section contents
/// and checksums are not looked at.
pub fn read_layout(bytes: &[u8]) -> Result<Layout, ReadError> {
    let id_len = bytes.len().min(IDENTIFIER.len());
    if bytes[..id_len] != IDENTIFIER[..id_len] {
        return Err(identifier_problem(bytes));
    }
    let available = bytes.len() as u64;
    if available < HEADER_LEN {
        return Err(ReadError::Truncated {
            what: "header",
            needed: HEADER_LEN,
            available,
        });
    }
    let header = Header {
        major_version: u16_at(bytes, 8),
        minor_version: u16_at(bytes, 10),
        section_count: u32_at(bytes, 12),
        file_length: u64_at(bytes, 16),
        flags: u32_at(bytes, 24),
        header_crc32: u32_at(bytes, 28),
    };
    if header.major_version != MAJOR_VERSION {
        return Err(ReadError::UnsupportedVersion {
            major: header.major_version,
            minor: header.minor_version,
        });
    }
    let directory_end = HEADER_LEN + DIRECTORY_ENTRY_LEN * u64::from(header.section_count);
    if directory_end > header.file_length {
        return Err(ReadError::DirectoryBeyondFileLength {
            section_count: header.section_count,
            file_length: header.file_length,
        });
    }
    if header.file_length != available {
        return Err(ReadError::LengthMismatch {
            header: header.file_length,
            actual: available,
        });
    }
    // directory_end <= file_length == bytes.len(), so these casts and slices are in range.
    let directory = &bytes[HEADER_LEN as usize..directory_end as usize];
    let mut hasher = crc32fast::Hasher::new();
    hasher.update(&bytes[..28]);
    hasher.update(directory);
    let computed = hasher.finalize();
    if computed != header.header_crc32 {
        return Err(ReadError::HeaderChecksum {
            stored: header.header_crc32,
            computed,
        });
    }

    let mut sections = Vec::with_capacity(header.section_count as usize);
    for (index, e) in directory
        .chunks_exact(DIRECTORY_ENTRY_LEN as usize)
        .enumerate()
    {
        let entry = SectionEntry {
            kind: SectionType::from_u32(u32_at(e, 0)),
            object: u32_at(e, 4),
            offset: u64_at(e, 8),
            length: u64_at(e, 16),
            crc32: u32_at(e, 24),
        };
        if entry.offset % SECTION_ALIGNMENT != 0 {
            return Err(ReadError::SectionMisaligned {
                index,
                section: entry.describe(),
                offset: entry.offset,
            });
        }
        if entry.offset < directory_end {
            return Err(ReadError::SectionInsideDirectory {
                index,
                section: entry.describe(),
                offset: entry.offset,
                directory_end,
            });
        }
        match entry.offset.checked_add(entry.length) {
            Some(end) if end <= header.file_length => {}
            _ => {
                return Err(ReadError::SectionOutOfBounds {
                    index,
                    section: entry.describe(),
                    offset: entry.offset,
                    length: entry.length,
                    file_length: header.file_length,
                })
            }
        }
        sections.push(entry);
    }

    // Overlaps: sort the non-empty sections by offset and compare neighbours.
    let mut order: Vec<usize> = (0..sections.len())
        .filter(|&i| sections[i].length > 0)
        .collect();
    order.sort_by_key(|&i| (sections[i].offset, i));
    for w in order.windows(2) {
        let (a, b) = (&sections[w[0]], &sections[w[1]]);
        if a.offset + a.length > b.offset {
            return Err(ReadError::SectionsOverlap {
                first: w[0].min(w[1]),
                second: w[0].max(w[1]),
            });
        }
    }

    // A known type at most once per object.
    let mut keys: Vec<(SectionType, u32, usize)> = sections
        .iter()
        .enumerate()
        .filter(|(_, s)| s.kind.is_known())
        .map(|(i, s)| (s.kind, s.object, i))
        .collect();
    keys.sort();
    for w in keys.windows(2) {
        if w[0].0 == w[1].0 && w[0].1 == w[1].1 {
            return Err(ReadError::DuplicateSection {
                first: w[0].2,
                second: w[1].2,
                section: sections[w[1].2].describe(),
            });
        }
    }
    Ok(Layout { header, sections })
}
