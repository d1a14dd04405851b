//! Writing refined meshes as Wavefront OBJ or glTF 2.0 (`.gltf` with an embedded base64 buffer,
//! or binary `.glb`), atomically: the file is written beside its destination under a temporary
//! name and renamed over it, so a reader never sees half a file.

use std::io::Write;
use std::path::{Path, PathBuf};

/// Errors of mesh export.
#[derive(Debug, thiserror::Error)]
pub enum ExportError {
    #[error("{path}: cannot write: {source}")]
    Io {
        path: PathBuf,
        #[source]
        source: std::io::Error,
    },
    #[error("{path}: unknown mesh extension; use .obj, .gltf or .glb")]
    UnknownFormat { path: PathBuf },
    #[error("{path}: position {index} is not finite; glTF cannot store it")]
    NotFinite { path: PathBuf, index: usize },
    #[error("{path}: the mesh is too large for a single glTF buffer")]
    TooLarge { path: PathBuf },
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
    if colours.len() != positions.len() {
        return Err(ExportError::ColourCount {
            path: path.to_owned(),
            colours: colours.len(),
            vertices: positions.len(),
        });
    }
    let clamped: Vec<[f32; 3]> = colours
        .iter()
        .map(|c| c.map(|x| if x.is_nan() { 0.0 } else { x.clamp(0.0, 1.0) }))
        .collect();
    write_any(path, positions, normals, Some(&clamped), indices)
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
    let bytes = match ext.as_deref() {
        Some("obj") => obj_bytes(positions, normals, colours, indices),
        Some("gltf") => gltf_bytes(path, positions, normals, colours, indices, false)?,
        Some("glb") => gltf_bytes(path, positions, normals, colours, indices, true)?,
        _ => {
            return Err(ExportError::UnknownFormat {
                path: path.to_owned(),
            })
        }
    };
    write_atomic(path, &bytes)
}

/// Writes `bytes` to a temporary file in `path`'s directory, then renames it to `path`.
pub fn write_atomic(path: &Path, bytes: &[u8]) -> Result<(), ExportError> {
    let io = |source| ExportError::Io {
        path: path.to_owned(),
        source,
    };
    let dir = match path.parent() {
        Some(d) if !d.as_os_str().is_empty() => d.to_owned(),
        _ => PathBuf::from("."),
    };
    let name = path
        .file_name()
        .map(|n| n.to_string_lossy().into_owned())
        .unwrap_or_default();
    let tmp = dir.join(format!(".{name}.{}.tmp", std::process::id()));
    let result = (|| {
        let mut f = std::fs::File::create(&tmp)?;
        f.write_all(bytes)?;
        f.sync_all()?;
        std::fs::rename(&tmp, path)
    })();
    if result.is_err() {
        let _ = std::fs::remove_file(&tmp);
    }
    result.map_err(io)
}

fn obj_bytes(
    positions: &[[f32; 3]],
    normals: &[[f32; 3]],
    colours: Option<&[[f32; 3]]>,
    indices: &[[u32; 3]],
) -> Vec<u8> {
    use std::fmt::Write as _;
    let mut s = String::with_capacity(positions.len() * 80 + indices.len() * 40);
    s.push_str("# written by hce subdivide\n");
    for (i, p) in positions.iter().enumerate() {
        match colours.and_then(|c| c.get(i)) {
            Some(c) => {
                let _ = writeln!(s, "v {} {} {} {} {} {}", p[0], p[1], p[2], c[0], c[1], c[2]);
            }
            None => {
                let _ = writeln!(s, "v {} {} {}", p[0], p[1], p[2]);
            }
        }
    }
    for n in normals {
        let _ = writeln!(s, "vn {} {} {}", n[0], n[1], n[2]);
    }
    let with_normals = normals.len() == positions.len();
    for t in indices {
        let [a, b, c] = t.map(|i| i + 1);
        if with_normals {
            let _ = writeln!(s, "f {a}//{a} {b}//{b} {c}//{c}");
        } else {
            let _ = writeln!(s, "f {a} {b} {c}");
        }
    }
    s.into_bytes()
}

fn base64(data: &[u8]) -> String {
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

/// A minimal glTF 2.0 asset: one mesh, one primitive (POSITION, NORMAL, u32 indices), one node.
fn gltf_bytes(
    path: &Path,
    positions: &[[f32; 3]],
    normals: &[[f32; 3]],
    colours: Option<&[[f32; 3]]>,
    indices: &[[u32; 3]],
    binary: bool,
) -> Result<Vec<u8>, ExportError> {
    if let Some(index) = positions
        .iter()
        .position(|p| !p.iter().all(|c| c.is_finite()))
    {
        return Err(ExportError::NotFinite {
            path: path.to_owned(),
            index,
        });
    }
    let pos_len = positions.len() * 12;
    let nrm_len = if normals.len() == positions.len() {
        normals.len() * 12
    } else {
        0
    };
    let colours = colours.filter(|c| c.len() == positions.len());
    let col_len = colours.map_or(0, |c| c.len() * 12);
    let idx_len = indices.len() * 12;
    let total = pos_len + nrm_len + col_len + idx_len;
    if total > u32::MAX as usize - 64 {
        return Err(ExportError::TooLarge {
            path: path.to_owned(),
        });
    }
    let mut bin = Vec::with_capacity(total);
    for p in positions {
        for c in p {
            bin.extend_from_slice(&c.to_le_bytes());
        }
    }
    if nrm_len > 0 {
        for n in normals {
            for c in n {
                bin.extend_from_slice(&c.to_le_bytes());
            }
        }
    }
    for c in colours.unwrap_or(&[]) {
        for x in c {
            bin.extend_from_slice(&x.to_le_bytes());
        }
    }
    for t in indices {
        for i in t {
            bin.extend_from_slice(&i.to_le_bytes());
        }
    }
    let mut min = [f32::INFINITY; 3];
    let mut max = [f32::NEG_INFINITY; 3];
    for p in positions {
        for k in 0..3 {
            min[k] = min[k].min(p[k]);
            max[k] = max[k].max(p[k]);
        }
    }
    if positions.is_empty() {
        min = [0.0; 3];
        max = [0.0; 3];
    }
    let uri = if binary {
        String::new()
    } else {
        format!(
            ",\"uri\":\"data:application/octet-stream;base64,{}\"",
            base64(&bin)
        )
    };
    let (attrs, views, accessors, idx_accessor) = {
        let mut views =
            format!("{{\"buffer\":0,\"byteOffset\":0,\"byteLength\":{pos_len},\"target\":34962}}");
        let mut accessors = format!(
            "{{\"bufferView\":0,\"componentType\":5126,\"count\":{},\"type\":\"VEC3\",\"min\":[{},{},{}],\"max\":[{},{},{}]}}",
            positions.len(),
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
                normals.len()
            ));
            attrs.push_str(",\"NORMAL\":1");
            next = 2;
        }
        if let Some(c) = colours {
            views.push_str(&format!(
                ",{{\"buffer\":0,\"byteOffset\":{},\"byteLength\":{col_len},\"target\":34962}}",
                pos_len + nrm_len
            ));
            accessors.push_str(&format!(
                ",{{\"bufferView\":{next},\"componentType\":5126,\"count\":{},\"type\":\"VEC3\"}}",
                c.len()
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
            indices.len() * 3
        ));
        (attrs, views, accessors, next)
    };
    let json = format!(
        "{{\"asset\":{{\"version\":\"2.0\",\"generator\":\"hce subdivide\"}},\"scene\":0,\"scenes\":[{{\"nodes\":[0]}}],\"nodes\":[{{\"mesh\":0}}],\"meshes\":[{{\"primitives\":[{{\"attributes\":{{{attrs}}},\"indices\":{idx_accessor},\"mode\":4}}]}}],\"buffers\":[{{\"byteLength\":{total}{uri}}}],\"bufferViews\":[{views}],\"accessors\":[{accessors}]}}"
    );
    if !binary {
        return Ok(json.into_bytes());
    }
    let mut json = json.into_bytes();
    while json.len() % 4 != 0 {
        json.push(b' ');
    }
    while bin.len() % 4 != 0 {
        bin.push(0);
    }
    let len = 12 + 8 + json.len() + 8 + bin.len();
    let mut out = Vec::with_capacity(len);
    out.extend_from_slice(b"glTF");
    out.extend_from_slice(&2u32.to_le_bytes());
    out.extend_from_slice(&(len as u32).to_le_bytes());
    out.extend_from_slice(&(json.len() as u32).to_le_bytes());
    out.extend_from_slice(b"JSON");
    out.extend_from_slice(&json);
    out.extend_from_slice(&(bin.len() as u32).to_le_bytes());
    out.extend_from_slice(b"BIN\0");
    out.extend_from_slice(&bin);
    Ok(out)
}

#[cfg(test)]
mod tests {
    use super::*;

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
    fn base64_matches_rfc4648_vectors() {
        assert_eq!(base64(b"f"), "Zg==");
        assert_eq!(base64(b"fo"), "Zm8=");
        assert_eq!(base64(b"foo"), "Zm9v");
        assert_eq!(base64(b"foobar"), "Zm9vYmFy");
    }
}
