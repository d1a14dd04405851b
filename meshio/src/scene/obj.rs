//! Wavefront OBJ + MTL reader (through `tobj`): one object per OBJ model (`o`/`g` group),
//! materials from MTL `Kd`, `Ke` and `map_Kd`. OBJ has no units and no transforms: coordinates
//! are taken as metres in world space.

use super::{
    ImportError, ImportOptions, ImportedObject, ImportedScene, Material, SourceFormat, Texture,
};
use glam::Mat4;
use std::cell::RefCell;
use std::path::Path;
use std::sync::Arc;

const LOAD: tobj::LoadOptions = tobj::LoadOptions {
    single_index: true,
    triangulate: true,
    ignore_points: true,
    ignore_lines: true,
};

pub(super) fn import(path: &Path, options: &ImportOptions) -> Result<ImportedScene, ImportError> {
    let bytes = std::fs::read(path).map_err(|source| ImportError::Io {
        path: path.to_path_buf(),
        source,
    })?;
    let base = path.parent().unwrap_or_else(|| Path::new("."));
    let mtl_warnings = RefCell::new(Vec::new());
    let loaded = tobj::load_obj_buf(&mut &bytes[..], &LOAD, |mtl| {
        load_mtl(base, mtl, &mut mtl_warnings.borrow_mut())
    });
    let mut scene = finish(path, Some(base), loaded, points_and_lines(&bytes), options)?;
    scene.warnings.extend(mtl_warnings.into_inner());
    Ok(scene)
}

/// The MTL library `mtl` (as `mtllib` names it) beside an OBJ in `base`.
fn load_mtl(base: &Path, mtl: &Path, warnings: &mut Vec<String>) -> tobj::MTLLoadResult {
    // Only a regular file: a device or a pipe named by `mtllib` would be read forever.
    let p = base.join(mtl);
    if !std::fs::metadata(&p).is_ok_and(|m| m.is_file()) {
        return Err(tobj::LoadError::OpenFileFailed);
    }
    let text = std::fs::read(&p).map_err(|_| tobj::LoadError::OpenFileFailed)?;
    let (clean, w) = sanitize_mtl(&text);
    warnings.extend(w);
    tobj::load_mtl_buf(&mut &clean[..])
}

/// The files besides the OBJ itself that [`import`] reads, as the OBJ and its MTL libraries
/// name them: each `mtllib` library and each material's `map_Kd` texture, in the order named.
pub(super) fn referenced_files(bytes: &[u8], base: &Path) -> Vec<String> {
    let names = RefCell::new(Vec::new());
    let loaded = tobj::load_obj_buf(&mut &bytes[..], &LOAD, |mtl| {
        names.borrow_mut().push(mtl.to_string_lossy().into_owned());
        load_mtl(base, mtl, &mut Vec::new())
    });
    let mut names = names.into_inner();
    if let Ok((_, Ok(materials))) = loaded {
        names.extend(materials.into_iter().filter_map(|m| m.diffuse_texture));
    }
    names
}

/// Drops the colour lines (`Ka`, `Kd`, `Ks`, `Ke`) with fewer than three values, on which
/// `tobj` 4.0 panics instead of returning an error, with a warning naming each.
fn sanitize_mtl(mtl: &[u8]) -> (Vec<u8>, Vec<String>) {
    let mut out = Vec::with_capacity(mtl.len());
    let mut warnings = Vec::new();
    for (n, line) in mtl.split(|&b| b == b'\n').enumerate() {
        let text = String::from_utf8_lossy(line);
        let mut words = text.split_whitespace();
        let key = words.next();
        if matches!(key, Some("Ka" | "Kd" | "Ks" | "Ke")) && words.count() < 3 {
            warnings.push(format!(
                "MTL line {}: {:?} needs three values (r g b); the line is ignored",
                n + 1,
                text.trim()
            ));
            continue;
        }
        out.extend_from_slice(line);
        out.push(b'\n');
    }
    (out, warnings)
}

/// Imports an OBJ held in memory, with the bytes of the MTL library its `mtllib` names (any
/// name resolves to them); `map_Kd` textures are not read (a warning each).
pub(super) fn import_bytes(
    path: &Path,
    obj: &[u8],
    mtl: Option<&[u8]>,
    options: &ImportOptions,
) -> Result<ImportedScene, ImportError> {
    let (clean, mtl_warnings) = match mtl {
        Some(m) => {
            let (c, w) = sanitize_mtl(m);
            (Some(c), w)
        }
        None => (None, Vec::new()),
    };
    let loaded = tobj::load_obj_buf(&mut &obj[..], &LOAD, |_| match &clean {
        Some(m) => tobj::load_mtl_buf(&mut &m[..]),
        None => Err(tobj::LoadError::OpenFileFailed),
    });
    let mut scene = finish(path, None, loaded, points_and_lines(obj), options)?;
    scene.warnings.extend(mtl_warnings);
    Ok(scene)
}

/// How many point (`p`) and line (`l`) elements the OBJ text holds: they are not baked.
fn points_and_lines(obj: &[u8]) -> (usize, usize) {
    let (mut p, mut l) = (0, 0);
    for line in obj.split(|&b| b == b'\n') {
        let line = line.trim_ascii_start();
        if line.starts_with(b"p ") || line.starts_with(b"p\t") {
            p += 1;
        } else if line.starts_with(b"l ") || line.starts_with(b"l\t") {
            l += 1;
        }
    }
    (p, l)
}

fn finish(
    path: &Path,
    base: Option<&Path>,
    loaded: tobj::LoadResult,
    (points, lines): (usize, usize),
    options: &ImportOptions,
) -> Result<ImportedScene, ImportError> {
    let (models, materials) = loaded.map_err(|e| ImportError::Obj {
        path: path.to_path_buf(),
        message: e.to_string(),
    })?;
    let mut warnings = Vec::new();
    if points + lines > 0 {
        warnings.push(format!(
            "{points} point and {lines} line elements are not surfaces; they are skipped"
        ));
    }
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
    let materials: Vec<Material> = materials
        .iter()
        .map(|m| {
            let texture = m
                .diffuse_texture
                .as_deref()
                .and_then(|t| match load_texture(base, t) {
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
        objects.push(ImportedObject {
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

fn load_texture(base: Option<&Path>, name: &str) -> Result<Texture, String> {
    let base = base.ok_or("external files are not followed when importing from memory")?;
    let path = base.join(name);
    if !std::fs::metadata(&path).is_ok_and(|m| m.is_file()) {
        return Err(format!("{} is not a readable regular file", path.display()));
    }
    let img = image::open(path).map_err(|e| e.to_string())?.to_rgb8();
    Texture::from_srgb8(img.width(), img.height(), 3, img.as_raw())
        .ok_or_else(|| "the image is empty".into())
}
