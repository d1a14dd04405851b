//! The glTF JSON and buffer reading that the extension's reader (`gltf`) and the accessor
//! readers (`accessor`, `meshopt`) share: the error type, checked lookups into the JSON's
//! arrays, and a buffer view's bytes. Its own module so that `gltf`, which uses the accessor
//! readers, and those readers do not import each other.

use serde_json::Value;

/// Why an asset cannot be read or extended.
#[derive(Debug, thiserror::Error, Clone, PartialEq, Eq)]
pub enum GltfError {
    #[error("GLB: {0} (glTF 2.0 specification, section 4.4 GLB File Format)")]
    Glb(String),
    #[error("glTF JSON: {0}")]
    Json(String),
    #[error("{location}: {message} (SPEC.md 3.3)")]
    Extension { location: String, message: String },
    #[error("buffers[{index}]: {message}")]
    Buffer { index: usize, message: String },
    /// Data compressed with an extension hce's readers do not decode (SPEC.md 2.6).
    #[error(
        "{location}: cannot check: {extension}-compressed data is not decoded by hce (SPEC.md 2.6)"
    )]
    Compressed { location: String, extension: String },
}

impl GltfError {
    /// The message as it reads after `at: ` (a located error's text without its location when
    /// that is `at`): for the messages that name the place they are about themselves.
    pub fn text_at(&self, at: &str) -> String {
        let text = self.to_string();
        match text.strip_prefix(at).and_then(|t| t.strip_prefix(": ")) {
            Some(rest) => rest.to_owned(),
            None => text,
        }
    }
}

pub(crate) fn index_of(v: &Value, key: &str, loc: &str) -> Result<usize, GltfError> {
    v.get(key)
        .and_then(Value::as_u64)
        .and_then(|i| usize::try_from(i).ok())
        .ok_or_else(|| GltfError::Json(format!("{loc}.{key} is missing or not an index")))
}

pub(crate) fn item<'a>(json: &'a Value, array: &str, i: usize) -> Result<&'a Value, GltfError> {
    json.get(array)
        .and_then(Value::as_array)
        .and_then(|a| a.get(i))
        .ok_or_else(|| GltfError::Json(format!("{array}[{i}] does not exist")))
}

/// The bytes of a buffer view.
pub fn buffer_view_bytes<'a>(
    json: &Value,
    buffers: &'a [Vec<u8>],
    view: usize,
) -> Result<&'a [u8], GltfError> {
    let loc = format!("bufferViews[{view}]");
    let v = item(json, "bufferViews", view)?;
    let buffer = index_of(v, "buffer", &loc)?;
    let offset = v.get("byteOffset").and_then(Value::as_u64).unwrap_or(0);
    let length = v
        .get("byteLength")
        .and_then(Value::as_u64)
        .ok_or_else(|| GltfError::Json(format!("{loc}.byteLength is missing")))?;
    let data = buffers
        .get(buffer)
        .ok_or_else(|| GltfError::Json(format!("{loc}.buffer {buffer} does not exist")))?;
    let end = offset
        .checked_add(length)
        .filter(|&e| e <= data.len() as u64)
        .ok_or_else(|| {
            GltfError::Json(format!(
                "{loc}: bytes {offset}+{length} run past buffer {buffer} ({} bytes)",
                data.len()
            ))
        })?;
    Ok(&data[offset as usize..end as usize])
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn a_located_message_drops_its_location_only_where_it_is_the_one_asked_for() {
        let e = GltfError::Compressed {
            location: "meshes[0].primitives[0]".into(),
            extension: "KHR_draco_mesh_compression".into(),
        };
        assert_eq!(
            e.text_at("meshes[0].primitives[0]"),
            "cannot check: KHR_draco_mesh_compression-compressed data is not decoded by hce (SPEC.md 2.6)"
        );
        // Another place (a prefix of it, too) keeps the whole message.
        assert_eq!(e.text_at("meshes[0]"), e.to_string());
        assert_eq!(e.text_at("meshes[1].primitives[0]"), e.to_string());
        let json = GltfError::Json("accessors[3] does not exist".into());
        assert_eq!(json.text_at("meshes[0].primitives[0]"), json.to_string());
    }
}
