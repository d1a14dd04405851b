//! A minimal loader for plain (not yet baked) meshes, so `hce render` can preview any OBJ or
//! glTF: positions, triangle indices and `COLOR_0` when present, read by the same reader as
//! [`crate::load_mesh`] (the guards of [`crate::gltf_guard`], meshes placed by their nodes'
//! world transforms through [`crate::scene_graph`]). `hce_runtime::plain::to_flat_object` turns
//! it into the flat object the runtime's flat kernel draws. [`PlainMesh`] is plain data, there
//! without features; [`load_plain_mesh`] comes with feature `import`.

#[cfg(feature = "import")]
use std::path::Path;

#[cfg(feature = "import")]
use crate::import::{read_triangles, ImportError, Wanted};

/// Triangles with optional linear per-vertex colours.
#[derive(Clone, Debug, Default, PartialEq)]
pub struct PlainMesh {
    pub positions: Vec<f32>,
    pub indices: Vec<u32>,
    /// Linear `r, g, b` per vertex, from glTF `COLOR_0` or OBJ vertex colours.
    pub colours: Option<Vec<f32>>,
}

/// Grey for the vertices without colours of a partly coloured file.
#[cfg(feature = "import")]
const NO_COLOUR: [f32; 3] = [0.5; 3];

/// Loads every triangle primitive of every mesh instance of an OBJ, glTF or GLB file into one
/// mesh, in world space.
#[cfg(feature = "import")]
pub fn load_plain_mesh(path: &Path) -> Result<PlainMesh, ImportError> {
    let read = read_triangles(
        path,
        Wanted {
            normals: false,
            colours: true,
        },
    )?;
    Ok(PlainMesh {
        positions: read.positions.iter().flatten().copied().collect(),
        indices: read.triangles.iter().flatten().copied().collect(),
        colours: read
            .colours
            .map(|c| c.iter().flat_map(|c| c.unwrap_or(NO_COLOUR)).collect()),
    })
}

#[cfg(all(test, feature = "import"))]
mod tests {
    use super::*;

    /// A one-triangle glTF (with `COLOR_0`) whose mesh sits under a translated, mirrored node.
    fn translated_gltf(dir: &Path) -> std::path::PathBuf {
        let mut bin = Vec::new();
        for p in [[0.0f32, 0.0, 0.0], [1.0, 0.0, 0.0], [0.0, 1.0, 0.0]] {
            bin.extend(p.iter().flat_map(|c| c.to_le_bytes()));
        }
        for c in [[1.0f32, 0.0, 0.0], [0.0, 1.0, 0.0], [0.0, 0.0, 1.0]] {
            bin.extend(c.iter().flat_map(|c| c.to_le_bytes()));
        }
        std::fs::write(dir.join("translated.bin"), &bin).unwrap();
        let json = r#"{"asset":{"version":"2.0"},"scene":0,"scenes":[{"nodes":[0]}],
            "nodes":[{"translation":[0,5,0],"children":[1]},{"mesh":0,"scale":[-1,1,1]}],
            "meshes":[{"primitives":[{"attributes":{"POSITION":0,"COLOR_0":1}}]}],
            "buffers":[{"byteLength":72,"uri":"translated.bin"}],
            "bufferViews":[{"buffer":0,"byteOffset":0,"byteLength":36},
                {"buffer":0,"byteOffset":36,"byteLength":36}],
            "accessors":[{"bufferView":0,"componentType":5126,"count":3,"type":"VEC3","min":[0,0,0],"max":[1,1,0]},
                {"bufferView":1,"componentType":5126,"count":3,"type":"VEC3"}]}"#;
        let path = dir.join("translated.gltf");
        std::fs::write(&path, json).unwrap();
        path
    }

    #[test]
    fn a_mesh_under_a_translated_node_previews_where_the_node_puts_it() {
        let dir = tempfile::tempdir().unwrap();
        let mesh = load_plain_mesh(&translated_gltf(dir.path())).unwrap();
        // Moved up 5 by the parent, mirrored in x by the child.
        assert_eq!(
            mesh.positions,
            vec![0.0, 5.0, 0.0, -1.0, 5.0, 0.0, 0.0, 6.0, 0.0]
        );
        // The mirror reverses the winding, so the triangle still faces +z.
        assert_eq!(mesh.indices, vec![0, 2, 1]);
        assert_eq!(
            mesh.colours,
            Some(vec![1.0, 0.0, 0.0, 0.0, 1.0, 0.0, 0.0, 0.0, 1.0])
        );
    }

    #[test]
    fn hostile_buffers_are_errors_not_panics() {
        let dir = tempfile::tempdir().unwrap();
        let path = translated_gltf(dir.path());
        // COLOR_0 claims more elements than its view holds.
        let text = std::fs::read_to_string(&path).unwrap().replace(
            r#""count":3,"type":"VEC3"}]"#,
            r#""count":3000,"type":"VEC3"}]"#,
        );
        std::fs::write(&path, text).unwrap();
        let e = load_plain_mesh(&path).unwrap_err().to_string();
        assert!(e.contains("do not fit in bufferViews[1]"), "{e}");
    }
}
