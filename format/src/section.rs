//! Section types (SPEC.md A.5): the four ASCII bytes that name what a directory entry holds.
//! Its own module because both the layout (which parses the directory) and the reader's errors
//! (which name the section at fault) speak of them.

use std::fmt;

/// A section type: four ASCII bytes (SPEC.md A.5).
#[derive(Clone, Copy, PartialEq, Eq, Hash, PartialOrd, Ord)]
pub struct SectionType(pub [u8; 4]);

impl SectionType {
    pub const META: Self = Self(*b"META");
    pub const OBJS: Self = Self(*b"OBJS");
    pub const POSN: Self = Self(*b"POSN");
    pub const TRIS: Self = Self(*b"TRIS");
    pub const ROFS: Self = Self(*b"ROFS");
    pub const RING: Self = Self(*b"RING");
    pub const VFLG: Self = Self(*b"VFLG");
    pub const SFLG: Self = Self(*b"SFLG");
    pub const CSPK: Self = Self(*b"CSPK");
    pub const NBRS: Self = Self(*b"NBRS");
    pub const EDGE: Self = Self(*b"EDGE");
    pub const TREC: Self = Self(*b"TREC");
    pub const NRML: Self = Self(*b"NRML");
    pub const BITS: Self = Self(*b"BITS");
    pub const COLR: Self = Self(*b"COLR");
    /// Corner colours (SPEC.md A.10): optional, since version 1.1.
    pub const CCOL: Self = Self(*b"CCOL");

    /// The per-object sections, in the order the writer emits them.
    pub const PER_OBJECT: [Self; 13] = [
        Self::POSN,
        Self::TRIS,
        Self::ROFS,
        Self::RING,
        Self::VFLG,
        Self::SFLG,
        Self::CSPK,
        Self::NBRS,
        Self::EDGE,
        Self::TREC,
        Self::NRML,
        Self::BITS,
        Self::COLR,
    ];

    pub fn from_u32(v: u32) -> Self {
        Self(v.to_le_bytes())
    }

    pub fn to_u32(self) -> u32 {
        u32::from_le_bytes(self.0)
    }

    /// True for the types this version of the specification defines.
    pub fn is_known(self) -> bool {
        self == Self::META || self == Self::OBJS || self.is_per_object()
    }

    /// True for types that belong to an object rather than to the file.
    pub fn is_per_object(self) -> bool {
        Self::PER_OBJECT.contains(&self) || self == Self::CCOL
    }
}

impl fmt::Display for SectionType {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        if self.0.iter().all(|b| b.is_ascii_graphic() || *b == b' ') {
            f.write_str(std::str::from_utf8(&self.0).unwrap_or("????"))
        } else {
            write!(f, "0x{:08x}", self.to_u32())
        }
    }
}

impl fmt::Debug for SectionType {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        write!(f, "SectionType({self})")
    }
}
