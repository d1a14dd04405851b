//! A baked asset refined to one level and written back as a glTF scene (`hce subdivide BAKED`):
//! every node with its name, transform (TRS or matrix, as in the input), children, camera,
//! lights and extras; every mesh (nodes sharing a mesh keep sharing it); materials, textures,
//! samplers and images; cameras and `KHR_lights_punctual` lights. Each baked primitive becomes
//! the refined surface of its part of its object, with `NORMAL` and `COLOR_0`; primitives
//! without baked data are copied as they are.
//!
//! # Refinement
//!
//! Each object is refined as the caller chose ([`hce_geometry::refine::refine_object_as`]):
//! multiresolution objects by Loop subdivision, flat objects from their trees (SPEC.md F.7.1)
//! or by the linear 1-to-4 split of the flat kernel (F.7.2), both coloured by the reconstruction of SPEC.md Appendix G. Flat objects get their vertices split at
//! coarse-triangle borders so that `NORMAL` can be the face normal (they are drawn faceted);
//! positions and colours are the runtime's: across a fold of more than 10 degrees each side's
//! copies carry that side's light (SPEC.md F.5), across a joined edge both carry the shared
//! vertex's blend.
//!
//! # `COLOR_0`
//!
//! As in `hce bake`'s output, `COLOR_0` is the light arriving at the vertex rather than the
//! outgoing radiosity, because glTF viewers multiply it by the base colour: the drawn radiosity
//! divided per channel by the primitive's `baseColorFactor` (floored at 0.02), times one
//! exposure per scene (the reciprocal of the 90th percentile of the vertices' largest channel),
//! clamped to [0, 1]; primitives with an emissive material get white.

use std::collections::HashMap;
use std::path::Path;

use hce_format::{
    check_links, colour_exposure, hash_hex, write_glb, LinkFault, LinkNext, LinkSink, Placement,
    PrimitiveLink, ALBEDO_FLOOR,
};
use hce_format::{Object, ObjectKind};
use serde_json::{json, Map, Value};

use hce_geometry::normal::{face_normal, unit_or_up};
use hce_geometry::refine::RefinedObject;
use hce_meshio::export::base64;
use hce_meshio::{write_atomic, FileWriteError};

const ARRAY_BUFFER: u32 = 34962;
const ELEMENT_ARRAY_BUFFER: u32 = 34963;
const FLOAT: u32 = 5126;
const UNSIGNED_INT: u32 = 5125;

/// Why a scene cannot be refined or written.
#[derive(Debug, thiserror::Error)]
pub enum SceneExportError {
    #[error("object {index} '{name}': {message}")]
    Object {
        index: usize,
        name: String,
        message: String,
    },
    #[error("{location}: {message}")]
    Gltf { location: String, message: String },
    #[error(transparent)]
    Write(#[from] FileWriteError),
}

/// Vertex data of one object as written: positions, normals and radiosity per output vertex,
/// and the output index triples of its fine triangles (in fine-triangle order).
struct ObjectGeometry {
    positions: Vec<[f32; 3]>,
    normals: Vec<[f32; 3]>,
    radiosity: Vec<[f32; 3]>,
    triangles: Vec<[u32; 3]>,
}

impl ObjectGeometry {
    /// Multiresolution objects keep the refined mesh as it is; flat objects get their vertices
    /// split per coarse triangle, each copy with the coarse face's normal.
    fn new(object: &Object, r: &RefinedObject) -> Self {
        let m = &r.mesh;
        if object.kind == ObjectKind::Multiresolution {
            return Self {
                positions: m.positions.clone(),
                // The F.6 normals as they are (unit, or (0, 0, 1)): normalising them again
                // would change their last bits (SPEC.md F.9).
                normals: m.normals.clone(),
                radiosity: r.colours.clone(),
                triangles: m.indices.clone(),
            };
        }
        let mut out = Self {
            positions: Vec::new(),
            normals: Vec::new(),
            radiosity: Vec::new(),
            triangles: Vec::with_capacity(m.indices.len()),
        };
        for t in 0..m.coarse_triangles {
            let tri = object.mesh.triangle(t).map(|v| object.mesh.position(v));
            let normal = unit_or_up(face_normal(tri));
            let mut local: HashMap<u32, u32> = HashMap::new();
            for f in &m.indices[r.triangles_of(t..t + 1)] {
                let tri = f.map(|i| {
                    *local.entry(i).or_insert_with(|| {
                        out.positions.push(m.positions[i as usize]);
                        out.normals.push(normal);
                        out.radiosity.push(r.colours[i as usize]);
                        (out.positions.len() - 1) as u32
                    })
                });
                out.triangles.push(tri);
            }
        }
        out
    }
}

/// The scene being written: JSON arrays and the one binary buffer.
struct Writer<'a> {
    input: &'a Value,
    buffers: &'a [Vec<u8>],
    bin: Vec<u8>,
    views: Vec<Value>,
    accessors: Vec<Value>,
    copied: HashMap<usize, usize>,
    /// Whether a copied primitive keeps `KHR_draco_mesh_compression` data.
    draco: bool,
}

impl Writer<'_> {
    fn view(&mut self, bytes: &[u8], target: Option<u32>, stride: Option<u64>) -> usize {
        let offset = self.bin.len().next_multiple_of(4);
        self.bin.resize(offset, 0);
        self.bin.extend_from_slice(bytes);
        let mut v = json!({ "buffer": 0, "byteOffset": offset, "byteLength": bytes.len() });
        if let Some(t) = target {
            v["target"] = json!(t);
        }
        if let Some(s) = stride {
            v["byteStride"] = json!(s);
        }
        self.views.push(v);
        self.views.len() - 1
    }

    fn vec3(&mut self, data: &[[f32; 3]], with_bounds: bool) -> usize {
        let bytes: Vec<u8> = data
            .iter()
            .flatten()
            .flat_map(|x| x.to_le_bytes())
            .collect();
        let view = self.view(&bytes, Some(ARRAY_BUFFER), None);
        let mut a = json!({ "bufferView": view, "componentType": FLOAT, "count": data.len(), "type": "VEC3" });
        if with_bounds && !data.is_empty() {
            let lo = (0..3).map(|k| data.iter().map(|p| p[k]).fold(f32::INFINITY, f32::min));
            let hi = (0..3).map(|k| data.iter().map(|p| p[k]).fold(f32::NEG_INFINITY, f32::max));
            a["min"] = json!(lo.collect::<Vec<_>>());
            a["max"] = json!(hi.collect::<Vec<_>>());
        }
        self.accessors.push(a);
        self.accessors.len() - 1
    }

    fn indices(&mut self, tris: &[[u32; 3]]) -> usize {
        let bytes: Vec<u8> = tris
            .iter()
            .flatten()
            .flat_map(|x| x.to_le_bytes())
            .collect();
        let view = self.view(&bytes, Some(ELEMENT_ARRAY_BUFFER), None);
        self.accessors.push(json!({ "bufferView": view, "componentType": UNSIGNED_INT, "count": 3 * tris.len(), "type": "SCALAR" }));
        self.accessors.len() - 1
    }

    /// Copies a buffer view of the input (its bytes, stride and target) into the output,
    /// decoded when it is `EXT_meshopt_compression`ed (the output compresses nothing, so it
    /// never needs that extension).
    fn copy_view(&mut self, index: usize) -> Result<usize, SceneExportError> {
        let (bytes, stride) =
            hce_format::view_bytes(self.input, self.buffers, index).map_err(|e| {
                SceneExportError::Gltf {
                    location: format!("bufferViews[{index}]"),
                    message: e.to_string(),
                }
            })?;
        let bytes = bytes.into_owned();
        let v = &self.input["bufferViews"][index];
        let target = v.get("target").and_then(Value::as_u64).map(|t| t as u32);
        let out = self.view(&bytes, target, stride);
        for key in ["name", "extras"] {
            if let Some(x) = v.get(key) {
                self.views[out][key] = x.clone();
            }
        }
        Ok(out)
    }

    /// Copies an input accessor (and its views, sparse ones included), once.
    fn copy_accessor(&mut self, index: usize) -> Result<usize, SceneExportError> {
        if let Some(&a) = self.copied.get(&index) {
            return Ok(a);
        }
        let mut a = self
            .input
            .get("accessors")
            .and_then(|a| a.get(index))
            .cloned()
            .ok_or_else(|| SceneExportError::Gltf {
                location: format!("accessors[{index}]"),
                message: "does not exist".into(),
            })?;
        if let Some(v) = a.get("bufferView").and_then(Value::as_u64) {
            a["bufferView"] = json!(self.copy_view(v as usize)?);
        }
        for part in ["indices", "values"] {
            if let Some(v) = a
                .get("sparse")
                .and_then(|s| s.get(part))
                .and_then(|p| p.get("bufferView"))
                .and_then(Value::as_u64)
            {
                a["sparse"][part]["bufferView"] = json!(self.copy_view(v as usize)?);
            }
        }
        self.accessors.push(a);
        let out = self.accessors.len() - 1;
        self.copied.insert(index, out);
        Ok(out)
    }

    /// A primitive without baked data, with its accessors copied.
    fn copy_primitive(&mut self, prim: &Value) -> Result<Value, SceneExportError> {
        let mut p = prim.clone();
        if let Some(attrs) = prim.get("attributes").and_then(Value::as_object) {
            for (name, a) in attrs {
                if let Some(i) = a.as_u64() {
                    p["attributes"][name] = json!(self.copy_accessor(i as usize)?);
                }
            }
        }
        if let Some(i) = prim.get("indices").and_then(Value::as_u64) {
            p["indices"] = json!(self.copy_accessor(i as usize)?);
        }
        // A Draco primitive keeps its compressed data (its attributes' accessors have no view).
        let draco = &["extensions", hce_format::DRACO, "bufferView"];
        if let Some(v) = draco
            .iter()
            .try_fold(prim, |v, k| v.get(k))
            .and_then(Value::as_u64)
        {
            p["extensions"][hce_format::DRACO]["bufferView"] = json!(self.copy_view(v as usize)?);
            self.draco = true;
        }
        if let Some(targets) = prim.get("targets").and_then(Value::as_array) {
            for (t, target) in targets.iter().enumerate() {
                for (name, a) in target.as_object().into_iter().flatten() {
                    if let Some(i) = a.as_u64() {
                        p["targets"][t][name] = json!(self.copy_accessor(i as usize)?);
                    }
                }
            }
        }
        Ok(p)
    }
}

/// Base colour (RGB factor) and whether the material emits, for `COLOR_0`.
fn material_response(input: &Value, material: Option<u64>) -> ([f32; 3], bool) {
    let m = material.and_then(|m| input.get("materials")?.get(m as usize));
    let Some(m) = m else {
        return ([1.0; 3], false);
    };
    let base = m
        .get("pbrMetallicRoughness")
        .and_then(|p| p.get("baseColorFactor"))
        .and_then(Value::as_array)
        .map(|f| [0, 1, 2].map(|k| f.get(k).and_then(Value::as_f64).unwrap_or(1.0) as f32))
        .unwrap_or([1.0; 3]);
    let emissive = m
        .get("emissiveFactor")
        .and_then(Value::as_array)
        .is_some_and(|f| f.iter().any(|x| x.as_f64().unwrap_or(0.0) > 0.0));
    (base, emissive)
}

/// The link check's sink here: a faulted link keeps the identity placement (the loader that
/// read the asset has already applied its policy to it).
struct SkipFaulted;

impl LinkSink for SkipFaulted {
    fn fault(&mut self, _: &PrimitiveLink, _: &str, _: LinkFault) -> LinkNext {
        LinkNext::SkipLink
    }
}

/// Object-space points in the primitive's space: `M⁻¹ x = (x - t) / s` (SPEC.md 2.6).
fn placed(points: &[[f32; 3]], place: &Placement) -> Vec<[f32; 3]> {
    points
        .iter()
        .map(|p| {
            std::array::from_fn(|a| ((f64::from(p[a]) - place.offset[a]) / place.scale) as f32)
        })
        .collect()
}

/// Writes a baked asset's `objects` (its container's, in order) with every object refined
/// (`refined[k]` for object `k`) as a `.glb` or `.gltf` (buffer embedded as a data URI). `input`
/// is the glTF JSON and `buffers` its loaded buffers, `None` for a `.hce` file (then each object
/// becomes one node and mesh of its name).
///
/// A primitive placed by an optimiser (SPEC.md 2.6) gets the refined object through `M⁻¹`, so
/// it is drawn where the primitive was, in the primitive's node.
pub fn write_refined_scene(
    path: &Path,
    objects: &[&Object],
    input: Option<(&Value, &[Vec<u8>])>,
    refined: &[RefinedObject],
) -> Result<(), SceneExportError> {
    // A bare container: one synthetic node and mesh per object, linked whole.
    let bare = input.is_none();
    let synthetic;
    let (input, buffers) = match input {
        Some(i) => i,
        None => {
            synthetic = hce_scene_json(objects);
            (&synthetic, &[][..])
        }
    };
    let links: Vec<PrimitiveLink> = if bare {
        (0..objects.len())
            .map(|k| PrimitiveLink {
                mesh: k,
                primitive: 0,
                object: k as u32,
                geometry_hash: objects[k].geometry_hash,
                first_triangle: 0,
            })
            .collect()
    } else {
        hce_format::primitive_links(input).map_err(|e| SceneExportError::Gltf {
            location: "meshes".into(),
            message: e.to_string(),
        })?
    };
    let link_of: HashMap<(usize, usize), &PrimitiveLink> =
        links.iter().map(|l| ((l.mesh, l.primitive), l)).collect();
    // Each linked primitive's placement onto its object (SPEC.md 2.6): an optimiser that
    // quantized the primitive moved the dequantization into the node, so the refined object,
    // in object space, is written through M⁻¹ into the primitive's space. The loader has
    // already accepted or reported each link; one that fails here keeps the identity.
    let placements: HashMap<(usize, usize), Placement> = if bare {
        HashMap::new()
    } else {
        let owned: Vec<Object> = objects.iter().map(|&o| o.clone()).collect();
        check_links(&owned, input, buffers, &links, &mut SkipFaulted)
            .map(|c| {
                c.links
                    .into_iter()
                    .map(|c| ((links[c.index].mesh, links[c.index].primitive), c.placement))
                    .collect()
            })
            .unwrap_or_default()
    };
    let geometry: Vec<ObjectGeometry> = objects
        .iter()
        .zip(refined)
        .map(|(o, r)| ObjectGeometry::new(o, r))
        .collect();

    // COLOR_0 per linked primitive, before the exposure: radiosity over base colour.
    struct Part {
        object: usize,
        placement: Option<Placement>,
        triangles: std::ops::Range<usize>,
        light: Vec<[f32; 3]>,
        emissive: bool,
    }
    let mut parts: HashMap<(usize, usize), Part> = HashMap::new();
    let mut maxima = Vec::new();
    let meshes = input
        .get("meshes")
        .and_then(Value::as_array)
        .cloned()
        .unwrap_or_default();
    for (m, mesh) in meshes.iter().enumerate() {
        let prims = mesh
            .get("primitives")
            .and_then(Value::as_array)
            .cloned()
            .unwrap_or_default();
        for (p, prim) in prims.iter().enumerate() {
            let Some(l) = link_of.get(&(m, p)) else {
                continue;
            };
            let k = l.object as usize;
            let Some(g) = geometry.get(k) else { continue };
            let coarse = hce_format::primitive_geometry(input, buffers, m, p)
                .map(|(_, t)| t)
                .unwrap_or(refined[k].mesh.coarse_triangles);
            let first = l.first_triangle as usize;
            let triangles = refined[k].triangles_of(first..first + coarse);
            let (base, emissive) =
                material_response(input, prim.get("material").and_then(Value::as_u64));
            let light: Vec<[f32; 3]> = g
                .radiosity
                .iter()
                .map(|c| [0, 1, 2].map(|i| c[i] / base[i].max(ALBEDO_FLOOR)))
                .collect();
            if !emissive {
                let mut used = vec![false; light.len()];
                for t in &g.triangles[triangles.clone()] {
                    for &i in t {
                        used[i as usize] = true;
                    }
                }
                maxima.extend(
                    light
                        .iter()
                        .zip(&used)
                        .filter(|(_, &u)| u)
                        .map(|(c, _)| c[0].max(c[1]).max(c[2])),
                );
            }
            parts.insert(
                (m, p),
                Part {
                    object: k,
                    placement: placements
                        .get(&(m, p))
                        .copied()
                        .filter(|p| !p.is_identity()),
                    triangles,
                    light,
                    emissive,
                },
            );
        }
    }
    let exposure = colour_exposure(&mut maxima);

    let mut w = Writer {
        input,
        buffers,
        bin: Vec::new(),
        views: Vec::new(),
        accessors: Vec::new(),
        copied: HashMap::new(),
        draco: false,
    };
    // Positions and normals once per object, shared by its primitives and instances.
    let mut object_accessors: HashMap<usize, (usize, usize)> = HashMap::new();
    let mut out_meshes = Vec::new();
    // Whether a primitive was copied as it is (its accessors may be quantized).
    let mut copied_primitive = false;
    let mut mesh_map: Vec<Option<usize>> = vec![None; meshes.len()];
    for (m, mesh) in meshes.iter().enumerate() {
        let prims = mesh
            .get("primitives")
            .and_then(Value::as_array)
            .cloned()
            .unwrap_or_default();
        let mut out_prims = Vec::new();
        for (p, prim) in prims.iter().enumerate() {
            let Some(part) = parts.get(&(m, p)) else {
                copied_primitive = true;
                out_prims.push(w.copy_primitive(prim)?);
                continue;
            };
            let g = &geometry[part.object];
            let (pos, nrm) = match object_accessors.get(&part.object) {
                Some(&a) => a,
                None => {
                    // The placement has one positive scale, so the normals stay as they are.
                    let pos = match &part.placement {
                        None => w.vec3(&g.positions, true),
                        Some(place) => w.vec3(&placed(&g.positions, place), true),
                    };
                    let a = (pos, w.vec3(&g.normals, false));
                    object_accessors.insert(part.object, a);
                    a
                }
            };
            let colours: Vec<[f32; 3]> = part
                .light
                .iter()
                .map(|c| {
                    if part.emissive {
                        [1.0; 3]
                    } else {
                        c.map(|x| {
                            let x = x * exposure;
                            if x.is_nan() {
                                0.0
                            } else {
                                x.clamp(0.0, 1.0)
                            }
                        })
                    }
                })
                .collect();
            let col = w.vec3(&colours, false);
            let idx = w.indices(&g.triangles[part.triangles.clone()]);
            let mut out = Map::new();
            out.insert(
                "attributes".into(),
                json!({ "POSITION": pos, "NORMAL": nrm, "COLOR_0": col }),
            );
            out.insert("indices".into(), json!(idx));
            out.insert("mode".into(), json!(4));
            for key in ["material", "extras"] {
                if let Some(v) = prim.get(key) {
                    out.insert(key.into(), v.clone());
                }
            }
            out_prims.push(Value::Object(out));
        }
        if out_prims.is_empty() {
            continue;
        }
        let mut out = json!({ "primitives": out_prims });
        for key in ["name", "weights", "extras"] {
            if let Some(v) = mesh.get(key) {
                out[key] = v.clone();
            }
        }
        mesh_map[m] = Some(out_meshes.len());
        out_meshes.push(out);
    }

    // Images stored in buffer views are copied; URIs are kept.
    let images: Option<Vec<Value>> = input
        .get("images")
        .and_then(Value::as_array)
        .map(|list| {
            list.iter()
                .map(|img| {
                    let mut img = img.clone();
                    if let Some(v) = img.get("bufferView").and_then(Value::as_u64) {
                        img["bufferView"] = json!(w.copy_view(v as usize)?);
                    }
                    Ok(img)
                })
                .collect::<Result<_, SceneExportError>>()
        })
        .transpose()?;

    let mut root = Map::new();
    let mut asset_info = json!({ "version": "2.0", "generator": "hce subdivide" });
    if let Some(c) = input.get("asset").and_then(|a| a.get("copyright")) {
        asset_info["copyright"] = c.clone();
    }
    root.insert("asset".into(), asset_info);
    for key in [
        "scene",
        "scenes",
        "cameras",
        "materials",
        "textures",
        "samplers",
        "extras",
    ] {
        if let Some(v) = input.get(key) {
            root.insert(key.into(), v.clone());
        }
    }
    if let Some(nodes) = input.get("nodes").and_then(Value::as_array) {
        let nodes: Vec<Value> = nodes
            .iter()
            .map(|n| {
                let mut n = n.clone();
                if let Some(o) = n.as_object_mut() {
                    // Skins and animations are not carried over: the refined meshes have no
                    // joints or weights.
                    o.remove("skin");
                    if let Some(m) = o.get("mesh").and_then(Value::as_u64) {
                        match mesh_map.get(m as usize).copied().flatten() {
                            Some(new) => {
                                o.insert("mesh".into(), json!(new));
                            }
                            None => {
                                o.remove("mesh");
                                o.remove("weights");
                            }
                        }
                    }
                }
                n
            })
            .collect();
        root.insert("nodes".into(), json!(nodes));
    }
    if !out_meshes.is_empty() {
        root.insert("meshes".into(), json!(out_meshes));
    }
    if let Some(images) = images {
        root.insert("images".into(), json!(images));
    }
    // Root extensions (KHR_lights_punctual, ...) without ours: the output carries no container.
    let ours = hce_format::EXTENSION_NAME;
    if let Some(ext) = input.get("extensions").and_then(Value::as_object) {
        let ext: Map<String, Value> = ext
            .iter()
            .filter(|(k, _)| *k != ours)
            .map(|(k, v)| (k.clone(), v.clone()))
            .collect();
        if !ext.is_empty() {
            root.insert("extensions".into(), Value::Object(ext));
        }
    }
    // The refined primitives are written in FLOAT: KHR_mesh_quantization stays only for
    // primitives copied as they are.
    let dropped = |e: &Value| {
        *e == ours
            || *e == hce_format::MESHOPT
            || (!copied_primitive && *e == "KHR_mesh_quantization")
            || (!w.draco && *e == hce_format::DRACO)
    };
    for key in ["extensionsUsed", "extensionsRequired"] {
        if let Some(list) = input.get(key).and_then(Value::as_array) {
            let list: Vec<Value> = list.iter().filter(|e| !dropped(e)).cloned().collect();
            if !list.is_empty() {
                root.insert(key.into(), json!(list));
            }
        }
    }
    let bin_len = w.bin.len();
    let mut buffer = json!({ "byteLength": bin_len });
    let gltf_text = path
        .extension()
        .is_some_and(|e| e.eq_ignore_ascii_case("gltf"));
    if gltf_text {
        buffer["uri"] = json!(format!(
            "data:application/octet-stream;base64,{}",
            base64(&w.bin)
        ));
    }
    if bin_len > 0 {
        root.insert("buffers".into(), json!([buffer]));
        root.insert("bufferViews".into(), json!(w.views));
        root.insert("accessors".into(), json!(w.accessors));
    }
    let json = Value::Object(root);
    let bytes = if gltf_text {
        serde_json::to_vec(&json).map_err(|e| SceneExportError::Gltf {
            location: "file".into(),
            message: e.to_string(),
        })?
    } else {
        write_glb(&json, &w.bin).map_err(|e| SceneExportError::Gltf {
            location: "file".into(),
            message: e.to_string(),
        })?
    };
    write_atomic(path, &bytes)?;
    Ok(())
}

/// The scene of a bare container: one node and one mesh per object, named after it, in its own
/// object space (a container has no scene graph).
fn hce_scene_json(objects: &[&Object]) -> Value {
    let nodes: Vec<Value> = objects
        .iter()
        .enumerate()
        .map(|(k, o)| json!({ "name": o.name, "mesh": k }))
        .collect();
    let meshes: Vec<Value> = objects
        .iter()
        .enumerate()
        .map(|(k, o)| {
            json!({ "name": o.name, "primitives": [{ "attributes": {}, "extensions": {
                hce_format::EXTENSION_NAME: { "object": k,
                    "geometryHash": hash_hex(o.geometry_hash) } } }] })
        })
        .collect();
    json!({
        "scene": 0,
        "scenes": [{ "nodes": (0..objects.len()).collect::<Vec<_>>() }],
        "nodes": nodes,
        "meshes": meshes,
    })
}

#[cfg(test)]
mod tests {
    use super::*;
    use hce_format::{example, read_accessor, GltfAsset};

    /// The example GLB as gltf-transform's `quantize` leaves it: positions as normalized SHORTs
    /// over the box (corners (-1, -1, 0), (1, -1, 0), (-1, 1, 0)), the dequantization (scale
    /// 0.5, translation (0.5, 0.5, 0)) in the node, `KHR_mesh_quantization` required.
    fn quantized_triangle() -> (Value, Vec<u8>) {
        let a = GltfAsset::from_glb(&example::triangle_glb()).expect("the example parses");
        let mut bin = a.bin.expect("a BIN chunk");
        let mut json = a.json;
        let at = bin.len();
        for q in [[-1i16, -1, 0, 0], [1, -1, 0, 0], [-1, 1, 0, 0]] {
            for c in q {
                bin.extend_from_slice(&(c * 32767).to_le_bytes());
            }
        }
        json["buffers"][0]["byteLength"] = json!(bin.len());
        json["bufferViews"]
            .as_array_mut()
            .expect("views")
            .push(json!({ "buffer": 0, "byteOffset": at, "byteLength": 24, "byteStride": 8 }));
        let view = json["bufferViews"].as_array().expect("views").len() - 1;
        json["accessors"][0] = json!({
            "bufferView": view, "componentType": 5122, "normalized": true, "count": 3,
            "type": "VEC3", "min": [-1.0, -1.0, 0.0], "max": [1.0, 1.0, 0.0]
        });
        json["nodes"][0]["scale"] = json!([0.5, 0.5, 0.5]);
        json["nodes"][0]["translation"] = json!([0.5, 0.5, 0.0]);
        json["extensionsUsed"] = json!(["EXT_hce_baked_lighting", "KHR_mesh_quantization"]);
        json["extensionsRequired"] = json!(["KHR_mesh_quantization"]);
        (json, bin)
    }

    #[test]
    fn a_quantized_primitive_gets_its_refined_object_through_the_inverse_placement() {
        let (json, bin) = quantized_triangle();
        let c = example::single_triangle();
        let objects: Vec<&Object> = c.objects.iter().collect();
        let refined =
            vec![hce_geometry::refine::refine_object(&c.objects[0], 1).expect("it refines")];
        let path = std::env::temp_dir().join(format!("hce-refined-{}.glb", std::process::id()));
        write_refined_scene(&path, &objects, Some((&json, &[bin])), &refined).expect("it writes");
        let bytes = std::fs::read(&path).expect("the output");
        std::fs::remove_file(&path).ok();
        let out = GltfAsset::from_glb(&bytes).expect("the output parses");
        let buffers = [out.bin.clone().expect("a BIN chunk")];
        let position = out.json["meshes"][0]["primitives"][0]["attributes"]["POSITION"]
            .as_u64()
            .expect("POSITION") as usize;
        let written = read_accessor(&out.json, &buffers, position).expect("FLOAT positions");
        // The node (kept as it was) times the written positions is where the refined object
        // is: the dequantization the node holds is undone by M⁻¹.
        let expected = &refined[0].mesh.positions;
        assert_eq!(written.count(), expected.len());
        for (w, e) in written.values.chunks_exact(3).zip(expected) {
            let drawn = [0.5 * w[0] + 0.5, 0.5 * w[1] + 0.5, 0.5 * w[2]];
            for a in 0..3 {
                assert!(
                    (drawn[a] - f64::from(e[a])).abs() < 1e-6,
                    "{drawn:?} vs {e:?}"
                );
            }
        }
        assert_eq!(out.json["nodes"][0]["scale"], json!([0.5, 0.5, 0.5]));
        // Every refined primitive is FLOAT: the output needs no KHR_mesh_quantization.
        assert!(out.json.get("extensionsRequired").is_none(), "{}", out.json);
        assert!(out.json.get("extensionsUsed").is_none(), "{}", out.json);
    }
}
