//! A fast reader for the plain OBJ files most meshes come as (`v`, `vn`, `vt`, triangles and
//! polygons with positive indices, comments), giving exactly what `tobj` gives for them
//! through the mesh reader (`import.rs`): positions in order of first reference, faces
//! fan-triangulated, corner normals from `vn` indices.
//!
//! `tobj` reads the Stanford bunny (2.4 MB) in about 40 ms, mostly allocating: a `String` per
//! line, a `Vec` per face and a hash-map lookup per corner. This reader scans the bytes once,
//! parses numbers with the same `f32::from_str` (so every value has the same bits) and remaps
//! vertices through a table. Anything it does not handle exactly as `tobj` would (objects and
//! groups after the first face, materials in use, lines and points, vertex colours or `w`,
//! relative or zero indices, an index out of range, a face corner without a normal in a file
//! with normals, non-ASCII text, a malformed number) makes it answer `None`, and `tobj` reads
//! the file instead: its results and its error messages stay the reference.

use crate::triangles::Triangles;

/// `char::is_whitespace` on ASCII (what `str::split_whitespace`, and so `tobj`, splits on).
#[inline(always)]
fn is_space(b: u8) -> bool {
    matches!(b, b' ' | b'\t' | b'\n' | 0x0b | 0x0c | b'\r')
}

/// The whitespace-separated words of one line, as byte ranges of the file's text.
struct Words<'a> {
    text: &'a str,
    pos: usize,
    end: usize,
}

impl<'a> Iterator for Words<'a> {
    type Item = &'a str;
    #[inline(always)]
    fn next(&mut self) -> Option<&'a str> {
        let b = self.text.as_bytes();
        while self.pos < self.end && is_space(b[self.pos]) {
            self.pos += 1;
        }
        if self.pos == self.end {
            return None;
        }
        let start = self.pos;
        while self.pos < self.end && !is_space(b[self.pos]) {
            self.pos += 1;
        }
        // Every byte is ASCII (checked before), so any byte offset is a char boundary.
        Some(&self.text[start..self.pos])
    }
}

/// `n` numbers from `words` (`None` if fewer, or one does not parse).
#[inline(always)]
fn floats<const N: usize>(words: &mut Words) -> Option<[f32; N]> {
    let mut out = [0.0; N];
    for x in &mut out {
        *x = words.next()?.parse().ok()?;
    }
    Some(out)
}

/// A 1-based index of plain decimal digits that fits in `u32` and is not zero.
#[inline(always)]
fn index(s: &[u8]) -> Option<u32> {
    if s.is_empty() || s.len() > 10 {
        return None;
    }
    let mut v = 0u64;
    for &b in s {
        if !b.is_ascii_digit() {
            return None;
        }
        v = v * 10 + u64::from(b - b'0');
    }
    u32::try_from(v).ok().filter(|&v| v > 0)
}

/// Absent index of a corner (`v//vn` has no texture coordinate).
const NONE: u32 = 0;

/// One face corner `v[/[vt][/[vn]]]`, 1-based, [`NONE`] where absent.
#[inline(always)]
fn corner(word: &str) -> Option<[u32; 3]> {
    let mut parts = word.as_bytes().split(|&b| b == b'/');
    let v = index(parts.next()?)?;
    let mut rest = [NONE; 2];
    for r in &mut rest {
        match parts.next() {
            None => break,
            Some([]) => {}
            Some(p) => *r = index(p)?,
        }
    }
    if parts.next().is_some() {
        return None;
    }
    Some([v, rest[0], rest[1]])
}

/// Reads `bytes` if it is a plain OBJ file this reader handles exactly as `tobj` does, else
/// `None` (see the module documentation).
pub(crate) fn read(bytes: &[u8]) -> Option<Triangles> {
    if !bytes.is_ascii() {
        return None;
    }
    let text = std::str::from_utf8(bytes).ok()?;
    let b = text.as_bytes();
    let mut positions: Vec<[f32; 3]> = Vec::with_capacity(bytes.len() / 64);
    let mut normals: Vec<[f32; 3]> = Vec::new();
    let mut texcoords = 0usize;
    // Face corners in file order, and where each face starts.
    let mut corners: Vec<[u32; 3]> = Vec::with_capacity(bytes.len() / 16);
    let mut face_start: Vec<u32> = Vec::with_capacity(bytes.len() / 32);
    let mut pos = 0;
    while pos < b.len() {
        let end = memchr_newline(b, pos);
        let mut words = Words { text, pos, end };
        pos = end + 1;
        let Some(first) = words.next() else {
            continue;
        };
        match first {
            "v" => {
                positions.push(floats::<3>(&mut words)?);
                // A fourth value is `w` or starts a colour: left to tobj.
                if words.next().is_some() {
                    return None;
                }
            }
            "vn" => normals.push(floats::<3>(&mut words)?),
            "vt" => {
                floats::<2>(&mut words)?;
                texcoords += 1;
            }
            "f" => {
                let start = corners.len();
                face_start.push(u32::try_from(start).ok()?);
                for w in words {
                    corners.push(corner(w)?);
                }
                // Points and lines (skipped by tobj's options) are left to it.
                if corners.len() - start < 3 {
                    return None;
                }
            }
            // A name before any face only names the one object; tobj starts a new object at
            // one after faces.
            "o" | "g" if face_start.is_empty() => {}
            "o" | "g" | "l" | "usemtl" => return None,
            // tobj would ask for the material library, which this reader never follows
            // (`read_obj` refuses every load), and ignores comments and unknown statements.
            _ => {}
        }
    }
    if face_start.is_empty() {
        return None;
    }
    let has_normals = !normals.is_empty();
    let (nv, nt, nn) = (positions.len(), texcoords, normals.len());
    let tris = corners.len() - 2 * face_start.len();
    let mut out = Triangles {
        positions: Vec::with_capacity(nv),
        triangles: Vec::with_capacity(tris),
        corner_normals: None,
        colours: None,
    };
    let mut corner_normals = Vec::with_capacity(if has_normals { 3 * tris } else { 0 });
    // New vertex number of each file vertex, by first reference (u32::MAX: not yet seen).
    let mut remap = vec![u32::MAX; nv];
    let mut take = |c: [u32; 3], out: &mut Triangles| -> Option<u32> {
        let v = c[0] as usize - 1;
        if v >= nv {
            return None;
        }
        // Texture coordinates are not kept, but tobj checks the ones it reads.
        if nt > 0 && c[1] != NONE && c[1] as usize > nt {
            return None;
        }
        if has_normals {
            // tobj makes up a normal for a corner without one; left to it.
            if c[2] == NONE || c[2] as usize > nn {
                return None;
            }
            corner_normals.push(normals[c[2] as usize - 1]);
        }
        if remap[v] == u32::MAX {
            remap[v] = out.positions.len() as u32;
            out.positions.push(positions[v]);
        }
        Some(remap[v])
    };
    for (f, &s) in face_start.iter().enumerate() {
        let s = s as usize;
        let e = face_start.get(f + 1).map_or(corners.len(), |&e| e as usize);
        let face = &corners[s..e];
        for k in 2..face.len() {
            let a = take(face[0], &mut out)?;
            let b = take(face[k - 1], &mut out)?;
            let c = take(face[k], &mut out)?;
            out.triangles.push([a, b, c]);
        }
    }
    if has_normals {
        out.corner_normals = Some(corner_normals);
    }
    Some(out)
}

/// The index of the next `\n` at or after `from`, or the length of `b`.
#[inline(always)]
fn memchr_newline(b: &[u8], from: usize) -> usize {
    b[from..]
        .iter()
        .position(|&c| c == b'\n')
        .map_or(b.len(), |i| from + i)
}
