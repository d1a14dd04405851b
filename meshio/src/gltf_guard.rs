//! Guards around the `gltf` crate for files that may be hostile: that crate's reader slices
//! buffers without checking, follows any buffer URI (absolute paths, `/dev/zero`) and indexes
//! some references before validating them, so a small file can make it panic, hang or allocate
//! without bound. Both glTF readers of hce (the runtime's mesh loader and the baker's scene
//! importer) go through these checks before they read any accessor.

use std::path::Path;

/// Checks the references that `gltf-json`'s own validation indexes without checking.
pub fn precheck(bytes: &[u8]) -> Result<(), String> {
    // Parsed leniently (invalid UTF-8 replaced), because the `gltf` crate's parser accepts
    // invalid UTF-8 in content it skips; a file that still does not parse is left to that
    // crate's better message.
    let text = if bytes.starts_with(b"glTF") {
        let len = bytes
            .get(12..16)
            .map_or(0, |b| u32::from_le_bytes([b[0], b[1], b[2], b[3]]) as usize);
        bytes.get(20..20usize.saturating_add(len)).unwrap_or(&[])
    } else {
        bytes
    };
    let Ok(json) = serde_json::from_str::<serde_json::Value>(&String::from_utf8_lossy(text)) else {
        return Ok(());
    };
    let json = &json;
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

/// Reads a URI relative to `base` (a base64 `data:` URI is decoded in place).
pub fn read_uri(base: &Path, uri: &str) -> Result<Vec<u8>, String> {
    if let Some(rest) = uri.strip_prefix("data:") {
        let (_, payload) = rest
            .split_once(";base64,")
            .ok_or("the data URI is not base64")?;
        return hce_format::gltf::decode_base64(payload).ok_or_else(|| "invalid base64".into());
    }
    if uri.contains("://") {
        return Err("only relative file URIs and data URIs are supported".into());
    }
    let rel = percent_decode(uri);
    if Path::new(&rel).is_absolute() {
        return Err(
            "an absolute path is not a relative URI; give the file relative to the scene".into(),
        );
    }
    let p = base.join(rel);
    // A device or a pipe (`/dev/zero`, a FIFO) would be read forever: only regular files,
    // whose size is known, are read.
    let meta = std::fs::metadata(&p).map_err(|e| format!("{}: {e}", p.display()))?;
    if !meta.is_file() {
        return Err(format!("{} is not a regular file", p.display()));
    }
    std::fs::read(&p).map_err(|e| format!("{}: {e}", p.display()))
}

/// Reads a URI relative to `base`; without a base only `data:` URIs can be read.
pub fn read_uri_from(base: Option<&Path>, uri: &str) -> Result<Vec<u8>, String> {
    match base {
        Some(base) => read_uri(base, uri),
        None if uri.starts_with("data:") => read_uri(Path::new(""), uri),
        None => Err("external files are not followed when importing from memory".into()),
    }
}

/// Every buffer's bytes, `None` where it could not be loaded (with a warning).
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
#[derive(Clone, Copy)]
pub enum AccessorUse {
    Position,
    Normal,
    TexCoord,
    Index,
}

impl AccessorUse {
    pub fn name(self) -> &'static str {
        match self {
            AccessorUse::Position => "POSITION",
            AccessorUse::Normal => "NORMAL",
            AccessorUse::TexCoord => "TEXCOORD_0",
            AccessorUse::Index => "indices",
        }
    }

    pub fn accepts(self, a: &gltf::Accessor) -> bool {
        use gltf::accessor::{DataType as D, Dimensions as Dim};
        match self {
            AccessorUse::Position | AccessorUse::Normal => {
                a.data_type() == D::F32 && a.dimensions() == Dim::Vec3
            }
            AccessorUse::TexCoord => {
                matches!(a.data_type(), D::F32 | D::U8 | D::U16) && a.dimensions() == Dim::Vec2
            }
            AccessorUse::Index => {
                matches!(a.data_type(), D::U8 | D::U16 | D::U32) && a.dimensions() == Dim::Scalar
            }
        }
    }
}

/// Checks that an accessor has the layout its use needs and lies inside loaded data, so that
/// the `gltf` reader cannot panic.
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
    }
}
