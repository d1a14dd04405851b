//! The cache key of a bake: a SHA-256 that names its output. A bake is deterministic (the same
//! bytes at any thread count) and reads nothing but its input files, so its output is a function
//! of those files' bytes, its parameters and the baker's version; the key is the SHA-256 of a
//! canonical document of exactly these. Build systems and `hce-batch` store outputs under it.
//!
//! The document (README.md, "Baking many assets") is one line of JSON, UTF-8, no whitespace,
//! with its members in this order:
//!
//! ```text
//! {"key_format":1,"hce":"0.1.0","inputs":[{"name":"scene.gltf","sha256":"9f86…"},…],"parameters":{"bf_epsilon":…,…}}
//! ```
//!
//! * `key_format`: [`KEY_FORMAT`], raised whenever the document changes shape.
//! * `hce`: the baker's package version.
//! * `inputs`: every file the import reads ([`hce_meshio::scene::input_files`]): the scene file
//!   as `scene.<ext>`, then the files it names by their path relative to it, sorted; each with
//!   the lower-case hex SHA-256 of its bytes, or `null` for a named file that cannot be read
//!   (the bake goes on without it, so its absence is part of the input).
//! * `parameters`: every parameter that can change the output, defaults filled in, sorted by
//!   name: those the container records ([`crate::pipeline::parameters_json`]), `multires` (the
//!   patterns, sorted, each once) and `output_format` (`glb`, `gltf` or `hce`). Nothing that
//!   cannot change the output takes part: not the thread count, the output's path or any other
//!   path, the time or the environment.
//!
//! Strings are written as JSON strings (`serde_json`'s escaping), numbers as the container's
//! `bake_parameters` writes them.

use std::collections::BTreeMap;
use std::io::Read;
use std::path::Path;

use hce_meshio::scene::{input_files, InputFile};
use serde_json::Value;
use sha2::{Digest, Sha256};

use crate::pipeline::{output_format, parameters_json, PipelineError, PipelineOptions};
use hce_meshio::scene::ImportError;

/// The version of the key document's shape.
pub const KEY_FORMAT: u32 = 1;

/// One input file with what the key saw of it.
#[derive(Clone, Debug, PartialEq, Eq)]
pub struct HashedInput {
    pub file: InputFile,
    /// Lower-case hex SHA-256 of the bytes; `None` when the file cannot be read.
    pub sha256: Option<String>,
    /// Its length in bytes, when read.
    pub bytes: Option<u64>,
}

/// A bake's key and everything it was computed from.
#[derive(Clone, Debug, PartialEq)]
pub struct CacheKey {
    pub inputs: Vec<HashedInput>,
    /// The canonical parameters, by name, each a JSON value.
    pub parameters: BTreeMap<String, Value>,
    /// The document whose SHA-256 is [`CacheKey::key`].
    pub document: String,
    /// Lower-case hex SHA-256 of [`CacheKey::document`].
    pub key: String,
}

/// The key of baking `input` with `options`, without baking. Fails as the bake would on
/// options it refuses, a scene file of unknown format or one that cannot be read.
pub fn cache_key(input: &Path, options: &PipelineOptions) -> Result<CacheKey, PipelineError> {
    let format = output_format(options)?;
    let mut inputs = Vec::new();
    for (i, file) in input_files(input)?.into_iter().enumerate() {
        let hashed = hash_file(&file.path);
        if i == 0 {
            // The scene file itself must be there: without it there is nothing to bake.
            if let Err(source) = hashed {
                return Err(ImportError::Io {
                    path: file.path,
                    source,
                }
                .into());
            }
        }
        let (sha256, bytes) = match hashed {
            Ok((h, n)) => (Some(h), Some(n)),
            Err(_) => (None, None),
        };
        inputs.push(HashedInput {
            file,
            sha256,
            bytes,
        });
    }
    let parameters = canonical_parameters(options, format);
    let document = key_document(&inputs, &parameters);
    let key = hex(&Sha256::digest(document.as_bytes()));
    Ok(CacheKey {
        inputs,
        parameters,
        document,
        key,
    })
}

/// Every parameter that can change the output of a bake with `options`, by name.
pub fn canonical_parameters(options: &PipelineOptions, format: &str) -> BTreeMap<String, Value> {
    let mut parameters: BTreeMap<String, Value> =
        match serde_json::from_str(&parameters_json(options)) {
            Ok(Value::Object(m)) => m.into_iter().collect(),
            _ => BTreeMap::new(),
        };
    let mut multires = options.import.multires.clone();
    multires.sort();
    multires.dedup();
    parameters.insert("multires".into(), Value::from(multires));
    parameters.insert("output_format".into(), Value::from(format));
    parameters
}

fn key_document(inputs: &[HashedInput], parameters: &BTreeMap<String, Value>) -> String {
    let string = |s: &str| Value::from(s).to_string();
    let inputs: Vec<String> = inputs
        .iter()
        .map(|i| {
            format!(
                "{{\"name\":{},\"sha256\":{}}}",
                string(&i.file.name),
                i.sha256.as_deref().map_or("null".into(), string)
            )
        })
        .collect();
    let parameters: Vec<String> = parameters
        .iter()
        .map(|(k, v)| format!("{}:{v}", string(k)))
        .collect();
    format!(
        "{{\"key_format\":{KEY_FORMAT},\"hce\":{},\"inputs\":[{}],\"parameters\":{{{}}}}}",
        string(env!("CARGO_PKG_VERSION")),
        inputs.join(","),
        parameters.join(",")
    )
}

/// The SHA-256 and length of a regular file's bytes, streamed.
fn hash_file(path: &Path) -> std::io::Result<(String, u64)> {
    if !std::fs::metadata(path)?.is_file() {
        return Err(std::io::Error::other("not a regular file"));
    }
    let mut file = std::fs::File::open(path)?;
    let mut hasher = Sha256::new();
    let mut buf = vec![0u8; 1 << 16];
    let mut total = 0u64;
    loop {
        let n = file.read(&mut buf)?;
        if n == 0 {
            break;
        }
        hasher.update(&buf[..n]);
        total += n as u64;
    }
    Ok((hex(&hasher.finalize()), total))
}

fn hex(bytes: &[u8]) -> String {
    bytes.iter().map(|b| format!("{b:02x}")).collect()
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn the_document_has_its_members_in_order_and_hashes_to_the_key() {
        let dir = tempfile::tempdir().unwrap();
        let scene = dir.path().join("a.obj");
        std::fs::write(
            &scene,
            "mtllib gone.mtl\nv 0 0 0\nv 1 0 0\nv 0 1 0\nf 1 2 3\n",
        )
        .unwrap();
        let k = cache_key(&scene, &PipelineOptions::default()).unwrap();
        let doc: Value = serde_json::from_str(&k.document).unwrap();
        assert!(
            k.document.starts_with("{\"key_format\":1,\"hce\":"),
            "{}",
            k.document
        );
        assert_eq!(doc["inputs"][0]["name"], "scene.obj");
        assert_eq!(doc["inputs"][1]["name"], "gone.mtl");
        assert_eq!(doc["inputs"][1]["sha256"], Value::Null);
        assert_eq!(doc["parameters"]["output_format"], "glb");
        assert_eq!(doc["parameters"]["levels"], 3);
        let names: Vec<&String> = doc["parameters"].as_object().unwrap().keys().collect();
        let mut sorted = names.clone();
        sorted.sort();
        assert_eq!(names, sorted);
        // SHA-256 of the empty string guards the digest and its hex.
        assert_eq!(
            hex(&Sha256::digest(b"")),
            "e3b0c44298fc1c149afbf4c8996fb92427ae41e4649b934ca495991b7852b855"
        );
        assert_eq!(k.key, hex(&Sha256::digest(k.document.as_bytes())));
        assert_eq!(
            k.inputs[0].bytes,
            Some(std::fs::metadata(&scene).unwrap().len())
        );
    }

    #[test]
    fn multires_patterns_are_a_set() {
        let mut a = PipelineOptions::default();
        a.import.multires = vec!["b*".into(), "a".into(), "b*".into()];
        let mut b = PipelineOptions::default();
        b.import.multires = vec!["a".into(), "b*".into()];
        assert_eq!(
            canonical_parameters(&a, "glb"),
            canonical_parameters(&b, "glb")
        );
    }

    #[test]
    fn a_refused_output_is_the_bakes_error() {
        let options = PipelineOptions {
            output: "x.png".into(),
            ..PipelineOptions::default()
        };
        let e = cache_key(Path::new("whatever.glb"), &options).unwrap_err();
        assert!(matches!(e, PipelineError::OutputExtension { .. }), "{e}");
    }
}
