//! Baked glTF output: the input scene written back as one GLB (or `.gltf` + `.bin`) with the
//! `EXT_hce_baked_lighting` extension (SPEC.md section 3) and `COLOR_0` vertex colours as the
//! fallback any viewer shows.
//!
//! The input's JSON is kept (nodes, materials, lights, cameras, extras) and edited: buffers are
//! merged into the one BIN buffer the extension needs, external images are embedded, meshes
//! used by several nodes are copied so that each instance carries its own lighting, and every
//! baked primitive gets a float `COLOR_0` accessor and its link to the container. An OBJ input
//! is converted to glTF first ([`obj_to_gltf`]).

mod from_obj;

pub use from_obj::obj_to_gltf;

use hce_format::{embed_container, link_primitive, write_glb, GltfAsset as Asset, PrimitiveLink};
use hce_meshio::gltf_guard::{percent_encode, read_uri};
use hce_meshio::scene::{ImportedScene, SourceFormat};
use hce_meshio::write_atomic;
use serde_json::{json, Value};
use std::path::{Path, PathBuf};

const ARRAY_BUFFER: u32 = 34962;
const FLOAT: u32 = 5126;

/// Why a baked asset cannot be produced or written.
#[derive(Debug, thiserror::Error)]
pub enum OutputError {
    #[error("{path}: cannot re-read the source scene: {message}")]
    Source { path: PathBuf, message: String },
    #[error("{0}")]
    Gltf(#[from] hce_format::GltfError),
    #[error("object {index} {name:?}: {message}")]
    Object {
        index: usize,
        name: String,
        message: String,
    },
    #[error("{0} (the caller must pass one entry per scene object)")]
    Mismatch(String),
    #[error("the container is unreadable: {0}")]
    Container(#[from] hce_format::ReadError),
    #[error(transparent)]
    Write(#[from] hce_meshio::FileWriteError),
    #[error("{path}: the output must end in .glb or .gltf")]
    OutputExtension { path: PathBuf },
}

/// Where a scene object's baked data lies in the container.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub struct ObjectLink {
    /// Index of the object in the container's object table.
    pub object: u32,
    /// Index of this primitive's first triangle among the object's coarse triangles (0 when
    /// the object is this primitive alone).
    pub first_triangle: u32,
}

/// A baked glTF asset in memory: JSON and the BIN buffer (buffer 0).
#[derive(Clone, Debug, PartialEq)]
pub struct BakedAsset {
    pub json: Value,
    pub bin: Vec<u8>,
}

impl BakedAsset {
    /// The asset as GLB bytes.
    pub fn to_glb(&self) -> Result<Vec<u8>, OutputError> {
        Ok(write_glb(&self.json, &self.bin)?)
    }

    /// Writes the asset atomically: `.glb` as one file; `.gltf` as the JSON plus a `.bin` of
    /// the same stem beside it (the `.bin` first, so that the JSON never names a missing file).
    pub fn write(&self, path: &Path) -> Result<(), OutputError> {
        let ext = path
            .extension()
            .and_then(|e| e.to_str())
            .map(str::to_ascii_lowercase);
        match ext.as_deref() {
            Some("glb") => Ok(write_atomic(path, &self.to_glb()?)?),
            Some("gltf") => {
                let bin_path = path.with_extension("bin");
                let bin_name = bin_path
                    .file_name()
                    .and_then(|n| n.to_str())
                    .ok_or_else(|| OutputError::OutputExtension {
                        path: path.to_path_buf(),
                    })?
                    .to_owned();
                let mut json = self.json.clone();
                if let Some(b0) = json.get_mut("buffers").and_then(|b| b.get_mut(0)) {
                    b0["uri"] = json!(percent_encode(&bin_name));
                }
                write_atomic(&bin_path, &self.bin)?;
                let text = serde_json::to_vec_pretty(&json)
                    .map_err(|e| hce_format::GltfError::Json(e.to_string()))?;
                Ok(write_atomic(path, &text)?)
            }
            _ => Err(OutputError::OutputExtension {
                path: path.to_path_buf(),
            }),
        }
    }
}

/// Bakes a scene into GLB bytes: see [`bake_gltf`].
pub fn write_baked_gltf(
    scene: &ImportedScene,
    colours: &[Vec<[f32; 3]>],
    container: &[u8],
    links: &[Option<ObjectLink>],
) -> Result<Vec<u8>, OutputError> {
    bake_gltf(scene, colours, container, links)?.to_glb()
}

/// Builds the baked asset.
///
/// * `colours[i]` holds one linear RGB colour per vertex of `scene.objects[i]`, in the
///   primitive's own vertex order (as read, before any welding); it is written as `COLOR_0`,
///   clamped to [0, 1] as glTF requires (scale it first for a brighter scene). Note that glTF
///   viewers multiply `COLOR_0` with the base colour.
/// * `container` is the whole `.hce` container.
/// * `links[i]` says which container object holds `scene.objects[i]`'s baked data (`None`: the
///   primitive gets vertex colours only).
///
/// The source is re-read from `scene.path`. The result is deterministic.
pub fn bake_gltf(
    scene: &ImportedScene,
    colours: &[Vec<[f32; 3]>],
    container: &[u8],
    links: &[Option<ObjectLink>],
) -> Result<BakedAsset, OutputError> {
    check_inputs(scene, colours, container, links)?;
    let (mut json, mut bin, mesh_of) = match scene.format {
        SourceFormat::Gltf | SourceFormat::Glb => {
            let (mut json, bin) = load_source(&scene.path)?;
            let mesh_of = deinstance(&mut json);
            let mesh_of = scene
                .objects
                .iter()
                .map(|o| o.node.and_then(|n| mesh_of.get(n).copied().flatten()))
                .collect::<Vec<_>>();
            (json, bin, mesh_of)
        }
        SourceFormat::Obj => {
            let (json, bin) = obj_to_gltf(scene)?;
            let mesh_of = (0..scene.objects.len()).map(Some).collect();
            (json, bin, mesh_of)
        }
    };
    for (i, o) in scene.objects.iter().enumerate() {
        let object_error = |message: String| OutputError::Object {
            index: i,
            name: o.name.clone(),
            message,
        };
        let mesh = mesh_of[i].ok_or_else(|| {
            object_error("its node has no mesh in the re-read source; was it edited?".into())
        })?;
        let accessor = push_colours(&mut json, &mut bin, &colours[i])?;
        let prim = json
            .get_mut("meshes")
            .and_then(|m| m.get_mut(mesh))
            .and_then(|m| m.get_mut("primitives"))
            .and_then(|p| p.get_mut(o.primitive))
            .and_then(|p| p.get_mut("attributes"))
            .and_then(Value::as_object_mut)
            .ok_or_else(|| {
                object_error(format!(
                    "meshes[{mesh}].primitives[{}] is missing in the re-read source",
                    o.primitive
                ))
            })?;
        prim.insert("COLOR_0".into(), json!(accessor));
        if let Some(link) = links[i] {
            link_primitive(
                &mut json,
                &PrimitiveLink {
                    mesh,
                    primitive: o.primitive,
                    object: link.object,
                    geometry_hash: o.geometry_hash(),
                    first_triangle: link.first_triangle,
                },
            )?;
        }
    }
    embed_container(&mut json, &mut bin, container)?;
    Ok(BakedAsset { json, bin })
}

fn check_inputs(
    scene: &ImportedScene,
    colours: &[Vec<[f32; 3]>],
    container: &[u8],
    links: &[Option<ObjectLink>],
) -> Result<(), OutputError> {
    let n = scene.objects.len();
    if colours.len() != n || links.len() != n {
        return Err(OutputError::Mismatch(format!(
            "{} colour lists and {} links for {n} scene objects",
            colours.len(),
            links.len()
        )));
    }
    let c = hce_format::read(container)?;
    // SPEC.md 3.3: primitives sharing a container object belong to one mesh and cover
    // disjoint triangle ranges of it.
    let mut by_object: std::collections::BTreeMap<u32, Vec<(u32, u64, usize)>> =
        std::collections::BTreeMap::new();
    for (i, (o, link)) in scene.objects.iter().zip(links).enumerate() {
        if let Some(l) = link {
            let end = u64::from(l.first_triangle) + o.triangle_count() as u64;
            by_object
                .entry(l.object)
                .or_default()
                .push((l.first_triangle, end, i));
        }
    }
    for (object, mut ranges) in by_object {
        ranges.sort_unstable();
        let first = &scene.objects[ranges[0].2];
        for pair in ranges.windows(2) {
            let (a, b) = (&scene.objects[pair[0].2], &scene.objects[pair[1].2]);
            let err = |message: String| OutputError::Object {
                index: pair[1].2,
                name: b.name.clone(),
                message,
            };
            if (b.node, b.mesh) != (first.node, first.mesh) {
                return Err(err(format!(
                    "shares container object {object} with {:?}, which is another mesh instance; \
                     one object may only be shared by primitives of one mesh",
                    first.name
                )));
            }
            if u64::from(pair[1].0) < pair[0].1 {
                return Err(err(format!(
                    "its triangles in container object {object} overlap those of {:?}",
                    a.name
                )));
            }
        }
    }
    for (i, o) in scene.objects.iter().enumerate() {
        let err = |message: String| OutputError::Object {
            index: i,
            name: o.name.clone(),
            message,
        };
        if colours[i].len() != o.vertex_count() {
            return Err(err(format!(
                "{} colours for {} vertices",
                colours[i].len(),
                o.vertex_count()
            )));
        }
        if let Some(v) = colours[i]
            .iter()
            .position(|c| c.iter().any(|x| !x.is_finite()))
        {
            return Err(err(format!("the colour of vertex {v} is not finite")));
        }
        if let Some(link) = links[i] {
            let target = c.objects.get(link.object as usize).ok_or_else(|| {
                err(format!(
                    "linked to container object {} but the container has {}",
                    link.object,
                    c.objects.len()
                ))
            })?;
            let end = u64::from(link.first_triangle) + o.triangle_count() as u64;
            if end > target.triangles.len() as u64 {
                return Err(err(format!(
                    "triangles {}..{end} exceed container object {} ({} triangles)",
                    link.first_triangle,
                    link.object,
                    target.triangles.len()
                )));
            }
        }
    }
    Ok(())
}

fn source_error(path: &Path, message: impl Into<String>) -> OutputError {
    OutputError::Source {
        path: path.to_path_buf(),
        message: message.into(),
    }
}

/// Re-reads the source glTF and merges all its buffers and external images into one BIN
/// buffer; any earlier `EXT_hce_baked_lighting` data is dropped.
fn load_source(path: &Path) -> Result<(Value, Vec<u8>), OutputError> {
    let bytes = std::fs::read(path).map_err(|e| source_error(path, e.to_string()))?;
    let asset = Asset::parse(&bytes)?;
    let base = path
        .parent()
        .unwrap_or_else(|| Path::new("."))
        .to_path_buf();
    let buffers = asset.buffers(|uri| read_uri(&base, uri))?;
    let mut json = asset.json;
    strip_extension(&mut json);
    // As the importer did (`gltf_guard::open`), so that node indices agree: one node per
    // instance, each then given its own mesh copy by `deinstance`.
    hce_meshio::gpu_instancing::expand(&mut json, &buffers)
        .map_err(|message| source_error(path, message))?;

    // Buffer starts aligned to 16 keep every view's offset alignment (at most 16 matters).
    let mut bin = Vec::new();
    let mut starts = Vec::with_capacity(buffers.len());
    let lengths: Vec<u64> = json
        .get("buffers")
        .and_then(Value::as_array)
        .map(|a| {
            a.iter()
                .map(|b| b.get("byteLength").and_then(Value::as_u64).unwrap_or(0))
                .collect()
        })
        .unwrap_or_default();
    for (b, data) in buffers.iter().enumerate() {
        bin.resize(bin.len().next_multiple_of(16), 0);
        starts.push(bin.len() as u64);
        let len = (lengths.get(b).copied().unwrap_or(0) as usize).min(data.len());
        bin.extend_from_slice(&data[..len]);
    }
    if let Some(views) = json.get_mut("bufferViews").and_then(Value::as_array_mut) {
        for (v, view) in views.iter_mut().enumerate() {
            let b = view
                .get("buffer")
                .and_then(Value::as_u64)
                .unwrap_or(u64::MAX);
            let start = starts.get(b as usize).copied().ok_or_else(|| {
                source_error(path, format!("bufferViews[{v}].buffer {b} does not exist"))
            })?;
            let offset = view.get("byteOffset").and_then(Value::as_u64).unwrap_or(0);
            view["buffer"] = json!(0);
            view["byteOffset"] = json!(start + offset);
        }
    }
    embed_images(path, &base, &mut json, &mut bin)?;
    if let Some(root) = json.as_object_mut() {
        root.insert("buffers".into(), json!([{ "byteLength": bin.len() }]));
    }
    Ok((json, bin))
}

/// Moves images referenced by file URI into buffer views, so that the GLB is self-contained
/// wherever it is written.
fn embed_images(
    path: &Path,
    base: &Path,
    json: &mut Value,
    bin: &mut Vec<u8>,
) -> Result<(), OutputError> {
    let count = json
        .get("images")
        .and_then(Value::as_array)
        .map_or(0, Vec::len);
    for i in 0..count {
        let uri = match json["images"][i].get("uri").and_then(Value::as_str) {
            Some(u) if !u.starts_with("data:") => u.to_owned(),
            _ => continue,
        };
        let lower = uri.to_ascii_lowercase();
        let mime = if lower.ends_with(".png") {
            "image/png"
        } else if lower.ends_with(".jpg") || lower.ends_with(".jpeg") {
            "image/jpeg"
        } else if let Some(m) = json["images"][i].get("mimeType").and_then(Value::as_str) {
            // Only the glTF core image types may sit in a buffer view without an extension.
            if m == "image/png" || m == "image/jpeg" {
                if m == "image/png" {
                    "image/png"
                } else {
                    "image/jpeg"
                }
            } else {
                continue;
            }
        } else {
            continue;
        };
        let data = read_uri(base, &uri)
            .map_err(|e| source_error(path, format!("images[{i}] {uri:?}: {e}")))?;
        bin.resize(bin.len().next_multiple_of(4), 0);
        let offset = bin.len();
        bin.extend_from_slice(&data);
        let views = json
            .as_object_mut()
            .and_then(|r| {
                r.entry("bufferViews")
                    .or_insert_with(|| json!([]))
                    .as_array_mut()
            })
            .ok_or_else(|| source_error(path, "\"bufferViews\" is not an array"))?;
        views.push(json!({ "buffer": 0, "byteOffset": offset, "byteLength": data.len() }));
        let view = views.len() - 1;
        let image = json["images"][i]
            .as_object_mut()
            .ok_or_else(|| source_error(path, format!("images[{i}] is not an object")))?;
        image.remove("uri");
        image.insert("bufferView".into(), json!(view));
        image.insert("mimeType".into(), json!(mime));
    }
    Ok(())
}

/// Removes a previous bake's extension objects (its container view is left unused).
fn strip_extension(json: &mut Value) {
    let name = hce_format::EXTENSION_NAME;
    remove_from_extensions(json, name);
    for key in ["extensionsUsed", "extensionsRequired"] {
        if let Some(list) = json.get_mut(key).and_then(Value::as_array_mut) {
            list.retain(|e| e != name);
            // The glTF schema requires these lists to be non-empty when present.
            if list.is_empty() {
                if let Some(root) = json.as_object_mut() {
                    root.remove(key);
                }
            }
        }
    }
    if let Some(meshes) = json.get_mut("meshes").and_then(Value::as_array_mut) {
        for prim in meshes
            .iter_mut()
            .filter_map(|m| m.get_mut("primitives").and_then(Value::as_array_mut))
            .flatten()
        {
            remove_from_extensions(prim, name);
        }
    }
}

/// Removes `extensions.<name>` from an object, and `extensions` itself when it becomes empty.
fn remove_from_extensions(v: &mut Value, name: &str) {
    let Some(obj) = v.as_object_mut() else {
        return;
    };
    if let Some(ext) = obj.get_mut("extensions").and_then(Value::as_object_mut) {
        ext.remove(name);
        if ext.is_empty() {
            obj.remove("extensions");
        }
    }
}

/// Gives every node its own mesh: the first node (in index order) that uses a mesh keeps it,
/// later ones get copies appended to `meshes`, since each instance is lit differently.
/// Returns the mesh of each node.
fn deinstance(json: &mut Value) -> Vec<Option<usize>> {
    let node_count = json
        .get("nodes")
        .and_then(Value::as_array)
        .map_or(0, Vec::len);
    let mut taken = std::collections::BTreeSet::new();
    let mut out = Vec::with_capacity(node_count);
    for n in 0..node_count {
        let Some(m) = json["nodes"][n]
            .get("mesh")
            .and_then(Value::as_u64)
            .map(|m| m as usize)
        else {
            out.push(None);
            continue;
        };
        if taken.insert(m) {
            out.push(Some(m));
            continue;
        }
        let Some(meshes) = json.get_mut("meshes").and_then(Value::as_array_mut) else {
            out.push(None);
            continue;
        };
        let Some(copy) = meshes.get(m).cloned() else {
            out.push(None);
            continue;
        };
        meshes.push(copy);
        let new = meshes.len() - 1;
        json["nodes"][n]["mesh"] = json!(new);
        out.push(Some(new));
    }
    out
}

/// Appends a float VEC3 accessor with the colours; returns its index.
fn push_colours(
    json: &mut Value,
    bin: &mut Vec<u8>,
    colours: &[[f32; 3]],
) -> Result<usize, OutputError> {
    bin.resize(bin.len().next_multiple_of(4), 0);
    let offset = bin.len();
    // glTF requires float colours in [0, 1] (the Khronos validator reports
    // ACCESSOR_NON_CLAMPED as an error), so brighter radiosity saturates in the fallback.
    for c in colours {
        for x in c {
            bin.extend_from_slice(&x.clamp(0.0, 1.0).to_le_bytes());
        }
    }
    let view = push(
        json,
        "bufferViews",
        json!({ "buffer": 0, "byteOffset": offset, "byteLength": 12 * colours.len(), "target": ARRAY_BUFFER }),
    )?;
    push(
        json,
        "accessors",
        json!({ "bufferView": view, "componentType": FLOAT, "count": colours.len(), "type": "VEC3" }),
    )
}

fn push(json: &mut Value, key: &str, item: Value) -> Result<usize, OutputError> {
    let list = json
        .as_object_mut()
        .and_then(|r| r.entry(key).or_insert_with(|| json!([])).as_array_mut())
        .ok_or_else(|| hce_format::GltfError::Json(format!("\"{key}\" is not an array")))?;
    list.push(item);
    Ok(list.len() - 1)
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn deinstancing_copies_shared_meshes_in_node_order() {
        let mut j = json!({
            "nodes": [{"mesh": 0}, {"mesh": 1}, {"mesh": 0}, {}, {"mesh": 0}],
            "meshes": [{"name": "a"}, {"name": "b"}]
        });
        let of = deinstance(&mut j);
        assert_eq!(of, [Some(0), Some(1), Some(2), None, Some(3)]);
        assert_eq!(j["meshes"].as_array().unwrap().len(), 4);
        assert_eq!(j["meshes"][3]["name"], "a");
        assert_eq!(j["nodes"][4]["mesh"], 3);
    }

    #[test]
    fn stripping_removes_a_previous_bake() {
        let mut j = json!({
            "extensionsUsed": ["KHR_lights_punctual", "EXT_hce_baked_lighting"],
            "extensions": {"EXT_hce_baked_lighting": {"bufferView": 0}},
            "meshes": [{"primitives": [{"extensions": {"EXT_hce_baked_lighting": {"object": 0}}}]}]
        });
        strip_extension(&mut j);
        assert_eq!(j["extensionsUsed"], json!(["KHR_lights_punctual"]));
        assert!(j.get("extensions").is_none());
        assert!(j["meshes"][0]["primitives"][0].get("extensions").is_none());
    }
}
