//! Wavefront OBJ + MTL reader (through `tobj`): one object per OBJ model (`o`/`g` group),
//! materials from MTL `Kd`, `Ke` and `map_Kd`. OBJ has no units and no transforms: coordinates
//! are taken as metres in world space.

use super::{
    ImportError, ImportOptions, ImportedScene, Material, SceneObject, SourceFormat, Texture,
};
use glam::Mat4;
use std::path::Path;
use std::sync::Arc;

pub(super) fn import(path: &Path, options: &ImportOptions) -> Result<ImportedScene, ImportError> {
    let load = tobj::LoadOptions {
        single_index: true,
        triangulate: true,
        ignore_points: true,
        ignore_lines: true,
    };
    let (models, materials) = tobj::load_obj(path, &load).map_err(|e| match e {
        tobj::LoadError::OpenFileFailed => ImportError::Io {
            path: path.to_path_buf(),
            source: std::io::Error::new(std::io::ErrorKind::NotFound, "cannot open the file"),
        },
        e => ImportError::Obj {
            path: path.to_path_buf(),
            message: e.to_string(),
        },
    })?;
    let mut warnings = Vec::new();
    let materials = match materials {
        Ok(m) => m,
        Err(e) => {
            warnings.push(format!(
                "the MTL library cannot be read ({e}); every object gets the default white \
                 material"
            ));
            Vec::new()
        }
    };
    let base = path.parent().unwrap_or_else(|| Path::new("."));
    let materials: Vec<Material> = materials
        .iter()
        .map(|m| {
            let texture =
                m.diffuse_texture
                    .as_deref()
                    .and_then(|t| match load_texture(&base.join(t)) {
                        Ok(t) => Some(Arc::new(t)),
                        Err(e) => {
                            warnings.push(format!(
                            "material {:?}: map_Kd {t:?} cannot be read ({e}); Kd alone is used",
                            m.name
                        ));
                            None
                        }
                    });
            Material {
                name: Some(m.name.clone()),
                base_color: m.diffuse.unwrap_or([1.0; 3]),
                base_color_texture: texture,
                emission: m.emissive.unwrap_or([0.0; 3]).map(|e| e.max(0.0)),
                // OBJ carries no culling information; both sides receive light.
                double_sided: true,
            }
        })
        .collect();
    let mut objects = Vec::new();
    for (i, model) in models.iter().enumerate() {
        let mesh = &model.mesh;
        let loc = format!("object {i} {:?}", model.name);
        if mesh.indices.is_empty() {
            warnings.push(format!(
                "{loc} has no faces (points or lines only); skipped"
            ));
            continue;
        }
        let n = mesh.positions.len() / 3;
        if let Some(bad) = mesh.indices.iter().find(|&&v| v as usize >= n) {
            warnings.push(format!("{loc}: index {bad} is out of range; skipped"));
            continue;
        }
        let positions: Vec<[f32; 3]> = mesh
            .positions
            .chunks_exact(3)
            .map(|p| [p[0], p[1], p[2]])
            .collect();
        if positions.iter().flatten().any(|c| !c.is_finite()) {
            warnings.push(format!("{loc}: a vertex position is not finite; skipped"));
            continue;
        }
        let normals = (mesh.normals.len() == 3 * n).then(|| {
            mesh.normals
                .chunks_exact(3)
                .map(|p| [p[0], p[1], p[2]])
                .collect()
        });
        // OBJ's v runs upwards, glTF's downwards from the top-left corner.
        let uv0 = (mesh.texcoords.len() == 2 * n).then(|| {
            mesh.texcoords
                .chunks_exact(2)
                .map(|t| [t[0], 1.0 - t[1]])
                .collect()
        });
        let material = mesh.material_id.filter(|&m| m < materials.len());
        objects.push(SceneObject {
            name: model.name.clone(),
            node: None,
            node_name: None,
            mesh: i,
            mesh_name: Some(model.name.clone()),
            primitive: 0,
            transform: Mat4::IDENTITY,
            world_positions: positions.clone(),
            positions,
            normals,
            uv0,
            indices: mesh.indices.clone(),
            material,
            multires: options.selects(&[Some(&model.name)]),
        });
    }
    Ok(ImportedScene {
        path: path.to_path_buf(),
        format: SourceFormat::Obj,
        objects,
        materials,
        lights: Vec::new(),
        camera: None,
        warnings,
        summary: String::new(),
    })
}

fn load_texture(path: &Path) -> Result<Texture, String> {
    let img = image::open(path).map_err(|e| e.to_string())?.to_rgb8();
    Texture::from_srgb8(img.width(), img.height(), 3, img.as_raw())
        .ok_or_else(|| "the image is empty".into())
}
