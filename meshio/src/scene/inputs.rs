//! The files an import of a scene reads: the scene file and every external file it names (a
//! glTF's buffers and images by URI, an OBJ's `mtllib` libraries and their `map_Kd` textures).
//! A bake is a function of these files' bytes and its parameters, so a cache key over them
//! (`hce_bake::cache_key`) names the output. The references are found by the importers' own
//! rules ([`crate::gltf_guard::uri_path`] for glTF URIs, `tobj` for OBJ and MTL), so that the
//! list is what [`super::import_scene`] would open.

use std::path::{Component, Path, PathBuf};

use super::ImportError;
use crate::gltf_guard::{lenient_json, percent_decode, uri_path, UriScope};

/// One file an import reads.
#[derive(Clone, Debug, PartialEq, Eq)]
pub struct InputFile {
    /// The file's name within the asset, which never depends on where the asset lies: for the
    /// scene file itself `scene.` and its extension in lower case (only its format matters to
    /// the import), for the others the path relative to the scene file's folder as the scene
    /// names it (URIs percent-decoded), `/`-separated, without `.` components.
    pub name: String,
    /// Where it is read from.
    pub path: PathBuf,
}

/// The scene file at `path` and the files it names, the scene file first and the others by
/// name, each once. A named file that does not exist is listed all the same (its absence
/// changes the bake: the importer warns and goes on without it); a URI the importer refuses
/// (absolute, another scheme) names no file and is left out.
pub fn input_files(path: &Path) -> Result<Vec<InputFile>, ImportError> {
    let ext = path
        .extension()
        .and_then(|e| e.to_str())
        .map(str::to_ascii_lowercase);
    let ext = match ext.as_deref() {
        Some(e @ ("gltf" | "glb" | "obj")) => e.to_owned(),
        _ => {
            return Err(ImportError::UnknownFormat {
                path: path.to_path_buf(),
            })
        }
    };
    let bytes = std::fs::read(path).map_err(|source| ImportError::Io {
        path: path.to_path_buf(),
        source,
    })?;
    let base = path.parent().unwrap_or_else(|| Path::new("."));
    let mut others: Vec<InputFile> = if ext == "obj" {
        super::obj::referenced_files(&bytes, base)
            .into_iter()
            .map(|name| InputFile {
                path: base.join(&name),
                name: normalised(Path::new(&name)),
            })
            .collect()
    } else {
        gltf_uris(&bytes)
            .into_iter()
            .filter_map(|uri| {
                let path = uri_path(base, &uri, UriScope::Relative).ok()?;
                Some(InputFile {
                    path,
                    name: normalised(Path::new(&percent_decode(&uri))),
                })
            })
            .collect()
    };
    others.sort_by(|a, b| a.name.cmp(&b.name));
    others.dedup_by(|a, b| a.name == b.name);
    let mut files = vec![InputFile {
        name: format!("scene.{ext}"),
        path: path.to_path_buf(),
    }];
    files.extend(others);
    Ok(files)
}

/// The file URIs (not `data:`) of a glTF's buffers and images: the files its importer reads.
fn gltf_uris(bytes: &[u8]) -> Vec<String> {
    let Some(json) = lenient_json(bytes) else {
        return Vec::new();
    };
    ["buffers", "images"]
        .iter()
        .filter_map(|k| json.get(k).and_then(|v| v.as_array()))
        .flatten()
        .filter_map(|item| item.get("uri").and_then(|u| u.as_str()))
        .filter(|uri| !uri.starts_with("data:"))
        .map(str::to_owned)
        .collect()
}

/// `p` with `/` between its components and its `.` components dropped (`..` kept).
fn normalised(p: &Path) -> String {
    p.components()
        .filter(|c| !matches!(c, Component::CurDir))
        .map(|c| c.as_os_str().to_string_lossy().into_owned())
        .collect::<Vec<_>>()
        .join("/")
}

#[cfg(test)]
mod tests {
    use super::*;

    fn names(files: &[InputFile]) -> Vec<&str> {
        files.iter().map(|f| f.name.as_str()).collect()
    }

    #[test]
    fn a_gltf_lists_its_external_buffers_and_images_once_each() {
        let dir = tempfile::tempdir().unwrap();
        let gltf = dir.path().join("Room.GLTF");
        std::fs::write(
            &gltf,
            r#"{"asset":{"version":"2.0"},
                "buffers":[{"byteLength":4,"uri":"./bin/a%20b.bin"},{"byteLength":4,"uri":"data:application/octet-stream;base64,AAAAAA=="}],
                "images":[{"uri":"../tex/wood.png"},{"uri":"../tex/wood.png"},{"uri":"file:///etc/passwd"}]}"#,
        )
        .unwrap();
        let files = input_files(&gltf).unwrap();
        assert_eq!(
            names(&files),
            ["scene.gltf", "../tex/wood.png", "bin/a b.bin"]
        );
        assert_eq!(files[0].path, gltf);
        assert_eq!(files[2].path, dir.path().join("bin/a b.bin"));
    }

    #[test]
    fn an_obj_lists_its_libraries_and_their_textures() {
        let dir = tempfile::tempdir().unwrap();
        std::fs::write(
            dir.path().join("m.obj"),
            "mtllib mats/room.mtl\nv 0 0 0\nv 1 0 0\nv 0 1 0\nusemtl a\nf 1 2 3\n",
        )
        .unwrap();
        std::fs::create_dir(dir.path().join("mats")).unwrap();
        std::fs::write(
            dir.path().join("mats/room.mtl"),
            "newmtl a\nKd 1 1 1\nmap_Kd wood.png\n",
        )
        .unwrap();
        let files = input_files(&dir.path().join("m.obj")).unwrap();
        // tobj resolves a texture against the OBJ's folder, as the importer does.
        assert_eq!(names(&files), ["scene.obj", "mats/room.mtl", "wood.png"]);
        assert_eq!(files[2].path, dir.path().join("wood.png"));
    }

    #[test]
    fn an_unknown_extension_is_an_error() {
        let e = input_files(Path::new("x.png")).unwrap_err();
        assert!(matches!(e, ImportError::UnknownFormat { .. }), "{e}");
    }
}
