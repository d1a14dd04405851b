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

/// Why a mesh ([`load_mesh`], [`crate::plain::load_plain_mesh`]) or a scene
/// ([`crate::scene::import_scene`]) cannot be imported: the one error of meshio's readers.
#[derive(Debug, thiserror::Error)]
pub enum ImportError {
    #[error("{path}: cannot read the file: {source}")]
    Io {
        path: PathBuf,
        #[source]
        source: std::io::Error,
    },
    #[error("{path}: not a readable OBJ file: {message}")]
    Obj { path: PathBuf, message: String },
    #[error("{path}: not a readable glTF 2.0 file: {source}")]
    Gltf {
        path: PathBuf,
        #[source]
        source: gltf::Error,
    },
    #[error("{path}: {message}")]
    Invalid { path: PathBuf, message: String },
    #[error("{path}: unknown format; use .gltf, .glb or .obj")]
    UnknownFormat { path: PathBuf },
    #[error("{path}: the file holds no triangles{}", warnings_suffix(.warnings))]
    NoTriangles {
        path: PathBuf,
        /// What the import skipped on the way (a scene's warnings), if anything.
        warnings: Vec<String>,
    },
    #[error(
        "{path}: the scene has no light source: no KHR_lights_punctual light and no material \
         with a non-zero emission; add a light, or an emissive material (emissiveFactor, \
         or Ke in MTL) on some geometry"
    )]
    NoLightSource { path: PathBuf },
}

fn warnings_suffix(w: &[String]) -> String {
    if w.is_empty() {
        String::new()
    } else {
        format!(" ({})", w.join("; "))
    }
}

/// Reads `.obj`, `.gltf` or `.glb`, chosen by extension, with corner normals where the file
/// has them.
pub fn load_mesh(path: &Path) -> Result<InputMesh, ImportError> {
    let read = read_triangles(
        path,
        Wanted {
            normals: true,
            colours: false,
        },
    )?;
    Ok(InputMesh {
        positions: read.positions,
        triangles: read.triangles,
        corner_normals: read.corner_normals,
    })
}

/// What a reader wants besides positions and triangles.
#[derive(Clone, Copy, Debug, Default)]
pub(crate) struct Wanted {
    /// Corner normals (glTF `NORMAL`, OBJ `vn`).
    pub normals: bool,
    /// Per-vertex colours (glTF `COLOR_0`, OBJ `v x y z r g b`).
    pub colours: bool,
}

pub(crate) use crate::triangles::Triangles;

/// The one mesh reader behind [`load_mesh`] and [`crate::plain::load_plain_mesh`].
pub(crate) fn read_triangles(path: &Path, wanted: Wanted) -> Result<Triangles, ImportError> {
    let ext = path
        .extension()
        .and_then(|e| e.to_str())
        .map(str::to_ascii_lowercase);
    let bytes = std::fs::read(path).map_err(|source| ImportError::Io {
        path: path.to_owned(),
        source,
    })?;
    let read = match ext.as_deref() {
        Some("obj") => read_obj(path, &bytes)?,
        Some("gltf") | Some("glb") => read_gltf(path, &bytes, wanted)?,
        _ => {
            return Err(ImportError::UnknownFormat {
                path: path.to_owned(),
            })
        }
    };
    if read.triangles.is_empty() {
        return Err(ImportError::NoTriangles {
            path: path.to_owned(),
            warnings: Vec::new(),
        });
    }
    Ok(read)
}

/// Reads an OBJ file; polygons are fan-triangulated by `tobj`, faces indexed by position.
/// `tobj` keeps only the positions that faces reference, so unused OBJ vertices are already
/// gone here (and the topology report counts none for OBJ input). `mtllib` is not followed:
/// materials are not needed here, and `tobj` panics on some malformed MTL files.
///
/// A plain file is read by [`crate::obj_fast`], which gives the same result several times
/// faster; everything else, errors included, goes through `tobj`.
fn read_obj(path: &Path, bytes: &[u8]) -> Result<Triangles, ImportError> {
    match crate::obj_fast::read(bytes) {
        Some(read) => Ok(read),
        None => read_obj_tobj(path, bytes),
    }
}

/// [`read_obj`] through `tobj`.
fn read_obj_tobj(path: &Path, bytes: &[u8]) -> Result<Triangles, ImportError> {
    let opts = tobj::LoadOptions {
        triangulate: true,
        single_index: false,
        ignore_points: true,
        ignore_lines: true,
    };
    let (models, _materials) = tobj::load_obj_buf(&mut &bytes[..], &opts, |_| {
        Err(tobj::LoadError::OpenFileFailed)
    })
    .map_err(|source| ImportError::Obj {
        path: path.to_owned(),
        message: source.to_string(),
    })?;
    let mut out = Triangles::default();
    let mut normals = Vec::new();
    let mut all_normals = true;
    let mut colours = Vec::new();
    let mut any_colour = false;
    for model in &models {
        let m = &model.mesh;
        let base = u32::try_from(out.positions.len()).map_err(|_| too_many(path))?;
        let nv = m.positions.len() / 3;
        out.positions
            .extend(m.positions.chunks_exact(3).map(|p| [p[0], p[1], p[2]]));
        if m.vertex_color.len() == 3 * nv {
            any_colour |= nv > 0;
            colours.extend(
                m.vertex_color
                    .chunks_exact(3)
                    .map(|c| Some([c[0], c[1], c[2]])),
            );
        } else {
            colours.extend(std::iter::repeat_n(None, nv));
        }
        let has_normals = m.normal_indices.len() == m.indices.len() && !m.normals.is_empty();
        all_normals &= has_normals;
        for (k, tri) in m.indices.chunks_exact(3).enumerate() {
            if tri.iter().any(|&i| i as usize >= nv) {
                return Err(ImportError::Invalid {
                    path: path.to_owned(),
                    message: format!(
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
                                message: format!(
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
    out.colours = any_colour.then_some(colours);
    Ok(out)
}

fn too_many(path: &Path) -> ImportError {
    ImportError::Invalid {
        path: path.to_owned(),
        message: "more than 2^32 vertices in all mesh instances; split the scene".into(),
    }
}

/// Reads every triangle primitive of every mesh instance of a glTF/GLB file, placed where the
/// scene puts it.
///
/// The nodes of the scene are walked by [`crate::scene_graph::walk`] (the default scene, else
/// the first, else every parentless node; a node hierarchy that is not a tree is refused here),
/// and each node's mesh is taken with the node's world transform: positions by the matrix,
/// corner normals by its inverse transpose, and a mirroring transform (negative determinant)
/// has its triangles' winding reversed so that they still face out. A mesh used by several
/// nodes contributes one copy per node. A file without nodes has its meshes taken once each,
/// untransformed, in mesh order. Primitives that are not triangle lists (points, lines,
/// strips, fans) are skipped.
///
/// Hostile files are errors, never a panic, a hang or an unbounded allocation: the file goes
/// through [`crate::gltf_guard`] (reference pre-check, buffers only from the GLB, `data:` URIs
/// and regular files relative to it, every accessor bounds-checked before it is read), and a
/// panic of the `gltf` crate that those checks miss is caught and reported as an error.
fn read_gltf(path: &Path, bytes: &[u8], wanted: Wanted) -> Result<Triangles, ImportError> {
    let base = path.parent().unwrap_or_else(|| Path::new("."));
    crate::gltf_guard::panic_free(|| read_gltf_checked(path, base, bytes, wanted)).unwrap_or_else(
        |message| {
            Err(ImportError::Invalid {
                path: path.to_owned(),
                message,
            })
        },
    )
}

fn read_gltf_checked(
    path: &Path,
    base: &Path,
    bytes: &[u8],
    wanted: Wanted,
) -> Result<Triangles, ImportError> {
    use crate::gltf_guard::{check_accessor, AccessorUse, OpenError};
    use crate::scene_graph::SceneWalk;
    let invalid = |message: String| ImportError::Invalid {
        path: path.to_owned(),
        message,
    };
    let gltf = crate::gltf_guard::open(bytes, Some(base)).map_err(|e| match e {
        OpenError::Invalid(what) => invalid(what),
        OpenError::Gltf(source) => ImportError::Gltf {
            path: path.to_owned(),
            source,
        },
    })?;
    let walk = crate::scene_graph::walk(&gltf.json).map_err(|e| invalid(e.to_string()))?;
    if let Some(&node) = walk.repeated.first() {
        return Err(invalid(SceneWalk::repeated_message(node)));
    }
    let doc = &gltf.document;
    let buffers = &gltf.buffers;
    let meshes: Vec<gltf::Mesh> = doc.meshes().collect();
    let instances: Vec<(usize, glam::Mat4)> = if doc.nodes().len() == 0 {
        (0..meshes.len())
            .map(|m| (m, glam::Mat4::IDENTITY))
            .collect()
    } else {
        walk.mesh_instances().map(|(v, m)| (m, v.world)).collect()
    };
    let mut out = Triangles::default();
    let mut normals = Vec::new();
    let mut all_normals = true;
    let mut colours = Vec::new();
    let mut any_colour = false;
    for (m, world) in instances {
        let mesh = &meshes[m];
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
            if wanted.normals {
                let normal_acc = prim.get(&gltf::Semantic::Normals);
                used.extend(normal_acc.map(|a| (a, AccessorUse::Normal)));
            }
            if wanted.colours {
                let colour_acc = prim.get(&gltf::Semantic::Colors(0));
                used.extend(colour_acc.map(|a| (a, AccessorUse::Colour)));
            }
            if let Err(e) = used
                .iter()
                .try_for_each(|(a, u)| check_accessor(a, *u, buffers))
            {
                let mut what =
                    format!("meshes[{}].primitives[{}]: {e}", mesh.index(), prim.index());
                for p in &gltf.buffer_problems {
                    what.push_str("; ");
                    what.push_str(p);
                }
                return Err(invalid(what));
            }
            let reader = prim.reader(|b| buffers.get(b.index()).and_then(|d| d.as_deref()));
            let position = prim.get(&gltf::Semantic::Positions);
            let Some(pos) = position.and_then(|a| {
                crate::gltf_guard::read_vec3(&gltf.json, buffers, &a, || reader.read_positions())
            }) else {
                continue;
            };
            let pos: Vec<[f32; 3]> = pos.into_iter().map(place).collect();
            let nv = pos.len();
            let base_v = u32::try_from(out.positions.len())
                .ok()
                .filter(|b| b.checked_add(nv as u32).is_some() && nv <= u32::MAX as usize)
                .ok_or_else(|| too_many(path))?;
            let prim_normals: Option<Vec<[f32; 3]>> = if wanted.normals {
                prim.get(&gltf::Semantic::Normals)
                    .and_then(|a| {
                        crate::gltf_guard::read_vec3(&gltf.json, buffers, &a, || {
                            reader.read_normals()
                        })
                    })
                    .map(|n| n.into_iter().map(turn).collect())
            } else {
                None
            };
            let indices: Vec<u32> = match reader.read_indices() {
                Some(i) => i.into_u32().collect(),
                None => (0..nv as u32).collect(),
            };
            let has_normals = prim_normals.as_ref().is_some_and(|n| n.len() == nv);
            all_normals &= has_normals;
            for (k, tri) in indices.chunks_exact(3).enumerate() {
                if tri.iter().any(|&i| i as usize >= nv) {
                    return Err(invalid(format!(
                        "meshes[{}].primitives[{}]: triangle {k} index out of bounds",
                        mesh.index(),
                        prim.index()
                    )));
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
            let prim_colours: Option<Vec<[f32; 3]>> = if wanted.colours {
                reader
                    .read_colors(0)
                    .map(|c| c.into_rgb_f32().collect::<Vec<_>>())
                    .filter(|c| c.len() == nv)
            } else {
                None
            };
            match prim_colours {
                Some(c) => {
                    any_colour = true;
                    colours.extend(c.into_iter().map(Some));
                }
                None => colours.extend(std::iter::repeat_n(None, nv)),
            }
            out.positions.extend(pos);
        }
    }
    if wanted.normals && all_normals && normals.len() == 3 * out.triangles.len() {
        out.corner_normals = Some(normals);
    }
    out.colours = any_colour.then_some(colours);
    Ok(out)
}

#[cfg(test)]
mod tests {
    use super::*;

    /// The fast OBJ reader on `text`, checked against `tobj`: where it reads the file it must
    /// give exactly what `tobj` gives (bit for bit); `None` means `tobj` reads it.
    fn fast_obj_agrees(text: &str) -> Option<Triangles> {
        let path = Path::new("t.obj");
        let fast = crate::obj_fast::read(text.as_bytes());
        if let Some(fast) = &fast {
            let slow = read_obj_tobj(path, text.as_bytes())
                .unwrap_or_else(|e| panic!("tobj refuses what the fast reader read: {e}\n{text}"));
            let bits = |t: &Triangles| {
                let p: Vec<[u32; 3]> = t.positions.iter().map(|p| p.map(f32::to_bits)).collect();
                let n: Option<Vec<[u32; 3]>> = t
                    .corner_normals
                    .as_ref()
                    .map(|n| n.iter().map(|n| n.map(f32::to_bits)).collect());
                (p, t.triangles.clone(), n, t.colours.is_some())
            };
            assert_eq!(bits(fast), bits(&slow), "{text}");
        }
        fast
    }

    #[test]
    fn fast_obj_reader_matches_tobj_on_plain_files() {
        let plain = [
            "v 0 0 0\nv 1 0 0\nv 0 1 0\nf 1 2 3\n",
            // Unused and forward-referenced vertices, first-reference order, a quad and a
            // pentagon (fans), comments, blank lines, CRLF, tabs, statements tobj ignores.
            "# c\r\nmtllib m.mtl\no bunny\ns off\n\nv 9 9 9\nf 4 3 2 5\r\nv 0 0 0\nv 1 0 0\n\
             v\t0 1 0 \nv 1e-3 -2.5E2 .5\nv 1 1 1\n f 2 3 4 5 6\n#x\nvp 1 2\n",
            // Normals and texture coordinates (three values, one ignored); extra vn values.
            "v 0 0 0\nv 1 0 0\nv 0 1 0\nv 1 1 0\nvt 0 0 0\nvt 1 0\nvn 0 0 1 7\nvn 0 0.6 0.8\n\
             f 1/1/1 2/2/2 3//1\nf 2//2 4//1 3//2\n",
            // Normals referenced out of order, vt indices ignored without vt lines.
            "vn 1 0 0\nvn 0 1 0\nv 0 0 0\nv 1 0 0\nv 0 1 0\nf 3/9/2 1/5/1 2//2\n",
            "v inf 0 NaN\nv 0 1 0\nv 0 0 1\nf 1/ 2/ 3/\n",
            "g first\nv -0 0 0\nv 1 0 0\nv 0 1 0\nf 001 2 3",
        ];
        for text in plain {
            assert!(fast_obj_agrees(text).is_some(), "{text}");
        }
        // Left to tobj (errors among them, which keep tobj's messages).
        let others = [
            "v 0 0 0\nv 1 0 0\nv 0 1 0\nf -3 -2 -1\n",
            "v 0 0 0\nv 1 0 0\nv 0 1 0\nf 0 1 2\n",
            "v 0 0 0\nv 1 0 0\nv 0 1 0\nf 1 2 3\ng two\nf 1 2 3\n",
            "v 0 0 0\nv 1 0 0\nv 0 1 0\nusemtl red\nf 1 2 3\n",
            "v 0 0 0\nv 1 0 0\nv 0 1 0\nl 1 2 3\nf 1 2 3\n",
            "v 0 0 0 1 0 0\nv 1 0 0 0 1 0\nv 0 1 0 0 0 1\nf 1 2 3\n",
            "v 0 0 0 2\nv 1 0 0\nv 0 1 0\nf 1 2 3\n",
            "v 0 0 0 # origin\nv 1 0 0\nv 0 1 0\nf 1 2 3\n",
            "v 0 0 0\nv 1 0 0\nv 0 1 0\nf 1 2\nf 1 2 3\n",
            "# caf\u{e9}\nv 0 0 0\nv 1 0 0\nv 0 1 0\nf 1 2 3\n",
            "v 0 0 x\nv 1 0 0\nv 0 1 0\nf 1 2 3\n",
            "v 0 0\nv 1 0 0\nv 0 1 0\nf 1 2 3\n",
            "v 0 0 0\nv 1 0 0\nv 0 1 0\nf 1 2 4\n",
            "v 0 0 0\nv 1 0 0\nv 0 1 0\nvn 0 0 1\nf 1//1 2//1 3\n",
            "v 0 0 0\nv 1 0 0\nv 0 1 0\nvn 0 0 1\nf 1//1 2//1 3//2\n",
            "v 0 0 0\nv 1 0 0\nv 0 1 0\nvt 0 0\nf 1/1 2/2 3/1\n",
            "v 0 0 0\nv 1 0 0\nv 0 1 0\nf 1/1/1/1 2 3\n",
            "v 0 0 0\nv 1 0 0\nv 0 1 0\nf +1 2 3\n",
            "v 0 0 0\nv 1 0 0\nv 0 1 0\nf 1 2 99999999999\n",
            "v 0 0 0\nv 1 0 0\n",
            "",
        ];
        for text in others {
            assert!(fast_obj_agrees(text).is_none(), "{text}");
        }
    }

    #[test]
    fn fast_obj_reader_matches_tobj_on_generated_files() {
        // Files from a small grammar of the statements above, valid and not (a fixed LCG:
        // deterministic); every one the fast reader takes must match tobj.
        let mut state = 0x9e37_79b9_u32;
        let mut rand = |n: u32| {
            state = state.wrapping_mul(1_664_525).wrapping_add(1_013_904_223);
            (state >> 8) % n
        };
        let mut taken = 0;
        for _ in 0..3000 {
            let mut text = String::new();
            let (nv, nn, nt) = (3 + rand(6), rand(3), rand(3));
            for _ in 0..nv {
                let c: Vec<String> = (0..3)
                    .map(|_| format!("{}", rand(2000) as f32 / 7.0 - 100.0))
                    .collect();
                text.push_str(&format!("v {}\n", c.join(" ")));
            }
            for _ in 0..nn {
                text.push_str("vn 0 0.6 0.8\n");
            }
            for _ in 0..nt {
                text.push_str("vt 0.5 0.25\n");
            }
            let style = rand(4);
            for _ in 0..1 + rand(4) {
                let corners = 3 + rand(3);
                let mut face = String::from("f");
                for _ in 0..corners {
                    // Mostly in range; now and then one past the end (or 0 for vt, vn).
                    let pick = |r: u32, n: u32| {
                        if r % 16 == 0 {
                            n + 1 - r % 2 * (n + 1)
                        } else {
                            1 + r % n.max(1)
                        }
                    };
                    let v = pick(rand(1 << 16), nv);
                    let vt = pick(rand(1 << 16), nt);
                    let vn = pick(rand(1 << 16), nn);
                    face.push(' ');
                    face.push_str(&v.to_string());
                    match (style + u32::from(rand(24) == 0)) % 4 {
                        0 => {}
                        1 => face.push_str(&format!("/{vt}")),
                        2 => face.push_str(&format!("//{vn}")),
                        _ => face.push_str(&format!("/{vt}/{vn}")),
                    }
                }
                text.push_str(&face);
                text.push_str(["\n", "\r\n", " \n", "\n\n# c\n"][rand(4) as usize]);
            }
            taken += usize::from(fast_obj_agrees(&text).is_some());
        }
        assert!(taken > 500, "{taken}");
    }

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
        let m = load_mesh(&path).unwrap();
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
        let err = load_mesh(&path).unwrap_err().to_string();
        assert!(err.contains("nodes[0] is reached twice"), "{err}");
    }

    #[test]
    fn gltf_without_nodes_has_its_meshes_taken_once_untransformed() {
        let dir = tempfile::tempdir().unwrap();
        let path = gltf_with_nodes(dir.path(), "[]", "[]");
        let text = std::fs::read_to_string(&path)
            .unwrap()
            .replace(r#""scene":0,"scenes":[{"nodes":[]}],"#, "")
            .replace(r#""nodes":[],"#, "");
        std::fs::write(&path, text).unwrap();
        let m = load_mesh(&path).unwrap();
        assert_eq!(
            m.positions,
            vec![[0.0, 0.0, 0.0], [1.0, 0.0, 0.0], [0.0, 1.0, 0.0]]
        );
        assert_eq!(m.triangles, vec![[0, 1, 2]]);
    }
}
