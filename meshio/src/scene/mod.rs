//! Scene input for the baker (`hce bake`, `hce reference`): glTF 2.0 (`.gltf`, `.glb`) and
//! Wavefront OBJ with MTL, read into one flat list of objects (one per node instance and
//! triangle primitive), materials, punctual lights and the camera, in a deterministic order.
//! glTF goes through the guards of [`crate::gltf_guard`] and the node walk of
//! [`crate::scene_graph`], as every glTF reader of hce does; [`ToSolver`] turns the result into
//! the solver's world-space [`Scene`](crate::solver_scene::Scene).
//!
//! Unsupported content (points, lines, non-triangle primitives, missing buffers, unknown
//! extensions) becomes a warning naming it; only a file that cannot be read at all, or a scene
//! with nothing to light it, is an error.

mod gltf;
mod inputs;
mod obj;
mod solver;
mod texture;

pub use crate::solver_scene::{LightKind, PunctualLight};
pub use inputs::{input_files, InputFile};
pub use solver::ToSolver;
pub use texture::{srgb_to_linear, Texture, WrapMode};

use glam::Mat4;
use std::path::{Path, PathBuf};
use std::sync::{Arc, LazyLock};

/// What to import and how to classify it.
#[derive(Clone, Debug, Default)]
pub struct ImportOptions {
    /// `--multires PATTERN` values, matched against node and mesh names (and, for OBJ, object
    /// and group names). `*` matches any run of characters, `?` one character; the pattern
    /// `all` makes every object multiresolution. Objects whose node extras hold
    /// `{"hce": {"multires": true}}` are multiresolution whatever the patterns.
    pub multires: Vec<String>,
}

impl ImportOptions {
    /// Whether an object with these names is selected by the `--multires` patterns.
    pub fn selects(&self, names: &[Option<&str>]) -> bool {
        self.multires.iter().any(|p| {
            p == "all"
                || names
                    .iter()
                    .flatten()
                    .any(|n| glob_match(p.as_bytes(), n.as_bytes()))
        })
    }
}

/// Shell-style matching of the whole name: `*` any run (possibly empty), `?` any one byte.
pub fn glob_match(pattern: &[u8], name: &[u8]) -> bool {
    // Iterative with one backtrack point: linear in practice, never exponential.
    let (mut p, mut n) = (0, 0);
    let mut star: Option<(usize, usize)> = None;
    while n < name.len() {
        match pattern.get(p) {
            Some(b'*') => {
                star = Some((p, n));
                p += 1;
            }
            Some(&c) if c == b'?' || c == name[n] => {
                p += 1;
                n += 1;
            }
            _ => match star {
                Some((sp, sn)) => {
                    p = sp + 1;
                    n = sn + 1;
                    star = Some((sp, sn + 1));
                }
                None => return false,
            },
        }
    }
    pattern[p.min(pattern.len())..].iter().all(|&c| c == b'*')
}

/// Why a scene cannot be imported: meshio's one reader error.
pub use crate::import::ImportError;

/// The file format a scene was read from.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum SourceFormat {
    Gltf,
    Glb,
    Obj,
}

/// One imported object: one triangle primitive of one mesh as placed by one node, in the form the
/// output writer needs (glTF indices, object-space data); the solver's view of it is a
/// [`crate::scene::SolverObject`].
#[derive(Clone, Debug)]
pub struct ImportedObject {
    /// The node's name (else the mesh's, else `node<N>`), with `#<primitive>` appended when
    /// the mesh has several primitives; stable across runs, not necessarily unique.
    pub name: String,
    /// glTF node index (`None` for OBJ).
    pub node: Option<usize>,
    pub node_name: Option<String>,
    /// glTF mesh index, or the OBJ model index.
    pub mesh: usize,
    pub mesh_name: Option<String>,
    /// Primitive index within the mesh (0 for OBJ).
    pub primitive: usize,
    /// Object space to world space (the node's global transform; identity for OBJ).
    pub transform: Mat4,
    /// Object-space positions as read (POSITION), one per vertex.
    pub positions: Vec<[f32; 3]>,
    /// Object-space normals as read (NORMAL), one per vertex, if the primitive has them.
    pub normals: Option<Vec<[f32; 3]>>,
    /// TEXCOORD_0 (OBJ `vt` with v flipped to glTF's top-left origin), if present.
    pub uv0: Option<Vec<[f32; 2]>>,
    /// Triangle corner indices as read (or `0..n` for a non-indexed primitive).
    pub indices: Vec<u32>,
    /// Positions transformed to world space.
    pub world_positions: Vec<[f32; 3]>,
    /// Index into [`ImportedScene::materials`]; `None` uses [`Material::default`].
    pub material: Option<usize>,
    /// Loop-subdivided at render time (`true`) or flat.
    pub multires: bool,
}

impl ImportedObject {
    pub fn triangle_count(&self) -> usize {
        self.indices.len() / 3
    }

    pub fn vertex_count(&self) -> usize {
        self.positions.len()
    }

    /// The geometry hash of SPEC.md 2.5: object-space positions read through the indices.
    pub fn geometry_hash(&self) -> u64 {
        hce_format::geometry_hash(self.indices.iter().map(|&i| self.positions[i as usize]))
    }

    /// UVs of triangle `t`'s corners, if the object has TEXCOORD_0.
    pub fn triangle_uvs(&self, t: usize) -> Option<[[f32; 2]; 3]> {
        let uv = self.uv0.as_ref()?;
        let i = &self.indices[3 * t..3 * t + 3];
        Some([0, 1, 2].map(|c| uv[i[c] as usize]))
    }

    /// Vertex normals in world space (through the inverse transpose of the transform,
    /// renormalised), if the object has normals; a normal that degenerates stays zero.
    pub fn world_normals(&self) -> Option<Vec<[f32; 3]>> {
        let m = glam::Mat3::from_mat4(self.transform).inverse().transpose();
        let n = self.normals.as_ref()?;
        Some(
            n.iter()
                .map(|&v| (m * glam::Vec3::from(v)).normalize_or_zero().to_array())
                .collect(),
        )
    }

    /// Whether the transform mirrors space (negative determinant), which flips the winding.
    pub fn mirrored(&self) -> bool {
        self.transform.determinant() < 0.0
    }
}

/// A diffuse material.
#[derive(Clone, Debug)]
pub struct Material {
    pub name: Option<String>,
    /// Linear RGB diffuse reflectance factor (glTF baseColorFactor, MTL Kd).
    pub base_color: [f32; 3],
    /// Base colour texture (sRGB decoded to linear), multiplied with `base_color`.
    pub base_color_texture: Option<Arc<Texture>>,
    /// Linear RGB emission: emissiveFactor × KHR_materials_emissive_strength (MTL Ke).
    pub emission: [f32; 3],
    pub double_sided: bool,
}

impl Default for Material {
    /// glTF's default material: white, not emissive, single-sided.
    fn default() -> Self {
        Self {
            name: None,
            base_color: [1.0; 3],
            base_color_texture: None,
            emission: [0.0; 3],
            double_sided: false,
        }
    }
}

impl Material {
    /// The diffuse reflectance averaged over a triangle given by its UV corners: the factor
    /// times the texture's average over the triangle (the factor alone without texture or UVs).
    pub fn reflectance_over(&self, uv: Option<[[f32; 2]; 3]>) -> [f32; 3] {
        match (&self.base_color_texture, uv) {
            (Some(tex), Some(uv)) => {
                let a = tex.average_over_triangle(uv);
                [0, 1, 2].map(|c| self.base_color[c] * a[c])
            }
            _ => self.base_color,
        }
    }

    pub fn is_emissive(&self) -> bool {
        self.emission.iter().any(|&e| e > 0.0)
    }
}

/// The projection of a camera.
#[derive(Clone, Copy, Debug, PartialEq)]
pub enum Projection {
    Perspective {
        yfov: f32,
        aspect_ratio: Option<f32>,
        znear: f32,
        zfar: Option<f32>,
    },
    Orthographic {
        xmag: f32,
        ymag: f32,
        znear: f32,
        zfar: f32,
    },
}

/// The first camera found in the scene, in node order.
#[derive(Clone, Debug)]
pub struct SceneCamera {
    pub node: usize,
    pub name: Option<String>,
    /// Camera to world (the camera looks along its local -Z, Y up).
    pub transform: Mat4,
    pub projection: Projection,
}

/// Everything the baker needs from a scene file.
#[derive(Clone, Debug)]
pub struct ImportedScene {
    pub path: PathBuf,
    pub format: SourceFormat,
    pub objects: Vec<ImportedObject>,
    pub materials: Vec<Material>,
    pub lights: Vec<PunctualLight>,
    pub camera: Option<SceneCamera>,
    /// Content that was skipped or approximated, each naming the thing.
    pub warnings: Vec<String>,
    /// One paragraph saying what was read, with units.
    pub summary: String,
}

impl ImportedScene {
    /// The material of an object (the glTF default material when it has none).
    pub fn material_of(&self, object: &ImportedObject) -> &Material {
        static DEFAULT: LazyLock<Material> = LazyLock::new(Material::default);
        object
            .material
            .and_then(|m| self.materials.get(m))
            .unwrap_or(&DEFAULT)
    }

    pub fn triangle_count(&self) -> usize {
        self.objects
            .iter()
            .map(ImportedObject::triangle_count)
            .sum()
    }

    /// The geometry hash of the whole scene: every object's world-space corners in object order.
    pub fn source_hash(&self) -> u64 {
        hce_format::geometry_hash(
            self.objects
                .iter()
                .flat_map(|o| o.indices.iter().map(|&i| o.world_positions[i as usize])),
        )
    }
}

/// Reads a scene, choosing the reader from the file extension (`.gltf`, `.glb`, `.obj`).
pub fn import_scene(path: &Path, options: &ImportOptions) -> Result<ImportedScene, ImportError> {
    let ext = path
        .extension()
        .and_then(|e| e.to_str())
        .map(str::to_ascii_lowercase);
    let scene = match ext.as_deref() {
        Some("gltf") | Some("glb") => gltf::import(path, options)?,
        Some("obj") => obj::import(path, options)?,
        _ => {
            return Err(ImportError::UnknownFormat {
                path: path.to_path_buf(),
            })
        }
    };
    finish(scene, options)
}

/// A scene file held in memory, for [`import_scene_bytes`].
#[derive(Clone, Copy, Debug)]
pub enum SceneBytes<'a> {
    /// A `.glb` or `.gltf` (JSON) file. Buffers and images are read from the file itself or
    /// from `data:` URIs; external files are not followed (a warning each).
    Gltf(&'a [u8]),
    /// An OBJ file and the MTL library it names, if any (whatever name `mtllib` gives resolves
    /// to these bytes); `map_Kd` textures are not read (a warning each).
    Obj {
        obj: &'a [u8],
        mtl: Option<&'a [u8]>,
    },
}

/// Reads a scene from memory: the same reader, checks and warnings as [`import_scene`], with
/// no file system access. Messages name the input `<memory>.glb`/`.gltf`/`.obj`.
pub fn import_scene_bytes(
    bytes: SceneBytes<'_>,
    options: &ImportOptions,
) -> Result<ImportedScene, ImportError> {
    let scene = match bytes {
        SceneBytes::Gltf(b) => {
            let name = if b.starts_with(b"glTF") {
                "<memory>.glb"
            } else {
                "<memory>.gltf"
            };
            gltf::import_bytes(Path::new(name), None, b, options)?
        }
        SceneBytes::Obj { obj, mtl } => {
            obj::import_bytes(Path::new("<memory>.obj"), obj, mtl, options)?
        }
    };
    finish(scene, options)
}

/// The checks every imported scene goes through: something to bake, something to light it.
fn finish(mut scene: ImportedScene, options: &ImportOptions) -> Result<ImportedScene, ImportError> {
    let path = scene.path.clone();
    let path = path.as_path();
    if scene.objects.is_empty() {
        return Err(ImportError::NoTriangles {
            path: path.to_path_buf(),
            warnings: scene.warnings,
        });
    }
    let emissive_used = scene
        .objects
        .iter()
        .any(|o| scene.material_of(o).is_emissive());
    let light_emits = scene
        .lights
        .iter()
        .any(|l| l.intensity > 0.0 && l.color.iter().any(|&c| c > 0.0));
    if !emissive_used && !light_emits {
        return Err(ImportError::NoLightSource {
            path: path.to_path_buf(),
        });
    }
    for p in &options.multires {
        if p != "all"
            && !scene.objects.iter().any(|o| {
                [o.node_name.as_deref(), o.mesh_name.as_deref()]
                    .iter()
                    .flatten()
                    .any(|n| glob_match(p.as_bytes(), n.as_bytes()))
            })
        {
            scene
                .warnings
                .push(format!("--multires {p:?} matches no node or mesh name"));
        }
    }
    scene.summary = summarise(&scene);
    Ok(scene)
}

fn summarise(s: &ImportedScene) -> String {
    let multires = s.objects.iter().filter(|o| o.multires).count();
    let emissive = s
        .objects
        .iter()
        .filter(|o| s.material_of(o).is_emissive())
        .count();
    let textured = s
        .materials
        .iter()
        .filter(|m| m.base_color_texture.is_some())
        .count();
    let units = match s.format {
        SourceFormat::Gltf | SourceFormat::Glb => {
            "glTF units: metres, node transforms applied, Y up"
        }
        SourceFormat::Obj => "OBJ has no units: assumed metres, no transform applied",
    };
    let kind = match s.format {
        SourceFormat::Gltf => "glTF 2.0 (JSON)",
        SourceFormat::Glb => "glTF 2.0 (GLB)",
        SourceFormat::Obj => "Wavefront OBJ",
    };
    let camera = match &s.camera {
        Some(c) => format!("camera {:?}", c.name.as_deref().unwrap_or("(unnamed)")),
        None => "no camera".into(),
    };
    format!(
        "Read {} ({kind}): {} objects ({multires} multiresolution, {} flat), {} triangles, \
         {} materials ({textured} textured), {emissive} emissive objects, {} punctual lights, \
         {camera}; {units}; {} warnings.",
        s.path.display(),
        s.objects.len(),
        s.objects.len() - multires,
        s.triangle_count(),
        s.materials.len(),
        s.lights.len(),
        s.warnings.len()
    )
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn glob_matches_whole_names() {
        assert!(glob_match(b"teapot", b"teapot"));
        assert!(!glob_match(b"teapot", b"teapot2"));
        assert!(glob_match(b"king_*", b"king_white"));
        assert!(!glob_match(b"king_*", b"queen_white"));
        assert!(glob_match(b"*_white", b"queen_white"));
        assert!(glob_match(b"q?een*", b"queen_black"));
        assert!(glob_match(b"*a*b*", b"xxaxxbxx"));
        assert!(!glob_match(b"*a*b", b"xxaxxbxx"));
        assert!(glob_match(b"*", b""));
        assert!(!glob_match(b"?", b""));
    }

    #[test]
    fn all_selects_everything_and_patterns_use_either_name() {
        let o = ImportOptions {
            multires: vec!["cup*".into()],
        };
        assert!(o.selects(&[Some("node"), Some("cup_mesh")]));
        assert!(!o.selects(&[Some("node"), None]));
        let all = ImportOptions {
            multires: vec!["all".into()],
        };
        assert!(all.selects(&[None, None]));
    }
}
