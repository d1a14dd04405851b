//! Errors of the reader and writer. Each variant cites the SPEC.md section it enforces.

use crate::section::SectionType;

/// Why bytes are not a readable container.
#[derive(Debug, thiserror::Error, Clone, PartialEq, Eq)]
pub enum ReadError {
    #[error("bad file identifier ({found}): {hint} (SPEC.md A.2)")]
    BadIdentifier { found: String, hint: &'static str },
    #[error("file truncated: the {what} needs {needed} bytes but only {available} are present (SPEC.md A.3)")]
    Truncated {
        what: &'static str,
        needed: u64,
        available: u64,
    },
    #[error("unsupported container version {major}.{minor}: this reader reads major version 1 only; use a newer hce (SPEC.md A.8)")]
    UnsupportedVersion { major: u16, minor: u16 },
    #[error("header says {section_count} sections, whose directory does not fit in file_length {file_length} (SPEC.md A.3)")]
    DirectoryBeyondFileLength {
        section_count: u32,
        file_length: u64,
    },
    #[error("header says the file is {header} bytes long but it is {actual} bytes: the file was {} (SPEC.md A.3)",
        if actual < header { "truncated" } else { "extended or concatenated" })]
    LengthMismatch { header: u64, actual: u64 },
    #[error("header checksum mismatch (stored {stored:08x}, computed {computed:08x}): the header or the section directory is corrupted (SPEC.md A.3)")]
    HeaderChecksum { stored: u32, computed: u32 },
    #[error(
        "sections[{index}] ({section}): offset {offset} is not a multiple of 256 (SPEC.md A.1)"
    )]
    SectionMisaligned {
        index: usize,
        section: String,
        offset: u64,
    },
    #[error("sections[{index}] ({section}): offset {offset} lies inside the header or directory, which end at {directory_end} (SPEC.md A.4)")]
    SectionInsideDirectory {
        index: usize,
        section: String,
        offset: u64,
        directory_end: u64,
    },
    #[error("sections[{index}] ({section}): bytes {offset}+{length} extend past the end of the file ({file_length} bytes) (SPEC.md A.4)")]
    SectionOutOfBounds {
        index: usize,
        section: String,
        offset: u64,
        length: u64,
        file_length: u64,
    },
    #[error("sections[{first}] and sections[{second}] overlap (SPEC.md A.4)")]
    SectionsOverlap { first: usize, second: usize },
    #[error("sections[{first}] and sections[{second}] are both {section}; a known section type appears once per object (SPEC.md A.4)")]
    DuplicateSection {
        first: usize,
        second: usize,
        section: String,
    },
    #[error("sections[{index}] ({section}): checksum mismatch (stored {stored:08x}, computed {computed:08x}): the section is corrupted (SPEC.md A.4)")]
    SectionChecksum {
        index: usize,
        section: String,
        stored: u32,
        computed: u32,
    },
    #[error("required section {kind} is missing{} (SPEC.md A.5)",
        match object { Some(o) => format!(" for object {o}"), None => String::new() })]
    MissingSection {
        kind: SectionType,
        object: Option<u32>,
    },
    #[error("sections[{index}] ({kind}): object index {object} is out of range; the file has {object_count} objects (SPEC.md A.4)")]
    SectionObjectOutOfRange {
        index: usize,
        kind: SectionType,
        object: u32,
        object_count: u32,
    },
    #[error("sections[{index}] ({kind}): a file-level section must have object 0xffffffff, found {object} (SPEC.md A.4)")]
    FileLevelSectionWithObject {
        index: usize,
        kind: SectionType,
        object: u32,
    },
    #[error("{section}: length is {actual} bytes but the object record implies {expected} (SPEC.md A.5)")]
    SectionLength {
        section: String,
        expected: u64,
        actual: u64,
    },
    #[error("META: {reason} (SPEC.md A.6)")]
    Metadata { reason: String },
    #[error("OBJS: {reason} (SPEC.md A.7)")]
    ObjectTable { reason: String },
    #[error("objects[{object}]: unknown kind {kind}; version 1 knows 0 (multiresolution) and 1 (flat) (SPEC.md A.7)")]
    UnknownObjectKind { object: u32, kind: u32 },
    #[error("objects[{object}]: edge_count is {stored} but the EDGE section's largest id + 1 is {computed} (SPEC.md A.7)")]
    EdgeCount {
        object: u32,
        stored: u32,
        computed: u64,
    },
}

/// Why a container cannot be written.
#[derive(Debug, thiserror::Error)]
pub enum WriteError {
    #[error(
        "objects[{object}].{field}: {reason}; fix the container before writing it (SPEC.md A.5)"
    )]
    Shape {
        object: usize,
        field: &'static str,
        reason: String,
    },
    #[error("{what} does not fit the 32-bit counts of container version 1 (SPEC.md A.7)")]
    TooLarge { what: String },
}
