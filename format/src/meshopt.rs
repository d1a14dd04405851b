//! The `EXT_meshopt_compression` decoder (KhronosGroup/glTF `extensions/2.0/Vendor/
//! EXT_meshopt_compression`, "Appendix A: Bitstream"), for the buffer views a primitive's
//! positions and indices are read from: the attribute codec (mode 0, version 0), the triangle
//! index codec (mode 1, versions 0 and 1) and the index sequence codec (mode 2), with the
//! `NONE` and `EXPONENTIAL` filters. Written from the specification and checked against the
//! streams of meshoptimizer's encoder in the tests; every read is bounds-checked, and the
//! decoded size is bounded by what the compressed bytes can encode before anything is
//! allocated. The `OCTAHEDRAL` and `QUATERNION` filters (normals, tangents, rotations: never
//! positions) are [`GltfError::Compressed`].

use crate::gltf_json::GltfError;
use serde_json::Value;

/// The extension's name, on buffer views and on the fallback buffer.
pub const EXTENSION: &str = "EXT_meshopt_compression";

fn bad(view: usize, message: impl std::fmt::Display) -> GltfError {
    GltfError::Json(format!(
        "bufferViews[{view}].extensions.{EXTENSION}: {message}"
    ))
}

/// The decoded bytes of buffer view `view`, whose extension object is `ext`: `count ·
/// byteStride` bytes, the layout the uncompressed view would have had.
pub fn decode_view(buffers: &[Vec<u8>], view: usize, ext: &Value) -> Result<Vec<u8>, GltfError> {
    let field = |key: &str| {
        ext.get(key)
            .and_then(Value::as_u64)
            .ok_or_else(|| bad(view, format!("{key} is missing or not an integer")))
    };
    let (buffer, length, stride, count) = (
        field("buffer")?,
        field("byteLength")?,
        field("byteStride")?,
        field("count")?,
    );
    let offset = ext.get("byteOffset").and_then(Value::as_u64).unwrap_or(0);
    let data = buffers
        .get(buffer as usize)
        .ok_or_else(|| bad(view, format!("buffer {buffer} does not exist")))?;
    let src = offset
        .checked_add(length)
        .filter(|&e| e <= data.len() as u64)
        .map(|e| &data[offset as usize..e as usize])
        .ok_or_else(|| {
            bad(
                view,
                format!(
                    "bytes {offset}+{length} run past buffer {buffer} ({} bytes)",
                    data.len()
                ),
            )
        })?;
    let mode = ext.get("mode").and_then(Value::as_str).unwrap_or("");
    let filter = ext.get("filter").and_then(Value::as_str).unwrap_or("NONE");
    // What the compressed bytes can encode at most (a group of 16 zero bytes costs 2 header
    // bits; a triangle and an index at least a byte each), so nothing larger is allocated.
    let most = match mode {
        "ATTRIBUTES" => length.saturating_mul(64).saturating_add(8192),
        "TRIANGLES" => length.saturating_mul(3),
        "INDICES" => length,
        m => {
            return Err(bad(
                view,
                format!("mode {m:?} is not ATTRIBUTES, TRIANGLES or INDICES"),
            ))
        }
    };
    let size = count
        .checked_mul(stride)
        .filter(|&s| count <= most && s <= 1 << 32)
        .ok_or_else(|| {
            bad(
                view,
                format!("{count} elements of {stride} bytes cannot come from {length} bytes"),
            )
        })? as usize;
    let (count, stride) = (count as usize, stride as usize);
    let mut out = vec![0u8; size];
    let fail = |what: &str| bad(view, format!("the {mode} stream is {what}"));
    match mode {
        "ATTRIBUTES" => {
            if stride == 0 || stride > 256 || stride % 4 != 0 {
                return Err(bad(
                    view,
                    format!("byteStride {stride} is not a multiple of 4 in 4..=256"),
                ));
            }
            decode_vertices(&mut out, count, stride, src).map_err(fail)?;
        }
        _ if stride != 2 && stride != 4 => {
            return Err(bad(
                view,
                format!("byteStride {stride} of indices is not 2 or 4"),
            ))
        }
        "TRIANGLES" => {
            if count % 3 != 0 {
                return Err(bad(view, format!("count {count} is not whole triangles")));
            }
            decode_triangles(&mut out, count, stride, src).map_err(fail)?;
        }
        _ => decode_sequence(&mut out, count, stride, src).map_err(fail)?,
    }
    match filter {
        "NONE" => {}
        "EXPONENTIAL" if stride % 4 == 0 => exponential(&mut out),
        "EXPONENTIAL" => return Err(bad(view, "the EXPONENTIAL filter needs a stride of 4n")),
        other => {
            return Err(GltfError::Compressed {
                location: format!("bufferViews[{view}]"),
                extension: format!("{EXTENSION} filter {other}"),
            })
        }
    }
    // The view's own buffer is the fallback; its bytes (if any) are never read.
    Ok(out)
}

/// The attribute codec's byte groups (A.1): 16 elements' byte `k`, 2, 4 or 8 bits each (or all
/// zero), a value of all ones in 2 or 4 bits meaning "the next byte after the group".
const GROUP: usize = 16;
const TAIL: usize = 32;

/// Decodes a vertex (attribute) stream of `count` elements of `stride` bytes into `out`.
fn decode_vertices(
    out: &mut [u8],
    count: usize,
    stride: usize,
    src: &[u8],
) -> Result<(), &'static str> {
    if src.len() < 1 + stride || src[0] & 0xf0 != 0xa0 {
        return Err("missing its 0xa0 header");
    }
    if src[0] & 0x0f != 0 {
        return Err("of a version other than 0");
    }
    let tail = stride.max(TAIL);
    if src.len() < 1 + tail {
        return Err("shorter than its tail");
    }
    let end = src.len() - tail;
    let mut last = [0u8; 256];
    last[..stride].copy_from_slice(&src[src.len() - stride..]);
    let block = ((8192 / stride) & !(GROUP - 1)).min(256);
    let mut at = 1usize;
    let mut buffer = [0u8; 256];
    let mut start = 0usize;
    while start < count {
        let n = block.min(count - start);
        let aligned = n.next_multiple_of(GROUP);
        for k in 0..stride {
            at = decode_bytes(src, end, at, &mut buffer[..aligned])?;
            let mut p = last[k];
            for (i, &d) in buffer[..n].iter().enumerate() {
                // Zigzag-coded byte deltas from the previous element's byte `k`.
                let v = ((d >> 1) ^ (d & 1).wrapping_neg()).wrapping_add(p);
                out[(start + i) * stride + k] = v;
                p = v;
            }
        }
        last[..stride].copy_from_slice(&out[(start + n - 1) * stride..(start + n) * stride]);
        start += n;
    }
    if at != end {
        return Err("not ending with its tail");
    }
    Ok(())
}

/// One byte of every element of a block: the group headers (2 bits per group, low bits first),
/// then the groups.
fn decode_bytes(
    src: &[u8],
    end: usize,
    mut at: usize,
    buffer: &mut [u8],
) -> Result<usize, &'static str> {
    let groups = buffer.len() / GROUP;
    let header_len = groups.div_ceil(4);
    let header = src
        .get(at..at + header_len)
        .filter(|_| at + header_len <= end)
        .ok_or("truncated")?;
    let header = header.to_vec();
    at += header_len;
    for g in 0..groups {
        let bits = (header[g / 4] >> ((g % 4) * 2)) & 3;
        let out = &mut buffer[g * GROUP..(g + 1) * GROUP];
        at = match bits {
            0 => {
                out.fill(0);
                at
            }
            3 => {
                out.copy_from_slice(
                    src.get(at..at + GROUP)
                        .filter(|_| at + GROUP <= end)
                        .ok_or("truncated")?,
                );
                at + GROUP
            }
            _ => {
                let width = if bits == 1 { 2 } else { 4 };
                let packed = GROUP * width / 8;
                let mut extra = at + packed;
                if extra > end {
                    return Err("truncated");
                }
                for (i, o) in out.iter_mut().enumerate() {
                    let byte = src[at + i * width / 8];
                    let shift = 8 - width - (i * width) % 8;
                    let v = (byte >> shift) & ((1 << width) - 1);
                    *o = if v == (1 << width) - 1 {
                        let b = *src.get(extra).filter(|_| extra < end).ok_or("truncated")?;
                        extra += 1;
                        b
                    } else {
                        v
                    };
                }
                extra
            }
        };
    }
    Ok(at)
}

fn write_index(out: &mut [u8], i: usize, stride: usize, v: u32) {
    let at = i * stride;
    if stride == 2 {
        out[at..at + 2].copy_from_slice(&(v as u16).to_le_bytes());
    } else {
        out[at..at + 4].copy_from_slice(&v.to_le_bytes());
    }
}

/// A LEB128-style unsigned integer of at most 5 bytes.
fn vbyte(src: &[u8], at: &mut usize) -> Result<u32, &'static str> {
    let mut result = 0u32;
    for i in 0..5 {
        let b = *src.get(*at).ok_or("truncated")?;
        *at += 1;
        result |= u32::from(b & 127) << (7 * i);
        if b < 128 {
            break;
        }
    }
    Ok(result)
}

/// A zigzag delta from `last`.
fn delta(src: &[u8], at: &mut usize, last: u32) -> Result<u32, &'static str> {
    let v = vbyte(src, at)?;
    Ok(last.wrapping_add((v >> 1) ^ (v & 1).wrapping_neg()))
}

/// The triangle codec (A.2): per triangle a code byte, FIFOs of 16 recent edges and vertices,
/// free indices as deltas, a 16-byte table of common auxiliary codes at the end.
fn decode_triangles(
    out: &mut [u8],
    count: usize,
    stride: usize,
    src: &[u8],
) -> Result<(), &'static str> {
    if src.len() < 1 + count / 3 + 16 || src[0] & 0xf0 != 0xe0 {
        return Err("missing its 0xe0 header or too short");
    }
    let version = src[0] & 0x0f;
    if version > 1 {
        return Err("of a version other than 0 or 1");
    }
    let mut edges = [[u32::MAX; 2]; 16];
    let mut vertices = [u32::MAX; 16];
    let (mut eo, mut vo) = (0usize, 0usize);
    let (mut next, mut last) = (0u32, 0u32);
    let fecmax = if version >= 1 { 13 } else { 15 };
    let mut data = 1 + count / 3;
    let safe_end = src.len() - 16;
    let table = &src[safe_end..];
    // The data before the table only: indices never read the table's bytes.
    let body = &src[..safe_end];
    let push_edge = |edges: &mut [[u32; 2]; 16], eo: &mut usize, a: u32, b: u32| {
        edges[*eo] = [a, b];
        *eo = (*eo + 1) & 15;
    };
    let push_vertex = |vertices: &mut [u32; 16], vo: &mut usize, v: u32, cond: bool| {
        vertices[*vo] = v;
        *vo = (*vo + usize::from(cond)) & 15;
    };
    for i in (0..count).step_by(3) {
        if data > safe_end {
            return Err("truncated");
        }
        let codetri = src[1 + i / 3];
        let (a, b, c);
        if codetri < 0xf0 {
            let fe = usize::from(codetri >> 4);
            [a, b] = edges[(eo.wrapping_sub(1 + fe)) & 15];
            let fec = usize::from(codetri & 15);
            if fec < fecmax {
                let fec0 = fec == 0;
                c = if fec0 {
                    next
                } else {
                    vertices[(vo.wrapping_sub(1 + fec)) & 15]
                };
                next += u32::from(fec0);
                push_vertex(&mut vertices, &mut vo, c, fec0);
            } else {
                c = match fec {
                    13 => last.wrapping_sub(1),
                    14 => last.wrapping_add(1),
                    _ => delta(body, &mut data, last)?,
                };
                last = c;
                push_vertex(&mut vertices, &mut vo, c, true);
            }
            push_edge(&mut edges, &mut eo, c, b);
            push_edge(&mut edges, &mut eo, a, c);
        } else {
            let (feb, fec, fea_free);
            let slow = codetri >= 0xfe;
            if !slow {
                let aux = table[usize::from(codetri & 15)];
                (feb, fec, fea_free) = (usize::from(aux >> 4), usize::from(aux & 15), false);
                a = next;
                next += 1;
            } else {
                let aux = *body.get(data).ok_or("truncated")?;
                data += 1;
                if aux == 0 {
                    next = 0;
                }
                (feb, fec, fea_free) = (
                    usize::from(aux >> 4),
                    usize::from(aux & 15),
                    codetri == 0xff,
                );
                a = if fea_free {
                    0
                } else {
                    next += 1;
                    next - 1
                };
            }
            let take = |fe: usize, next: &mut u32| {
                if fe == 0 {
                    *next += 1;
                    *next - 1
                } else {
                    vertices[(vo.wrapping_sub(fe)) & 15]
                }
            };
            let mut bb = take(feb, &mut next);
            let mut cc = take(fec, &mut next);
            let mut aa = a;
            if slow {
                if fea_free {
                    aa = delta(body, &mut data, last)?;
                    last = aa;
                }
                if feb == 15 {
                    bb = delta(body, &mut data, last)?;
                    last = bb;
                }
                if fec == 15 {
                    cc = delta(body, &mut data, last)?;
                    last = cc;
                }
            }
            (b, c) = (bb, cc);
            let a = aa;
            push_vertex(&mut vertices, &mut vo, a, true);
            // A free index (15) advances the FIFO only on the slow path, as the encoder does.
            push_vertex(&mut vertices, &mut vo, b, feb == 0 || (slow && feb == 15));
            push_vertex(&mut vertices, &mut vo, c, fec == 0 || (slow && fec == 15));
            push_edge(&mut edges, &mut eo, b, a);
            push_edge(&mut edges, &mut eo, c, b);
            push_edge(&mut edges, &mut eo, a, c);
            write_index(out, i, stride, a);
            write_index(out, i + 1, stride, b);
            write_index(out, i + 2, stride, c);
            continue;
        }
        write_index(out, i, stride, a);
        write_index(out, i + 1, stride, b);
        write_index(out, i + 2, stride, c);
    }
    if data != safe_end {
        return Err("not ending at its code table");
    }
    Ok(())
}

/// The index sequence codec (A.3): per index a zigzag delta from one of two baselines.
fn decode_sequence(
    out: &mut [u8],
    count: usize,
    stride: usize,
    src: &[u8],
) -> Result<(), &'static str> {
    if src.len() < 1 + count + 4 || src[0] & 0xf0 != 0xd0 {
        return Err("missing its 0xd0 header or too short");
    }
    if src[0] & 0x0f > 1 {
        return Err("of a version other than 0 or 1");
    }
    let safe_end = src.len() - 4;
    let body = &src[..safe_end + 4];
    let mut last = [0u32; 2];
    let mut at = 1usize;
    for i in 0..count {
        if at >= safe_end {
            return Err("truncated");
        }
        let v = vbyte(body, &mut at)?;
        let current = (v & 1) as usize;
        let v = v >> 1;
        let index = last[current].wrapping_add((v >> 1) ^ (v & 1).wrapping_neg());
        last[current] = index;
        write_index(out, i, stride, index);
    }
    if at != safe_end {
        return Err("not ending at its tail");
    }
    Ok(())
}

/// The `EXPONENTIAL` filter (A.4): each 32-bit value is a signed 24-bit mantissa and a signed
/// 8-bit exponent (the top byte), decoded to the `f32` `m · 2^e`.
fn exponential(out: &mut [u8]) {
    for v in out.chunks_exact_mut(4) {
        let w = u32::from_le_bytes([v[0], v[1], v[2], v[3]]);
        let e = (w as i32) >> 24;
        let m = ((w << 8) as i32) >> 8;
        // 2^e built from its bits, as the reference decoder does (e = −127 gives 0).
        let f = f32::from_bits(((e + 127) as u32).wrapping_shl(23)) * m as f32;
        v.copy_from_slice(&f.to_le_bytes());
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    // Streams written by meshoptimizer's encoder (its Python package, 0.2.30a0) and what its
    // decoder makes of them; `format/tests/meshopt/README.md` says how they were made.
    const VERTICES: &[u8] = include_bytes!("../tests/meshopt/vertices-300x8.bin");
    const VERTICES_DECODED: &[u8] = include_bytes!("../tests/meshopt/vertices-300x8.decoded.bin");
    const TRIANGLES: [(&[u8], &[u8]); 2] = [
        (
            include_bytes!("../tests/meshopt/triangles-v0.bin"),
            include_bytes!("../tests/meshopt/triangles-v0.decoded.bin"),
        ),
        (
            include_bytes!("../tests/meshopt/triangles-v1.bin"),
            include_bytes!("../tests/meshopt/triangles-v1.decoded.bin"),
        ),
    ];
    const SEQUENCE: &[u8] = include_bytes!("../tests/meshopt/sequence.bin");
    const SEQUENCE_DECODED: &[u8] = include_bytes!("../tests/meshopt/sequence.decoded.bin");

    #[test]
    fn attribute_streams_decode_as_meshoptimizer_does() {
        // 300 elements of 8 bytes: two blocks of at most 256, every group width used.
        let mut out = vec![0u8; 2400];
        decode_vertices(&mut out, 300, 8, VERTICES).unwrap();
        assert_eq!(out, VERTICES_DECODED);
    }

    #[test]
    fn triangle_streams_of_both_versions_decode_as_meshoptimizer_does() {
        for (stream, decoded) in TRIANGLES {
            let mut out = vec![0u8; 984 * 4];
            decode_triangles(&mut out, 984, 4, stream).unwrap();
            assert_eq!(out, decoded);
            // And as 16-bit indices.
            let mut short = vec![0u8; 984 * 2];
            decode_triangles(&mut short, 984, 2, stream).unwrap();
            assert!(short
                .chunks_exact(2)
                .zip(decoded.chunks_exact(4))
                .all(|(s, d)| s == &d[..2]));
        }
    }

    #[test]
    fn index_sequences_decode_as_meshoptimizer_does() {
        let mut out = vec![0u8; 800];
        decode_sequence(&mut out, 200, 4, SEQUENCE).unwrap();
        assert_eq!(out, SEQUENCE_DECODED);
    }

    #[test]
    fn truncated_or_altered_streams_are_errors_not_panics() {
        let mut out = vec![0u8; 2400];
        for cut in [0, 1, 9, 40, VERTICES.len() / 2, VERTICES.len() - 1] {
            assert!(
                decode_vertices(&mut out, 300, 8, &VERTICES[..cut]).is_err(),
                "{cut}"
            );
        }
        // A block more than the stream holds (within a block, elements up to the next four
        // groups cannot be told from padding, as in meshoptimizer's decoder).
        let mut more = vec![0u8; 600 * 8];
        assert!(decode_vertices(&mut more, 600, 8, VERTICES).is_err());
        let (stream, _) = TRIANGLES[1];
        let mut out = vec![0u8; 984 * 4];
        for cut in [0, 1, 17, stream.len() / 2, stream.len() - 1] {
            assert!(
                decode_triangles(&mut out, 984, 4, &stream[..cut]).is_err(),
                "{cut}"
            );
        }
        let mut wrong = stream.to_vec();
        wrong[0] = 0xe7;
        assert!(decode_triangles(&mut out, 984, 4, &wrong).is_err());
        let mut out = vec![0u8; 800];
        assert!(decode_sequence(&mut out, 200, 4, &SEQUENCE[..SEQUENCE.len() - 1]).is_err());
        // Every single-byte change decodes or fails, never panics.
        for at in 0..stream.len() {
            let mut s = stream.to_vec();
            s[at] ^= 0x5a;
            let mut out = vec![0u8; 984 * 4];
            let _ = decode_triangles(&mut out, 984, 4, &s);
        }
        for at in 0..VERTICES.len() {
            let mut s = VERTICES.to_vec();
            s[at] ^= 0xa5;
            let mut out = vec![0u8; 2400];
            let _ = decode_vertices(&mut out, 300, 8, &s);
        }
    }

    #[test]
    fn exponential_values_are_mantissa_times_two_to_the_exponent() {
        let word = |m: i32, e: i32| (((e as u32) << 24) | (m as u32 & 0xff_ffff)).to_le_bytes();
        let mut b: Vec<u8> = [word(3, -1), word(-5, 2), word(7, -127), word(1, 0)].concat();
        exponential(&mut b);
        let f: Vec<f32> = b
            .chunks_exact(4)
            .map(|c| f32::from_le_bytes([c[0], c[1], c[2], c[3]]))
            .collect();
        assert_eq!(f, [1.5, -20.0, 0.0, 1.0]);
    }

    #[test]
    fn a_view_larger_than_its_stream_can_encode_is_refused_before_allocating() {
        let ext = serde_json::json!({
            "buffer": 0, "byteLength": 4, "byteStride": 4, "count": 1u64 << 40, "mode": "INDICES"
        });
        let e = decode_view(&[vec![0xd1, 0, 0, 0]], 0, &ext).unwrap_err();
        assert!(e.to_string().contains("cannot come from 4 bytes"), "{e}");
    }
}
