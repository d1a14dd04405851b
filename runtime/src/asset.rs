//! Baked assets: open a `.glb` / `.gltf` that carries `EXT_hce_baked_lighting`, or a bare `.hce`
//! container, check everything a refinement kernel will index, and expose the objects with their
//! instances (glTF node world transforms), bounds and the scene's camera.
//!
//! This module has no GPU dependency (it builds with `--no-default-features`); the GPU resources
//! of a loaded asset are [`crate::gpu::GpuScene`]'s business.
//!
//! # What is checked
//!
//! * The container, byte for byte (SPEC.md Appendix A, checksums and padding included), then
//!   every content rule of Appendix C through [`hce_format::validate_bytes`]: indices, adjacency tables, record ranges
//!   into `NRML`/`COLR`, trees inside the bitstream and at most 12 deep. A kernel that reads a
//!   validated object cannot index out of bounds.
//! * Each object's geometry hash (SPEC.md 2.5) against its control mesh (`POSN` through `TRIS`),
//!   and, for glTF, that each linked primitive has the same geometry as its object's triangle
//!   range (SPEC.md 2.6: its hash, or else its triangles paired with the range's, so optimised
//!   files still load); each primitive's triangle range inside its object, ranges not
//!   overlapping. An object is drawn where its primitive is: the node's transform times the
//!   inverse of the primitive's placement (the dequantization a quantizer moved into the node).
//! * The glTF scene graph: node and mesh indices in range, finite transforms, camera
//!   parameters.
//!
//! With [`OpenOptions::strict`] (the default) any of these problems is an error. Without it,
//! problems with single primitives follow SPEC.md 3.5: the primitive's link is ignored, with a
//! warning in [`Asset::warnings`], and the rest of the asset loads.
//!
//! # Where the mesh of a `.hce` file comes from
//!
//! A bare container is self-contained: each object's control mesh (`POSN`, `TRIS`) *is* the mesh
//! that was baked (its geometry hash is checked against it), so nothing else is looked up. A
//! container carries no scene graph, so each object gets one instance with the identity
//! transform: the objects appear in their own object spaces, which is the scene's layout only
//! when the baked scene had no node transforms. Bake to `.glb` to keep instances and cameras.
//!
//! # Instances
//!
//! The scene is walked by `hce_meshio::scene_graph::walk`, the walk `hce bake` places meshes
//! with (the default scene, else the first, else every node without a parent; depth first in
//! child order; the same world transforms to the bit; a node reached twice is walked once, with
//! a warning). Every node whose mesh has a primitive linked to object `k` adds one [`Instance`]
//! of object `k` with the node's world transform (several primitives of one mesh that share an
//! object add it once). `hce bake` copies meshes per node, so each of its objects has exactly
//! one instance.
//!
//! # Where the container is
//!
//! [`GltfSource`] is the one way hce finds a baked container in a glTF or GLB: the JSON and
//! every buffer (external files through [`buffer_files`]: inside the asset's folder, regular
//! files, each once), then the buffer view the root extension names. `hce inspect` and
//! `hce subdivide` use it too.
//!
//! # Memory
//!
//! Files of [`MMAP_THRESHOLD`] bytes or more are memory-mapped rather than read, so that opening
//! a large asset does not first copy it whole into the heap; the container's arrays are then
//! copied once into [`Object`]s, the form the kernels upload.

use std::collections::{HashMap, HashSet};
use std::path::{Path, PathBuf};

use glam::{Mat4, Vec3};
use hce_format::{GltfError, LinkFault, LinkNext, PrimitiveLink};
use hce_format::{Metadata, Object, ObjectKind, Problem, ReadError};
use hce_meshio::gltf_guard::{self, UriScope};
use hce_meshio::scene_graph;
use serde_json::Value;

/// Files at least this large (16 MiB) are memory-mapped instead of read into memory.
pub const MMAP_THRESHOLD: u64 = 16 << 20;

/// Problems listed in an [`AssetError::Invalid`] message before the rest are only counted.
const PROBLEMS_SHOWN: usize = 5;

/// Why an asset cannot be opened. Every message names the file and the part of it at fault, and
/// carries the underlying error's text itself (no `source` chain to print twice).
#[derive(Debug, thiserror::Error)]
pub enum AssetError {
    #[error("{path}: {error}")]
    Io { path: String, error: std::io::Error },
    #[error("{path}: not a baked asset: expected a .glb or .gltf with {ext} or a .hce container", ext = hce_format::EXTENSION_NAME)]
    UnknownFormat { path: String },
    #[error("{path}: {error}")]
    Gltf { path: String, error: GltfError },
    #[error("{path}: the asset does not use {ext}; bake it with `hce bake` first", ext = hce_format::EXTENSION_NAME)]
    NotBaked { path: String },
    #[error("{path}: container: {error}")]
    Container { path: String, error: ReadError },
    #[error("{path}: the container fails validation with {} problem(s): {}; run `hce validate` for the full list",
        problems.len(), summary(problems))]
    Invalid {
        path: String,
        problems: Vec<Problem>,
    },
    #[error("{path}: {location}: {message}")]
    Link {
        path: String,
        location: String,
        message: String,
    },
    #[error("{path}: {location} (object {object} '{name}'): geometry hash {computed:016x} differs from the baked {stored:016x}: the mesh was edited after baking; bake it again (SPEC.md 3.5)")]
    StaleGeometry {
        path: String,
        location: String,
        object: u32,
        name: String,
        stored: u64,
        computed: u64,
    },
    #[error("{path}: {location}: {message}")]
    Scene {
        path: String,
        location: String,
        message: String,
    },
}

fn summary(problems: &[Problem]) -> String {
    let mut s = problems
        .iter()
        .take(PROBLEMS_SHOWN)
        .map(ToString::to_string)
        .collect::<Vec<_>>()
        .join("; ");
    if problems.len() > PROBLEMS_SHOWN {
        s.push_str(&format!("; and {} more", problems.len() - PROBLEMS_SHOWN));
    }
    s
}

/// Options of [`Asset::open_with`].
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub struct OpenOptions {
    /// Reject the asset on any bad primitive link or geometry-hash mismatch (default `true`).
    /// When `false`, such primitives are ignored with a warning, as SPEC.md 3.5 allows, and
    /// objects left without a primitive get no instance.
    pub strict: bool,
}

impl Default for OpenOptions {
    fn default() -> Self {
        Self { strict: true }
    }
}

/// The kind of file an asset came from.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum AssetFormat {
    Glb,
    Gltf,
    Hce,
}

impl AssetFormat {
    /// The format of a file's bytes: from its first bytes (GLB and container identifiers),
    /// else from `path`'s extension (`.gltf` JSON; `.hce`, whose reader then says what is wrong
    /// with the identifier). `None` for anything else.
    pub fn detect(path: &Path, bytes: &[u8]) -> Option<AssetFormat> {
        let extension_is = |ext: &str| {
            path.extension()
                .is_some_and(|e| e.eq_ignore_ascii_case(ext))
        };
        if bytes.starts_with(b"glTF") {
            Some(AssetFormat::Glb)
        } else if bytes.starts_with(HCE_IDENTIFIER) {
            Some(AssetFormat::Hce)
        } else if extension_is("gltf") || bytes.first() == Some(&b'{') {
            Some(AssetFormat::Gltf)
        } else if extension_is("hce") {
            Some(AssetFormat::Hce)
        } else {
            None
        }
    }
}

/// An axis-aligned box.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Bounds {
    pub min: [f32; 3],
    pub max: [f32; 3],
}

impl Bounds {
    /// The box around `x, y, z` triples; `None` when there are none.
    pub fn of_points(points: impl IntoIterator<Item = [f32; 3]>) -> Option<Self> {
        let mut out: Option<Bounds> = None;
        for p in points {
            let b = out.get_or_insert(Bounds { min: p, max: p });
            for (k, &c) in p.iter().enumerate() {
                b.min[k] = b.min[k].min(c);
                b.max[k] = b.max[k].max(c);
            }
        }
        out
    }

    pub fn union(self, other: Bounds) -> Bounds {
        Bounds {
            min: std::array::from_fn(|k| self.min[k].min(other.min[k])),
            max: std::array::from_fn(|k| self.max[k].max(other.max[k])),
        }
    }

    /// The box around this one's eight corners carried by `m`.
    pub fn transformed(&self, m: &Mat4) -> Bounds {
        let corners = (0..8).map(|i| {
            let p = Vec3::new(
                if i & 1 == 0 { self.min[0] } else { self.max[0] },
                if i & 2 == 0 { self.min[1] } else { self.max[1] },
                if i & 4 == 0 { self.min[2] } else { self.max[2] },
            );
            m.transform_point3(p).to_array()
        });
        // Eight corners: never empty.
        Bounds::of_points(corners).unwrap_or(*self)
    }

    pub fn centre(&self) -> [f32; 3] {
        std::array::from_fn(|k| 0.5 * (self.min[k] + self.max[k]))
    }

    /// Half the diagonal: the radius of the bounding sphere around [`Bounds::centre`].
    pub fn radius(&self) -> f32 {
        0.5 * (Vec3::from(self.max) - Vec3::from(self.min)).length()
    }
}

/// One placement of an object in the scene.
#[derive(Clone, Debug, PartialEq)]
pub struct Instance {
    /// The glTF node, `None` for a `.hce` file.
    pub node: Option<usize>,
    /// The node's name, or the object's for a `.hce` file.
    pub name: String,
    /// Object space (the control mesh's) to world.
    pub transform: Mat4,
}

/// A container object with where it is drawn.
#[derive(Clone, Debug, PartialEq)]
pub struct AssetObject {
    /// Index in the container's object table.
    pub index: u32,
    /// The validated object: control mesh, adjacency tables, trees, normals, colours.
    pub object: Object,
    /// Empty when no node of the scene uses the object (it is then not drawn).
    pub instances: Vec<Instance>,
    /// Bounds of the control points in object space. Loop subdivision keeps the surface inside
    /// the control points' convex hull, so they bound every level.
    pub bounds: Bounds,
    /// Mean length of the control triangles' edges in object space (for level of detail).
    pub mean_edge_length: f32,
    /// Depth of the deepest HCE tree: the level at which every element has its own triangles.
    pub tree_depth: u32,
}

impl AssetObject {
    pub fn name(&self) -> &str {
        &self.object.name
    }

    pub fn kind(&self) -> ObjectKind {
        self.object.kind
    }

    /// Bounds of every instance in world space; `None` without instances.
    pub fn world_bounds(&self) -> Option<Bounds> {
        self.instances
            .iter()
            .map(|i| self.bounds.transformed(&i.transform))
            .reduce(Bounds::union)
    }
}

/// The scene's perspective camera (glTF: the first camera node met in the walk of the scene).
/// The camera looks along its local −Z with +Y up.
#[derive(Clone, Debug, PartialEq)]
pub struct SceneCamera {
    pub node: usize,
    pub name: String,
    pub eye: [f32; 3],
    /// Unit view direction.
    pub forward: [f32; 3],
    /// Unit up direction (perpendicular to `forward`).
    pub up: [f32; 3],
    /// Vertical field of view in degrees.
    pub fov_y_degrees: f32,
    /// The aspect ratio the camera was authored for, when the file says.
    pub aspect_ratio: Option<f32>,
}

/// A loaded, validated baked asset.
#[derive(Clone, Debug, PartialEq)]
pub struct Asset {
    /// The file it came from, as given to [`Asset::open`].
    pub path: PathBuf,
    pub format: AssetFormat,
    pub metadata: Metadata,
    /// Every container object, in container order.
    pub objects: Vec<AssetObject>,
    pub camera: Option<SceneCamera>,
    /// Parts of the file that were skipped, each naming the part and why.
    pub warnings: Vec<String>,
}

/// The bytes of a file: read, or mapped when large.
enum FileBytes {
    Read(Vec<u8>),
    Mapped(memmap2::Mmap),
}

impl std::ops::Deref for FileBytes {
    type Target = [u8];
    fn deref(&self) -> &[u8] {
        match self {
            FileBytes::Read(v) => v,
            FileBytes::Mapped(m) => m,
        }
    }
}

fn read_file(path: &Path) -> Result<FileBytes, std::io::Error> {
    let file = std::fs::File::open(path)?;
    let len = file.metadata()?.len();
    if len >= MMAP_THRESHOLD {
        // Large files are mapped rather than read (see `crate::mmap` for the safety argument).
        let map = crate::mmap::map_read_only(&file)?;
        Ok(FileBytes::Mapped(map))
    } else {
        let mut v = Vec::with_capacity(len as usize);
        std::io::Read::read_to_end(&mut std::io::BufReader::new(file), &mut v)?;
        Ok(FileBytes::Read(v))
    }
}

const HCE_IDENTIFIER: &[u8; 4] = b"\x89HCE";

/// A glTF or GLB asset's JSON and buffers: where hce finds a baked container. Asset loading,
/// `hce inspect` and `hce subdivide` all go through it.
#[derive(Clone, Debug, PartialEq)]
pub struct GltfSource {
    /// Whether it came from a GLB (else a `.gltf`).
    pub glb: bool,
    pub json: Value,
    /// Every buffer, in `buffers` order.
    pub buffers: Vec<Vec<u8>>,
}

impl GltfSource {
    /// The format it was read from.
    pub fn format(&self) -> AssetFormat {
        if self.glb {
            AssetFormat::Glb
        } else {
            AssetFormat::Gltf
        }
    }

    /// Parses a `.gltf` or `.glb` and loads its buffers: the GLB's BIN chunk, `data:` URIs, and
    /// other URIs through `resolve` ([`buffer_files`] for files beside it).
    pub fn parse(
        bytes: &[u8],
        resolve: impl FnMut(&str) -> Result<Vec<u8>, String>,
    ) -> Result<Self, GltfError> {
        let glb = bytes.starts_with(b"glTF");
        Self::load(hce_format::GltfAsset::parse(bytes)?, glb, resolve)
    }

    fn load(
        asset: hce_format::GltfAsset,
        glb: bool,
        resolve: impl FnMut(&str) -> Result<Vec<u8>, String>,
    ) -> Result<Self, GltfError> {
        let buffers = asset.buffers(resolve)?;
        let mut json = asset.json;
        // Every instance of an EXT_mesh_gpu_instancing node drawn as a node of its own, with
        // the node's object (the bake placed the one primitive; its instances share its light).
        hce_meshio::gpu_instancing::expand(&mut json, &buffers).map_err(GltfError::Json)?;
        Ok(Self { glb, json, buffers })
    }

    /// Reads a `.gltf` or `.glb` file that uses the extension, with its buffers (external ones
    /// through [`buffer_files`]); `None`, without loading any buffer, when it does not use it.
    pub fn open_baked(path: &Path) -> Result<Option<Self>, AssetError> {
        let shown = || path.display().to_string();
        let gltf_err = |error| AssetError::Gltf {
            path: shown(),
            error,
        };
        let bytes = read_file(path).map_err(|error| AssetError::Io {
            path: shown(),
            error,
        })?;
        let asset = hce_format::GltfAsset::parse(&bytes).map_err(gltf_err)?;
        if hce_format::root_link(&asset.json)
            .map_err(gltf_err)?
            .is_none()
        {
            return Ok(None);
        }
        let dir = path.parent().map(Path::to_path_buf).unwrap_or_default();
        Self::load(asset, bytes.starts_with(b"glTF"), buffer_files(&dir))
            .map(Some)
            .map_err(gltf_err)
    }

    /// The container bytes: the buffer view the root `EXT_hce_baked_lighting` object names
    /// (SPEC.md 3.2), checked to lie inside its buffer; `None` when the asset does not use the
    /// extension.
    pub fn container(&self) -> Result<Option<&[u8]>, GltfError> {
        hce_format::container_bytes(&self.json, &self.buffers)
    }
}

/// Loads the external buffer files of an asset in `dir`: URIs relative to it, percent-decoded,
/// inside the folder only (`hce_meshio::gltf_guard::UriScope::Folder`: a baked asset may come
/// from anywhere), regular files only, and each file once, so that many buffers naming one big
/// file do not multiply memory.
pub fn buffer_files(dir: &Path) -> impl FnMut(&str) -> Result<Vec<u8>, String> {
    let dir = dir.to_path_buf();
    let mut seen = HashSet::new();
    move |uri| {
        let file = gltf_guard::uri_path(&dir, uri, UriScope::Folder)?;
        let key = std::fs::canonicalize(&file).unwrap_or_else(|_| file.clone());
        if !seen.insert(key) {
            return Err(
                "another buffer already uses this file; each buffer file is loaded once".into(),
            );
        }
        gltf_guard::read_regular_file(&file)
    }
}

impl Asset {
    /// Opens a `.glb`, `.gltf` or `.hce` file with the default (strict) options.
    pub fn open(path: impl AsRef<Path>) -> Result<Self, AssetError> {
        Self::open_with(path, &OpenOptions::default())
    }

    /// Opens a `.glb`, `.gltf` or `.hce` file. The format is recognised from the first bytes
    /// (GLB and container identifiers), else from the extension (`.gltf` JSON). External
    /// buffers of a `.gltf` are read from its folder (plain relative names only).
    pub fn open_with(path: impl AsRef<Path>, options: &OpenOptions) -> Result<Self, AssetError> {
        let path = path.as_ref();
        let shown = path.display().to_string();
        let bytes = read_file(path).map_err(|error| AssetError::Io {
            path: shown.clone(),
            error,
        })?;
        let dir = path.parent().map(Path::to_path_buf).unwrap_or_default();
        let format =
            AssetFormat::detect(path, &bytes).ok_or(AssetError::UnknownFormat { path: shown })?;
        Self::from_bytes(path, format, &bytes, buffer_files(&dir), options)
    }

    /// Builds an asset from bytes already in memory; `resolve` loads a `.gltf`'s external
    /// buffers by URI ([`buffer_files`] for files beside it). `path` only names the asset in
    /// messages.
    pub fn from_bytes(
        path: &Path,
        format: AssetFormat,
        bytes: &[u8],
        resolve: impl FnMut(&str) -> Result<Vec<u8>, String>,
        options: &OpenOptions,
    ) -> Result<Self, AssetError> {
        match format {
            AssetFormat::Hce => {
                let loader = Loader::new(path, options);
                let container = loader.container(bytes)?;
                let objects = container
                    .objects
                    .into_iter()
                    .enumerate()
                    .map(|(i, object)| {
                        let name = object.name.clone();
                        loader.finish_object(
                            i as u32,
                            object,
                            vec![Instance {
                                node: None,
                                name,
                                transform: Mat4::IDENTITY,
                            }],
                        )
                    })
                    .collect::<Result<Vec<_>, _>>()?;
                Ok(Asset {
                    path: path.to_path_buf(),
                    format,
                    metadata: container.metadata,
                    objects,
                    camera: None,
                    warnings: loader.warnings,
                })
            }
            AssetFormat::Glb | AssetFormat::Gltf => {
                let source =
                    GltfSource::parse(bytes, resolve).map_err(|error| AssetError::Gltf {
                        path: path.display().to_string(),
                        error,
                    })?;
                Self::from_gltf(path, &source, options)
            }
        }
    }

    /// Builds an asset from a glTF or GLB already parsed with its buffers (for a caller that
    /// also needs them, as `hce subdivide` does to write the refined scene).
    pub fn from_gltf(
        path: &Path,
        source: &GltfSource,
        options: &OpenOptions,
    ) -> Result<Self, AssetError> {
        let mut loader = Loader::new(path, options);
        let (metadata, objects, camera) = loader.gltf(source)?;
        Ok(Asset {
            path: path.to_path_buf(),
            format: source.format(),
            metadata,
            objects,
            camera,
            warnings: loader.warnings,
        })
    }

    /// What can be drawn of a glTF that does not use the extension ([`AssetError::NotBaked`]),
    /// for a viewer that would rather show it than nothing: its scene as one flat object in
    /// world space, one colour per triangle from its `COLOR_0` (the fallback `hce bake` writes,
    /// SPEC.md F.9, which optimisers keep when they drop the extension) or, without `COLOR_0`,
    /// a grey preview light ([`crate::plain::gltf_plain_mesh`],
    /// [`crate::plain::to_flat_object`]). Its first warning says that the file has no baked
    /// lighting and what is drawn instead.
    pub fn plain_preview(path: &Path, source: &GltfSource) -> Result<Self, AssetError> {
        let loader = Loader::new(path, &OpenOptions::default());
        let walk = scene_graph::walk(&source.json).map_err(|e| AssetError::Scene {
            path: loader.path.clone(),
            location: e.location,
            message: e.message,
        })?;
        let mut skipped = Vec::new();
        let mesh =
            crate::plain::gltf_plain_mesh(&source.json, &source.buffers, &walk, &mut skipped)
                .map_err(|e| loader.gltf_err(e))?;
        let name = path
            .file_stem()
            .map(|s| s.to_string_lossy().into_owned())
            .unwrap_or_default();
        let (object, _) = crate::plain::to_flat_object(&name, &mesh);
        if object.triangles.is_empty() {
            return Err(AssetError::NotBaked {
                path: loader.path.clone(),
            });
        }
        let drawn = if mesh.colours.is_some() {
            "drawn with its COLOR_0 vertex colours (one colour per triangle), not baked light"
        } else {
            "drawn in a grey preview light: it has no COLOR_0 either"
        };
        let mut warnings = vec![format!(
            "no baked lighting: the file does not use {} (it was never baked, or a tool that \
             does not know the extension dropped it: see the README, \"Optimising baked \
             files\"); {drawn}",
            hce_format::EXTENSION_NAME
        )];
        warnings.extend(walk.repeated_warnings());
        warnings.extend(skipped);
        let instance = Instance {
            node: None,
            name: name.clone(),
            transform: Mat4::IDENTITY,
        };
        let object = loader.finish_object(0, object, vec![instance])?;
        Ok(Asset {
            path: path.to_path_buf(),
            format: source.format(),
            metadata: Metadata {
                generator: source
                    .json
                    .pointer("/asset/generator")
                    .and_then(Value::as_str)
                    .unwrap_or_default()
                    .to_owned(),
                ..Metadata::default()
            },
            objects: vec![object],
            camera: None,
            warnings,
        })
    }

    /// World bounds of every instance of every object; `None` when nothing is drawn.
    pub fn bounds(&self) -> Option<Bounds> {
        self.objects
            .iter()
            .filter_map(AssetObject::world_bounds)
            .reduce(Bounds::union)
    }

    /// Number of (object, instance) pairs: the draws of one frame.
    pub fn instance_count(&self) -> usize {
        self.objects.iter().map(|o| o.instances.len()).sum()
    }

    /// Every control triangle of every instance, in world space (coarse geometry, e.g. for
    /// placing a camera).
    pub fn world_triangles(&self) -> Vec<[[f32; 3]; 3]> {
        let mut out = Vec::new();
        for o in &self.objects {
            let m = &o.object.mesh;
            for inst in &o.instances {
                for t in 0..m.triangle_count() {
                    let tri = m.triangle(t);
                    out.push(tri.map(|v| {
                        inst.transform
                            .transform_point3(Vec3::from(m.position(v)))
                            .to_array()
                    }));
                }
            }
        }
        out
    }
}

/// Opening state: the file name for messages, the policy and the warnings so far.
struct Loader {
    path: String,
    strict: bool,
    warnings: Vec<String>,
}

impl Loader {
    fn new(path: &Path, options: &OpenOptions) -> Self {
        Loader {
            path: path.display().to_string(),
            strict: options.strict,
            warnings: Vec::new(),
        }
    }

    fn gltf_err(&self, source: GltfError) -> AssetError {
        AssetError::Gltf {
            path: self.path.clone(),
            error: source,
        }
    }

    fn scene_err(&self, location: impl Into<String>, message: impl Into<String>) -> AssetError {
        AssetError::Scene {
            path: self.path.clone(),
            location: location.into(),
            message: message.into(),
        }
    }

    /// Reads and validates a container in one pass ([`hce_format::read_validated`]: every
    /// checksum, the padding, every content rule and each object's geometry hash).
    fn container(&self, bytes: &[u8]) -> Result<hce_format::Container, AssetError> {
        let (container, problems) =
            hce_format::read_validated(bytes).map_err(|error| AssetError::Container {
                path: self.path.clone(),
                error,
            })?;
        if !problems.is_empty() {
            return Err(AssetError::Invalid {
                path: self.path.clone(),
                problems,
            });
        }
        Ok(container)
    }

    /// What the renderer needs of a validated object (its geometry hash was checked with the
    /// rest of the container).
    fn finish_object(
        &self,
        index: u32,
        object: Object,
        instances: Vec<Instance>,
    ) -> Result<AssetObject, AssetError> {
        let mesh = &object.mesh;
        let points = mesh.positions.chunks_exact(3).map(|p| [p[0], p[1], p[2]]);
        let bounds = Bounds::of_points(points).unwrap_or(Bounds {
            min: [0.0; 3],
            max: [0.0; 3],
        });
        let mut sum = 0f64;
        for t in 0..mesh.triangle_count() {
            let c = mesh.triangle(t).map(|v| Vec3::from(mesh.position(v)));
            for e in 0..3 {
                sum += f64::from((c[e] - c[(e + 1) % 3]).length());
            }
        }
        let mean_edge_length = (sum / (3 * mesh.triangle_count()).max(1) as f64) as f32;
        // Validation decoded every tree already, so none fails here.
        let tree_depth = hce_format::triangle_trees(&object)
            .iter()
            .filter_map(|t| t.as_ref().ok().map(|s| s.depth))
            .max()
            .unwrap_or(0);
        Ok(AssetObject {
            index,
            object,
            instances,
            bounds,
            mean_edge_length,
            tree_depth,
        })
    }

    fn gltf(
        &mut self,
        source: &GltfSource,
    ) -> Result<(Metadata, Vec<AssetObject>, Option<SceneCamera>), AssetError> {
        let container_bytes = source
            .container()
            .map_err(|e| self.gltf_err(e))?
            .ok_or_else(|| AssetError::NotBaked {
                path: self.path.clone(),
            })?;
        let container = self.container(container_bytes)?;
        let json = &source.json;
        let links = hce_format::primitive_links(json).map_err(|e| self.gltf_err(e))?;
        let good = self.check_links(&container, source, &links)?;

        // Objects of each mesh, in first-primitive order, from the links that passed, each with
        // its placement (SPEC.md 2.6): the object drawn in the primitive's node goes where the
        // primitive is, through `M⁻¹` (the dequantization an optimiser moved into the node).
        let mut mesh_objects: HashMap<usize, Vec<(u32, Mat4)>> = HashMap::new();
        for (l, placement) in &good {
            let list = mesh_objects.entry(l.mesh).or_default();
            if !list.iter().any(|(o, _)| *o == l.object) {
                list.push((
                    l.object,
                    Mat4::from_cols_array(&placement.inverse_columns()),
                ));
            }
        }
        let walk = scene_graph::walk(json).map_err(|e| AssetError::Scene {
            path: self.path.clone(),
            location: e.location,
            message: e.message,
        })?;
        self.warnings.extend(walk.repeated_warnings());
        let mut instances: Vec<Vec<Instance>> = vec![Vec::new(); container.objects.len()];
        let mut camera = None;
        for visit in &walk.visits {
            let (node, world) = (visit.node, &visit.world);
            let n = &json["nodes"][node];
            let name = n
                .get("name")
                .and_then(Value::as_str)
                .map(str::to_owned)
                .unwrap_or_else(|| format!("nodes[{node}]"));
            if let Some(m) = visit.mesh {
                for &(o, placement) in mesh_objects.get(&m).map(Vec::as_slice).unwrap_or(&[]) {
                    instances[o as usize].push(Instance {
                        node: Some(node),
                        name: name.clone(),
                        transform: *world * placement,
                    });
                }
            }
            if camera.is_none() {
                if let Some(c) = n.get("camera") {
                    camera = self.camera(json, node, &name, c, world)?;
                }
            }
        }
        let mut objects = Vec::with_capacity(container.objects.len());
        for (i, (object, inst)) in container.objects.into_iter().zip(instances).enumerate() {
            if inst.is_empty() {
                self.warnings.push(format!(
                    "objects[{i}] '{}' is used by no node of the scene; it is not drawn",
                    object.name
                ));
            }
            objects.push(self.finish_object(i as u32, object, inst)?);
        }
        Ok((container.metadata, objects, camera))
    }

    /// SPEC.md 3.3 and 3.5 for every primitive link ([`hce_format::check_links`], the validator's
    /// rules, the same-geometry rule of 2.6 among them), strict or lenient; returns the links
    /// that passed with their placements. An object linked from two meshes is drawn as both
    /// link it (the validator reports it).
    fn check_links(
        &mut self,
        container: &hce_format::Container,
        source: &GltfSource,
        links: &[PrimitiveLink],
    ) -> Result<Vec<(PrimitiveLink, hce_format::Placement)>, AssetError> {
        let mut sink = LinkPolicy {
            loader: self,
            container,
            error: None,
        };
        let good = hce_format::check_links(
            &container.objects,
            &source.json,
            &source.buffers,
            links,
            &mut sink,
        );
        match (good, sink.error) {
            (Ok(good), _) => Ok(good
                .links
                .into_iter()
                .map(|c| (links[c.index].clone(), c.placement))
                .collect()),
            (Err(_), Some(e)) => Err(e),
            // The policy stops only with an error; should that change, still no panic.
            (Err(_), None) => Err(self.scene_err("meshes", "the link check stopped")),
        }
    }

    /// The camera of a node, or `None` (with a warning) for cameras that cannot be used.
    fn camera(
        &mut self,
        json: &Value,
        node: usize,
        name: &str,
        index: &Value,
        world: &Mat4,
    ) -> Result<Option<SceneCamera>, AssetError> {
        let at = format!("nodes[{node}].camera");
        let c = index
            .as_u64()
            .and_then(|i| json.get("cameras")?.as_array()?.get(i as usize))
            .ok_or_else(|| self.scene_err(&at, "does not name a camera of `cameras`"))?;
        if c.get("type").and_then(Value::as_str) != Some("perspective") {
            self.warnings.push(format!(
                "{at}: only perspective cameras are used; this one is ignored"
            ));
            return Ok(None);
        }
        let p = c.get("perspective");
        let yfov = p
            .and_then(|p| p.get("yfov"))
            .and_then(Value::as_f64)
            .filter(|y| y.is_finite() && *y > 0.0 && *y < std::f64::consts::PI)
            .ok_or_else(|| self.scene_err(&at, "perspective.yfov must be in (0, π) radians"))?;
        let aspect_ratio = p
            .and_then(|p| p.get("aspectRatio"))
            .and_then(Value::as_f64)
            .map(|a| a as f32)
            .filter(|a| a.is_finite() && *a > 0.0);
        let eye = world.transform_point3(Vec3::ZERO);
        let forward = world.transform_vector3(Vec3::NEG_Z).normalize_or_zero();
        let up = world.transform_vector3(Vec3::Y);
        let up = (up - forward * up.dot(forward)).normalize_or_zero();
        if forward == Vec3::ZERO || up == Vec3::ZERO || !eye.is_finite() {
            self.warnings.push(format!(
                "{at}: the node's transform collapses the camera's axes; it is ignored"
            ));
            return Ok(None);
        }
        Ok(Some(SceneCamera {
            node,
            name: name.to_owned(),
            eye: eye.to_array(),
            forward: forward.to_array(),
            up: up.to_array(),
            fov_y_degrees: (yfov as f32).to_degrees(),
            aspect_ratio,
        }))
    }
}

/// The loader's sink for link faults: with [`OpenOptions::strict`] the first is the error;
/// without, each bad primitive is ignored with a warning (SPEC.md 3.5).
struct LinkPolicy<'a> {
    loader: &'a mut Loader,
    container: &'a hce_format::Container,
    error: Option<AssetError>,
}

impl hce_format::LinkSink for LinkPolicy<'_> {
    fn fault(&mut self, link: &PrimitiveLink, at: &str, fault: LinkFault) -> LinkNext {
        let path = self.loader.path.clone();
        let link_err = |message: String| AssetError::Link {
            path: path.clone(),
            location: at.to_owned(),
            message,
        };
        let error = match fault {
            // Drawable: each mesh's nodes get an instance.
            LinkFault::OtherMesh { .. } => return LinkNext::Continue,
            LinkFault::ObjectOutOfRange { objects } => link_err(format!(
                "object {} is out of range; the container has {objects} objects",
                link.object
            )),
            LinkFault::Geometry(e) => {
                link_err(format!("cannot read its geometry: {}", e.text_at(at)))
            }
            LinkFault::Unchecked(e) => link_err(format!(
                "{}; its baked lighting is not applied (SPEC.md 3.5)",
                e.text_at(at)
            )),
            LinkFault::Stale { computed, stored } | LinkFault::WholeObject { computed, stored } => {
                AssetError::StaleGeometry {
                    path,
                    location: at.to_owned(),
                    object: link.object,
                    name: self
                        .container
                        .objects
                        .get(link.object as usize)
                        .map(|o| o.name.clone())
                        .unwrap_or_default(),
                    stored,
                    computed,
                }
            }
            edited @ (LinkFault::Edited { .. } | LinkFault::Placement { .. }) => {
                let (location, message) = edited.describe(link, at);
                AssetError::Link {
                    path,
                    location,
                    message,
                }
            }
            LinkFault::Range {
                end,
                triangles,
                name,
            } => link_err(format!(
                "triangles {}..{end} exceed object {} '{name}' with {triangles} triangles",
                link.first_triangle, link.object
            )),
            LinkFault::Overlap { other } => link_err(format!(
                "its triangle range overlaps that of {other} for object {} (SPEC.md 3.3)",
                link.object
            )),
        };
        if self.loader.strict {
            self.error = Some(error);
            LinkNext::Stop
        } else {
            self.loader
                .warnings
                .push(format!("{error}; the primitive is ignored (SPEC.md 3.5)"));
            LinkNext::SkipLink
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use hce_format::example;

    fn open_glb(bytes: &[u8], options: &OpenOptions) -> Result<Asset, AssetError> {
        Asset::from_bytes(
            Path::new("test.glb"),
            AssetFormat::Glb,
            bytes,
            |_| Err("no external buffers".into()),
            options,
        )
    }

    #[test]
    fn example_glb_opens_with_one_identity_instance() {
        let asset = open_glb(&example::triangle_glb(), &OpenOptions::default()).unwrap();
        assert_eq!(asset.objects.len(), 1);
        let o = &asset.objects[0];
        assert_eq!(o.name(), "tri");
        assert_eq!(o.instances.len(), 1);
        assert_eq!(o.instances[0].node, Some(0));
        assert_eq!(o.instances[0].transform, Mat4::IDENTITY);
        assert_eq!(o.tree_depth, 2);
        assert_eq!(
            asset.bounds().unwrap(),
            Bounds {
                min: [0.0; 3],
                max: [1.0, 1.0, 0.0]
            }
        );
        // Edges 1, √2, 1.
        assert!((o.mean_edge_length - (2.0 + 2f32.sqrt()) / 3.0).abs() < 1e-6);
        assert!(asset.camera.is_none());
        assert!(asset.warnings.is_empty(), "{:?}", asset.warnings);
    }

    /// Edits the example GLB's JSON (its BIN chunk is kept).
    fn edited_glb(edit: impl FnOnce(&mut Value)) -> Vec<u8> {
        let a = hce_format::GltfAsset::from_glb(&example::triangle_glb()).unwrap();
        let mut json = a.json;
        edit(&mut json);
        hce_format::write_glb(&json, a.bin.as_deref().unwrap_or(&[])).unwrap()
    }

    #[test]
    fn node_transforms_and_camera_are_read() {
        let glb = edited_glb(|j| {
            j["nodes"] = serde_json::json!([
                { "children": [1, 2], "translation": [0.0, 0.0, 5.0] },
                { "mesh": 0, "scale": [2.0, 2.0, 2.0], "name": "big" },
                { "camera": 0, "rotation": [0.0, 1.0, 0.0, 0.0] }
            ]);
            j["scenes"] = serde_json::json!([{ "nodes": [0] }]);
            j["cameras"] = serde_json::json!([
                { "type": "perspective", "perspective": { "yfov": 0.5, "znear": 0.1 } }
            ]);
        });
        let asset = open_glb(&glb, &OpenOptions::default()).unwrap();
        let inst = &asset.objects[0].instances;
        assert_eq!(inst.len(), 1);
        assert_eq!(inst[0].name, "big");
        let b = asset.bounds().unwrap();
        assert_eq!((b.min, b.max), ([0.0, 0.0, 5.0], [2.0, 2.0, 5.0]));
        let cam = asset.camera.unwrap();
        assert_eq!(cam.eye, [0.0, 0.0, 5.0]);
        // Turned half around Y: looks along +Z.
        assert!((Vec3::from(cam.forward) - Vec3::Z).length() < 1e-6);
        assert!((cam.fov_y_degrees - 0.5f32.to_degrees()).abs() < 1e-4);
    }

    #[test]
    fn edited_mesh_is_stale_unless_lenient() {
        // Move one vertex of the primitive: its hash no longer matches the baked one.
        let a = hce_format::GltfAsset::from_glb(&example::triangle_glb()).unwrap();
        let mut bin = a.bin.unwrap();
        bin[12..16].copy_from_slice(&0.5f32.to_le_bytes());
        let glb = hce_format::write_glb(&a.json, &bin).unwrap();
        let e = open_glb(&glb, &OpenOptions::default()).unwrap_err();
        assert!(
            e.to_string()
                .contains("not the same geometry as object 0 'tri' triangles 0..1 (SPEC.md 2.6)"),
            "{e}"
        );
        assert!(e.to_string().contains("bake it again"), "{e}");
        let lenient = open_glb(&glb, &OpenOptions { strict: false }).unwrap();
        assert!(lenient.objects[0].instances.is_empty());
        assert_eq!(lenient.warnings.len(), 2, "{:?}", lenient.warnings);
    }

    #[test]
    fn a_quantized_primitive_places_its_object_where_the_primitive_is() {
        // What gltf-transform's `quantize` does to the example: positions as normalized SHORTs
        // over the box, the dequantization (scale 0.5, offset (0.5, 0.5, 0)) in the node.
        let a = hce_format::GltfAsset::from_glb(&example::triangle_glb()).unwrap();
        let mut bin = a.bin.unwrap();
        let mut json = a.json;
        let at = bin.len();
        for q in [[-1i16, -1, 0, 0], [1, -1, 0, 0], [-1, 1, 0, 0]] {
            for c in q {
                bin.extend_from_slice(&(c * 32767).to_le_bytes());
            }
        }
        json["buffers"][0]["byteLength"] = serde_json::json!(bin.len());
        json["bufferViews"].as_array_mut().unwrap().push(
            serde_json::json!({ "buffer": 0, "byteOffset": at, "byteLength": 24, "byteStride": 8 }),
        );
        let view = json["bufferViews"].as_array().unwrap().len() - 1;
        json["accessors"][0] = serde_json::json!({
            "bufferView": view, "componentType": 5122, "normalized": true, "count": 3, "type": "VEC3"
        });
        json["nodes"][0]["scale"] = serde_json::json!([0.5, 0.5, 0.5]);
        json["nodes"][0]["translation"] = serde_json::json!([0.5, 0.5, 0.0]);
        let glb = hce_format::write_glb(&json, &bin).unwrap();
        let asset = open_glb(&glb, &OpenOptions::default()).unwrap();
        let t = asset.objects[0].instances[0].transform;
        assert!(t.abs_diff_eq(Mat4::IDENTITY, 1e-6), "{t}");
        let b = asset.bounds().unwrap();
        assert_eq!((b.min, b.max), ([0.0; 3], [1.0, 1.0, 0.0]));
        // With the node's scale 1 instead of 0.5 the primitive is drawn twice the size, at
        // (-0.5, -0.5, 0), (1.5, -0.5, 0), (-0.5, 1.5, 0): the node times M⁻¹ (x ↦ 2x - (1, 1, 0))
        // puts the object's corners there too.
        json["nodes"][0]["scale"] = serde_json::json!([1.0, 1.0, 1.0]);
        let glb = hce_format::write_glb(&json, &bin).unwrap();
        let b = open_glb(&glb, &OpenOptions::default())
            .unwrap()
            .bounds()
            .unwrap();
        assert_eq!((b.min, b.max), ([-0.5, -0.5, 0.0], [1.5, 1.5, 0.0]));
    }

    #[test]
    fn bad_scene_graphs_are_errors_or_warnings() {
        let out_of_range = edited_glb(|j| j["scenes"] = serde_json::json!([{ "nodes": [7] }]));
        let e = open_glb(&out_of_range, &OpenOptions::default()).unwrap_err();
        assert!(e.to_string().contains("scenes[0].nodes[0]"), "{e}");
        let bad_matrix = edited_glb(|j| j["nodes"][0]["matrix"] = serde_json::json!([1.0, 2.0]));
        let e = open_glb(&bad_matrix, &OpenOptions::default()).unwrap_err();
        assert!(e.to_string().contains("nodes[0].matrix"), "{e}");
        // A cycle is walked once, with a warning, not forever.
        let cycle = edited_glb(|j| {
            j["nodes"] = serde_json::json!([{ "mesh": 0, "children": [1] }, { "children": [0] }]);
        });
        let asset = open_glb(&cycle, &OpenOptions::default()).unwrap();
        assert_eq!(asset.objects[0].instances.len(), 1);
        assert!(
            asset.warnings[0].contains("reached twice"),
            "{:?}",
            asset.warnings
        );
        let plain = edited_glb(|j| {
            j.as_object_mut().unwrap().remove("extensions");
        });
        assert!(matches!(
            open_glb(&plain, &OpenOptions::default()),
            Err(AssetError::NotBaked { .. })
        ));
    }

    /// The example GLB without the extension, as an optimiser that does not know it writes it;
    /// with `colours` (RGBA, normalized bytes) as its `COLOR_0` and its node moved by 5 in z.
    fn stripped_glb(colours: Option<[[u8; 4]; 3]>) -> Vec<u8> {
        let a = hce_format::GltfAsset::from_glb(&example::triangle_glb()).unwrap();
        let mut json = a.json;
        let mut bin = a.bin.unwrap();
        let j = json.as_object_mut().unwrap();
        j.remove("extensions");
        j.remove("extensionsUsed");
        json["meshes"][0]["primitives"][0]
            .as_object_mut()
            .unwrap()
            .remove("extensions");
        json["nodes"][0]["translation"] = serde_json::json!([0.0, 0.0, 5.0]);
        if let Some(colours) = colours {
            let at = bin.len();
            bin.extend(colours.iter().flatten());
            json["bufferViews"]
                .as_array_mut()
                .unwrap()
                .push(serde_json::json!({ "buffer": 0, "byteOffset": at, "byteLength": 12 }));
            let view = json["bufferViews"].as_array().unwrap().len() - 1;
            json["accessors"]
                .as_array_mut()
                .unwrap()
                .push(serde_json::json!({
                    "bufferView": view, "componentType": 5121, "normalized": true, "count": 3,
                    "type": "VEC4"
                }));
            let accessor = json["accessors"].as_array().unwrap().len() - 1;
            json["meshes"][0]["primitives"][0]["attributes"]["COLOR_0"] = accessor.into();
            json["buffers"][0]["byteLength"] = bin.len().into();
        }
        hce_format::write_glb(&json, &bin).unwrap()
    }

    fn preview(glb: &[u8]) -> Asset {
        let source = GltfSource::parse(glb, |_| Err("no external buffers".into())).unwrap();
        assert!(matches!(
            Asset::from_gltf(Path::new("plain.glb"), &source, &OpenOptions::default()),
            Err(AssetError::NotBaked { .. })
        ));
        Asset::plain_preview(Path::new("plain.glb"), &source).unwrap()
    }

    #[test]
    fn a_glb_without_the_extension_previews_its_colour_0_in_world_space() {
        let red_green_blue = [[255, 0, 0, 255], [0, 255, 0, 255], [0, 0, 255, 128]];
        let asset = preview(&stripped_glb(Some(red_green_blue)));
        assert_eq!(asset.objects.len(), 1);
        let o = &asset.objects[0];
        assert_eq!(o.object.kind, ObjectKind::Flat);
        assert_eq!(o.instances.len(), 1);
        assert_eq!(o.instances[0].transform, Mat4::IDENTITY);
        // The node's translation is in the positions.
        assert_eq!(
            o.object.mesh.positions,
            [0.0, 0.0, 5.0, 1.0, 0.0, 5.0, 0.0, 1.0, 5.0]
        );
        // The corners' mean colour, the alpha dropped.
        let c = hce_format::rgb9e5::decode(o.object.colours[0]);
        for k in 0..3 {
            assert!((c[k] - 1.0 / 3.0).abs() < 2e-3, "{c:?}");
        }
        assert!(asset.warnings[0].starts_with("no baked lighting"));
        assert!(
            asset.warnings[0].contains("COLOR_0 vertex colours"),
            "{:?}",
            asset.warnings
        );
        assert_eq!(asset.metadata.generator, "hce tests");
    }

    #[test]
    fn a_glb_without_the_extension_or_colours_previews_in_grey() {
        let asset = preview(&stripped_glb(None));
        let c = hce_format::rgb9e5::decode(asset.objects[0].object.colours[0]);
        assert!(c[0] == c[1] && c[1] == c[2] && c[0] > 0.0, "{c:?}");
        assert!(
            asset.warnings[0].contains("grey preview light"),
            "{:?}",
            asset.warnings
        );
    }

    #[test]
    fn hce_container_opens_with_its_own_mesh() {
        let bytes = hce_format::write(&example::two_triangles()).unwrap();
        let asset = Asset::from_bytes(
            Path::new("two.hce"),
            AssetFormat::Hce,
            &bytes,
            |_| Err(String::new()),
            &OpenOptions::default(),
        )
        .unwrap();
        assert_eq!(asset.objects[0].instances[0].transform, Mat4::IDENTITY);
        assert_eq!(asset.instance_count(), 1);
        assert_eq!(asset.world_triangles().len(), 2);
        // A container whose stored hash does not match its control mesh is refused.
        let mut c = example::two_triangles();
        c.objects[0].geometry_hash ^= 1;
        let bytes = hce_format::write(&c).unwrap();
        let e = Asset::from_bytes(
            Path::new("two.hce"),
            AssetFormat::Hce,
            &bytes,
            |_| Err(String::new()),
            &OpenOptions::default(),
        )
        .unwrap_err();
        // The validator catches it (SPEC.md Appendix C) before the loader's own hash check.
        assert!(
            e.to_string().starts_with("two.hce: ")
                && e.to_string().contains("objects[0].geometry_hash"),
            "{e}"
        );
    }

    #[test]
    fn truncated_and_bit_flipped_files_are_errors_not_panics() {
        let glb = example::triangle_glb();
        for len in 0..glb.len() {
            assert!(
                open_glb(&glb[..len], &OpenOptions::default()).is_err(),
                "truncated to {len} bytes"
            );
        }
        // Where the container lies in the GLB: a flip there must be caught by its checksums.
        let container = hce_format::write(&example::single_triangle()).unwrap();
        let start = glb
            .windows(container.len())
            .position(|w| w == container.as_slice())
            .unwrap();
        let mut accepted_outside = 0;
        for i in 0..glb.len() {
            for bit in [0, 3, 7] {
                let mut b = glb.clone();
                b[i] ^= 1 << bit;
                let r = open_glb(&b, &OpenOptions::default());
                if (start..start + container.len()).contains(&i) {
                    assert!(
                        r.is_err(),
                        "flip of bit {bit} at container byte {}",
                        i - start
                    );
                } else if r.is_ok() {
                    accepted_outside += 1;
                }
            }
        }
        // Some flips outside the container are harmless (JSON whitespace, the generator
        // string, padding); most are not, but none may panic.
        assert!(accepted_outside < glb.len() * 3, "{accepted_outside}");
    }

    /// The preview of a file without the extension reads accessors, materials and the scene
    /// graph from the file: a damaged one is an error or a preview, never a panic.
    #[test]
    fn a_damaged_file_without_the_extension_previews_or_errs_without_panicking() {
        let glb = stripped_glb(Some([[255, 0, 0, 255], [0, 255, 0, 255], [0, 0, 255, 255]]));
        let try_preview = |bytes: &[u8]| {
            GltfSource::parse(bytes, |_| Err("no external buffers".into()))
                .ok()
                .map(|s| Asset::plain_preview(Path::new("damaged.glb"), &s).is_ok())
        };
        assert_eq!(try_preview(&glb), Some(true));
        for len in 0..glb.len() {
            let _ = try_preview(&glb[..len]);
        }
        let mut previewed = 0;
        for i in 0..glb.len() {
            for bit in [0, 3, 7] {
                let mut b = glb.clone();
                b[i] ^= 1 << bit;
                previewed += usize::from(try_preview(&b) == Some(true));
            }
        }
        assert!(previewed > 0 && previewed < 3 * glb.len(), "{previewed}");
    }
}
