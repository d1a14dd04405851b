//! Triangle-mesh import from Wavefront OBJ (through `tobj`) and glTF 2.0 (through `gltf`).
//!
//! Topology is always built from position indices: an OBJ file is read with `tobj`'s
//! multi-index layout (never `single_index`, which would split vertices at texture seams), and
//! glTF primitives, whose vertices are split at every attribute seam, are reconnected by welding
//! equal positions. Per-corner normals are kept when the input has them, because an edge whose
//! two sides disagree on a normal is one the author made hard (`--creases auto`).

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

/// Reads every triangle primitive of every mesh instance of a glTF/GLB file, placed where the
/// scene puts it.
///
/// The nodes of the default scene (the first scene when none is named default) are walked
/// depth-first in file order, and each node's mesh is taken with the node's world transform
/// (the product of its ancestors' and its own matrix or TRS): positions by the matrix, corner
/// normals by its inverse transpose, and a mirroring transform (negative determinant) has its
/// triangles' winding reversed so that they still face out. A mesh used by several nodes
/// contributes one copy per node. A file without scenes has its meshes taken once each,
/// untransformed, in mesh order. Primitives that are not triangle lists (points, lines,
/// strips, fans) are skipped.
///
/// Hostile files are errors, never a panic, a hang or an unbounded allocation: the file goes
/// through [`crate::gltf_guard`] (reference pre-check, buffers only from the GLB, `data:` URIs
/// and regular files relative to it, every accessor bounds-checked before it is read), and a
/// panic of the `gltf` crate that those checks miss is caught and reported as an error.
pub fn load_gltf(path: &Path) -> Result<InputMesh, ImportError> {
    let bytes = std::fs::read(path).map_err(|source| ImportError::Io {
        path: path.to_owned(),
        source,
    })?;
    crate::gltf_guard::precheck(&bytes).map_err(|what| ImportError::Invalid {
        path: path.to_owned(),
        what,
    })?;
    std::panic::catch_unwind(std::panic::AssertUnwindSafe(|| {
        load_gltf_checked(path, &bytes)
    }))
    .unwrap_or_else(|panic| {
        let what = panic
            .downcast_ref::<&str>()
            .map(|s| s.to_string())
            .or_else(|| panic.downcast_ref::<String>().cloned())
            .unwrap_or_default();
        Err(ImportError::Invalid {
            path: path.to_owned(),
            what: format!("the glTF reader failed on this file ({what})"),
        })
    })
}

fn load_gltf_checked(path: &Path, bytes: &[u8]) -> Result<InputMesh, ImportError> {
    use crate::gltf_guard::{check_accessor, load_buffers, AccessorUse};
    let gltf = gltf::Gltf::from_slice(bytes).map_err(|source| ImportError::Gltf {
        path: path.to_owned(),
        source,
    })?;
    let base = path.parent().unwrap_or_else(|| Path::new("."));
    let mut buffer_problems = Vec::new();
    let buffers = load_buffers(
        &gltf.document,
        Some(base),
        gltf.blob.clone(),
        &mut buffer_problems,
    );
    let doc = &gltf.document;
    let mut instances: Vec<(gltf::Mesh, glam::Mat4)> = Vec::new();
    match doc.default_scene().or_else(|| doc.scenes().next()) {
        Some(scene) => {
            // An explicit stack and a visited set: a malformed file whose nodes do not form a
            // tree (a cycle, or a node with two parents) must be an error, not a stack
            // overflow, an endless walk or an exponential number of instances.
            let mut seen = vec![false; doc.nodes().len()];
            let mut stack: Vec<(gltf::Node, glam::Mat4)> =
                scene.nodes().map(|n| (n, glam::Mat4::IDENTITY)).collect();
            stack.reverse();
            while let Some((node, parent)) = stack.pop() {
                if std::mem::replace(&mut seen[node.index()], true) {
                    return Err(ImportError::Invalid {
                        path: path.to_owned(),
                        what: format!(
                            "nodes[{}] is reached twice from scene {}; glTF nodes must form trees (one parent per node, no cycles)",
                            node.index(),
                            scene.index()
                        ),
                    });
                }
                let world = parent * glam::Mat4::from_cols_array_2d(&node.transform().matrix());
                if let Some(mesh) = node.mesh() {
                    instances.push((mesh, world));
                }
                let children: Vec<_> = node.children().collect();
                stack.extend(children.into_iter().rev().map(|c| (c, world)));
            }
        }
        None => instances.extend(doc.meshes().map(|m| (m, glam::Mat4::IDENTITY))),
    }
    let mut out = InputMesh::default();
    let mut normals = Vec::new();
    let mut all_normals = true;
    for (mesh, world) in instances {
        let identity = world == glam::Mat4::IDENTITY;
        let mirrored = world.determinant() < 0.0;
        let normal_matrix = glam::Mat3::from_mat4(world).inverse().transpose();
        let place = |p: [f32; 3]| -> [f32; 3] {
            if identity {
                p
            } else {
                world.transform_point3(glam::Vec3::from(p)).to_array()
            }
        };
        let turn = |n: [f32; 3]| -> [f32; 3] {
            if identity {
                n
            } else {
                (normal_matrix * glam::Vec3::from(n))
                    .normalize_or_zero()
                    .to_array()
            }
        };
        for prim in mesh.primitives() {
            if prim.mode() != gltf::mesh::Mode::Triangles {
                continue;
            }
            let Some(pos_acc) = prim.get(&gltf::Semantic::Positions) else {
                continue;
            };
            let mut used = vec![(pos_acc, AccessorUse::Position)];
            used.extend(prim.indices().map(|a| (a, AccessorUse::Index)));
            let normal_acc = prim.get(&gltf::Semantic::Normals);
            used.extend(normal_acc.map(|a| (a, AccessorUse::Normal)));
            if let Err(e) = used
                .iter()
                .try_for_each(|(a, u)| check_accessor(a, *u, &buffers))
            {
                let mut what =
                    format!("meshes[{}].primitives[{}]: {e}", mesh.index(), prim.index());
                for p in &buffer_problems {
                    what.push_str("; ");
                    what.push_str(p);
                }
                return Err(ImportError::Invalid {
                    path: path.to_owned(),
                    what,
                });
            }
            let reader = prim.reader(|b| buffers.get(b.index()).and_then(|d| d.as_deref()));
            let Some(pos) = reader.read_positions() else {
                continue;
            };
            let pos: Vec<[f32; 3]> = pos.map(place).collect();
            let nv = pos.len();
            let base_v = u32::try_from(out.positions.len())
                .ok()
                .filter(|b| b.checked_add(nv as u32).is_some() && nv <= u32::MAX as usize)
                .ok_or_else(|| ImportError::Invalid {
                    path: path.to_owned(),
                    what: "more than 2^32 vertices in all mesh instances; split the scene".into(),
                })?;
            let prim_normals: Option<Vec<[f32; 3]>> =
                reader.read_normals().map(|n| n.map(turn).collect());
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
                let tri = if mirrored {
                    [tri[0], tri[2], tri[1]]
                } else {
                    [tri[0], tri[1], tri[2]]
                };
                out.triangles.push(tri.map(|i| base_v + i));
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

#[cfg(test)]
mod tests {
    use super::*;

    /// A one-triangle mesh (corner normals `(0.6, 0, 0.8)`) in a `.gltf` with an external
    /// buffer, used by the nodes given as JSON.
    fn gltf_with_nodes(dir: &Path, nodes: &str, scene_nodes: &str) -> PathBuf {
        let mut bin = Vec::new();
        for p in [[0.0f32, 0.0, 0.0], [1.0, 0.0, 0.0], [0.0, 1.0, 0.0]] {
            bin.extend(p.iter().flat_map(|c| c.to_le_bytes()));
        }
        for _ in 0..3 {
            bin.extend([0.6f32, 0.0, 0.8].iter().flat_map(|c| c.to_le_bytes()));
        }
        bin.extend([0u32, 1, 2].iter().flat_map(|i| i.to_le_bytes()));
        std::fs::write(dir.join("tri.bin"), &bin).unwrap();
        let json = format!(
            r#"{{"asset":{{"version":"2.0"}},"scene":0,"scenes":[{{"nodes":{scene_nodes}}}],
            "nodes":{nodes},
            "meshes":[{{"primitives":[{{"attributes":{{"POSITION":0,"NORMAL":1}},"indices":2}}]}}],
            "buffers":[{{"byteLength":84,"uri":"tri.bin"}}],
            "bufferViews":[{{"buffer":0,"byteOffset":0,"byteLength":36}},
                {{"buffer":0,"byteOffset":36,"byteLength":36}},
                {{"buffer":0,"byteOffset":72,"byteLength":12}}],
            "accessors":[{{"bufferView":0,"componentType":5126,"count":3,"type":"VEC3","min":[0,0,0],"max":[1,1,0]}},
                {{"bufferView":1,"componentType":5126,"count":3,"type":"VEC3"}},
                {{"bufferView":2,"componentType":5125,"count":3,"type":"SCALAR"}}]}}"#
        );
        let path = dir.join("scene.gltf");
        std::fs::write(&path, json).unwrap();
        path
    }

    #[test]
    fn gltf_meshes_are_placed_by_their_node_transforms() {
        let dir = tempfile::tempdir().unwrap();
        // Node 0 translates its child node 1, which scales the mesh by (2, 1, 1); node 2
        // mirrors a second instance in x.
        let path = gltf_with_nodes(
            dir.path(),
            r#"[{"translation":[10,0,0],"children":[1]},{"scale":[2,1,1],"mesh":0},
                {"scale":[-1,1,1],"mesh":0}]"#,
            "[0, 2]",
        );
        let m = load_gltf(&path).unwrap();
        assert_eq!(
            m.positions,
            vec![
                [10.0, 0.0, 0.0],
                [12.0, 0.0, 0.0],
                [10.0, 1.0, 0.0],
                [0.0, 0.0, 0.0],
                [-1.0, 0.0, 0.0],
                [0.0, 1.0, 0.0],
            ]
        );
        // The mirrored copy keeps facing +z: its winding is reversed.
        assert_eq!(m.triangles, vec![[0, 1, 2], [3, 5, 4]]);
        let n = m.corner_normals.unwrap();
        // Normals go by the inverse transpose: x scaled by 1/2 under the (2, 1, 1) scale.
        let len = (0.3f32 * 0.3 + 0.8 * 0.8).sqrt();
        let want = [0.3 / len, 0.0, 0.8 / len];
        for k in 0..3 {
            assert!((n[0][k] - want[k]).abs() < 1e-6, "{:?}", n[0]);
            assert!((n[3][k] - [-0.6, 0.0, 0.8][k]).abs() < 1e-6, "{:?}", n[3]);
        }
    }

    #[test]
    fn gltf_nodes_that_are_not_a_tree_are_refused() {
        let dir = tempfile::tempdir().unwrap();
        let path = gltf_with_nodes(
            dir.path(),
            r#"[{"children":[1]},{"children":[0],"mesh":0}]"#,
            "[0]",
        );
        let err = load_gltf(&path).unwrap_err().to_string();
        assert!(err.contains("nodes[0] is reached twice"), "{err}");
    }
}
