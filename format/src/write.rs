//! The writer: serialises a [`Container`] byte for byte as SPEC.md Appendix A describes.
//! Output depends only on the container's content, so the same content gives the same bytes.

use crate::error::WriteError;
use crate::layout::*;
use crate::model::{Container, Object, ObjectKind};
use crate::section::SectionType;

fn shape(object: usize, field: &'static str, reason: String) -> WriteError {
    WriteError::Shape {
        object,
        field,
        reason,
    }
}

fn count_u32(n: usize, what: impl FnOnce() -> String) -> Result<u32, WriteError> {
    u32::try_from(n).map_err(|_| WriteError::TooLarge { what: what() })
}

/// The counts of one object record (SPEC.md A.7), checked against the arrays' shapes.
pub(crate) struct Counts {
    pub vertices: u32,
    pub triangles: u32,
    pub ring: u32,
    pub edges: u32,
    pub normals: u32,
    pub colours: u32,
}

fn object_counts(i: usize, o: &Object) -> Result<Counts, WriteError> {
    let m = &o.mesh;
    if m.positions.len() % 3 != 0 {
        return Err(shape(
            i,
            "mesh.positions",
            format!("length {} is not a multiple of 3", m.positions.len()),
        ));
    }
    if m.triangles.len() % 3 != 0 {
        return Err(shape(
            i,
            "mesh.triangles",
            format!("length {} is not a multiple of 3", m.triangles.len()),
        ));
    }
    let v = m.positions.len() / 3;
    let f = m.triangles.len() / 3;
    let expect = |field: &'static str, len: usize, want: usize, what: &str| {
        if len == want {
            Ok(())
        } else {
            Err(shape(
                i,
                field,
                format!("length {len}, expected {want} ({what})"),
            ))
        }
    };
    expect(
        "mesh.ring_offsets",
        m.ring_offsets.len(),
        v + 1,
        "vertices + 1",
    )?;
    expect(
        "mesh.vertex_flags",
        m.vertex_flags.len(),
        v,
        "one per vertex",
    )?;
    expect(
        "mesh.spoke_flags",
        m.spoke_flags.len(),
        m.ring.len(),
        "one per ring entry",
    )?;
    expect(
        "mesh.corner_spokes",
        m.corner_spokes.len(),
        3 * f,
        "three per triangle",
    )?;
    expect(
        "mesh.neighbours",
        m.neighbours.len(),
        3 * f,
        "three per triangle",
    )?;
    expect("mesh.edges", m.edges.len(), 3 * f, "three per triangle")?;
    expect(
        "triangles",
        o.triangles.len(),
        f,
        "one record per mesh triangle",
    )?;
    if !o.corner_colours.is_empty() {
        expect(
            "corner_colours",
            o.corner_colours.len(),
            3 * o.colours.len(),
            "none, or three per colour",
        )?;
    }
    let words = o.bit_len.div_ceil(32);
    if words != o.bits.len() as u64 {
        return Err(shape(
            i,
            "bits",
            format!(
                "{} words hold {} bits, expected {words} words for bit_len {}",
                o.bits.len(),
                o.bits.len() as u64 * 32,
                o.bit_len
            ),
        ));
    }
    let edges = match m.edges.iter().max() {
        None => 0,
        Some(&e) => e
            .checked_add(1)
            .ok_or_else(|| shape(i, "mesh.edges", "edge id 0xffffffff is reserved".into()))?,
    };
    let name = || format!("objects[{i}]");
    Ok(Counts {
        vertices: count_u32(v, || format!("{}: {v} vertices", name()))?,
        triangles: count_u32(f, || format!("{}: {f} triangles", name()))?,
        ring: count_u32(m.ring.len(), || {
            format!("{}: ring of {} entries", name(), m.ring.len())
        })?,
        edges,
        normals: count_u32(o.normals.len(), || {
            format!("{}: {} normals", name(), o.normals.len())
        })?,
        colours: count_u32(o.colours.len(), || {
            format!("{}: {} colours", name(), o.colours.len())
        })?,
    })
}

fn u32s(values: &[u32]) -> Vec<u8> {
    values.iter().flat_map(|v| v.to_le_bytes()).collect()
}

fn f32s(values: impl IntoIterator<Item = f32>) -> Vec<u8> {
    values.into_iter().flat_map(|v| v.to_le_bytes()).collect()
}

fn per_object_section(kind: SectionType, o: &Object) -> Vec<u8> {
    let m = &o.mesh;
    match kind {
        SectionType::POSN => f32s(m.positions.iter().copied()),
        SectionType::TRIS => u32s(&m.triangles),
        SectionType::ROFS => u32s(&m.ring_offsets),
        SectionType::RING => u32s(&m.ring),
        SectionType::VFLG => u32s(&m.vertex_flags),
        SectionType::SFLG => u32s(&m.spoke_flags),
        SectionType::CSPK => u32s(&m.corner_spokes),
        SectionType::NBRS => u32s(&m.neighbours),
        SectionType::EDGE => u32s(&m.edges),
        SectionType::TREC => o
            .triangles
            .iter()
            .flat_map(|t| [t.bits_start, t.colour_start, t.normal_start, t.normal_count])
            .flat_map(u32::to_le_bytes)
            .collect(),
        SectionType::NRML => f32s(o.normals.iter().flatten().copied()),
        SectionType::BITS => u32s(&o.bits),
        SectionType::COLR => u32s(&o.colours),
        SectionType::CCOL => u32s(&o.corner_colours),
        _ => Vec::new(),
    }
}

fn metadata_section(c: &Container) -> Result<Vec<u8>, WriteError> {
    let m = &c.metadata;
    let g = count_u32(m.generator.len(), || "metadata.generator".into())?;
    let p = count_u32(m.bake_parameters.len(), || {
        "metadata.bake_parameters".into()
    })?;
    let mut out = Vec::with_capacity(16 + m.generator.len() + m.bake_parameters.len());
    out.extend_from_slice(&m.source_hash.to_le_bytes());
    out.extend_from_slice(&g.to_le_bytes());
    out.extend_from_slice(&p.to_le_bytes());
    out.extend_from_slice(m.generator.as_bytes());
    out.extend_from_slice(m.bake_parameters.as_bytes());
    Ok(out)
}

fn objects_section(c: &Container, counts: &[Counts]) -> Result<Vec<u8>, WriteError> {
    let k = count_u32(c.objects.len(), || format!("{} objects", c.objects.len()))?;
    let mut out = Vec::new();
    out.extend_from_slice(&k.to_le_bytes());
    out.extend_from_slice(&OBJECT_RECORD_LEN.to_le_bytes());
    let mut name_offset: u64 = 0;
    for (o, n) in c.objects.iter().zip(counts) {
        let off = u32::try_from(name_offset).map_err(|_| WriteError::TooLarge {
            what: "object names".into(),
        })?;
        let len = count_u32(o.name.len(), || format!("object name {:?}", o.name))?;
        name_offset += o.name.len() as u64;
        let kind: u32 = match o.kind {
            ObjectKind::Multiresolution => 0,
            ObjectKind::Flat => 1,
        };
        for v in [off, len, kind, 0] {
            out.extend_from_slice(&v.to_le_bytes());
        }
        out.extend_from_slice(&o.geometry_hash.to_le_bytes());
        for v in [
            n.vertices,
            n.triangles,
            n.ring,
            n.edges,
            n.normals,
            n.colours,
        ] {
            out.extend_from_slice(&v.to_le_bytes());
        }
        out.extend_from_slice(&o.bit_len.to_le_bytes());
        out.extend_from_slice(&0u64.to_le_bytes());
    }
    for o in &c.objects {
        out.extend_from_slice(o.name.as_bytes());
    }
    Ok(out)
}

/// Serialises a container (SPEC.md Appendix A). Fails only when the arrays' lengths disagree
/// with each other (for example `positions.len()` not a multiple of 3) or exceed the 32-bit
/// counts of version 1; content is not validated (use [`crate::validate()`]).
pub fn write(c: &Container) -> Result<Vec<u8>, WriteError> {
    let counts = c
        .objects
        .iter()
        .enumerate()
        .map(|(i, o)| object_counts(i, o))
        .collect::<Result<Vec<_>, _>>()?;
    let mut sections: Vec<(SectionType, u32, Vec<u8>)> = vec![
        (SectionType::META, FILE_LEVEL, metadata_section(c)?),
        (SectionType::OBJS, FILE_LEVEL, objects_section(c, &counts)?),
    ];
    for (i, o) in c.objects.iter().enumerate() {
        for kind in SectionType::PER_OBJECT {
            // i < u32::MAX: objects_section checked the object count.
            sections.push((kind, i as u32, per_object_section(kind, o)));
        }
        if !o.corner_colours.is_empty() {
            let kind = SectionType::CCOL;
            sections.push((kind, i as u32, per_object_section(kind, o)));
        }
    }
    // A file without corner colours is a version 1.0 file, byte for byte as before them.
    let minor = if c.objects.iter().any(|o| !o.corner_colours.is_empty()) {
        MINOR_VERSION
    } else {
        0
    };
    let section_count = count_u32(sections.len(), || "the section directory".into())?;
    let directory_end = HEADER_LEN + DIRECTORY_ENTRY_LEN * u64::from(section_count);

    let mut directory = Vec::with_capacity(sections.len() * DIRECTORY_ENTRY_LEN as usize);
    let mut cursor = directory_end;
    let mut file_length = directory_end;
    for (kind, object, data) in &sections {
        let offset = cursor.next_multiple_of(SECTION_ALIGNMENT);
        let length = data.len() as u64;
        cursor = offset + length;
        file_length = file_length.max(offset + length);
        directory.extend_from_slice(&kind.to_u32().to_le_bytes());
        directory.extend_from_slice(&object.to_le_bytes());
        directory.extend_from_slice(&offset.to_le_bytes());
        directory.extend_from_slice(&length.to_le_bytes());
        directory.extend_from_slice(&crc32fast::hash(data).to_le_bytes());
        directory.extend_from_slice(&0u32.to_le_bytes());
    }
    let file_len = usize::try_from(file_length).map_err(|_| WriteError::TooLarge {
        what: "the file".into(),
    })?;

    let mut out = Vec::with_capacity(file_len);
    out.extend_from_slice(&IDENTIFIER);
    out.extend_from_slice(&MAJOR_VERSION.to_le_bytes());
    out.extend_from_slice(&minor.to_le_bytes());
    out.extend_from_slice(&section_count.to_le_bytes());
    out.extend_from_slice(&file_length.to_le_bytes());
    out.extend_from_slice(&0u32.to_le_bytes());
    let mut hasher = crc32fast::Hasher::new();
    hasher.update(&out);
    hasher.update(&directory);
    out.extend_from_slice(&hasher.finalize().to_le_bytes());
    out.extend_from_slice(&directory);
    for (_, _, data) in &sections {
        let offset = (out.len() as u64).next_multiple_of(SECTION_ALIGNMENT) as usize;
        // Trailing empty sections may sit at an aligned offset past the last byte of data.
        out.resize(offset, 0);
        out.extend_from_slice(data);
    }
    out.resize(file_len, 0);
    Ok(out)
}
