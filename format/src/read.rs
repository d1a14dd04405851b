//! The reader: rebuilds a [`Container`] from bytes (SPEC.md Appendix A).
//!
//! It never panics and never allocates more than the input can justify: every count read from
//! the file is checked, with checked arithmetic, against the length of the section that holds
//! the data, and every array is built from bytes that are present. Content invariants (indices
//! in range, adjacency consistency, trees) are left to [`crate::validate()`].

use crate::error::ReadError;
use crate::layout::*;
use crate::model::{Container, ControlMesh, Metadata, Object, ObjectKind, TriangleRecord};
use crate::section::SectionType;
use std::collections::BTreeMap;

/// What the reader checks beyond structure.
#[derive(Clone, Copy, Debug)]
pub struct ReadOptions {
    /// Verify every section's CRC-32 (default `true`). The validator turns it off to go on and
    /// report content problems after listing checksum mismatches.
    pub verify_checksums: bool,
}

impl Default for ReadOptions {
    fn default() -> Self {
        Self {
            verify_checksums: true,
        }
    }
}

/// One object record as stored (SPEC.md A.7).
#[derive(Clone, Debug, PartialEq, Eq)]
pub struct ObjectRecord {
    pub name: String,
    pub kind: u32,
    pub geometry_hash: u64,
    pub vertex_count: u32,
    pub triangle_count: u32,
    pub ring_length: u32,
    pub edge_count: u32,
    pub normal_count: u32,
    pub colour_count: u32,
    pub bit_len: u64,
}

/// Reads and checks a container, checksums included.
pub fn read(bytes: &[u8]) -> Result<Container, ReadError> {
    read_with(bytes, &ReadOptions::default())
}

/// Reads a container with explicit options.
pub fn read_with(bytes: &[u8], options: &ReadOptions) -> Result<Container, ReadError> {
    let layout = read_layout(bytes)?;
    read_from_layout(bytes, &layout, options)
}

fn file_section<'a>(
    bytes: &'a [u8],
    layout: &Layout,
    kind: SectionType,
) -> Result<&'a [u8], ReadError> {
    for (index, s) in layout.sections.iter().enumerate() {
        if s.kind == kind {
            if s.object != FILE_LEVEL {
                return Err(ReadError::FileLevelSectionWithObject {
                    index,
                    kind,
                    object: s.object,
                });
            }
            return Ok(s.data(bytes));
        }
    }
    Err(ReadError::MissingSection { kind, object: None })
}

/// Parses the `META` section (SPEC.md A.6).
pub fn read_metadata(data: &[u8]) -> Result<Metadata, ReadError> {
    let bad = |reason: String| ReadError::Metadata { reason };
    if data.len() < 16 {
        return Err(bad(format!(
            "section is {} bytes, the fixed part needs 16",
            data.len()
        )));
    }
    let g = u64::from(u32_at(data, 8));
    let p = u64::from(u32_at(data, 12));
    let end = 16 + g + p;
    if end > data.len() as u64 {
        return Err(bad(format!(
            "generator ({g} bytes) and bake parameters ({p} bytes) run past the section's {} bytes",
            data.len()
        )));
    }
    let text = |range: std::ops::Range<usize>, what: &str| {
        String::from_utf8(data[range].to_vec())
            .map_err(|_| bad(format!("{what} is not valid UTF-8")))
    };
    let g_end = 16 + g as usize;
    Ok(Metadata {
        source_hash: u64_at(data, 0),
        generator: text(16..g_end, "generator")?,
        bake_parameters: text(g_end..end as usize, "bake parameters")?,
    })
}

/// Parses the `OBJS` section (SPEC.md A.7).
pub fn read_object_table(data: &[u8]) -> Result<Vec<ObjectRecord>, ReadError> {
    let bad = |reason: String| ReadError::ObjectTable { reason };
    if data.len() < 8 {
        return Err(bad(format!(
            "section is {} bytes, the fixed part needs 8",
            data.len()
        )));
    }
    let count = u32_at(data, 0);
    let record_size = u32_at(data, 4);
    if record_size < OBJECT_RECORD_LEN {
        return Err(bad(format!("record_size {record_size} is smaller than the {OBJECT_RECORD_LEN} bytes of version 1.0")));
    }
    let pool_start = u64::from(count) * u64::from(record_size) + 8;
    if pool_start > data.len() as u64 {
        return Err(bad(format!(
            "{count} records of {record_size} bytes do not fit in the section's {} bytes",
            data.len()
        )));
    }
    let pool = &data[pool_start as usize..];
    let mut records = Vec::with_capacity(count as usize);
    for i in 0..count as usize {
        let r = &data[8 + i * record_size as usize..];
        let name_offset = u64::from(u32_at(r, 0));
        let name_length = u64::from(u32_at(r, 4));
        let name_end = name_offset + name_length;
        if name_end > pool.len() as u64 {
            return Err(bad(format!("objects[{i}]: name bytes {name_offset}..{name_end} lie outside the {}-byte name pool", pool.len())));
        }
        let name = String::from_utf8(pool[name_offset as usize..name_end as usize].to_vec())
            .map_err(|_| bad(format!("objects[{i}]: name is not valid UTF-8")))?;
        records.push(ObjectRecord {
            name,
            kind: u32_at(r, 8),
            geometry_hash: u64_at(r, 16),
            vertex_count: u32_at(r, 24),
            triangle_count: u32_at(r, 28),
            ring_length: u32_at(r, 32),
            edge_count: u32_at(r, 36),
            normal_count: u32_at(r, 40),
            colour_count: u32_at(r, 44),
            bit_len: u64_at(r, 48),
        });
    }
    Ok(records)
}

fn u32_array(data: &[u8]) -> Vec<u32> {
    data.chunks_exact(4)
        .map(|c| u32::from_le_bytes([c[0], c[1], c[2], c[3]]))
        .collect()
}

fn f32_array(data: &[u8]) -> Vec<f32> {
    data.chunks_exact(4)
        .map(|c| f32::from_le_bytes([c[0], c[1], c[2], c[3]]))
        .collect()
}

/// Expected byte length of a per-object section from the object's record, or `None` on overflow.
pub fn expected_length(kind: SectionType, r: &ObjectRecord) -> Option<u64> {
    let v = u64::from(r.vertex_count);
    let f = u64::from(r.triangle_count);
    let elements = match kind {
        SectionType::POSN => 3 * v,
        SectionType::TRIS | SectionType::CSPK | SectionType::NBRS | SectionType::EDGE => 3 * f,
        SectionType::ROFS => v + 1,
        SectionType::RING | SectionType::SFLG => u64::from(r.ring_length),
        SectionType::VFLG => v,
        SectionType::TREC => 4 * f,
        SectionType::NRML => 3 * u64::from(r.normal_count),
        SectionType::BITS => r.bit_len.div_ceil(32),
        SectionType::COLR => u64::from(r.colour_count),
        SectionType::CCOL => 3 * u64::from(r.colour_count),
        _ => return None,
    };
    elements.checked_mul(4)
}

/// Reads the container described by an already checked layout.
pub fn read_from_layout(
    bytes: &[u8],
    layout: &Layout,
    options: &ReadOptions,
) -> Result<Container, ReadError> {
    if options.verify_checksums {
        for (index, s) in layout.sections.iter().enumerate() {
            let computed = s.computed_crc32(bytes);
            if computed != s.crc32 {
                return Err(ReadError::SectionChecksum {
                    index,
                    section: s.describe(),
                    stored: s.crc32,
                    computed,
                });
            }
        }
    }
    let metadata = read_metadata(file_section(bytes, layout, SectionType::META)?)?;
    let records = read_object_table(file_section(bytes, layout, SectionType::OBJS)?)?;
    let object_count = records.len() as u32;

    // Index the known per-object sections; skip unknown types (SPEC.md A.8).
    let mut by_key: BTreeMap<(u32, SectionType), &SectionEntry> = BTreeMap::new();
    for (index, s) in layout.sections.iter().enumerate() {
        if !s.kind.is_per_object() {
            if s.kind.is_known() && s.object != FILE_LEVEL {
                return Err(ReadError::FileLevelSectionWithObject {
                    index,
                    kind: s.kind,
                    object: s.object,
                });
            }
            continue;
        }
        if s.object >= object_count {
            return Err(ReadError::SectionObjectOutOfRange {
                index,
                kind: s.kind,
                object: s.object,
                object_count,
            });
        }
        by_key.insert((s.object, s.kind), s);
    }

    let mut objects = Vec::new();
    for (i, r) in records.iter().enumerate() {
        let i = i as u32;
        let kind = match r.kind {
            0 => ObjectKind::Multiresolution,
            1 => ObjectKind::Flat,
            k => return Err(ReadError::UnknownObjectKind { object: i, kind: k }),
        };
        // Check every section's presence and length before decoding any, so that a record with
        // huge counts fails before anything is allocated.
        let mut data: [&[u8]; 13] = [&[]; 13];
        for (slot, kind) in SectionType::PER_OBJECT.iter().enumerate() {
            let s = by_key.get(&(i, *kind)).ok_or(ReadError::MissingSection {
                kind: *kind,
                object: Some(i),
            })?;
            let expected = expected_length(*kind, r);
            if expected != Some(s.length) {
                return Err(ReadError::SectionLength {
                    section: s.describe(),
                    expected: expected.unwrap_or(u64::MAX),
                    actual: s.length,
                });
            }
            data[slot] = s.data(bytes);
        }
        let [posn, tris, rofs, ring, vflg, sflg, cspk, nbrs, edge, trec, nrml, bits, colr] = data;
        // Optional (SPEC.md A.10): absent, the object has no corner colours.
        let ccol = match by_key.get(&(i, SectionType::CCOL)) {
            None => &[][..],
            Some(s) => {
                let expected = expected_length(SectionType::CCOL, r);
                if expected != Some(s.length) {
                    return Err(ReadError::SectionLength {
                        section: s.describe(),
                        expected: expected.unwrap_or(u64::MAX),
                        actual: s.length,
                    });
                }
                s.data(bytes)
            }
        };
        let edges = u32_array(edge);
        let computed_edges = edges.iter().max().map_or(0, |&e| u64::from(e) + 1);
        if computed_edges != u64::from(r.edge_count) {
            return Err(ReadError::EdgeCount {
                object: i,
                stored: r.edge_count,
                computed: computed_edges,
            });
        }
        let normals = f32_array(nrml);
        objects.push(Object {
            name: r.name.clone(),
            kind,
            geometry_hash: r.geometry_hash,
            mesh: ControlMesh {
                positions: f32_array(posn),
                triangles: u32_array(tris),
                ring_offsets: u32_array(rofs),
                ring: u32_array(ring),
                vertex_flags: u32_array(vflg),
                spoke_flags: u32_array(sflg),
                corner_spokes: u32_array(cspk),
                neighbours: u32_array(nbrs),
                edges,
            },
            triangles: u32_array(trec)
                .chunks_exact(4)
                .map(|t| TriangleRecord {
                    bits_start: t[0],
                    colour_start: t[1],
                    normal_start: t[2],
                    normal_count: t[3],
                })
                .collect(),
            normals: normals
                .chunks_exact(3)
                .map(|n| [n[0], n[1], n[2]])
                .collect(),
            bits: u32_array(bits),
            bit_len: r.bit_len,
            colours: u32_array(colr),
            corner_colours: u32_array(ccol),
        });
    }
    Ok(Container { metadata, objects })
}
