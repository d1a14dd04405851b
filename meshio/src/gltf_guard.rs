//! Guards around the `gltf` crate for files that may be hostile: that crate's reader slices
//! buffers without checking, follows any buffer URI (absolute paths, `/dev/zero`) and indexes
//! some references before validating them, so a small file can make it panic, hang or allocate
//! without bound. Every glTF reader of hce goes through these checks: `open` (the JSON
//! pre-check, the `gltf` crate's parse, buffers loaded one by one through [`read_uri`]),
//! `check_accessor` before any accessor is read, and `panic_free` around the whole read for
//! the panics the checks miss. The baker's scene importer, the mesh reader of `hce subdivide`
//! and the preview reader of `hce render` all use `open`; the runtime, which parses glTF
//! without the `gltf` crate, reads external files through [`uri_path`] and
//! [`read_regular_file`].
//!
//! Only the URI functions are built without the `import` feature.

use std::path::{Component, Path, PathBuf};

use serde_json::Value;

/// The JSON of a `.gltf` or of a GLB's JSON chunk, parsed leniently (invalid UTF-8 replaced,
/// because the `gltf` crate's parser accepts invalid UTF-8 in content it skips); `None` when it
/// does not parse at all.
pub fn lenient_json(bytes: &[u8]) -> Option<Value> {
    let text = if bytes.starts_with(b"glTF") {
        let len = bytes
            .get(12..16)
            .map_or(0, |b| u32::from_le_bytes([b[0], b[1], b[2], b[3]]) as usize);
        bytes.get(20..20usize.saturating_add(len)).unwrap_or(&[])
    } else {
        bytes
    };
    serde_json::from_str::<Value>(&String::from_utf8_lossy(text)).ok()
}

/// Checks the references that `gltf-json`'s own validation indexes without checking.
pub fn precheck(json: &Value) -> Result<(), String> {
    let accessors = json
        .get("accessors")
        .and_then(|a| a.as_array())
        .map_or(0, Vec::len);
    let meshes = json.get("meshes").and_then(|m| m.as_array());
    for (m, mesh) in meshes.into_iter().flatten().enumerate() {
        let prims = mesh.get("primitives").and_then(|p| p.as_array());
        for (p, prim) in prims.into_iter().flatten().enumerate() {
            let attributes = prim.get("attributes").and_then(|a| a.as_object());
            for (name, index) in attributes.into_iter().flatten() {
                if index.as_u64().is_none_or(|i| i >= accessors as u64) {
                    return Err(format!(
                        "meshes[{m}].primitives[{p}].attributes.{name}: {index} is not an \
                         accessor index (the file has {accessors} accessors)"
                    ));
                }
            }
        }
    }
    Ok(())
}

/// Percent-encodes every byte but RFC 3986's unreserved characters, for a file name written
/// into a glTF `uri` or a URL path.
pub fn percent_encode(s: &str) -> String {
    s.bytes()
        .map(|b| match b {
            b'A'..=b'Z' | b'a'..=b'z' | b'0'..=b'9' | b'-' | b'.' | b'_' | b'~' => {
                (b as char).to_string()
            }
            _ => format!("%{b:02X}"),
        })
        .collect()
}

pub fn percent_decode(s: &str) -> String {
    let b = s.as_bytes();
    let mut out = Vec::with_capacity(b.len());
    let mut i = 0;
    while i < b.len() {
        let hex = |c: u8| (c as char).to_digit(16);
        if b[i] == b'%' && i + 2 < b.len() {
            if let (Some(h), Some(l)) = (hex(b[i + 1]), hex(b[i + 2])) {
                out.push((h * 16 + l) as u8);
                i += 3;
                continue;
            }
        }
        out.push(b[i]);
        i += 1;
    }
    String::from_utf8_lossy(&out).into_owned()
}

/// How far a relative URI may reach from the file that names it.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum UriScope {
    /// Anywhere relative to the file, `..` included: scenes an author bakes, whose buffers and
    /// textures often sit in a sibling folder.
    Relative,
    /// Only inside the file's folder (no `..`): baked assets a viewer opens, which may come
    /// from anywhere.
    Folder,
}

/// The file a URI names relative to `base`: percent-decoded, never absolute, never another
/// scheme, within `scope`. (`data:` URIs name no file; [`read_uri`] decodes them.)
pub fn uri_path(base: &Path, uri: &str, scope: UriScope) -> Result<PathBuf, String> {
    if uri.contains("://") {
        return Err("only relative file URIs and data URIs are supported".into());
    }
    let rel = percent_decode(uri);
    let rel = Path::new(&rel);
    for c in rel.components() {
        match c {
            Component::Normal(_) | Component::CurDir => {}
            Component::ParentDir if scope == UriScope::Relative => {}
            Component::ParentDir => {
                return Err("only relative paths inside the asset's folder are followed".into())
            }
            Component::RootDir | Component::Prefix(_) => {
                return Err(
                    "an absolute path is not a relative URI; give the file relative to \
                            the scene"
                        .into(),
                )
            }
        }
    }
    Ok(base.join(rel))
}

/// Reads a regular file: a device or a pipe (`/dev/zero`, a FIFO) would be read forever, so
/// only files whose size is known are read.
pub fn read_regular_file(p: &Path) -> Result<Vec<u8>, String> {
    let meta = std::fs::metadata(p).map_err(|e| format!("{}: {e}", p.display()))?;
    if !meta.is_file() {
        return Err(format!("{} is not a regular file", p.display()));
    }
    std::fs::read(p).map_err(|e| format!("{}: {e}", p.display()))
}

/// Reads a URI relative to `base` (a base64 `data:` URI is decoded in place), with `..`
/// allowed ([`UriScope::Relative`]): the reader of scenes being baked.
pub fn read_uri(base: &Path, uri: &str) -> Result<Vec<u8>, String> {
    if let Some(rest) = uri.strip_prefix("data:") {
        let (_, payload) = rest
            .split_once(";base64,")
            .ok_or("the data URI is not base64")?;
        return hce_format::decode_base64(payload).ok_or_else(|| "invalid base64".into());
    }
    read_regular_file(&uri_path(base, uri, UriScope::Relative)?)
}

/// Reads a URI relative to `base`; without a base only `data:` URIs can be read.
pub fn read_uri_from(base: Option<&Path>, uri: &str) -> Result<Vec<u8>, String> {
    match base {
        Some(base) => read_uri(base, uri),
        None if uri.starts_with("data:") => read_uri(Path::new(""), uri),
        None => Err("external files are not followed when importing from memory".into()),
    }
}

/// A glTF or GLB read through the guards.
#[cfg(feature = "import")]
pub struct GuardedGltf {
    /// The JSON, for [`crate::scene_graph::walk`] and whatever the document does not expose.
    pub json: Value,
    /// The `gltf` crate's validated document.
    pub document: gltf::Document,
    /// Every buffer's bytes, `None` where it could not be loaded.
    pub buffers: Vec<Option<Vec<u8>>>,
    /// Why each missing buffer is missing, naming it.
    pub buffer_problems: Vec<String>,
}

/// Why [`open`] refused a file.
#[cfg(feature = "import")]
#[derive(Debug)]
pub enum OpenError {
    /// A reference the `gltf` crate would follow unchecked.
    Invalid(String),
    /// The `gltf` crate's own parse or validation failed.
    Gltf(gltf::Error),
}

/// Parses a `.gltf` or `.glb` held in memory and loads its buffers: the GLB's BIN chunk,
/// `data:` URIs, and files relative to `base` through [`read_uri`] (none without a base).
/// Run it, and everything that reads the result, inside [`panic_free`].
#[cfg(feature = "import")]
pub fn open(bytes: &[u8], base: Option<&Path>) -> Result<GuardedGltf, OpenError> {
    // A file whose JSON does not parse is left to the `gltf` crate's better message.
    let json = lenient_json(bytes);
    if let Some(json) = &json {
        precheck(json).map_err(OpenError::Invalid)?;
    }
    let gltf::Gltf { document, blob } = if requires_handled(json.as_ref()) {
        // The `gltf` crate refuses a file that requires an extension it does not know.
        // KHR_mesh_quantization only widens the component types of POSITION, NORMAL and
        // TEXCOORD, which `AccessorUse::accepts` lets through and hce-format's reader decodes
        // (`read_dequantized`); EXT_mesh_gpu_instancing is expanded into nodes below. So the
        // document is validated without those entries.
        let gltf::Gltf { document, blob } =
            gltf::Gltf::from_slice_without_validation(bytes).map_err(OpenError::Gltf)?;
        let mut root = document.into_json();
        root.extensions_required
            .retain(|e| !HANDLED.contains(&e.as_str()));
        let document = gltf::Document::from_json(root).map_err(OpenError::Gltf)?;
        gltf::Gltf { document, blob }
    } else {
        gltf::Gltf::from_slice(bytes).map_err(OpenError::Gltf)?
    };
    let mut json = json.ok_or_else(|| OpenError::Invalid("the JSON cannot be read".into()))?;
    let mut buffer_problems = Vec::new();
    let buffers = load_buffers(&document, base, blob, &mut buffer_problems);
    let document = if crate::gpu_instancing::used(&json) {
        let loaded: Vec<Vec<u8>> = buffers
            .iter()
            .map(|b| b.clone().unwrap_or_default())
            .collect();
        crate::gpu_instancing::expand(&mut json, &loaded).map_err(OpenError::Invalid)?;
        let mut root: gltf::json::Root = serde_json::from_value(json.clone())
            .map_err(|e| OpenError::Invalid(format!("the expanded instances: {e}")))?;
        root.extensions_required
            .retain(|e| !HANDLED.contains(&e.as_str()));
        gltf::Document::from_json(root).map_err(OpenError::Gltf)?
    } else {
        document
    };
    Ok(GuardedGltf {
        json,
        document,
        buffers,
        buffer_problems,
    })
}

/// The extension that lets POSITION, NORMAL and TEXCOORD be integers (normalized or not).
#[cfg(feature = "import")]
pub const QUANTIZATION: &str = "KHR_mesh_quantization";

/// Required extensions whose content the readers handle themselves: [`QUANTIZATION`], and
/// `EXT_mesh_gpu_instancing`, which [`open`] expands into one node per instance.
#[cfg(feature = "import")]
const HANDLED: [&str; 2] = [QUANTIZATION, crate::gpu_instancing::EXTENSION];

/// Whether the file lists one of [`HANDLED`] in `extensionsRequired`.
#[cfg(feature = "import")]
fn requires_handled(json: Option<&Value>) -> bool {
    json.and_then(|j| j.get("extensionsRequired"))
        .and_then(Value::as_array)
        .is_some_and(|a| a.iter().any(|e| HANDLED.iter().any(|h| e == h)))
}

/// The values of accessor `a` as `f32`, integers dequantized as glTF 3.11 says (a normalized
/// signed `b`-bit value `c` is `max(c / (2^(b−1) − 1), −1)`, unsigned `c / (2^b − 1)`), by
/// hce-format's reader ([`hce_format::read_accessor`], the one the runtime and `hce validate`
/// read primitives with): for the component types KHR_mesh_quantization allows, which the
/// `gltf` crate's reader does not decode. `N` components per element.
#[cfg(feature = "import")]
pub fn read_dequantized<const N: usize>(
    json: &Value,
    buffers: &[Option<Vec<u8>>],
    a: &gltf::Accessor,
) -> Result<Vec<[f32; N]>, String> {
    // hce-format reads whole buffers; an accessor checked by `check_accessor` reads only loaded
    // ones, and the others are never touched.
    let loaded: Vec<Vec<u8>> = buffers
        .iter()
        .map(|b| b.clone().unwrap_or_default())
        .collect();
    let values = hce_format::read_accessor(json, &loaded, a.index()).map_err(|e| e.to_string())?;
    if values.components != N {
        return Err(format!(
            "accessors[{}] has {} components, not {N}",
            a.index(),
            values.components
        ));
    }
    Ok(values
        .values
        .chunks_exact(N)
        .map(|c| std::array::from_fn(|k| c[k] as f32))
        .collect())
}

/// The `VEC3` values of a POSITION or NORMAL accessor that [`check_accessor`] accepted:
/// through the `gltf` crate's reader (`read`) when they are `FLOAT`, through
/// [`read_dequantized`] when KHR_mesh_quantization made them integers. `None` when neither
/// can read them.
#[cfg(feature = "import")]
pub fn read_vec3<I: Iterator<Item = [f32; 3]>>(
    json: &Value,
    buffers: &[Option<Vec<u8>>],
    a: &gltf::Accessor,
    read: impl FnOnce() -> Option<I>,
) -> Option<Vec<[f32; 3]>> {
    if a.data_type() == gltf::accessor::DataType::F32 {
        read().map(Iterator::collect)
    } else {
        read_dequantized::<3>(json, buffers, a).ok()
    }
}

/// Runs a read and turns a panic into an error message. The checks of this module cover
/// every panic of the `gltf` crate we know of; this catches the ones we do not, so that a bad
/// file is an error, never a crash.
#[cfg(feature = "import")]
pub fn panic_free<T>(read: impl FnOnce() -> T) -> Result<T, String> {
    std::panic::catch_unwind(std::panic::AssertUnwindSafe(read)).map_err(|panic| {
        let what = panic
            .downcast_ref::<&str>()
            .map(|s| s.to_string())
            .or_else(|| panic.downcast_ref::<String>().cloned())
            .unwrap_or_default();
        format!("the glTF reader failed on this file ({what})")
    })
}

/// Every buffer's bytes, `None` where it could not be loaded (with a warning).
#[cfg(feature = "import")]
pub fn load_buffers(
    document: &gltf::Document,
    base: Option<&Path>,
    mut blob: Option<Vec<u8>>,
    warnings: &mut Vec<String>,
) -> Vec<Option<Vec<u8>>> {
    document
        .buffers()
        .map(|b| {
            let data = match b.source() {
                gltf::buffer::Source::Bin => blob
                    .take()
                    .ok_or_else(|| "the GLB has no BIN chunk for it".to_string()),
                gltf::buffer::Source::Uri(uri) => {
                    read_uri_from(base, uri).map_err(|e| format!("cannot load {uri:?}: {e}"))
                }
            };
            match data {
                Ok(d) if d.len() >= b.length() => Some(d),
                Ok(d) => {
                    warnings.push(format!(
                        "buffers[{}] has {} bytes but byteLength is {}; primitives reading \
                         from it are skipped",
                        b.index(),
                        d.len(),
                        b.length()
                    ));
                    None
                }
                Err(e) => {
                    warnings.push(format!(
                        "buffers[{}] is missing ({e}); primitives reading from it are skipped",
                        b.index()
                    ));
                    None
                }
            }
        })
        .collect()
}

/// The accessor layouts the `gltf` reader handles for each use; it reinterprets bytes by the
/// expected type (or reaches `unreachable!`), so anything else must be refused beforehand.
#[cfg(feature = "import")]
#[derive(Clone, Copy)]
pub enum AccessorUse {
    Position,
    Normal,
    TexCoord,
    Colour,
    Index,
}

#[cfg(feature = "import")]
impl AccessorUse {
    pub fn name(self) -> &'static str {
        match self {
            AccessorUse::Position => "POSITION",
            AccessorUse::Normal => "NORMAL",
            AccessorUse::TexCoord => "TEXCOORD_0",
            AccessorUse::Colour => "COLOR_0",
            AccessorUse::Index => "indices",
        }
    }

    pub fn accepts(self, a: &gltf::Accessor) -> bool {
        use gltf::accessor::{DataType as D, Dimensions as Dim};
        match self {
            // FLOAT, or the integers of KHR_mesh_quantization (read by `read_dequantized`).
            AccessorUse::Position => {
                a.dimensions() == Dim::Vec3 && !matches!(a.data_type(), D::U32)
            }
            AccessorUse::Normal => {
                a.dimensions() == Dim::Vec3
                    && (a.data_type() == D::F32
                        || (a.normalized() && matches!(a.data_type(), D::I8 | D::I16)))
            }
            AccessorUse::TexCoord => {
                matches!(a.data_type(), D::F32 | D::U8 | D::U16) && a.dimensions() == Dim::Vec2
            }
            AccessorUse::Colour => {
                matches!(a.data_type(), D::F32 | D::U8 | D::U16)
                    && matches!(a.dimensions(), Dim::Vec3 | Dim::Vec4)
            }
            AccessorUse::Index => {
                matches!(a.data_type(), D::U8 | D::U16 | D::U32) && a.dimensions() == Dim::Scalar
            }
        }
    }
}

/// Checks that an accessor has the layout its use needs and lies inside loaded data, so that
/// the `gltf` reader cannot panic.
#[cfg(feature = "import")]
pub fn check_accessor(
    a: &gltf::Accessor,
    use_: AccessorUse,
    buffers: &[Option<Vec<u8>>],
) -> Result<(), String> {
    let loc = format!("accessors[{}]", a.index());
    if !use_.accepts(a) {
        return Err(format!(
            "{loc} is {:?} {:?}, which glTF does not allow for {}",
            a.data_type(),
            a.dimensions(),
            use_.name()
        ));
    }
    if a.sparse().is_some() {
        return Err(format!("{loc} is sparse, which is not supported"));
    }
    let view = a.view().ok_or_else(|| format!("{loc} has no bufferView"))?;
    let data = buffers
        .get(view.buffer().index())
        .and_then(Option::as_ref)
        .ok_or_else(|| {
            format!(
                "{loc} reads buffers[{}], which is missing",
                view.buffer().index()
            )
        })?;
    let view_end = view.offset().checked_add(view.length());
    if view_end.is_none_or(|e| e > data.len()) {
        return Err(format!(
            "bufferViews[{}] runs past the end of its buffer",
            view.index()
        ));
    }
    let size = a.size();
    let stride = view.stride().unwrap_or(size);
    if stride < size {
        return Err(format!(
            "bufferViews[{}].byteStride {stride} is smaller than the {size}-byte elements of {loc}",
            view.index()
        ));
    }
    // The reader computes `count - 1` unchecked.
    if a.count() == 0 {
        return Err(format!("{loc} has count 0"));
    }
    let needed = (a.count() - 1)
        .checked_mul(stride)
        .and_then(|x| x.checked_add(a.offset()))
        .and_then(|x| x.checked_add(size));
    if needed.is_none_or(|n| n > view.length()) {
        return Err(format!(
            "{loc}: {} elements do not fit in bufferViews[{}]",
            a.count(),
            view.index()
        ));
    }
    Ok(())
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn percent_decoding() {
        assert_eq!(percent_decode("a%20b.bin"), "a b.bin");
        assert_eq!(percent_decode("100%"), "100%");
        assert_eq!(percent_decode("%4"), "%4");
        for name in ["a b#.bin", "ü/%x.png", "plain-name_1.~"] {
            assert_eq!(percent_decode(&percent_encode(name)), name);
        }
        assert_eq!(percent_encode("a b#.bin"), "a%20b%23.bin");
    }

    #[test]
    fn uris_stay_relative_and_folder_uris_stay_inside() {
        let base = Path::new("scenes");
        let ok = |uri, scope| uri_path(base, uri, scope);
        assert_eq!(
            ok("tex/a%20b.png", UriScope::Folder).unwrap(),
            Path::new("scenes/tex/a b.png")
        );
        assert_eq!(
            ok("../shared/x.bin", UriScope::Relative).unwrap(),
            Path::new("scenes/../shared/x.bin")
        );
        for (uri, scope, says) in [
            ("../x.bin", UriScope::Folder, "inside the asset's folder"),
            (
                "a/%2e%2e/%2e%2e/x.bin",
                UriScope::Folder,
                "inside the asset's folder",
            ),
            ("/dev/zero", UriScope::Relative, "absolute path"),
            ("%2Fetc%2Fpasswd", UriScope::Folder, "absolute path"),
            (
                "https://example.com/x.bin",
                UriScope::Relative,
                "only relative",
            ),
        ] {
            let e = ok(uri, scope).unwrap_err();
            assert!(e.contains(says), "{uri}: {e}");
        }
    }
}
