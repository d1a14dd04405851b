//! The `EXT_hce_baked_lighting` glTF extension (SPEC.md Section 3): finding the container in a
//! GLB or `.gltf` asset, reading the per-primitive links, recomputing primitive geometry hashes,
//! and embedding a container into an asset being written.
//!
//! Plain GLB chunk parsing and `serde_json`, without the `gltf` crate, so that hce-format stays
//! free of geometry dependencies. Every size and index read from the asset is checked; nothing
//! panics on any input.

use crate::accessor::{read_primitive, PrimitiveMesh, DRACO};
pub use crate::gltf_json::{buffer_view_bytes, GltfError};
use crate::model::geometry_hash;
use crate::same_geometry::{primitive_box, same_surface, Mismatch, Placement};
use serde_json::{json, Map, Value};
use std::rc::Rc;

pub const EXTENSION_NAME: &str = "EXT_hce_baked_lighting";
const GLB_MAGIC: &[u8; 4] = b"glTF";
const CHUNK_JSON: u32 = 0x4E4F_534A;
const CHUNK_BIN: u32 = 0x004E_4942;

fn u32_le(b: &[u8], at: usize) -> Option<u32> {
    Some(u32::from_le_bytes(
        b.get(at..at.checked_add(4)?)?.try_into().ok()?,
    ))
}

/// A parsed asset: its JSON and, for GLB, its BIN chunk.
#[derive(Clone, Debug, PartialEq)]
pub struct Asset {
    pub json: Value,
    pub bin: Option<Vec<u8>>,
}

impl Asset {
    /// Parses a GLB file.
    pub fn from_glb(bytes: &[u8]) -> Result<Self, GltfError> {
        let bad = |m: String| GltfError::Glb(m);
        if bytes.len() < 12 || &bytes[..4] != GLB_MAGIC {
            return Err(bad(
                "missing the 12-byte header starting with \"glTF\"".into()
            ));
        }
        let version = u32_le(bytes, 4).unwrap_or(0);
        if version != 2 {
            return Err(bad(format!(
                "container version {version}, only 2 is supported"
            )));
        }
        let length = u32_le(bytes, 8).unwrap_or(0) as usize;
        if length != bytes.len() {
            return Err(bad(format!(
                "header length {length} but the file has {} bytes",
                bytes.len()
            )));
        }
        let mut at = 12usize;
        let mut json = None;
        let mut bin = None;
        while at < bytes.len() {
            let (Some(len), Some(kind)) = (u32_le(bytes, at), u32_le(bytes, at + 4)) else {
                return Err(bad(format!("chunk header at byte {at} is truncated")));
            };
            let start = at + 8;
            let end = start
                .checked_add(len as usize)
                .filter(|&e| e <= bytes.len())
                .ok_or_else(|| {
                    bad(format!(
                        "chunk at byte {at} of {len} bytes runs past the end of the file"
                    ))
                })?;
            let data = &bytes[start..end];
            match kind {
                CHUNK_JSON if json.is_none() && at == 12 => json = Some(data),
                CHUNK_BIN if bin.is_none() && json.is_some() => bin = Some(data.to_vec()),
                CHUNK_JSON | CHUNK_BIN => {
                    return Err(bad(format!("unexpected chunk {kind:#x} at byte {at}")))
                }
                _ => {} // Unknown chunks are skipped, as the glTF specification requires.
            }
            at = end.next_multiple_of(4);
        }
        let json = json.ok_or_else(|| bad("no JSON chunk".into()))?;
        Ok(Self {
            json: parse_json(json)?,
            bin,
        })
    }

    /// Parses a `.gltf` JSON file (its buffers are resolved later with [`Asset::buffers`]).
    pub fn from_gltf(bytes: &[u8]) -> Result<Self, GltfError> {
        Ok(Self {
            json: parse_json(bytes)?,
            bin: None,
        })
    }

    /// Parses either form, looking at the first bytes.
    pub fn parse(bytes: &[u8]) -> Result<Self, GltfError> {
        if bytes.starts_with(GLB_MAGIC) {
            Self::from_glb(bytes)
        } else {
            Self::from_gltf(bytes)
        }
    }

    /// Loads every buffer: the GLB BIN chunk for a buffer without `uri`, base64 `data:` URIs
    /// decoded here, other URIs through `resolve` (relative to the asset, chosen by the caller).
    pub fn buffers(
        &self,
        mut resolve: impl FnMut(&str) -> Result<Vec<u8>, String>,
    ) -> Result<Vec<Vec<u8>>, GltfError> {
        let Some(list) = self.json.get("buffers") else {
            return Ok(Vec::new());
        };
        let list = list
            .as_array()
            .ok_or_else(|| GltfError::Json("\"buffers\" is not an array".into()))?;
        let mut out = Vec::new();
        for (index, b) in list.iter().enumerate() {
            let bad = |message: String| GltfError::Buffer { index, message };
            let byte_length = b
                .get("byteLength")
                .and_then(Value::as_u64)
                .ok_or_else(|| bad("missing byteLength".into()))?;
            let data = match b.get("uri").and_then(Value::as_str) {
                None if index == 0 => self
                    .bin
                    .clone()
                    .ok_or_else(|| bad("has no uri and the asset has no BIN chunk".into()))?,
                // EXT_meshopt_compression's fallback buffer: no data, never read (its views
                // are read decoded from the compressed buffer they name).
                None if is_meshopt_fallback(b) => {
                    out.push(Vec::new());
                    continue;
                }
                None => {
                    return Err(bad(
                        "has no uri; only buffer 0 may use the GLB BIN chunk (or an EXT_meshopt_compression fallback buffer)".into()
                    ))
                }
                Some(uri) if uri.starts_with("data:") => {
                    let (_, payload) = uri
                        .split_once(";base64,")
                        .ok_or_else(|| bad("data URI is not base64".into()))?;
                    decode_base64(payload)
                        .ok_or_else(|| bad("data URI holds invalid base64".into()))?
                }
                Some(uri) => resolve(uri).map_err(|e| bad(format!("cannot load {uri:?}: {e}")))?,
            };
            // The BIN chunk may be padded by up to 3 bytes (glTF 2.0, 4.4.3.3).
            if (data.len() as u64) < byte_length {
                return Err(bad(format!(
                    "byteLength {byte_length} but only {} bytes are present",
                    data.len()
                )));
            }
            out.push(data);
        }
        Ok(out)
    }
}

/// A buffer marked as `EXT_meshopt_compression`'s fallback (`"fallback": true`).
fn is_meshopt_fallback(buffer: &Value) -> bool {
    buffer
        .get("extensions")
        .and_then(|e| e.get(crate::accessor::MESHOPT))
        .and_then(|m| m.get("fallback"))
        .and_then(Value::as_bool)
        == Some(true)
}

fn parse_json(bytes: &[u8]) -> Result<Value, GltfError> {
    let v: Value = serde_json::from_slice(bytes).map_err(|e| GltfError::Json(e.to_string()))?;
    if !v.is_object() {
        return Err(GltfError::Json("the top level is not an object".into()));
    }
    Ok(v)
}

/// Decodes standard base64 (with optional padding); `None` on any invalid character.
pub fn decode_base64(s: &str) -> Option<Vec<u8>> {
    let s = s.trim_end_matches('=');
    let mut out = Vec::with_capacity(s.len() / 4 * 3 + 3);
    let (mut acc, mut n) = (0u32, 0);
    for c in s.bytes() {
        let v = match c {
            b'A'..=b'Z' => c - b'A',
            b'a'..=b'z' => c - b'a' + 26,
            b'0'..=b'9' => c - b'0' + 52,
            b'+' => 62,
            b'/' => 63,
            _ => return None,
        };
        acc = (acc << 6) | u32::from(v);
        n += 6;
        if n >= 8 {
            n -= 8;
            out.push((acc >> n) as u8);
        }
    }
    Some(out)
}

/// The root extension object: where the container is.
#[derive(Clone, Debug, PartialEq, Eq)]
pub struct RootLink {
    pub buffer_view: usize,
    pub version: Option<String>,
}

/// One primitive's extension object (SPEC.md 3.3).
#[derive(Clone, Debug, PartialEq, Eq)]
pub struct PrimitiveLink {
    pub mesh: usize,
    pub primitive: usize,
    pub object: u32,
    pub geometry_hash: u64,
    pub first_triangle: u32,
}

fn ext_error(location: impl Into<String>, message: impl Into<String>) -> GltfError {
    GltfError::Extension {
        location: location.into(),
        message: message.into(),
    }
}

/// The root extension object, or `None` when the asset does not use the extension.
pub fn root_link(json: &Value) -> Result<Option<RootLink>, GltfError> {
    let Some(ext) = json.get("extensions").and_then(|e| e.get(EXTENSION_NAME)) else {
        return Ok(None);
    };
    let loc = format!("extensions.{EXTENSION_NAME}");
    let buffer_view = ext
        .get("bufferView")
        .and_then(Value::as_u64)
        .ok_or_else(|| ext_error(&loc, "bufferView is missing or not a non-negative integer"))?;
    Ok(Some(RootLink {
        buffer_view: usize::try_from(buffer_view)
            .map_err(|_| ext_error(&loc, "bufferView is too large"))?,
        version: ext
            .get("version")
            .and_then(Value::as_str)
            .map(str::to_owned),
    }))
}

/// Every primitive's extension object, in mesh and primitive order; the first malformed one is
/// an error (see [`scan_primitive_links`] to keep going).
pub fn primitive_links(json: &Value) -> Result<Vec<PrimitiveLink>, GltfError> {
    let (links, errors) = scan_primitive_links(json);
    match errors.into_iter().next() {
        Some(e) => Err(e),
        None => Ok(links),
    }
}

/// Every well-formed primitive extension object, in mesh and primitive order, and one error
/// per malformed one (SPEC.md 3.3, the primitive schema), so that one bad primitive does not
/// hide the others.
pub fn scan_primitive_links(json: &Value) -> (Vec<PrimitiveLink>, Vec<GltfError>) {
    let mut out = Vec::new();
    let mut errors = Vec::new();
    let meshes = json
        .get("meshes")
        .and_then(Value::as_array)
        .map(Vec::as_slice)
        .unwrap_or(&[]);
    for (m, mesh) in meshes.iter().enumerate() {
        let prims = mesh
            .get("primitives")
            .and_then(Value::as_array)
            .map(Vec::as_slice)
            .unwrap_or(&[]);
        for (p, prim) in prims.iter().enumerate() {
            let Some(ext) = prim.get("extensions").and_then(|e| e.get(EXTENSION_NAME)) else {
                continue;
            };
            let loc = format!("meshes[{m}].primitives[{p}].extensions.{EXTENSION_NAME}");
            let before = errors.len();
            if !ext.is_object() {
                errors.push(ext_error(&loc, "is not a JSON object"));
                continue;
            }
            let object = ext
                .get("object")
                .and_then(Value::as_u64)
                .and_then(|o| u32::try_from(o).ok());
            if object.is_none() {
                errors.push(ext_error(
                    format!("{loc}.object"),
                    "is missing or not an integer in 0..2^32",
                ));
            }
            let text = ext.get("geometryHash");
            let hash = text
                .and_then(Value::as_str)
                .filter(|h| {
                    h.len() == 16 && h.bytes().all(|c| matches!(c, b'0'..=b'9' | b'a'..=b'f'))
                })
                .and_then(|h| u64::from_str_radix(h, 16).ok());
            if hash.is_none() {
                let found = text.map_or("nothing".to_owned(), Value::to_string);
                errors.push(ext_error(
                    format!("{loc}.geometryHash"),
                    format!("must be 16 lowercase hexadecimal digits, found {found}"),
                ));
            }
            let first_triangle = match ext.get("firstTriangle") {
                None => Some(0),
                Some(v) => {
                    let f = v.as_u64().and_then(|f| u32::try_from(f).ok());
                    if f.is_none() {
                        errors.push(ext_error(
                            format!("{loc}.firstTriangle"),
                            "is not an integer in 0..2^32",
                        ));
                    }
                    f
                }
            };
            if let (Some(object), Some(geometry_hash), Some(first_triangle), true) =
                (object, hash, first_triangle, errors.len() == before)
            {
                out.push(PrimitiveLink {
                    mesh: m,
                    primitive: p,
                    object,
                    geometry_hash,
                    first_triangle,
                });
            }
        }
    }
    (out, errors)
}

/// The container bytes of an asset that uses the extension, or `None` if it does not.
pub fn container_bytes<'a>(
    json: &Value,
    buffers: &'a [Vec<u8>],
) -> Result<Option<&'a [u8]>, GltfError> {
    match root_link(json)? {
        None => Ok(None),
        Some(r) => buffer_view_bytes(json, buffers, r.buffer_view).map(Some),
    }
}

/// The geometry hash (SPEC.md 2.5) and triangle count of a triangle primitive, recomputed from
/// its POSITION accessor (decoded and dequantized, [`read_primitive`]) and indices.
pub fn primitive_geometry(
    json: &Value,
    buffers: &[Vec<u8>],
    mesh: usize,
    primitive: usize,
) -> Result<(u64, usize), GltfError> {
    let m = read_primitive(json, buffers, mesh, primitive)?;
    Ok((geometry_hash(m.corners_f32()), m.triangles.len()))
}

/// Formats a geometry hash as in the extension JSON.
pub fn hash_hex(hash: u64) -> String {
    format!("{hash:016x}")
}

fn object_mut<'a>(v: &'a mut Value, key: &str) -> Result<&'a mut Map<String, Value>, GltfError> {
    let root = v
        .as_object_mut()
        .ok_or_else(|| GltfError::Json("not an object".into()))?;
    root.entry(key.to_owned())
        .or_insert_with(|| json!({}))
        .as_object_mut()
        .ok_or_else(|| GltfError::Json(format!("\"{key}\" is not an object")))
}

fn array_mut<'a>(v: &'a mut Value, key: &str) -> Result<&'a mut Vec<Value>, GltfError> {
    let root = v
        .as_object_mut()
        .ok_or_else(|| GltfError::Json("not an object".into()))?;
    root.entry(key.to_owned())
        .or_insert_with(|| json!([]))
        .as_array_mut()
        .ok_or_else(|| GltfError::Json(format!("\"{key}\" is not an array")))
}

/// Appends `container` to the BIN buffer (buffer 0) at a 256-byte aligned offset, adds a buffer
/// view for it, points the root extension object at it and lists the extension in
/// `extensionsUsed` (never `extensionsRequired`). Returns the buffer view index. Buffer 0 is
/// created when the asset has none; its `byteLength` is updated.
pub fn embed_container(
    json: &mut Value,
    bin: &mut Vec<u8>,
    container: &[u8],
) -> Result<usize, GltfError> {
    let offset = bin.len().next_multiple_of(256);
    bin.resize(offset, 0);
    bin.extend_from_slice(container);
    let buffers = array_mut(json, "buffers")?;
    if buffers.is_empty() {
        buffers.push(json!({}));
    }
    let b0 = buffers[0]
        .as_object_mut()
        .ok_or_else(|| GltfError::Json("buffers[0] is not an object".into()))?;
    if b0.contains_key("uri") {
        return Err(GltfError::Json(
            "buffers[0] has a uri; the container goes into the GLB BIN chunk".into(),
        ));
    }
    b0.insert("byteLength".into(), json!(bin.len()));
    let views = array_mut(json, "bufferViews")?;
    views.push(json!({ "buffer": 0, "byteOffset": offset, "byteLength": container.len() }));
    let view = views.len() - 1;
    // The version of the container embedded (A.3): 1.0 without corner colours, 1.1 with them.
    let version = match container.get(8..12) {
        Some(v) => format!(
            "{}.{}",
            u16::from_le_bytes([v[0], v[1]]),
            u16::from_le_bytes([v[2], v[3]])
        ),
        None => format!("{}.{}", crate::MAJOR_VERSION, crate::MINOR_VERSION),
    };
    object_mut(json, "extensions")?.insert(
        EXTENSION_NAME.into(),
        json!({ "bufferView": view, "version": version }),
    );
    let used = array_mut(json, "extensionsUsed")?;
    if !used.iter().any(|e| e == EXTENSION_NAME) {
        used.push(json!(EXTENSION_NAME));
    }
    Ok(view)
}

/// Writes a primitive's extension object (SPEC.md 3.3).
pub fn link_primitive(json: &mut Value, link: &PrimitiveLink) -> Result<(), GltfError> {
    let loc = format!("meshes[{}].primitives[{}]", link.mesh, link.primitive);
    let prim = json
        .get_mut("meshes")
        .and_then(|m| m.get_mut(link.mesh))
        .and_then(|m| m.get_mut("primitives"))
        .and_then(|p| p.get_mut(link.primitive))
        .ok_or_else(|| GltfError::Json(format!("{loc} does not exist")))?;
    let mut ext = json!({ "object": link.object, "geometryHash": hash_hex(link.geometry_hash) });
    if link.first_triangle != 0 {
        ext["firstTriangle"] = json!(link.first_triangle);
    }
    object_mut(prim, "extensions")?.insert(EXTENSION_NAME.into(), ext);
    Ok(())
}

/// Serialises a GLB: JSON chunk padded with spaces, BIN chunk padded with zeros, both to 4 bytes
/// (glTF 2.0, 4.4.3). The BIN chunk is omitted when `bin` is empty.
pub fn write_glb(json: &Value, bin: &[u8]) -> Result<Vec<u8>, GltfError> {
    let mut text = serde_json::to_vec(json).map_err(|e| GltfError::Json(e.to_string()))?;
    text.resize(text.len().next_multiple_of(4), b' ');
    let bin_padded = bin.len().next_multiple_of(4);
    let total = 12 + 8 + text.len() + if bin.is_empty() { 0 } else { 8 + bin_padded };
    let total32 = u32::try_from(total)
        .map_err(|_| GltfError::Glb(format!("{total} bytes exceed the 4 GiB GLB limit")))?;
    let mut out = Vec::with_capacity(total);
    out.extend_from_slice(GLB_MAGIC);
    out.extend_from_slice(&2u32.to_le_bytes());
    out.extend_from_slice(&total32.to_le_bytes());
    out.extend_from_slice(&(text.len() as u32).to_le_bytes());
    out.extend_from_slice(&CHUNK_JSON.to_le_bytes());
    out.extend_from_slice(&text);
    if !bin.is_empty() {
        out.extend_from_slice(&(bin_padded as u32).to_le_bytes());
        out.extend_from_slice(&CHUNK_BIN.to_le_bytes());
        out.extend_from_slice(bin);
        out.resize(total, 0);
    }
    Ok(out)
}

/// A linked primitive as read once: its triangles and their geometry hash (SPEC.md 2.5).
struct LinkedMesh {
    hash: u64,
    mesh: PrimitiveMesh,
}

/// [`read_primitive`] for every link, reading each distinct (POSITION, indices, mode,
/// compression) combination once: the work stays linear in the buffers even when thousands of
/// primitives share one accessor.
fn linked_meshes(
    json: &Value,
    buffers: &[Vec<u8>],
    links: &[PrimitiveLink],
) -> Vec<Result<Rc<LinkedMesh>, GltfError>> {
    let mut cache: std::collections::HashMap<String, Result<Rc<LinkedMesh>, GltfError>> =
        std::collections::HashMap::new();
    links
        .iter()
        .map(|l| {
            let prim = json
                .get("meshes")
                .and_then(|m| m.get(l.mesh))
                .and_then(|m| m.get("primitives"))
                .and_then(|p| p.get(l.primitive));
            let key = match prim {
                Some(p) => format!(
                    "{}/{}/{}/{}",
                    p.get("attributes")
                        .and_then(|a| a.get("POSITION"))
                        .unwrap_or(&Value::Null),
                    p.get("indices").unwrap_or(&Value::Null),
                    p.get("mode").unwrap_or(&Value::Null),
                    p.get("extensions").and_then(|e| e.get(DRACO)).is_some()
                ),
                None => format!("missing {}/{}", l.mesh, l.primitive),
            };
            cache
                .entry(key)
                .or_insert_with(|| {
                    read_primitive(json, buffers, l.mesh, l.primitive).map(|mesh| {
                        Rc::new(LinkedMesh {
                            hash: geometry_hash(mesh.corners_f32()),
                            mesh,
                        })
                    })
                })
                .clone()
        })
        .collect()
}

/// [`primitive_geometry`] for every link (each distinct primitive read once): hash and
/// triangle count.
pub fn linked_geometries(
    json: &Value,
    buffers: &[Vec<u8>],
    links: &[PrimitiveLink],
) -> Vec<Result<(u64, usize), GltfError>> {
    linked_meshes(json, buffers, links)
        .into_iter()
        .map(|m| m.map(|m| (m.hash, m.mesh.triangles.len())))
        .collect()
}

/// Validates a glTF asset that uses the extension (SPEC.md 3.3, 3.5, Appendix C and E.2):
/// the root object and its buffer view, the embedded container (every rule of
/// [`crate::validate_bytes`]), and every primitive link: well-formed, object in range, one mesh
/// per object, triangle range inside the object and not overlapping another primitive's, the
/// same geometry as its range (SPEC.md 2.6). When the container cannot be read, the link checks
/// that need no object are still made. `buffers` are the asset's loaded buffers
/// ([`Asset::buffers`]). An empty result means the asset is valid; an asset that does not use
/// the extension is one problem. The warnings of [`validate_asset_report`] are left out.
pub fn validate_asset(json: &Value, buffers: &[Vec<u8>]) -> Vec<crate::Problem> {
    validate_asset_report(json, buffers).problems
}

/// What [`validate_asset_report`] finds: problems make the asset invalid; warnings do not
/// (a primitive that cannot be checked, SPEC.md 2.6, is drawn without its lighting).
#[derive(Clone, Debug, Default, PartialEq, Eq)]
pub struct AssetReport {
    pub problems: Vec<crate::Problem>,
    pub warnings: Vec<crate::Problem>,
}

/// [`validate_asset`] with its warnings.
pub fn validate_asset_report(json: &Value, buffers: &[Vec<u8>]) -> AssetReport {
    let mut p = crate::validate::Problems::default();
    let container = validate_root(json, buffers, &mut p);
    let (links, errors) = scan_primitive_links(json);
    for e in errors {
        push_error(&mut p, e);
    }
    let mut warnings = crate::validate::Problems::default();
    // Without a readable container the checks of rule 15 that read only the asset still run
    // (SPEC.md Appendix C, stages 1 and 2): an edited mesh is worth reporting either way.
    let _ = check_links_against(
        container.as_ref().map(|c| c.objects.as_slice()),
        json,
        buffers,
        &links,
        &mut LinkProblems {
            problems: &mut p,
            warnings: &mut warnings,
        },
    );
    AssetReport {
        problems: p.finish(),
        warnings: warnings.finish(),
    }
}

/// The validator's sink for link faults: every one, located, and on to the next check; a
/// primitive that cannot be checked is a warning.
struct LinkProblems<'a> {
    problems: &'a mut crate::validate::Problems,
    warnings: &'a mut crate::validate::Problems,
}

impl LinkSink for LinkProblems<'_> {
    fn fault(&mut self, link: &PrimitiveLink, at: &str, fault: LinkFault) -> LinkNext {
        if let LinkFault::Unchecked(e) = &fault {
            // The error names its own location; where that is the primitive's, say it once.
            let text = e.text_at(at);
            self.warnings.push(
                at,
                format!("{text}; loaders draw its plain primitive without the baked lighting"),
            );
            return LinkNext::Continue;
        }
        let (location, message) = fault.describe(link, at);
        self.problems.push(location, message);
        LinkNext::Continue
    }
}

/// What is wrong with one primitive link (SPEC.md 3.3, 3.5), as [`check_links`] finds it.
#[derive(Clone, Debug, PartialEq)]
pub enum LinkFault {
    /// The link names no object of the container, which has `objects`.
    ObjectOutOfRange { objects: usize },
    /// The object is linked from primitives of another mesh, `mesh`, too.
    OtherMesh { mesh: usize },
    /// The primitive's triangles cannot be read.
    Geometry(GltfError),
    /// The primitive's triangles are compressed in a way hce does not decode
    /// ([`GltfError::Compressed`]): it cannot be checked (SPEC.md 2.6).
    Unchecked(GltfError),
    /// The primitive's triangles hash to `computed`, not to the link's `geometryHash`, and
    /// there is no container (or no range inside it) to compare them with (SPEC.md 2.6).
    Stale { computed: u64, stored: u64 },
    /// The primitive's triangles hash to `computed`, not to `stored`, and the surface match of
    /// SPEC.md 2.6 fails against the object's range: the mesh was edited after baking.
    Edited {
        mismatch: Mismatch,
        computed: u64,
        stored: u64,
        name: String,
        end: u64,
    },
    /// The primitive is the whole object and hashes to its `geometryHash`, but not to the
    /// object's `geometry_hash`.
    WholeObject { computed: u64, stored: u64 },
    /// The primitive's triangles end at `end`, past the object's `triangles`.
    Range {
        end: u64,
        triangles: usize,
        name: String,
    },
    /// The primitive's triangle range overlaps that of the primitive at `other` (a location
    /// such as `meshes[0].primitives[1]`), an earlier range of the same object.
    Overlap { other: String },
    /// The primitive's placement (SPEC.md 2.6) differs from that of `other`, an earlier
    /// primitive of the same mesh and object.
    Placement { other: String },
}

impl LinkFault {
    /// The hashes of a stale primitive: computed and stored.
    pub fn stale_hashes(&self) -> Option<(u64, u64)> {
        match *self {
            LinkFault::Stale { computed, stored }
            | LinkFault::WholeObject { computed, stored }
            | LinkFault::Edited {
                computed, stored, ..
            } => Some((computed, stored)),
            _ => None,
        }
    }

    /// The fault as `hce validate` prints it (SPEC.md E.2): a location and a message.
    pub fn describe(&self, link: &PrimitiveLink, at: &str) -> (String, String) {
        let object_at = || format!("{at}.extensions.{EXTENSION_NAME}.object");
        match self {
            LinkFault::ObjectOutOfRange { objects } => (
                object_at(),
                format!(
                    "object {} is out of range; the container has {objects} objects (SPEC.md 3.5)",
                    link.object
                ),
            ),
            LinkFault::OtherMesh { mesh } => (
                object_at(),
                format!(
                    "object {} is already linked from meshes[{mesh}]; an object may be shared by primitives of one mesh only (instance the mesh instead) (SPEC.md 3.3)",
                    link.object
                ),
            ),
            LinkFault::Geometry(e) | LinkFault::Unchecked(e) => (at.to_owned(), e.text_at(at)),
            LinkFault::Stale { computed, stored } => (
                at.to_owned(),
                format!(
                    "geometry hash {computed:016x} differs from the baked {stored:016x}: the mesh was edited after baking; bake it again"
                ),
            ),
            LinkFault::Edited {
                mismatch,
                name,
                end,
                ..
            } => (
                at.to_owned(),
                format!(
                    "not the same geometry as object {} '{name}' triangles {}..{end} (SPEC.md 2.6): {mismatch}; the mesh was edited after baking; bake it again",
                    link.object, link.first_triangle
                ),
            ),
            LinkFault::WholeObject { computed, stored } => (
                at.to_owned(),
                format!(
                    "geometryHash {computed:016x} covers the whole of object {} but differs from its geometry_hash {stored:016x} (SPEC.md 3.3)",
                    link.object
                ),
            ),
            LinkFault::Range { end, triangles, .. } => (
                at.to_owned(),
                format!(
                    "triangles {}..{end} exceed object {}'s {triangles} triangles",
                    link.first_triangle, link.object
                ),
            ),
            LinkFault::Overlap { other } => (
                at.to_owned(),
                format!(
                    "triangle range overlaps that of {other} for object {} (SPEC.md 3.3)",
                    link.object
                ),
            ),
            LinkFault::Placement { other } => (
                at.to_owned(),
                format!(
                    "its placement onto object {} (SPEC.md 2.6) differs from that of {other}, a primitive of the same mesh and object; the object cannot be drawn in both places (SPEC.md 3.3)",
                    link.object
                ),
            ),
        }
    }
}

/// What [`check_links`] does after a fault, as its sink decides.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum LinkNext {
    /// Go on checking this link.
    Continue,
    /// Leave this link out: no further check of it, and not among the links that passed.
    SkipLink,
    /// End the check.
    Stop,
}

/// Where [`check_links`] reports faults: the validator collects them all, a loader rejects the
/// asset at the first (strict) or ignores the primitive with a warning (lenient, SPEC.md 3.5).
pub trait LinkSink {
    /// A fault of `link`, whose location is `at` (`meshes[m].primitives[p]`).
    fn fault(&mut self, link: &PrimitiveLink, at: &str, fault: LinkFault) -> LinkNext;
}

/// A link that passed [`check_links`], with where its object goes.
#[derive(Clone, Debug, PartialEq)]
pub struct CheckedLink {
    /// The index into the `links` given to [`check_links`].
    pub index: usize,
    /// The primitive's placement onto its object (SPEC.md 2.6): a loader that draws the object
    /// in this primitive's node draws it with the node's transform times
    /// [`Placement::inverse_columns`].
    pub placement: Placement,
}

/// The links that passed [`check_links`], in the order given.
#[derive(Clone, Debug, Default, PartialEq)]
pub struct CheckedLinks {
    pub links: Vec<CheckedLink>,
}

/// The check of every primitive link against the container's `objects`, written once (SPEC.md
/// 3.3, 3.5): the object in range and linked from one mesh only, the primitive's triangles
/// readable and the same geometry as its range (SPEC.md 2.6: the hash fast path, else the
/// surface match), inside the object and not overlapping another primitive's range, one
/// placement per mesh and object. Returns the links the sink did not skip, each with its
/// placement, or `Err(Stop)` when it stopped.
pub fn check_links(
    objects: &[crate::Object],
    json: &Value,
    buffers: &[Vec<u8>],
    links: &[PrimitiveLink],
    sink: &mut impl LinkSink,
) -> Result<CheckedLinks, crate::rules::Stop> {
    check_links_against(Some(objects), json, buffers, links, sink)
}

/// [`check_links`] with the container's objects, or `None` when the container cannot be read:
/// then only the checks that read the asset alone are made (one mesh per object, readable
/// triangles, `geometryHash`, no overlap), and those that need an object (in range, the range
/// inside it, its `geometry_hash`, the surface match) are skipped (SPEC.md Appendix C).
fn check_links_against(
    objects: Option<&[crate::Object]>,
    json: &Value,
    buffers: &[Vec<u8>],
    links: &[PrimitiveLink],
    sink: &mut impl LinkSink,
) -> Result<CheckedLinks, crate::rules::Stop> {
    let meshes = linked_meshes(json, buffers, links);
    let mut good: Vec<CheckedLink> = Vec::with_capacity(links.len());
    // (object, first triangle, end, location, link index) of each range that was read.
    let mut ranges: Vec<(u32, u64, u64, String, usize)> = Vec::new();
    let mut mesh_of: std::collections::HashMap<u32, usize> = std::collections::HashMap::new();
    // The first placement of each (object, mesh), and where it came from.
    let mut placed: std::collections::HashMap<(u32, usize), (Placement, String)> =
        std::collections::HashMap::new();
    'links: for (i, (l, g)) in links.iter().zip(meshes).enumerate() {
        let at = format!("meshes[{}].primitives[{}]", l.mesh, l.primitive);
        // Each fault: on, leave this link out, or stop.
        macro_rules! fault {
            ($f:expr) => {
                match sink.fault(l, &at, $f) {
                    LinkNext::Continue => {}
                    LinkNext::SkipLink => continue 'links,
                    LinkNext::Stop => return Err(crate::rules::Stop),
                }
            };
        }
        let object = match objects {
            Some(objects) => {
                let Some(object) = objects.get(l.object as usize) else {
                    fault!(LinkFault::ObjectOutOfRange {
                        objects: objects.len()
                    });
                    continue;
                };
                Some(object)
            }
            None => None,
        };
        match mesh_of.entry(l.object) {
            std::collections::hash_map::Entry::Vacant(v) => {
                v.insert(l.mesh);
            }
            std::collections::hash_map::Entry::Occupied(o) if *o.get() != l.mesh => {
                fault!(LinkFault::OtherMesh { mesh: *o.get() })
            }
            std::collections::hash_map::Entry::Occupied(_) => {}
        }
        let linked = match g {
            Ok(g) => g,
            Err(e @ GltfError::Compressed { .. }) => {
                fault!(LinkFault::Unchecked(e));
                continue;
            }
            Err(e) => {
                fault!(LinkFault::Geometry(e));
                continue;
            }
        };
        let (hash, triangles) = (linked.hash, linked.mesh.triangles.len());
        let end = u64::from(l.first_triangle) + triangles as u64;
        let inside = object.filter(|o| end <= o.triangles.len() as u64);
        let mut placement = Placement::identity(primitive_box(&linked.mesh));
        if hash == l.geometry_hash {
            if let Some(object) = object.filter(|o| {
                l.first_triangle == 0 && triangles == o.triangles.len() && hash != o.geometry_hash
            }) {
                fault!(LinkFault::WholeObject {
                    computed: hash,
                    stored: object.geometry_hash
                });
            }
        } else if let Some(object) = inside {
            let first = l.first_triangle as usize;
            let range = object
                .mesh
                .triangles
                .get(3 * first..3 * (first + triangles))
                .unwrap_or(&[]);
            match same_surface(&object.mesh.positions, range, &linked.mesh, first) {
                Ok(p) => placement = p,
                Err(mismatch) => fault!(LinkFault::Edited {
                    mismatch,
                    computed: hash,
                    stored: l.geometry_hash,
                    name: object.name.clone(),
                    end,
                }),
            }
        } else {
            fault!(LinkFault::Stale {
                computed: hash,
                stored: l.geometry_hash
            });
        }
        if let Some(object) = object.filter(|o| end > o.triangles.len() as u64) {
            fault!(LinkFault::Range {
                end,
                triangles: object.triangles.len(),
                name: object.name.clone(),
            });
        }
        match placed.entry((l.object, l.mesh)) {
            std::collections::hash_map::Entry::Vacant(v) => {
                v.insert((placement, at.clone()));
            }
            std::collections::hash_map::Entry::Occupied(o)
                if !o.get().0.agrees_with(&placement) =>
            {
                let other = o.get().1.clone();
                fault!(LinkFault::Placement { other })
            }
            std::collections::hash_map::Entry::Occupied(_) => {}
        }
        ranges.push((l.object, u64::from(l.first_triangle), end, at, i));
        good.push(CheckedLink {
            index: i,
            placement,
        });
    }
    ranges.sort();
    let mut skipped = vec![false; links.len()];
    for w in ranges.windows(2) {
        if w[0].0 == w[1].0 && w[1].1 < w[0].2 {
            let fault = LinkFault::Overlap {
                other: w[0].3.clone(),
            };
            match sink.fault(&links[w[1].4], &w[1].3, fault) {
                LinkNext::Continue => {}
                LinkNext::SkipLink => skipped[w[1].4] = true,
                LinkNext::Stop => return Err(crate::rules::Stop),
            }
        }
    }
    good.retain(|c| !skipped[c.index]);
    Ok(CheckedLinks { links: good })
}

fn push_error(p: &mut crate::validate::Problems, e: GltfError) {
    match e {
        GltfError::Extension { location, message } => {
            p.push(location, format!("{message} (SPEC.md 3.3)"))
        }
        other => p.push("file", other.to_string()),
    }
}

/// Whether the asset says anything of the extension: lists it in `extensionsUsed` or
/// `extensionsRequired`, or has its root or a primitive object. A file that says nothing was
/// never baked, or lost its baked lighting to a tool that drops unknown extensions whole; one
/// that says something is held to [`root_problems`].
pub fn mentions_extension(json: &Value) -> bool {
    let listed = |key: &str| {
        json.get(key)
            .and_then(Value::as_array)
            .is_some_and(|a| a.iter().any(|e| e == EXTENSION_NAME))
    };
    let primitives = json
        .get("meshes")
        .and_then(Value::as_array)
        .into_iter()
        .flatten()
        .filter_map(|m| m.get("primitives").and_then(Value::as_array))
        .flatten();
    listed("extensionsUsed")
        || listed("extensionsRequired")
        || json
            .pointer(&format!("/extensions/{EXTENSION_NAME}"))
            .is_some()
        || primitives.into_iter().any(|p| {
            p.pointer(&format!("/extensions/{EXTENSION_NAME}"))
                .is_some()
        })
}

/// The rules of the root object that need no buffer (SPEC.md 3.2, 3.3): `extensionsUsed` and
/// `extensionsRequired`, the root object and its version, the container's buffer view's keys and
/// alignment, as [`validate_asset`] reports them. A loader that reads the container itself
/// (the browser's) checks these first.
pub fn root_problems(json: &Value) -> Vec<crate::Problem> {
    let mut p = crate::validate::Problems::default();
    let _ = check_root(json, &mut p);
    p.finish()
}

/// [`root_problems`] into `p`; the root link when there is one.
fn check_root(json: &Value, p: &mut crate::validate::Problems) -> Option<RootLink> {
    let root_at = format!("extensions.{EXTENSION_NAME}");
    let listed = |key: &str| {
        json.get(key)
            .and_then(Value::as_array)
            .is_some_and(|a| a.iter().any(|e| e == EXTENSION_NAME))
    };
    if !listed("extensionsUsed") {
        p.push(
            "extensionsUsed",
            format!(
                "does not list {EXTENSION_NAME}; an asset that uses it MUST list it (SPEC.md 3.2)"
            ),
        );
    }
    if listed("extensionsRequired") {
        p.push(
            "extensionsRequired",
            format!("lists {EXTENSION_NAME}; it MUST NOT be required, loaders without it draw the plain meshes (SPEC.md 3.2)"),
        );
    }
    let link = match root_link(json) {
        Ok(Some(l)) => l,
        Ok(None) => {
            p.push(
                root_at,
                format!(
                    "missing: the asset does not use {EXTENSION_NAME}; bake it with `hce bake`"
                ),
            );
            return None;
        }
        Err(e) => {
            push_error(p, e);
            return None;
        }
    };
    if let Some(v) = json.get("extensions").and_then(|e| e.get(EXTENSION_NAME)) {
        match v.get("version") {
            None => {}
            Some(Value::String(s)) if is_version(s) => {}
            Some(other) => p.push(
                format!("{root_at}.version"),
                format!("{other} does not match \"major.minor\" (^[0-9]+\\.[0-9]+$, SPEC.md 3.3)"),
            ),
        }
    }
    let view_at = format!("bufferViews[{}]", link.buffer_view);
    if let Some(view) = json
        .get("bufferViews")
        .and_then(Value::as_array)
        .and_then(|v| v.get(link.buffer_view))
    {
        for key in ["byteStride", "target"] {
            if view.get(key).is_some() {
                p.push(
                    format!("{view_at}.{key}"),
                    "the container's buffer view MUST NOT have byteStride or target (SPEC.md 3.3)",
                );
            }
        }
        let offset = view.get("byteOffset").and_then(Value::as_u64).unwrap_or(0);
        if offset % 4 != 0 {
            p.push(
                format!("{view_at}.byteOffset"),
                format!("{offset} is not a multiple of 4 (SPEC.md 3.3; 256 is recommended)"),
            );
        }
    }
    Some(link)
}

/// The root object, `extensionsUsed` / `extensionsRequired` and the container's buffer view
/// (SPEC.md 3.2, 3.3); then the container itself. Returns the container when it could be read.
fn validate_root(
    json: &Value,
    buffers: &[Vec<u8>],
    p: &mut crate::validate::Problems,
) -> Option<crate::Container> {
    let root_at = format!("extensions.{EXTENSION_NAME}");
    let link = check_root(json, p)?;
    let bytes = match buffer_view_bytes(json, buffers, link.buffer_view) {
        Ok(b) => b,
        Err(e) => {
            p.push(format!("{root_at}.bufferView"), e.to_string());
            return None;
        }
    };
    crate::validate::validate_bytes_into(bytes, p)
}

/// `^[0-9]+\.[0-9]+$`, the schema's version pattern.
fn is_version(s: &str) -> bool {
    let digits = |x: &str| !x.is_empty() && x.bytes().all(|c| c.is_ascii_digit());
    s.split_once('.')
        .is_some_and(|(a, b)| digits(a) && digits(b))
}
