//! glTF 2.0 reader: the default scene's node hierarchy with global transforms, every triangle
//! primitive, materials (baseColorFactor and baseColorTexture, emissiveFactor with
//! KHR_materials_emissive_strength), KHR_lights_punctual lights and the first camera;
//! KHR_mesh_quantization accessors, and EXT_mesh_gpu_instancing nodes as one node per instance
//! ([`crate::gpu_instancing`]).
//!
//! The file is opened through [`crate::gltf_guard::open`], whose buffers are loaded one by one
//! so that a missing or short buffer only drops the primitives that read from it; every
//! accessor is bounds-checked before the `gltf` crate's reader touches it, because that reader
//! slices without checking. Nodes are placed by [`crate::scene_graph::walk`].

use super::{
    ImportError, ImportOptions, ImportedObject, ImportedScene, LightKind, Material, Projection,
    PunctualLight, SceneCamera, SourceFormat, Texture, WrapMode,
};
use ::gltf::khr_lights_punctual::Kind;
use ::gltf::mesh::Mode;
use glam::{Mat4, Vec3};
use std::collections::BTreeMap;
use std::path::Path;
use std::sync::Arc;

use crate::gltf_guard::{
    check_accessor, panic_free, read_uri_from, read_vec3, AccessorUse as Use, OpenError,
};
use crate::scene_graph::walk;

/// Extensions whose content this reader uses (the rest are reported as ignored).
const SUPPORTED_EXTENSIONS: &[&str] = &["KHR_lights_punctual", "KHR_materials_emissive_strength"];

pub(super) fn import(path: &Path, options: &ImportOptions) -> Result<ImportedScene, ImportError> {
    let bytes = std::fs::read(path).map_err(|source| ImportError::Io {
        path: path.to_path_buf(),
        source,
    })?;
    import_bytes(
        path,
        Some(path.parent().unwrap_or_else(|| Path::new("."))),
        &bytes,
        options,
    )
}

/// Imports a `.glb` or `.gltf` held in memory. `path` names it in messages; external buffers
/// and images are read relative to `base`, or not at all (a warning each) when it is `None`.
pub(super) fn import_bytes(
    path: &Path,
    base: Option<&Path>,
    bytes: &[u8],
    options: &ImportOptions,
) -> Result<ImportedScene, ImportError> {
    panic_free(|| import_checked(path, base, bytes, options)).unwrap_or_else(|message| {
        Err(ImportError::Invalid {
            path: path.to_path_buf(),
            message: format!("invalid glTF: {message}"),
        })
    })
}

fn import_checked(
    path: &Path,
    base: Option<&Path>,
    bytes: &[u8],
    options: &ImportOptions,
) -> Result<ImportedScene, ImportError> {
    let format = if bytes.starts_with(b"glTF") {
        SourceFormat::Glb
    } else {
        SourceFormat::Gltf
    };
    let invalid = |message: String| ImportError::Invalid {
        path: path.to_path_buf(),
        message: format!("invalid glTF: {message}"),
    };
    let gltf = crate::gltf_guard::open(bytes, base).map_err(|e| match e {
        OpenError::Invalid(message) => invalid(message),
        OpenError::Gltf(source) => ImportError::Gltf {
            path: path.to_path_buf(),
            source,
        },
    })?;
    let document = &gltf.document;
    let buffers = &gltf.buffers;
    let mut warnings = Vec::new();

    // KHR_mesh_quantization is read (its integer positions and normals dequantized), and
    // EXT_mesh_gpu_instancing was expanded into nodes by `open`.
    for ext in document
        .extensions_used()
        .filter(|&e| e != crate::gltf_guard::QUANTIZATION)
    {
        if ext == hce_format::EXTENSION_NAME {
            warnings.push(format!(
                "{ext}: the input already carries baked lighting; it is ignored and replaced"
            ));
        } else if !SUPPORTED_EXTENSIONS.contains(&ext) {
            warnings.push(format!("extension {ext} is not supported and is ignored"));
        }
    }
    warnings.extend(gltf.buffer_problems.iter().cloned());
    let materials = read_materials(document, base, buffers, &mut warnings);

    let mut scene = ImportedScene {
        path: path.to_path_buf(),
        format,
        objects: Vec::new(),
        materials,
        lights: Vec::new(),
        camera: None,
        warnings: Vec::new(),
        summary: String::new(),
    };

    let walk = walk(&gltf.json).map_err(|e| invalid(e.to_string()))?;
    warnings.extend(walk.repeated_warnings());
    let nodes: Vec<::gltf::Node> = document.nodes().collect();
    for visit in &walk.visits {
        let node = &nodes[visit.node];
        let world = visit.world;
        if let Some(mesh) = node.mesh() {
            read_mesh_instance(
                node,
                &mesh,
                world,
                &gltf.json,
                buffers,
                options,
                &mut scene,
                &mut warnings,
            );
        }
        if let Some(light) = node.light() {
            let index = scene.lights.len();
            scene.lights.push(light_of(index, node, &light, world));
        }
        if let (Some(cam), None) = (node.camera(), &scene.camera) {
            scene.camera = Some(SceneCamera {
                node: node.index(),
                name: node.name().or(cam.name()).map(str::to_owned),
                transform: world,
                projection: match cam.projection() {
                    ::gltf::camera::Projection::Perspective(p) => Projection::Perspective {
                        yfov: p.yfov(),
                        aspect_ratio: p.aspect_ratio(),
                        znear: p.znear(),
                        zfar: p.zfar(),
                    },
                    ::gltf::camera::Projection::Orthographic(o) => Projection::Orthographic {
                        xmag: o.xmag(),
                        ymag: o.ymag(),
                        znear: o.znear(),
                        zfar: o.zfar(),
                    },
                },
            });
        }
    }
    scene.warnings = warnings;
    Ok(scene)
}

fn multires_extra(node: &::gltf::Node) -> bool {
    node.extras()
        .as_ref()
        .and_then(|raw| serde_json::from_str::<serde_json::Value>(raw.get()).ok())
        .and_then(|v| v.get("hce")?.get("multires")?.as_bool())
        .unwrap_or(false)
}

#[allow(clippy::too_many_arguments)]
fn read_mesh_instance(
    node: &::gltf::Node,
    mesh: &::gltf::Mesh,
    world: Mat4,
    json: &serde_json::Value,
    buffers: &[Option<Vec<u8>>],
    options: &ImportOptions,
    scene: &mut ImportedScene,
    warnings: &mut Vec<String>,
) {
    let multires = multires_extra(node) || options.selects(&[node.name(), mesh.name()]);
    let prim_count = mesh.primitives().len();
    for prim in mesh.primitives() {
        let loc = format!(
            "nodes[{}] {:?}: meshes[{}].primitives[{}]",
            node.index(),
            node.name().unwrap_or(""),
            mesh.index(),
            prim.index()
        );
        let mode = prim.mode();
        if mode != Mode::Triangles {
            warnings.push(format!(
                "{loc} has mode {mode:?}; only triangle lists (mode 4) are baked, it is skipped"
            ));
            continue;
        }
        let Some(pos_acc) = prim.get(&::gltf::Semantic::Positions) else {
            warnings.push(format!("{loc} has no POSITION; skipped"));
            continue;
        };
        let mut used = vec![(pos_acc.clone(), Use::Position)];
        used.extend(prim.indices().map(|a| (a, Use::Index)));
        if let Err(e) = used
            .iter()
            .try_for_each(|(a, u)| check_accessor(a, *u, buffers))
        {
            warnings.push(format!("{loc}: {e}; skipped"));
            continue;
        }
        let reader = prim.reader(|b| buffers.get(b.index()).and_then(|d| d.as_deref()));
        let Some(positions) = read_vec3(json, buffers, &pos_acc, || reader.read_positions()) else {
            warnings.push(format!("{loc}: POSITION cannot be read; skipped"));
            continue;
        };
        if positions.iter().flatten().any(|c| !c.is_finite()) {
            warnings.push(format!("{loc}: POSITION holds a non-finite value; skipped"));
            continue;
        }
        let n = positions.len();
        let indices: Vec<u32> = match reader.read_indices() {
            Some(i) => i.into_u32().collect(),
            None => match u32::try_from(n) {
                Ok(n) => (0..n).collect(),
                Err(_) => {
                    warnings.push(format!("{loc}: too many vertices; skipped"));
                    continue;
                }
            },
        };
        if indices.len() % 3 != 0 {
            warnings.push(format!(
                "{loc}: {} indices are not whole triangles; skipped",
                indices.len()
            ));
            continue;
        }
        if let Some(bad) = indices.iter().find(|&&i| i as usize >= n) {
            warnings.push(format!(
                "{loc}: index {bad} is out of range ({n} vertices); skipped"
            ));
            continue;
        }
        if indices.is_empty() {
            warnings.push(format!("{loc} has no triangles; skipped"));
            continue;
        }
        let normals = prim
            .get(&::gltf::Semantic::Normals)
            .filter(|a| match check_accessor(a, Use::Normal, buffers) {
                Ok(()) if a.count() == n => true,
                Ok(()) => {
                    warnings.push(format!(
                        "{loc}: NORMAL count differs from POSITION; ignored"
                    ));
                    false
                }
                Err(e) => {
                    warnings.push(format!("{loc}: NORMAL ignored: {e}"));
                    false
                }
            })
            .and_then(|a| read_vec3(json, buffers, &a, || reader.read_normals()));
        let uv0 = prim
            .get(&::gltf::Semantic::TexCoords(0))
            .filter(|a| match check_accessor(a, Use::TexCoord, buffers) {
                Ok(()) if a.count() == n => true,
                Ok(()) => {
                    warnings.push(format!(
                        "{loc}: TEXCOORD_0 count differs from POSITION; ignored"
                    ));
                    false
                }
                Err(e) => {
                    warnings.push(format!("{loc}: TEXCOORD_0 ignored: {e}"));
                    false
                }
            })
            .and_then(|_| reader.read_tex_coords(0))
            .map(|r| r.into_f32().collect::<Vec<_>>());
        let world_positions: Vec<[f32; 3]> = positions
            .iter()
            .map(|&p| world.transform_point3(Vec3::from(p)).to_array())
            .collect();
        if world_positions.iter().flatten().any(|c| !c.is_finite()) {
            warnings.push(format!(
                "{loc}: the node transform makes a position non-finite; skipped"
            ));
            continue;
        }
        let base_name = node
            .name()
            .map(str::to_owned)
            .or_else(|| mesh.name().map(str::to_owned))
            .unwrap_or_else(|| format!("node{}", node.index()));
        let name = if prim_count > 1 {
            format!("{base_name}#{}", prim.index())
        } else {
            base_name
        };
        scene.objects.push(ImportedObject {
            name,
            node: Some(node.index()),
            node_name: node.name().map(str::to_owned),
            mesh: mesh.index(),
            mesh_name: mesh.name().map(str::to_owned),
            primitive: prim.index(),
            transform: world,
            positions,
            normals,
            uv0,
            indices,
            world_positions,
            material: prim.material().index(),
            multires,
        });
    }
}

fn light_of(
    index: usize,
    node: &::gltf::Node,
    light: &::gltf::khr_lights_punctual::Light,
    world: Mat4,
) -> PunctualLight {
    let kind = match light.kind() {
        Kind::Point => LightKind::Point,
        Kind::Directional => LightKind::Directional,
        Kind::Spot {
            inner_cone_angle,
            outer_cone_angle,
        } => LightKind::Spot {
            inner_cone_angle,
            outer_cone_angle,
        },
    };
    PunctualLight {
        name: light
            .name()
            .or(node.name())
            .map_or_else(|| format!("light {index}"), str::to_owned),
        kind,
        position: world.transform_point3(Vec3::ZERO).to_array(),
        direction: world
            .transform_vector3(Vec3::NEG_Z)
            .normalize_or_zero()
            .to_array(),
        color: light.color(),
        intensity: light.intensity(),
        range: light.range(),
    }
}

fn wrap_mode(m: ::gltf::texture::WrappingMode) -> WrapMode {
    match m {
        ::gltf::texture::WrappingMode::ClampToEdge => WrapMode::ClampToEdge,
        ::gltf::texture::WrappingMode::MirroredRepeat => WrapMode::MirroredRepeat,
        ::gltf::texture::WrappingMode::Repeat => WrapMode::Repeat,
    }
}

/// Decodes an image into linear RGB, or says why it cannot be.
fn decode_image(
    image: &::gltf::Image,
    base: Option<&Path>,
    buffers: &[Option<Vec<u8>>],
) -> Result<Texture, String> {
    use ::gltf::image::Format;
    if let ::gltf::image::Source::View { view, .. } = image.source() {
        // `image::Data::from_source` slices the buffer without checking.
        let ok = buffers
            .get(view.buffer().index())
            .and_then(Option::as_ref)
            .is_some_and(|d| {
                view.offset()
                    .checked_add(view.length())
                    .is_some_and(|e| e <= d.len())
            });
        if !ok {
            return Err(format!(
                "bufferViews[{}] is missing or out of range",
                view.index()
            ));
        }
    }
    if let ::gltf::image::Source::Uri { uri, .. } = image.source() {
        if !uri.starts_with("data:") {
            // The `gltf` crate would read any path, devices included: read it here instead.
            let bytes = read_uri_from(base, uri)?;
            let img = image::load_from_memory(&bytes)
                .map_err(|e| e.to_string())?
                .to_rgb8();
            return Texture::from_srgb8(img.width(), img.height(), 3, img.as_raw())
                .ok_or_else(|| "the decoded image is empty".into());
        }
    }
    let data: Vec<::gltf::buffer::Data> = buffers
        .iter()
        .map(|b| ::gltf::buffer::Data(b.clone().unwrap_or_default()))
        .collect();
    let img =
        ::gltf::image::Data::from_source(image.source(), base, &data).map_err(|e| e.to_string())?;
    let (channels, wide) = match img.format {
        Format::R8 => (1, false),
        Format::R8G8 => (2, false),
        Format::R8G8B8 => (3, false),
        Format::R8G8B8A8 => (4, false),
        Format::R16 => (1, true),
        Format::R16G16 => (2, true),
        Format::R16G16B16 => (3, true),
        Format::R16G16B16A16 => (4, true),
        f => return Err(format!("pixel format {f:?} is not supported")),
    };
    // 16-bit channels keep their high byte: 8 bits are plenty for an average reflectance.
    let pixels: Vec<u8> = if wide {
        img.pixels.chunks_exact(2).map(|c| c[1]).collect()
    } else {
        img.pixels
    };
    // Two-channel images are luminance + alpha: the first channel is the grey level.
    let (pixels, channels) = if channels == 2 {
        (pixels.chunks_exact(2).map(|c| c[0]).collect(), 1)
    } else {
        (pixels, channels)
    };
    Texture::from_srgb8(img.width, img.height, channels, &pixels)
        .ok_or_else(|| "the decoded image is empty or truncated".into())
}

fn read_materials(
    document: &::gltf::Document,
    base: Option<&Path>,
    buffers: &[Option<Vec<u8>>],
    warnings: &mut Vec<String>,
) -> Vec<Material> {
    let mut decoded: BTreeMap<usize, Option<Arc<Texture>>> = BTreeMap::new();
    document
        .materials()
        .map(|m| {
            let loc = format!(
                "materials[{}] {:?}",
                m.index().unwrap_or(0),
                m.name().unwrap_or("")
            );
            let pbr = m.pbr_metallic_roughness();
            let f = pbr.base_color_factor();
            let texture = pbr.base_color_texture().and_then(|info| {
                if info.tex_coord() != 0 {
                    warnings.push(format!(
                        "{loc}: baseColorTexture uses TEXCOORD_{}; only TEXCOORD_0 is read, \
                         the texture is ignored",
                        info.tex_coord()
                    ));
                    return None;
                }
                let tex = info.texture();
                let image = tex.source();
                let entry = decoded.entry(image.index()).or_insert_with(|| {
                    match decode_image(&image, base, buffers) {
                        Ok(t) => Some(Arc::new(t)),
                        Err(e) => {
                            warnings.push(format!(
                                "images[{}] cannot be decoded ({e}); materials using it take \
                                 baseColorFactor alone",
                                image.index()
                            ));
                            None
                        }
                    }
                });
                entry.as_ref().map(|t| {
                    let sampler = tex.sampler();
                    let (s, t_mode) = (wrap_mode(sampler.wrap_s()), wrap_mode(sampler.wrap_t()));
                    if t.wrap_s == s && t.wrap_t == t_mode {
                        Arc::clone(t)
                    } else {
                        let mut t2 = Texture::clone(t);
                        t2.wrap_s = s;
                        t2.wrap_t = t_mode;
                        Arc::new(t2)
                    }
                })
            });
            if m.emissive_texture().is_some() {
                warnings.push(format!(
                    "{loc}: emissiveTexture is not supported; emissiveFactor alone is used"
                ));
            }
            let strength = m.emissive_strength().unwrap_or(1.0);
            Material {
                name: m.name().map(str::to_owned),
                base_color: [f[0], f[1], f[2]],
                base_color_texture: texture,
                emission: m.emissive_factor().map(|e| e * strength),
                double_sided: m.double_sided(),
            }
        })
        .collect()
}
