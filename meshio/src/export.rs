//! Writing refined meshes as Wavefront OBJ or glTF 2.0 (`.gltf` with an embedded base64 buffer,
//! or binary `.glb`), through [`crate::atomic`].

use std::io::Write;
use std::path::{Path, PathBuf};

use crate::atomic::{write_atomic, write_atomic_with, AtomicFile, FileWriteError};

/// Errors of mesh export.
#[derive(Debug, thiserror::Error)]
pub enum ExportError {
    #[error(transparent)]
    Write(#[from] FileWriteError),
    #[error("{path}: unknown mesh extension; use .obj, .gltf or .glb")]
    UnknownFormat { path: PathBuf },
    #[error("{path}: position {index} is not finite; glTF cannot store it")]
    NotFinite { path: PathBuf, index: usize },
    #[error("{path}: the mesh is too large for a single glTF buffer")]
    TooLarge { path: PathBuf },
    #[error("{path}: unclamped colours need an .obj output (glTF holds COLOR_0 in [0, 1] only)")]
    UnclampedNeedsObj { path: PathBuf },
    #[error("{path}: {colours} vertex colours for {vertices} vertices; give one per vertex")]
    ColourCount {
        path: PathBuf,
        colours: usize,
        vertices: usize,
    },
}

/// Writes a triangle mesh with per-vertex normals; the format follows the extension.
pub fn write_mesh(
    path: &Path,
    positions: &[[f32; 3]],
    normals: &[[f32; 3]],
    indices: &[[u32; 3]],
) -> Result<(), ExportError> {
    write_any(path, positions, normals, None, indices)
}

/// [`write_mesh`] with one linear RGB colour per vertex: glTF and GLB get a `COLOR_0` float
/// VEC3 accessor, OBJ gets `v x y z r g b` lines. glTF requires `COLOR_0` in [0, 1] (the Khronos
/// validator rejects anything else), so colours are clamped to [0, 1] (NaN becomes 0) in every
/// format; radiosity above 1 is lost, as a viewer would clip it anyway.
pub fn write_mesh_with_colours(
    path: &Path,
    positions: &[[f32; 3]],
    normals: &[[f32; 3]],
    colours: &[[f32; 3]],
    indices: &[[u32; 3]],
) -> Result<(), ExportError> {
    let clamped = finite_colours(path, positions, colours, |x| x.clamp(0.0, 1.0))?;
    write_any(path, positions, normals, Some(&clamped), indices)
}

/// [`write_mesh_with_colours`] for OBJ without the clamp: the colours as they are (NaN becomes
/// 0), so that radiosity above 1 can be measured. glTF cannot hold them, so any other extension
/// is an error.
pub fn write_obj_with_unclamped_colours(
    path: &Path,
    positions: &[[f32; 3]],
    normals: &[[f32; 3]],
    colours: &[[f32; 3]],
    indices: &[[u32; 3]],
) -> Result<(), ExportError> {
    let is_obj = path
        .extension()
        .is_some_and(|e| e.eq_ignore_ascii_case("obj"));
    if !is_obj {
        return Err(ExportError::UnclampedNeedsObj {
            path: path.to_owned(),
        });
    }
    let finite = finite_colours(path, positions, colours, |x| x)?;
    write_any(path, positions, normals, Some(&finite), indices)
}

/// One colour per vertex checked, NaN made 0 and every other value passed through `limit`.
fn finite_colours(
    path: &Path,
    positions: &[[f32; 3]],
    colours: &[[f32; 3]],
    limit: impl Fn(f32) -> f32,
) -> Result<Vec<[f32; 3]>, ExportError> {
    if colours.len() != positions.len() {
        return Err(ExportError::ColourCount {
            path: path.to_owned(),
            colours: colours.len(),
            vertices: positions.len(),
        });
    }
    Ok(colours
        .iter()
        .map(|c| c.map(|x| if x.is_nan() { 0.0 } else { limit(x) }))
        .collect())
}

fn write_any(
    path: &Path,
    positions: &[[f32; 3]],
    normals: &[[f32; 3]],
    colours: Option<&[[f32; 3]]>,
    indices: &[[u32; 3]],
) -> Result<(), ExportError> {
    let ext = path
        .extension()
        .and_then(|e| e.to_str())
        .map(str::to_ascii_lowercase);
    match ext.as_deref() {
        Some("obj") => Ok(write_atomic_with(path, |w| {
            write_obj(w, positions, normals, colours, indices)
        })?),
        Some("gltf") => {
            let bytes = gltf_text(path, positions, normals, colours, indices)?;
            Ok(write_atomic(path, &bytes)?)
        }
        Some("glb") => {
            let glb = Glb::new(path, positions, normals, colours, indices)?;
            Ok(write_atomic_with(path, |w| glb.write(w))?)
        }
        _ => Err(ExportError::UnknownFormat {
            path: path.to_owned(),
        }),
    }
}

/// Items formatted per parallel task, and tasks per batch written in order: the text in memory
/// at once stays a few tens of megabytes, whatever the mesh size.
const BLOCK: usize = 1 << 14;
const BATCH: usize = 16;

/// Formats `items` in parallel blocks and writes the blocks in order, so the output is the
/// same whatever the thread count.
fn write_parallel<T: Sync>(
    w: &mut dyn Write,
    items: &[T],
    line: impl Fn(&mut Vec<u8>, usize, &T) + Sync,
) -> std::io::Result<()> {
    use rayon::prelude::*;
    for (b, batch) in items.chunks(BLOCK * BATCH).enumerate() {
        let texts: Vec<Vec<u8>> = batch
            .par_chunks(BLOCK)
            .enumerate()
            .map(|(k, block)| {
                let mut s = Vec::with_capacity(block.len() * 40);
                let first = b * BLOCK * BATCH + k * BLOCK;
                for (i, item) in block.iter().enumerate() {
                    line(&mut s, first + i, item);
                }
                s
            })
            .collect();
        for t in &texts {
            w.write_all(t)?;
        }
    }
    Ok(())
}

/// Appends the decimal digits of `x`.
fn push_u32(s: &mut Vec<u8>, x: u32) {
    s.extend_from_slice(itoa::Buffer::new().format(x).as_bytes());
}

/// Appends the shortest decimal text that reads back as exactly `x` (Schubfach, through
/// `zmij`: about ten times faster than `Display`, which dominated OBJ output; it may use an
/// exponent, `1e-7`, which every OBJ reader and Rust's `f32::from_str` accept).
/// An integral value drops zmij's trailing `.0`, as `Display` does.
fn push_f32(s: &mut Vec<u8>, x: f32) {
    let mut buf = zmij::Buffer::new();
    let text = buf.format(x);
    s.extend_from_slice(text.strip_suffix(".0").unwrap_or(text).as_bytes());
}

fn write_obj(
    w: &mut dyn Write,
    positions: &[[f32; 3]],
    normals: &[[f32; 3]],
    colours: Option<&[[f32; 3]]>,
    indices: &[[u32; 3]],
) -> std::io::Result<()> {
    w.write_all(b"# written by hce subdivide\n")?;
    let colours = colours.filter(|c| c.len() == positions.len());
    write_parallel(w, positions, |s, i, p| {
        s.extend_from_slice(b"v");
        for &x in p.iter().chain(colours.map(|c| &c[i]).into_iter().flatten()) {
            s.push(b' ');
            push_f32(s, x);
        }
        s.push(b'\n');
    })?;
    write_parallel(w, normals, |s, _, n| {
        s.extend_from_slice(b"vn");
        for &x in n {
            s.push(b' ');
            push_f32(s, x);
        }
        s.push(b'\n');
    })?;
    let with_normals = normals.len() == positions.len();
    write_parallel(w, indices, |s, _, t| {
        s.push(b'f');
        for &i in t {
            s.push(b' ');
            push_u32(s, i.wrapping_add(1));
            if with_normals {
                s.extend_from_slice(b"//");
                push_u32(s, i.wrapping_add(1));
            }
        }
        s.push(b'\n');
    })
}

pub fn base64(data: &[u8]) -> String {
    const T: &[u8; 64] = b"ABCDEFGHIJKLMNOPQRSTUVWXYZabcdefghijklmnopqrstuvwxyz0123456789+/";
    let mut out = String::with_capacity(data.len().div_ceil(3) * 4);
    for c in data.chunks(3) {
        let b = [c[0], *c.get(1).unwrap_or(&0), *c.get(2).unwrap_or(&0)];
        let n = (u32::from(b[0]) << 16) | (u32::from(b[1]) << 8) | u32::from(b[2]);
        for k in 0..4 {
            if k <= c.len() {
                out.push(T[((n >> (18 - 6 * k)) & 63) as usize] as char);
            } else {
                out.push('=');
            }
        }
    }
    out
}

/// Writes `data` as little-endian bytes: straight from memory on a little-endian machine,
/// converted in bounded pieces elsewhere.
fn write_le<T: bytemuck::Pod>(w: &mut dyn Write, data: &[T]) -> std::io::Result<()> {
    let bytes: &[u8] = bytemuck::cast_slice(data);
    if cfg!(target_endian = "little") {
        return w.write_all(bytes);
    }
    // Every element here is made of 4-byte words (f32 or u32).
    for piece in bytes.chunks(1 << 16) {
        let swapped: Vec<u8> = piece
            .chunks_exact(4)
            .flat_map(|b| [b[3], b[2], b[1], b[0]])
            .collect();
        w.write_all(&swapped)?;
    }
    Ok(())
}

/// The JSON and buffer layout of a minimal glTF 2.0 asset: one mesh, one primitive
/// (POSITION, NORMAL, optional COLOR_0, u32 indices), one node. The binary buffer is
/// positions, normals, colours, indices.
struct Glb<'a> {
    json: String,
    positions: &'a [[f32; 3]],
    normals: &'a [[f32; 3]],
    colours: Option<&'a [[f32; 3]]>,
    indices: &'a [[u32; 3]],
    bin_len: usize,
}

impl<'a> Glb<'a> {
    fn new(
        path: &Path,
        positions: &'a [[f32; 3]],
        normals: &'a [[f32; 3]],
        colours: Option<&'a [[f32; 3]]>,
        indices: &'a [[u32; 3]],
    ) -> Result<Self, ExportError> {
        Self::with_uri(path, positions, normals, colours, indices, |_| None)
    }

    /// `uri` gives the buffer's URI from the layout, or `None` for the GLB binary chunk.
    fn with_uri(
        path: &Path,
        positions: &'a [[f32; 3]],
        normals: &'a [[f32; 3]],
        colours: Option<&'a [[f32; 3]]>,
        indices: &'a [[u32; 3]],
        uri: impl FnOnce(&Glb) -> Option<String>,
    ) -> Result<Self, ExportError> {
        use rayon::prelude::*;
        // One pass over the positions in fixed chunks: each chunk's first position that is not
        // finite, and its bounds (min and max are exact and order-independent, so the parallel
        // reduction is deterministic). Two passes, a search then a fold, took several times as
        // long on the 27 MB of the Stanford bunny at level 3 (some 50 ms against 9).
        const SCAN: usize = 1 << 14;
        /// A chunk's bounds, or the index of its first position that is not finite.
        type Scan = Result<([f32; 3], [f32; 3]), usize>;
        let scans: Vec<Scan> = positions
            .par_chunks(SCAN)
            .enumerate()
            .map(|(c, chunk)| {
                let (mut lo, mut hi) = ([f32::INFINITY; 3], [f32::NEG_INFINITY; 3]);
                for (i, p) in chunk.iter().enumerate() {
                    if !p.iter().all(|c| c.is_finite()) {
                        return Err(c * SCAN + i);
                    }
                    for k in 0..3 {
                        lo[k] = lo[k].min(p[k]);
                        hi[k] = hi[k].max(p[k]);
                    }
                }
                Ok((lo, hi))
            })
            .collect();
        let (mut min, mut max) = ([f32::INFINITY; 3], [f32::NEG_INFINITY; 3]);
        for scan in scans {
            match scan {
                Ok((lo, hi)) => {
                    min = std::array::from_fn(|k| min[k].min(lo[k]));
                    max = std::array::from_fn(|k| max[k].max(hi[k]));
                }
                Err(index) => {
                    return Err(ExportError::NotFinite {
                        path: path.to_owned(),
                        index,
                    })
                }
            }
        }
        let normals = if normals.len() == positions.len() {
            normals
        } else {
            &[]
        };
        let colours = colours.filter(|c| c.len() == positions.len());
        let pos_len = positions.len() * 12;
        let nrm_len = normals.len() * 12;
        let col_len = colours.map_or(0, |c| c.len() * 12);
        let idx_len = indices.len() * 12;
        let total = pos_len + nrm_len + col_len + idx_len;
        if total > u32::MAX as usize - 64 {
            return Err(ExportError::TooLarge {
                path: path.to_owned(),
            });
        }
        let (min, max) = if positions.is_empty() {
            ([0.0; 3], [0.0; 3])
        } else {
            (min, max)
        };
        let mut glb = Glb {
            json: String::new(),
            positions,
            normals,
            colours,
            indices,
            bin_len: total,
        };
        let uri = uri(&glb)
            .map(|u| format!(",\"uri\":\"{u}\""))
            .unwrap_or_default();
        glb.json = glb_json(
            positions.len(),
            normals.len(),
            colours.map(|c| c.len()),
            indices.len(),
            min,
            max,
            &uri,
        );
        Ok(glb)
    }

    /// The binary buffer, in order.
    fn write_bin(&self, w: &mut dyn Write) -> std::io::Result<()> {
        write_le(w, self.positions)?;
        write_le(w, self.normals)?;
        write_le(w, self.colours.unwrap_or(&[]))?;
        write_le(w, self.indices)
    }

    /// The GLB container: header, JSON chunk (space-padded), BIN chunk (zero-padded).
    fn write(&self, w: &mut dyn Write) -> std::io::Result<()> {
        w.write_all(&glb_head(&self.json, self.bin_len))?;
        self.write_bin(w)?;
        w.write_all(&[0u8; 3][..bin_pad(self.bin_len)])
    }
}

fn bin_pad(bin_len: usize) -> usize {
    (4 - bin_len % 4) % 4
}

/// Everything of a GLB before the binary buffer: the header, the JSON chunk (space-padded)
/// and the BIN chunk's header.
fn glb_head(json: &str, bin_len: usize) -> Vec<u8> {
    let json_pad = (4 - json.len() % 4) % 4;
    let json_len = json.len() + json_pad;
    let bin_len = bin_len + bin_pad(bin_len);
    let len = 12 + 8 + json_len + 8 + bin_len;
    let mut w = Vec::with_capacity(28 + json_len);
    w.extend_from_slice(b"glTF");
    w.extend_from_slice(&2u32.to_le_bytes());
    w.extend_from_slice(&(len as u32).to_le_bytes());
    w.extend_from_slice(&(json_len as u32).to_le_bytes());
    w.extend_from_slice(b"JSON");
    w.extend_from_slice(json.as_bytes());
    w.extend_from_slice(&b"   "[..json_pad]);
    w.extend_from_slice(&(bin_len as u32).to_le_bytes());
    w.extend_from_slice(b"BIN\0");
    w
}

/// A GLB of positions, normals and indices ([`write_mesh`]'s layout, bytes for bytes) written
/// while its buffers are still being computed: the header goes first, from the element counts
/// and the position bounds given in advance, then each range of the buffers as it is done,
/// from another thread (the page-cache copies and the disk writes overlap the computation).
/// [`GlbStream::finish`] checks the bounds against the finished positions and, should they
/// differ, writes the file again from the buffers, so the file is always [`write_mesh`]'s.
/// The write is atomic as every other ([`AtomicFile`]): dropping the stream unfinished
/// removes the temporary file. Unix only (positioned writes).
#[cfg(unix)]
pub struct GlbStream {
    file: AtomicFile,
    json: String,
    /// File offsets of the positions, the normals and the indices.
    offsets: [u64; 3],
    bin_len: usize,
    /// The first error of a positioned write (reported by `finish`).
    error: std::sync::Mutex<Option<std::io::Error>>,
}

#[cfg(unix)]
impl GlbStream {
    /// Starts `path` (a `.glb`) for `vertices` positions and normals and `triangles`
    /// triangles, positions bounded by `bounds`. `None` where the file cannot be streamed (a
    /// mesh too large for one buffer, or a big-endian machine): write it with
    /// [`write_mesh`] instead.
    pub fn create(
        path: &Path,
        vertices: usize,
        triangles: usize,
        bounds: ([f32; 3], [f32; 3]),
    ) -> Result<Option<Self>, ExportError> {
        let bin_len = vertices * 24 + triangles * 12;
        if cfg!(target_endian = "big") || bin_len > u32::MAX as usize - 64 {
            return Ok(None);
        }
        let json = glb_json(vertices, vertices, None, triangles, bounds.0, bounds.1, "");
        let head = glb_head(&json, bin_len);
        let file = AtomicFile::create(path)?;
        {
            use std::os::unix::fs::FileExt;
            file.file()
                .write_all_at(&head, 0)
                .map_err(|e| file.error(e))?;
        }
        let p = head.len() as u64;
        let v = vertices as u64 * 12;
        Ok(Some(Self {
            file,
            json,
            offsets: [p, p + v, p + 2 * v],
            bin_len,
            error: std::sync::Mutex::new(None),
        }))
    }

    fn put<T: bytemuck::Pod>(&self, part: usize, first: usize, data: &[T]) {
        use std::os::unix::fs::FileExt;
        let offset = self.offsets[part] + (first * std::mem::size_of::<T>()) as u64;
        if let Err(e) = self
            .file
            .file()
            .write_all_at(bytemuck::cast_slice(data), offset)
        {
            let mut slot = self.error.lock().unwrap_or_else(|p| p.into_inner());
            slot.get_or_insert(e);
        }
    }

    /// Positions `first ..` (little-endian machines only: [`GlbStream::create`] checks).
    pub fn positions(&self, first: usize, data: &[[f32; 3]]) {
        self.put(0, first, data);
    }

    /// Normals `first ..`.
    pub fn normals(&self, first: usize, data: &[[f32; 3]]) {
        self.put(1, first, data);
    }

    /// Triangles `first ..`.
    pub fn indices(&self, first: usize, data: &[[u32; 3]]) {
        self.put(2, first, data);
    }

    /// Writes what has been written so far to disk (and waits for it), so that the final
    /// flush has only the rest to do.
    pub fn flush_written(&self) {
        if let Err(e) = self.file.file().sync_data() {
            let mut slot = self.error.lock().unwrap_or_else(|p| p.into_inner());
            slot.get_or_insert(e);
        }
    }

    /// Completes the file from the finished buffers, of which the first `unwritten`
    /// positions and normals were not streamed, checks it as [`write_mesh`] checks a mesh
    /// (finite positions, the bounds), flushes it to disk and renames it over the destination.
    pub fn finish(
        self,
        path: &Path,
        positions: &[[f32; 3]],
        normals: &[[f32; 3]],
        indices: &[[u32; 3]],
        unwritten: usize,
    ) -> Result<(), ExportError> {
        let glb = Glb::new(path, positions, normals, None, indices)?;
        let io = |e| ExportError::Write(self.file.error(e));
        if let Some(e) = self.error.lock().unwrap_or_else(|p| p.into_inner()).take() {
            return Err(io(e));
        }
        if glb.json == self.json && glb.bin_len == self.bin_len {
            self.positions(0, &positions[..unwritten]);
            self.normals(0, &normals[..unwritten]);
            let end = self.offsets[2] + (indices.len() * 12) as u64;
            use std::os::unix::fs::FileExt;
            self.file
                .file()
                .write_all_at(&[0u8; 3][..bin_pad(self.bin_len)], end)
                .map_err(io)?;
            if let Some(e) = self.error.lock().unwrap_or_else(|p| p.into_inner()).take() {
                return Err(io(e));
            }
        } else {
            // The bounds given were not the output's: the file is written again, whole.
            use std::io::Seek;
            let mut f = self.file.file();
            f.set_len(0).map_err(io)?;
            f.seek(std::io::SeekFrom::Start(0)).map_err(io)?;
            let mut w = std::io::BufWriter::with_capacity(1 << 20, f);
            glb.write(&mut w).map_err(io)?;
            w.flush().map_err(io)?;
        }
        Ok(self.file.commit()?)
    }
}

/// The JSON of a [`Glb`] with these element counts and position bounds (`uri`: the buffer's
/// `,"uri":...` member, or empty).
fn glb_json(
    n_pos: usize,
    n_nrm: usize,
    colours: Option<usize>,
    n_tri: usize,
    min: [f32; 3],
    max: [f32; 3],
    uri: &str,
) -> String {
    let pos_len = n_pos * 12;
    let nrm_len = n_nrm * 12;
    let col_len = colours.map_or(0, |c| c * 12);
    let idx_len = n_tri * 12;
    let total = pos_len + nrm_len + col_len + idx_len;
    let mut views =
        format!("{{\"buffer\":0,\"byteOffset\":0,\"byteLength\":{pos_len},\"target\":34962}}");
    let mut accessors = format!(
        "{{\"bufferView\":0,\"componentType\":5126,\"count\":{},\"type\":\"VEC3\",\"min\":[{},{},{}],\"max\":[{},{},{}]}}",
        n_pos,
        min[0], min[1], min[2], max[0], max[1], max[2]
    );
    let mut attrs = String::from("\"POSITION\":0");
    let mut next = 1;
    if nrm_len > 0 {
        views.push_str(&format!(
            ",{{\"buffer\":0,\"byteOffset\":{pos_len},\"byteLength\":{nrm_len},\"target\":34962}}"
        ));
        accessors.push_str(&format!(
            ",{{\"bufferView\":1,\"componentType\":5126,\"count\":{},\"type\":\"VEC3\"}}",
            n_nrm
        ));
        attrs.push_str(",\"NORMAL\":1");
        next = 2;
    }
    if let Some(n_col) = colours {
        views.push_str(&format!(
            ",{{\"buffer\":0,\"byteOffset\":{},\"byteLength\":{col_len},\"target\":34962}}",
            pos_len + nrm_len
        ));
        accessors.push_str(&format!(
            ",{{\"bufferView\":{next},\"componentType\":5126,\"count\":{},\"type\":\"VEC3\"}}",
            n_col
        ));
        attrs.push_str(&format!(",\"COLOR_0\":{next}"));
        next += 1;
    }
    views.push_str(&format!(
        ",{{\"buffer\":0,\"byteOffset\":{},\"byteLength\":{idx_len},\"target\":34963}}",
        pos_len + nrm_len + col_len
    ));
    accessors.push_str(&format!(
        ",{{\"bufferView\":{next},\"componentType\":5125,\"count\":{},\"type\":\"SCALAR\"}}",
        n_tri * 3
    ));
    format!(
        "{{\"asset\":{{\"version\":\"2.0\",\"generator\":\"hce subdivide\"}},\"scene\":0,\"scenes\":[{{\"nodes\":[0]}}],\"nodes\":[{{\"mesh\":0}}],\"meshes\":[{{\"primitives\":[{{\"attributes\":{{{attrs}}},\"indices\":{next},\"mode\":4}}]}}],\"buffers\":[{{\"byteLength\":{total}{uri}}}],\"bufferViews\":[{views}],\"accessors\":[{accessors}]}}"
    )
}

/// A `.gltf` text with the buffer embedded as a base64 data URI.
fn gltf_text(
    path: &Path,
    positions: &[[f32; 3]],
    normals: &[[f32; 3]],
    colours: Option<&[[f32; 3]]>,
    indices: &[[u32; 3]],
) -> Result<Vec<u8>, ExportError> {
    let glb = Glb::with_uri(path, positions, normals, colours, indices, |g| {
        let mut bin = Vec::with_capacity(g.bin_len);
        // Writing into memory cannot fail.
        let _ = g.write_bin(&mut bin);
        Some(format!(
            "data:application/octet-stream;base64,{}",
            base64(&bin)
        ))
    })?;
    Ok(glb.json.into_bytes())
}

#[cfg(test)]
mod tests {
    use super::*;

    #[cfg(feature = "import")]
    #[test]
    fn gltf_and_glb_round_trip_through_the_importer() {
        let dir = tempfile::tempdir().unwrap();
        let p = [
            [0.0, 0.0, 0.0],
            [1.0, 0.0, 0.0],
            [0.0, 1.0, 0.5],
            [1.0, 1.0, 0.25],
        ];
        let n = [[0.0, 0.0, 1.0]; 4];
        let t = [[0, 1, 2], [1, 3, 2]];
        for ext in ["gltf", "glb", "obj"] {
            let path = dir.path().join(format!("m.{ext}"));
            write_mesh(&path, &p, &n, &t).unwrap();
            let back = crate::import::load_mesh(&path).unwrap();
            assert_eq!(back.positions, p.to_vec(), "{ext}");
            assert_eq!(back.triangles, t.to_vec(), "{ext}");
            assert_eq!(back.corner_normals.unwrap().len(), 6, "{ext}");
        }
        // Only the destination is left: the temporary file was renamed.
        assert_eq!(std::fs::read_dir(dir.path()).unwrap().count(), 3);
    }

    #[cfg(feature = "import")]
    #[test]
    fn colours_are_written_clamped_as_color_0_and_obj_vertex_colours() {
        let dir = tempfile::tempdir().unwrap();
        let p = [[0.0, 0.0, 0.0], [1.0, 0.0, 0.0], [0.0, 1.0, 0.0]];
        let n = [[0.0, 0.0, 1.0]; 3];
        let c = [[0.25, 0.5, 0.75], [2.0, -1.0, f32::NAN], [1.0, 0.0, 0.125]];
        let clamped = [[0.25, 0.5, 0.75], [1.0, 0.0, 0.0], [1.0, 0.0, 0.125]];
        for ext in ["gltf", "glb"] {
            let path = dir.path().join(format!("m.{ext}"));
            write_mesh_with_colours(&path, &p, &n, &c, &[[0, 1, 2]]).unwrap();
            let (doc, buffers, _) = gltf::import(&path).unwrap();
            let prim = doc.meshes().next().unwrap().primitives().next().unwrap();
            let reader = prim.reader(|b| Some(&buffers[b.index()]));
            let got: Vec<[f32; 3]> = reader.read_colors(0).unwrap().into_rgb_f32().collect();
            assert_eq!(got, clamped.to_vec(), "{ext}");
            let idx: Vec<u32> = reader.read_indices().unwrap().into_u32().collect();
            assert_eq!(idx, vec![0, 1, 2], "{ext}");
        }
        let path = dir.path().join("m.obj");
        write_mesh_with_colours(&path, &p, &n, &c, &[[0, 1, 2]]).unwrap();
        let text = std::fs::read_to_string(&path).unwrap();
        assert!(text.contains("v 1 0 0 1 0 0\n"), "{text}");
        let short = write_mesh_with_colours(&path, &p, &n, &c[..2], &[[0, 1, 2]]);
        assert!(matches!(
            short,
            Err(ExportError::ColourCount { colours: 2, .. })
        ));
    }

    #[test]
    fn unclamped_obj_colours_keep_values_above_one() {
        let dir = tempfile::tempdir().unwrap();
        let p = [[0.0, 0.0, 0.0], [1.0, 0.0, 0.0], [0.0, 1.0, 0.0]];
        let n = [[0.0, 0.0, 1.0]; 3];
        let c = [[0.25, 0.5, 0.75], [2.5, -1.0, f32::NAN], [1.0, 0.0, 0.125]];
        let path = dir.path().join("m.obj");
        write_obj_with_unclamped_colours(&path, &p, &n, &c, &[[0, 1, 2]]).unwrap();
        let text = std::fs::read_to_string(&path).unwrap();
        assert!(text.contains("v 1 0 0 2.5 -1 0\n"), "{text}");
        let glb = dir.path().join("m.glb");
        let refused = write_obj_with_unclamped_colours(&glb, &p, &n, &c, &[[0, 1, 2]]);
        assert!(matches!(
            refused,
            Err(ExportError::UnclampedNeedsObj { .. })
        ));
        assert!(!glb.exists());
        let short = write_obj_with_unclamped_colours(&path, &p, &n, &c[..2], &[[0, 1, 2]]);
        assert!(matches!(
            short,
            Err(ExportError::ColourCount { colours: 2, .. })
        ));
    }

    #[test]
    fn obj_numbers_read_back_exactly() {
        let mut special = vec![
            0.0f32,
            -0.0,
            1.0,
            -1.0,
            0.1,
            1e-7,
            3.4028235e38,
            -1.1754944e-38,
            1e-45,
            16777216.0,
            123456.79,
        ];
        // Every exponent, pseudo-random mantissas (a fixed LCG: deterministic).
        let mut state = 0x2545_f491_u32;
        for _ in 0..200_000 {
            state = state.wrapping_mul(1_664_525).wrapping_add(1_013_904_223);
            let x = f32::from_bits(state);
            if x.is_finite() {
                special.push(x);
            }
        }
        let mut s = Vec::new();
        for &x in &special {
            s.clear();
            push_f32(&mut s, x);
            let text = std::str::from_utf8(&s).unwrap();
            let back: f32 = text.parse().unwrap();
            assert_eq!(back.to_bits(), x.to_bits(), "{x:e} written as {text}");
            // Never longer than Display's shortest text (plus an exponent's few bytes).
            assert!(text.len() <= format!("{x}").len().max(16), "{text}");
        }
        s.clear();
        push_f32(&mut s, 2.0);
        push_u32(&mut s, 4_294_967_295);
        assert_eq!(s, b"24294967295");
    }

    #[cfg(unix)]
    #[test]
    fn a_streamed_glb_is_write_mesh_s_byte_for_byte() {
        let dir = tempfile::tempdir().unwrap();
        let p: Vec<[f32; 3]> = (0..40)
            .map(|i| [i as f32 * 0.25, (i % 7) as f32 - 3.0, -(i as f32) / 9.0])
            .collect();
        let n: Vec<[f32; 3]> = (0..40).map(|i| [0.0, (i as f32).sin(), 1.0]).collect();
        let t: Vec<[u32; 3]> = (0..30).map(|i| [i, i + 1, i + 7]).collect();
        let want_path = dir.path().join("want.glb");
        write_mesh(&want_path, &p, &n, &t).unwrap();
        let want = std::fs::read(&want_path).unwrap();
        let lo = [0.0, -3.0, -39.0 / 9.0];
        let hi = [9.75, 3.0, 0.0];
        let path = dir.path().join("m.glb");
        // Right bounds (the streamed file), wrong ones (written again whole).
        for bounds in [(lo, hi), ([0.0; 3], [1.0; 3])] {
            std::fs::write(&path, b"old").unwrap();
            let s = GlbStream::create(&path, p.len(), t.len(), bounds)
                .unwrap()
                .unwrap();
            // Out of order, in pieces, the first 5 vertices left to `finish`.
            s.indices(10, &t[10..]);
            s.positions(20, &p[20..]);
            s.normals(5, &n[5..]);
            s.flush_written();
            s.positions(5, &p[5..20]);
            s.indices(0, &t[..10]);
            assert_eq!(std::fs::read(&path).unwrap(), b"old");
            s.finish(&path, &p, &n, &t, 5).unwrap();
            assert_eq!(std::fs::read(&path).unwrap(), want);
            assert_eq!(std::fs::read_dir(dir.path()).unwrap().count(), 2);
        }
        // An unfinished stream, or a refused mesh, leaves the old file and no temporary.
        std::fs::write(&path, b"old").unwrap();
        let s = GlbStream::create(&path, p.len(), t.len(), (lo, hi))
            .unwrap()
            .unwrap();
        s.positions(0, &p);
        drop(s);
        let mut bad = p.clone();
        bad[3][1] = f32::NAN;
        let s = GlbStream::create(&path, p.len(), t.len(), (lo, hi))
            .unwrap()
            .unwrap();
        let e = s.finish(&path, &bad, &n, &t, 0).unwrap_err();
        assert!(matches!(e, ExportError::NotFinite { index: 3, .. }), "{e}");
        assert_eq!(std::fs::read(&path).unwrap(), b"old");
        assert_eq!(std::fs::read_dir(dir.path()).unwrap().count(), 2);
    }

    #[test]
    fn base64_matches_rfc4648_vectors() {
        assert_eq!(base64(b"f"), "Zg==");
        assert_eq!(base64(b"fo"), "Zm8=");
        assert_eq!(base64(b"foo"), "Zm9v");
        assert_eq!(base64(b"foobar"), "Zm9vYmFy");
    }
}
