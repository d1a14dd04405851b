//! Scene import: glTF 2.0 (`.gltf`/`.glb`) and Wavefront OBJ with MTL into the solver's
//! [`Scene`].
//!
//! glTF: the default scene's node hierarchy with transforms, every triangle primitive,
//! reflectance = `baseColorFactor` × the average of `baseColorTexture` over each triangle (16
//! stratified nearest-texel samples, sRGB decoded), emission = `emissiveFactor` ×
//! `KHR_materials_emissive_strength`, and `KHR_lights_punctual` lights. OBJ: `Kd` and `Ke`.
//! Which objects are multiresolution: name patterns (`*` wildcards, matched against node and
//! mesh names, `all` for every object) or `"hce": {"multires": true}` in a node's extras.
//! Unsupported content is skipped with a warning naming it; a scene with no light source is an
//! error (raised by [`Scene::validate`]).

use std::path::Path;

use glam::{Mat4, Vec3};

use crate::scene::{LightKind, PunctualLight, Scene, SceneObject};

/// Import options.
#[derive(Clone, Debug, Default, PartialEq)]
pub struct ImportOptions {
    /// Name patterns of multiresolution objects (`*` matches any run of characters; `all`
    /// selects every object).
    pub multires: Vec<String>,
}

/// The scene and what was skipped or assumed.
#[derive(Debug)]
pub struct Imported {
    pub scene: Scene,
    pub warnings: Vec<String>,
}

/// Import failures.
#[derive(Debug, thiserror::Error)]
pub enum ImportError {
    #[error("{file}: {reason}")]
    Read { file: String, reason: String },
    #[error("{file}: unsupported file extension (use .gltf, .glb or .obj)")]
    UnknownFormat { file: String },
}

/// Whether `name` matches `pattern` with `*` wildcards.
pub fn matches(pattern: &str, name: &str) -> bool {
    if pattern == "all" || pattern == "*" {
        return true;
    }
    let parts: Vec<&str> = pattern.split('*').collect();
    if parts.len() == 1 {
        return pattern == name;
    }
    let mut rest = name;
    for (i, part) in parts.iter().enumerate() {
        if i == 0 {
            let Some(r) = rest.strip_prefix(part) else {
                return false;
            };
            rest = r;
        } else if i == parts.len() - 1 {
            return rest.ends_with(part);
        } else if let Some(at) = rest.find(part) {
            rest = &rest[at + part.len()..];
        } else {
            return false;
        }
    }
    true
}

fn is_multires(opts: &ImportOptions, names: &[&str]) -> bool {
    opts.multires
        .iter()
        .any(|p| names.iter().any(|n| matches(p, n)))
}

/// Imports a scene file, choosing the reader by extension.
pub fn import(path: &Path, opts: &ImportOptions) -> Result<Imported, ImportError> {
    let ext = path
        .extension()
        .and_then(|e| e.to_str())
        .map(str::to_ascii_lowercase)
        .unwrap_or_default();
    match ext.as_str() {
        "gltf" | "glb" => import_gltf(path, opts),
        "obj" => import_obj(path, opts),
        _ => Err(ImportError::UnknownFormat {
            file: path.display().to_string(),
        }),
    }
}

fn srgb_to_linear(c: f32) -> f32 {
    if c <= 0.04045 {
        c / 12.92
    } else {
        ((c + 0.055) / 1.055).powf(2.4)
    }
}

/// Average linear colour of `image` over the UV triangle `uv` (nearest texel, repeat wrap).
fn texture_average(image: &gltf::image::Data, uv: [[f32; 2]; 3]) -> Option<[f32; 3]> {
    use gltf::image::Format;
    let channels = match image.format {
        Format::R8G8B8 => 3,
        Format::R8G8B8A8 => 4,
        _ => return None,
    };
    let (w, h) = (image.width as usize, image.height as usize);
    if w == 0 || h == 0 || image.pixels.len() < w * h * channels {
        return None;
    }
    let mut sum = [0.0f32; 3];
    let mut rng = crate::element::Rng::new(w as u64, h as u64, 0x7e);
    let n = 16;
    for i in 0..n {
        let t = [Vec3::X, Vec3::Y, Vec3::Z];
        let b = crate::element::jittered_point(t, i, n, &mut rng);
        let u = b.x * uv[0][0] + b.y * uv[1][0] + b.z * uv[2][0];
        let v = b.x * uv[0][1] + b.y * uv[1][1] + b.z * uv[2][1];
        let x = ((u.rem_euclid(1.0) * w as f32) as usize).min(w - 1);
        let y = ((v.rem_euclid(1.0) * h as f32) as usize).min(h - 1);
        let px = &image.pixels[(y * w + x) * channels..];
        for c in 0..3 {
            sum[c] += srgb_to_linear(f32::from(px[c]) / 255.0);
        }
    }
    Some(sum.map(|s| s / n as f32))
}

/// Image index, texture coordinates of the corners and baseColorFactor of a textured triangle.
type TexturedTriangle = (usize, [[f32; 2]; 3], [f32; 3]);

fn import_gltf(path: &Path, opts: &ImportOptions) -> Result<Imported, ImportError> {
    let file = path.display().to_string();
    let (doc, buffers, images) = gltf::import(path).map_err(|e| ImportError::Read {
        file: file.clone(),
        reason: e.to_string(),
    })?;
    let mut scene = Scene::default();
    let mut warnings = Vec::new();
    let shared_images = std::sync::Arc::new(images);
    let images = &*shared_images;
    let Some(root_scene) = doc.default_scene().or_else(|| doc.scenes().next()) else {
        warnings.push(format!("{file}: no scene; nothing imported"));
        return Ok(Imported { scene, warnings });
    };
    let mut stack: Vec<(gltf::Node, Mat4)> =
        root_scene.nodes().map(|n| (n, Mat4::IDENTITY)).collect();
    stack.reverse();
    while let Some((node, parent)) = stack.pop() {
        let world = parent * Mat4::from_cols_array_2d(&node.transform().matrix());
        let node_name = node
            .name()
            .map(str::to_string)
            .unwrap_or_else(|| format!("node{}", node.index()));
        for child in node.children().collect::<Vec<_>>().into_iter().rev() {
            stack.push((child, world));
        }
        if let Some(light) = node.light() {
            let position = world.transform_point3(Vec3::ZERO).to_array();
            let direction = world
                .transform_vector3(Vec3::NEG_Z)
                .normalize_or_zero()
                .to_array();
            let kind = match light.kind() {
                gltf::khr_lights_punctual::Kind::Point => LightKind::Point,
                gltf::khr_lights_punctual::Kind::Directional => LightKind::Directional,
                gltf::khr_lights_punctual::Kind::Spot {
                    inner_cone_angle,
                    outer_cone_angle,
                } => LightKind::Spot {
                    inner_cone_angle,
                    outer_cone_angle,
                },
            };
            scene.lights.push(PunctualLight {
                name: light.name().unwrap_or(&node_name).to_string(),
                kind,
                position,
                direction,
                color: light.color(),
                intensity: light.intensity(),
                range: light.range(),
            });
        }
        let Some(mesh) = node.mesh() else { continue };
        let mesh_name = mesh.name().unwrap_or("").to_string();
        let extras_multires = node
            .extras()
            .as_ref()
            .and_then(|raw| serde_json::from_str::<serde_json::Value>(raw.get()).ok())
            .and_then(|v| v.get("hce")?.get("multires")?.as_bool())
            .unwrap_or(false);
        let mut obj = SceneObject::new(node_name.clone(), Vec::new(), Vec::new(), [0.0; 3]);
        // Per triangle: where a texture applies.
        let mut textured: Vec<Option<TexturedTriangle>> = Vec::new();
        obj.multires = extras_multires || is_multires(opts, &[&node_name, &mesh_name]);
        // A mirroring transform flips the winding.
        let flip = world.determinant() < 0.0;
        for (pi, prim) in mesh.primitives().enumerate() {
            let what = format!("{file}: node '{node_name}' mesh '{mesh_name}' primitive {pi}");
            if prim.mode() != gltf::mesh::Mode::Triangles {
                warnings.push(format!(
                    "{what}: mode {:?} is not triangles; skipped",
                    prim.mode()
                ));
                continue;
            }
            let reader = prim.reader(|b| buffers.get(b.index()).map(|d| &d.0[..]));
            let Some(positions) = reader.read_positions() else {
                warnings.push(format!("{what}: no POSITION attribute; skipped"));
                continue;
            };
            let positions: Vec<[f32; 3]> = positions
                .map(|p| world.transform_point3(Vec3::from(p)).to_array())
                .collect();
            let indices: Vec<u32> = match reader.read_indices() {
                Some(i) => i.into_u32().collect(),
                None => (0..positions.len() as u32).collect(),
            };
            if indices.iter().any(|&i| i as usize >= positions.len()) {
                warnings.push(format!("{what}: an index is out of range; skipped"));
                continue;
            }
            let uvs: Option<Vec<[f32; 2]>> =
                reader.read_tex_coords(0).map(|t| t.into_f32().collect());
            let material = prim.material();
            let pbr = material.pbr_metallic_roughness();
            let factor = pbr.base_color_factor();
            let texture = pbr.base_color_texture();
            if let Some(info) = &texture {
                if info.tex_coord() != 0 {
                    warnings.push(format!(
                        "{what}: baseColorTexture uses TEXCOORD_{}; only TEXCOORD_0 is read, \
                         texture ignored",
                        info.tex_coord()
                    ));
                }
            }
            let image_index = texture
                .as_ref()
                .filter(|i| i.tex_coord() == 0)
                .map(|i| i.texture().source().index())
                .filter(|&i| i < images.len());
            let image = image_index.map(|i| &images[i]);
            let strength = material.emissive_strength().unwrap_or(1.0);
            let emission = material.emissive_factor().map(|e| e * strength);
            let base = obj.positions.len() as u32;
            obj.positions.extend(&positions);
            let mut degenerate = 0;
            let mut unreadable_texture = false;
            for tri in indices.chunks_exact(3) {
                let mut t = [tri[0], tri[1], tri[2]];
                if flip {
                    t.swap(1, 2);
                }
                let [a, b, c] = t.map(|i| Vec3::from(positions[i as usize]));
                if (b - a).cross(c - a).length_squared() <= 0.0
                    || t[0] == t[1]
                    || t[1] == t[2]
                    || t[0] == t[2]
                {
                    degenerate += 1;
                    continue;
                }
                let mut rho = [factor[0], factor[1], factor[2]];
                let mut tex = None;
                if let (Some(img), Some(uv)) = (image, &uvs) {
                    let tri_uv = t.map(|i| uv[i as usize]);
                    match texture_average(img, tri_uv) {
                        Some(avg) => {
                            tex = image_index.map(|ii| (ii, tri_uv, rho));
                            for k in 0..3 {
                                rho[k] *= avg[k];
                            }
                        }
                        None => unreadable_texture = true,
                    }
                }
                textured.push(tex);
                obj.triangles.push(t.map(|i| i + base));
                obj.reflectance.push(rho.map(|x| x.clamp(0.0, 1.0)));
                obj.emission.push(emission);
            }
            if degenerate > 0 {
                warnings.push(format!("{what}: {degenerate} degenerate triangles skipped"));
            }
            if unreadable_texture {
                warnings.push(format!(
                    "{what}: baseColorTexture format not supported (8-bit RGB/RGBA only); \
                     baseColorFactor used alone"
                ));
            }
            if indices.len() % 3 != 0 {
                warnings.push(format!(
                    "{what}: index count is not a multiple of 3; tail ignored"
                ));
            }
        }
        if textured.iter().any(Option::is_some) {
            // Each element averages the texture over exactly the part of the triangle it
            // covers; untextured triangles keep their constant reflectance.
            let images = std::sync::Arc::clone(&shared_images);
            let constant = obj.reflectance.clone();
            obj.reflectance_fn =
                Some(std::sync::Arc::new(
                    move |t: usize, bary: [[f32; 3]; 3]| match textured.get(t).copied().flatten() {
                        Some((ii, uv, factor)) => {
                            let sub = bary.map(|b| {
                                [
                                    b[0] * uv[0][0] + b[1] * uv[1][0] + b[2] * uv[2][0],
                                    b[0] * uv[0][1] + b[1] * uv[1][1] + b[2] * uv[2][1],
                                ]
                            });
                            match texture_average(&images[ii], sub) {
                                Some(avg) => {
                                    [0, 1, 2].map(|k| (factor[k] * avg[k]).clamp(0.0, 1.0))
                                }
                                None => constant[t],
                            }
                        }
                        None => constant.get(t).copied().unwrap_or([0.0; 3]),
                    },
                ));
        }
        if !obj.triangles.is_empty() {
            scene.objects.push(obj);
        }
    }
    Ok(Imported { scene, warnings })
}

fn import_obj(path: &Path, opts: &ImportOptions) -> Result<Imported, ImportError> {
    let file = path.display().to_string();
    let load = tobj::LoadOptions {
        triangulate: true,
        single_index: false,
        ..Default::default()
    };
    let (models, materials) = tobj::load_obj(path, &load).map_err(|e| ImportError::Read {
        file: file.clone(),
        reason: e.to_string(),
    })?;
    let mut warnings = Vec::new();
    let materials = materials.unwrap_or_else(|e| {
        warnings.push(format!("{file}: materials not loaded ({e}); grey 0.5 used"));
        Vec::new()
    });
    let mut scene = Scene::default();
    for m in models {
        let mesh = &m.mesh;
        let positions: Vec<[f32; 3]> = mesh
            .positions
            .chunks_exact(3)
            .map(|p| [p[0], p[1], p[2]])
            .collect();
        let (rho, emission) = match mesh.material_id.and_then(|i| materials.get(i)) {
            Some(mat) => {
                let ke = mat.emissive.or_else(|| {
                    let v: Vec<f32> = mat
                        .unknown_param
                        .get("Ke")?
                        .split_whitespace()
                        .filter_map(|x| x.parse().ok())
                        .collect();
                    (v.len() == 3).then(|| [v[0], v[1], v[2]])
                });
                (mat.diffuse.unwrap_or([0.5; 3]), ke.unwrap_or([0.0; 3]))
            }
            None => ([0.5; 3], [0.0; 3]),
        };
        let mut obj = SceneObject::new(m.name.clone(), positions, Vec::new(), [0.0; 3]);
        obj.multires = is_multires(opts, &[&m.name]);
        let mut skipped = 0;
        for t in mesh.indices.chunks_exact(3) {
            let t = [t[0], t[1], t[2]];
            if t.iter().any(|&i| i as usize >= obj.positions.len()) {
                skipped += 1;
                continue;
            }
            let [a, b, c] = t.map(|i| Vec3::from(obj.positions[i as usize]));
            if (b - a).cross(c - a).length_squared() <= 0.0 {
                skipped += 1;
                continue;
            }
            obj.triangles.push(t);
            obj.reflectance.push(rho.map(|x| x.clamp(0.0, 1.0)));
            obj.emission.push(emission);
        }
        if skipped > 0 {
            warnings.push(format!(
                "{file}: object '{}': {skipped} degenerate or out-of-range triangles skipped",
                m.name
            ));
        }
        if !obj.triangles.is_empty() {
            scene.objects.push(obj);
        }
    }
    Ok(Imported { scene, warnings })
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn wildcard_patterns() {
        assert!(matches("bunny*", "bunny_hi"));
        assert!(matches("*wall*", "left_wall_2"));
        assert!(!matches("*wall", "wall_2"));
        assert!(matches("all", "x"));
        assert!(!matches("box", "boxes"));
    }

    #[test]
    fn obj_with_mtl_reads_diffuse_and_emission() {
        let dir = tempfile::tempdir().unwrap();
        std::fs::write(
            dir.path().join("s.mtl"),
            "newmtl lamp\nKd 0.2 0.3 0.4\nKe 5 5 5\n",
        )
        .unwrap();
        let obj = dir.path().join("s.obj");
        std::fs::write(
            &obj,
            "mtllib s.mtl\no panel\nv 0 0 0\nv 1 0 0\nv 1 1 0\nv 0 1 0\nusemtl lamp\nf 1 2 3 4\n",
        )
        .unwrap();
        let opts = ImportOptions {
            multires: vec!["pan*".into()],
        };
        let im = import(&obj, &opts).unwrap();
        let o = &im.scene.objects[0];
        assert_eq!(o.triangles.len(), 2);
        assert_eq!(o.reflectance[0], [0.2, 0.3, 0.4]);
        assert_eq!(o.emission[1], [5.0, 5.0, 5.0]);
        assert!(o.multires);
        assert!(im.scene.validate().is_ok());
    }

    #[test]
    fn gltf_nodes_lights_and_materials() {
        let dir = tempfile::tempdir().unwrap();
        // One triangle (positions as base64 floats) under a translated node, and a point light.
        let pos: Vec<f32> = vec![0.0, 0.0, 0.0, 1.0, 0.0, 0.0, 0.0, 1.0, 0.0];
        let bytes: Vec<u8> = pos.iter().flat_map(|f| f.to_le_bytes()).collect();
        std::fs::write(dir.path().join("b.bin"), &bytes).unwrap();
        let json = serde_json::json!({
            "asset": {"version": "2.0"},
            "extensionsUsed": ["KHR_lights_punctual", "KHR_materials_emissive_strength"],
            "extensions": {"KHR_lights_punctual": {"lights": [
                {"type": "point", "intensity": 7.0, "color": [1.0, 0.5, 0.25]}
            ]}},
            "scene": 0,
            "scenes": [{"nodes": [0, 1]}],
            "nodes": [
                {"name": "floor", "mesh": 0, "translation": [0.0, 0.0, 2.0],
                 "extras": {"hce": {"multires": true}}},
                {"name": "lamp", "translation": [0.0, 0.0, 5.0],
                 "extensions": {"KHR_lights_punctual": {"light": 0}}}
            ],
            "meshes": [{"name": "tri", "primitives": [
                {"attributes": {"POSITION": 0}, "material": 0},
                {"attributes": {"POSITION": 0}, "mode": 1}
            ]}],
            "materials": [{"pbrMetallicRoughness": {"baseColorFactor": [0.5, 0.6, 0.7, 1.0]},
                           "emissiveFactor": [1.0, 0.0, 0.0],
                           "extensions": {"KHR_materials_emissive_strength":
                                          {"emissiveStrength": 3.0}}}],
            "buffers": [{"uri": "b.bin", "byteLength": 36}],
            "bufferViews": [{"buffer": 0, "byteLength": 36}],
            "accessors": [{"bufferView": 0, "componentType": 5126, "count": 3, "type": "VEC3",
                           "min": [0.0, 0.0, 0.0], "max": [1.0, 1.0, 0.0]}]
        });
        let path = dir.path().join("s.gltf");
        std::fs::write(&path, json.to_string()).unwrap();
        let im = import(&path, &ImportOptions::default()).unwrap();
        let o = &im.scene.objects[0];
        assert!(o.multires);
        assert_eq!(o.positions[1], [1.0, 0.0, 2.0]);
        assert_eq!(o.reflectance[0], [0.5, 0.6, 0.7]);
        assert_eq!(o.emission[0], [3.0, 0.0, 0.0]);
        let l = &im.scene.lights[0];
        assert_eq!(
            (l.kind, l.intensity, l.position),
            (LightKind::Point, 7.0, [0.0, 0.0, 5.0])
        );
        assert!(
            im.warnings.iter().any(|w| w.contains("primitive 1")),
            "{:?}",
            im.warnings
        );
    }

    #[test]
    fn gltf_texture_is_averaged_per_element() {
        let dir = tempfile::tempdir().unwrap();
        // A 2 × 1 texture: left texel red, right texel green.
        let file = std::fs::File::create(dir.path().join("t.png")).unwrap();
        let mut enc = png::Encoder::new(std::io::BufWriter::new(file), 2, 1);
        enc.set_color(png::ColorType::Rgb);
        enc.set_depth(png::BitDepth::Eight);
        enc.write_header()
            .unwrap()
            .write_image_data(&[255, 0, 0, 0, 255, 0])
            .unwrap();
        let pos: [f32; 9] = [0.0, 0.0, 0.0, 1.0, 0.0, 0.0, 0.0, 1.0, 0.0];
        let uv: [f32; 6] = [0.0, 0.0, 1.0, 0.0, 0.0, 1.0];
        let bytes: Vec<u8> = pos
            .iter()
            .chain(&uv)
            .flat_map(|f| f.to_le_bytes())
            .collect();
        std::fs::write(dir.path().join("b.bin"), &bytes).unwrap();
        let json = serde_json::json!({
            "asset": {"version": "2.0"},
            "scenes": [{"nodes": [0]}],
            "nodes": [{"name": "floor", "mesh": 0}],
            "meshes": [{"primitives": [
                {"attributes": {"POSITION": 0, "TEXCOORD_0": 1}, "material": 0}
            ]}],
            "materials": [{"pbrMetallicRoughness": {"baseColorTexture": {"index": 0}},
                           "emissiveFactor": [1.0, 1.0, 1.0]}],
            "textures": [{"source": 0}],
            "images": [{"uri": "t.png"}],
            "buffers": [{"uri": "b.bin", "byteLength": 60}],
            "bufferViews": [{"buffer": 0, "byteLength": 36},
                            {"buffer": 0, "byteOffset": 36, "byteLength": 24}],
            "accessors": [
                {"bufferView": 0, "componentType": 5126, "count": 3, "type": "VEC3",
                 "min": [0.0, 0.0, 0.0], "max": [1.0, 1.0, 0.0]},
                {"bufferView": 1, "componentType": 5126, "count": 3, "type": "VEC2"}
            ]
        });
        let path = dir.path().join("s.gltf");
        std::fs::write(&path, json.to_string()).unwrap();
        let im = import(&path, &ImportOptions::default()).unwrap();
        let o = &im.scene.objects[0];
        let f = o
            .reflectance_fn
            .as_ref()
            .expect("textured object gets a hook");
        let key = |c| crate::element::ElemKey::root(0).child(c).barycentric();
        // Left child (u from 0.5 to 1) is green; Top child (u below 0.5) red.
        assert_eq!(f(0, key(1)), [0.0, 1.0, 0.0]);
        assert_eq!(f(0, key(0)), [1.0, 0.0, 0.0]);
        // The triangle's own average mixes both.
        let r = o.reflectance[0];
        assert!(r[0] > 0.2 && r[1] > 0.2 && r[2] == 0.0, "{r:?}");
    }
}
