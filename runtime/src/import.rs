//! Triangle-mesh import from Wavefront OBJ (through `tobj`) and glTF 2.0 (through `gltf`), and
//! position welding.
//!
//! Topology is always built from position indices: an OBJ file is read with `tobj`'s
//! multi-index layout (never `single_index`, which would split vertices at texture seams), and
//! glTF primitives, whose vertices are split at every attribute seam, are reconnected by welding
//! equal positions. Per-corner normals are kept when the input has them, because an edge whose
//! two sides disagree on a normal is one the author made hard (`--creases auto`).

use std::collections::HashMap;
use std::path::{Path, PathBuf};

/// An unwelded triangle mesh as read from a file.
#[derive(Clone, Debug, Default, PartialEq)]
pub struct InputMesh {
    /// Vertex positions, in file order (all OBJ groups / glTF primitives concatenated).
    pub positions: Vec<[f32; 3]>,
    /// Counter-clockwise triangles indexing `positions`.
    pub triangles: Vec<[u32; 3]>,
    /// One normal per triangle corner (`3 * t + c`), when every triangle has them.
    pub corner_normals: Option<Vec<[f32; 3]>>,
}

/// Errors of mesh import.
#[derive(Debug, thiserror::Error)]
pub enum ImportError {
    #[error("{path}: cannot read the file: {source}")]
    Io {
        path: PathBuf,
        #[source]
        source: std::io::Error,
    },
    #[error("{path}: not a readable OBJ file: {source}")]
    Obj {
        path: PathBuf,
        #[source]
        source: tobj::LoadError,
    },
    #[error("{path}: not a readable glTF 2.0 file: {source}")]
    Gltf {
        path: PathBuf,
        #[source]
        source: gltf::Error,
    },
    #[error("{path}: {what}")]
    Invalid { path: PathBuf, what: String },
    #[error("{path}: unknown mesh extension; use .obj, .gltf or .glb")]
    UnknownFormat { path: PathBuf },
    #[error("{path}: the file holds no triangles")]
    Empty { path: PathBuf },
}

/// Reads `.obj`, `.gltf` or `.glb`, chosen by extension.
pub fn load_mesh(path: &Path) -> Result<InputMesh, ImportError> {
    let ext = path
        .extension()
        .and_then(|e| e.to_str())
        .map(str::to_ascii_lowercase);
    // The parsers report a missing or unreadable file as a parse failure; say what it is.
    std::fs::File::open(path).map_err(|source| ImportError::Io {
        path: path.to_owned(),
        source,
    })?;
    let mesh = match ext.as_deref() {
        Some("obj") => load_obj(path)?,
        Some("gltf") | Some("glb") => load_gltf(path)?,
        _ => {
            return Err(ImportError::UnknownFormat {
                path: path.to_owned(),
            })
        }
    };
    if mesh.triangles.is_empty() {
        return Err(ImportError::Empty {
            path: path.to_owned(),
        });
    }
    Ok(mesh)
}

/// Reads an OBJ file; polygons are fan-triangulated by `tobj`, faces indexed by position.
/// `tobj` keeps only the positions that faces reference, so unused OBJ vertices are already
/// gone here (and the topology report counts none for OBJ input).
pub fn load_obj(path: &Path) -> Result<InputMesh, ImportError> {
    let opts = tobj::LoadOptions {
        triangulate: true,
        single_index: false,
        ignore_points: true,
        ignore_lines: true,
    };
    let (models, _materials) = tobj::load_obj(path, &opts).map_err(|source| ImportError::Obj {
        path: path.to_owned(),
        source,
    })?;
    let mut out = InputMesh::default();
    let mut normals = Vec::new();
    let mut all_normals = true;
    for model in &models {
        let m = &model.mesh;
        let base = out.positions.len() as u32;
        let nv = m.positions.len() / 3;
        out.positions
            .extend(m.positions.chunks_exact(3).map(|p| [p[0], p[1], p[2]]));
        let has_normals = m.normal_indices.len() == m.indices.len() && !m.normals.is_empty();
        all_normals &= has_normals;
        for (k, tri) in m.indices.chunks_exact(3).enumerate() {
            if tri.iter().any(|&i| i as usize >= nv) {
                return Err(ImportError::Invalid {
                    path: path.to_owned(),
                    what: format!(
                        "object '{}' face {k} references a missing vertex",
                        model.name
                    ),
                });
            }
            out.triangles
                .push([base + tri[0], base + tri[1], base + tri[2]]);
            if has_normals {
                for c in 0..3 {
                    let n = m.normal_indices[3 * k + c] as usize;
                    let v =
                        m.normals
                            .get(3 * n..3 * n + 3)
                            .ok_or_else(|| ImportError::Invalid {
                                path: path.to_owned(),
                                what: format!(
                                    "object '{}' face {k} references missing normal {}",
                                    model.name,
                                    n + 1
                                ),
                            })?;
                    normals.push([v[0], v[1], v[2]]);
                }
            }
        }
    }
    if all_normals && normals.len() == 3 * out.triangles.len() {
        out.corner_normals = Some(normals);
    }
    Ok(out)
}

/// Reads every triangle primitive of every mesh of a glTF/GLB file.
///
/// Node transforms are NOT applied: each mesh is taken once, in its own coordinates, in mesh
/// order, because the control mesh subdivided here is the mesh asset itself (a mesh instanced by
/// several nodes is one object). Primitives that are not triangle lists (points, lines, strips,
/// fans) are skipped.
pub fn load_gltf(path: &Path) -> Result<InputMesh, ImportError> {
    let gltf_err = |source| ImportError::Gltf {
        path: path.to_owned(),
        source,
    };
    let gltf = gltf::Gltf::open(path).map_err(gltf_err)?;
    let base = path.parent();
    let buffers =
        gltf::import_buffers(&gltf.document, base, gltf.blob.clone()).map_err(gltf_err)?;
    let mut out = InputMesh::default();
    let mut normals = Vec::new();
    let mut all_normals = true;
    for mesh in gltf.document.meshes() {
        for prim in mesh.primitives() {
            if prim.mode() != gltf::mesh::Mode::Triangles {
                continue;
            }
            let reader = prim.reader(|b| buffers.get(b.index()).map(|d| &d.0[..]));
            let Some(pos) = reader.read_positions() else {
                continue;
            };
            let base_v = out.positions.len() as u32;
            let pos: Vec<[f32; 3]> = pos.collect();
            let nv = pos.len();
            let prim_normals: Option<Vec<[f32; 3]>> = reader.read_normals().map(|n| n.collect());
            let indices: Vec<u32> = match reader.read_indices() {
                Some(i) => i.into_u32().collect(),
                None => (0..nv as u32).collect(),
            };
            let has_normals = prim_normals.as_ref().is_some_and(|n| n.len() == nv);
            all_normals &= has_normals;
            for (k, tri) in indices.chunks_exact(3).enumerate() {
                if tri.iter().any(|&i| i as usize >= nv) {
                    return Err(ImportError::Invalid {
                        path: path.to_owned(),
                        what: format!(
                            "meshes[{}].primitives[{}]: triangle {k} index out of bounds",
                            mesh.index(),
                            prim.index()
                        ),
                    });
                }
                out.triangles
                    .push([base_v + tri[0], base_v + tri[1], base_v + tri[2]]);
                if let (true, Some(n)) = (has_normals, prim_normals.as_ref()) {
                    normals.extend(tri.iter().map(|&i| n[i as usize]));
                }
            }
            out.positions.extend(pos);
        }
    }
    if all_normals && normals.len() == 3 * out.triangles.len() {
        out.corner_normals = Some(normals);
    }
    Ok(out)
}

/// The result of welding: unique positions and the map from input vertices to them.
#[derive(Clone, Debug, Default, PartialEq)]
pub struct Weld {
    /// Welded positions, in order of first occurrence in the input vertex list.
    pub positions: Vec<[f32; 3]>,
    /// `input_to_welded[i]`: the welded vertex of input vertex `i`.
    pub input_to_welded: Vec<u32>,
}

/// Welds input vertices whose positions are equal (`tolerance == 0`: bitwise equal, with `-0.0`
/// taken as `0.0`), or within `tolerance` (Euclidean) of the first vertex of a cluster. Each
/// input vertex joins the earliest welded vertex within reach, so the result depends only on the
/// input order.
pub fn weld(positions: &[[f32; 3]], tolerance: f32) -> Weld {
    let mut out = Weld {
        positions: Vec::new(),
        input_to_welded: Vec::with_capacity(positions.len()),
    };
    if tolerance <= 0.0 {
        let mut map: HashMap<[u32; 3], u32> = HashMap::with_capacity(positions.len());
        for p in positions {
            // Adding 0.0 turns -0.0 into +0.0 and leaves every other value unchanged.
            let key = p.map(|c| (c + 0.0).to_bits());
            let id = *map.entry(key).or_insert_with(|| {
                out.positions.push(*p);
                out.positions.len() as u32 - 1
            });
            out.input_to_welded.push(id);
        }
        return out;
    }
    // Uniform grid of cell size `tolerance`: a vertex within reach lies in one of 27 cells.
    let cell = |p: &[f32; 3]| p.map(|c| (c / tolerance).floor() as i64);
    let mut grid: HashMap<[i64; 3], Vec<u32>> = HashMap::new();
    let tol2 = tolerance * tolerance;
    for p in positions {
        let c = cell(p);
        let mut found: Option<u32> = None;
        for dx in -1..=1 {
            for dy in -1..=1 {
                for dz in -1..=1 {
                    if let Some(list) = grid.get(&[c[0] + dx, c[1] + dy, c[2] + dz]) {
                        for &w in list {
                            let q = out.positions[w as usize];
                            let d2 = (0..3).map(|k| (q[k] - p[k]) * (q[k] - p[k])).sum::<f32>();
                            if d2 <= tol2 && found.is_none_or(|f| w < f) {
                                found = Some(w);
                            }
                        }
                    }
                }
            }
        }
        let id = found.unwrap_or_else(|| {
            out.positions.push(*p);
            let id = out.positions.len() as u32 - 1;
            grid.entry(c).or_default().push(id);
            id
        });
        out.input_to_welded.push(id);
    }
    out
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn weld_merges_equal_positions_and_signed_zero() {
        let w = weld(
            &[
                [0.0, 0.0, 0.0],
                [1.0, 0.0, 0.0],
                [-0.0, 0.0, 0.0],
                [1.0, 0.0, 0.0],
            ],
            0.0,
        );
        assert_eq!(w.input_to_welded, vec![0, 1, 0, 1]);
        assert_eq!(w.positions.len(), 2);
    }

    #[test]
    fn weld_with_tolerance_joins_near_points_only() {
        let w = weld(
            &[[0.0, 0.0, 0.0], [0.0009, 0.0, 0.0], [0.01, 0.0, 0.0]],
            0.001,
        );
        assert_eq!(w.input_to_welded, vec![0, 0, 1]);
    }
}
