//! A minimal glTF 2.0 binary (GLB) writer for [`Scene`]s, through `gltf-json`.
//!
//! Layout (glTF 2.0 specification, section 4.4 "Binary glTF Layout"): a 12-byte header, a JSON
//! chunk padded with spaces and a BIN chunk padded with zeros, both to 4 bytes. Every primitive
//! gets three tightly packed buffer views (POSITION, NORMAL, indices), each starting on a 4-byte
//! boundary. One node per object, each with its own mesh: baked data is attached per mesh
//! primitive, so two nodes must never share a mesh.
//!
//! Output vertices are split per smoothing group (see [`crate::mesh`]), so hard edges come out
//! as split normals. Positions are snapped to 2⁻²⁰ (see [`snap`]) before the normals are
//! computed, which makes the bytes independent of the platform's `sin`/`cos`. JSON keys come
//! out in `gltf-json`'s struct order, so the bytes do not depend on `serde_json` features.

use std::collections::BTreeMap;

use gltf_json as json;
use json::validation::{Checked, USize64};

use crate::mesh::snap;
use crate::scene::Scene;

/// Why a scene could not be written.
#[derive(Debug, thiserror::Error)]
pub enum GlbError {
    #[error("object {object:?}, primitive {primitive}: no triangles; drop the primitive")]
    EmptyPrimitive { object: String, primitive: usize },
    #[error(
        "object {object:?}, primitive {primitive}: material {material} does not exist \
         (the scene has {count})"
    )]
    MissingMaterial {
        object: String,
        primitive: usize,
        material: usize,
        count: usize,
    },
    #[error(
        "object {object:?}, primitive {primitive}: vertex {vertex} has a zero normal \
         (its triangles are degenerate); weld the mesh first"
    )]
    ZeroNormal {
        object: String,
        primitive: usize,
        vertex: u32,
    },
    #[error("the binary chunk would be {0} bytes, more than GLB's 32-bit lengths allow")]
    TooLarge(u64),
    #[error("serialising the glTF JSON: {0}")]
    Json(#[from] json::Error),
}

/// Vertices of one primitive as written: split per smoothing group, in order of first use.
struct Split {
    positions: Vec<[f32; 3]>,
    normals: Vec<[f32; 3]>,
    indices: Vec<u32>,
}

fn split_vertices(
    prim: &crate::scene::Primitive,
    object: &str,
    primitive: usize,
) -> Result<Split, GlbError> {
    let mesh = &prim.mesh;
    let snapped: Vec<glam::DVec3> = mesh.positions.iter().map(|p| p.map(snap)).collect();
    let mut key_to_vertex: BTreeMap<(u32, u32), u32> = BTreeMap::new();
    let mut keys: Vec<u32> = Vec::new();
    let mut sums: Vec<glam::DVec3> = Vec::new();
    let mut indices = Vec::with_capacity(mesh.triangles.len() * 3);
    for (t, &g) in mesh.triangles.iter().zip(&mesh.groups) {
        let [a, b, c] = t.map(|i| snapped[i as usize]);
        // Area-weighted: the cross product's length is twice the triangle's area.
        let n = (b - a).cross(c - a);
        for &i in t {
            let next = keys.len() as u32;
            let v = *key_to_vertex.entry((i, g)).or_insert(next);
            if v == next {
                keys.push(i);
                sums.push(glam::DVec3::ZERO);
            }
            sums[v as usize] += n;
            indices.push(v);
        }
    }
    let mut normals = Vec::with_capacity(sums.len());
    for (v, s) in sums.iter().enumerate() {
        let len = s.length();
        if len.is_nan() || len <= 1e-300 {
            return Err(GlbError::ZeroNormal {
                object: object.to_string(),
                primitive,
                vertex: v as u32,
            });
        }
        normals.push((*s / len).as_vec3().to_array());
    }
    let positions = keys
        .iter()
        .map(|&i| snapped[i as usize].as_vec3().to_array())
        .collect();
    Ok(Split {
        positions,
        normals,
        indices,
    })
}

/// The rotation that turns a glTF camera (looking down its local -Z, +Y up) at `eye` towards
/// `target`, keeping world +Y up.
pub fn look_rotation(eye: glam::DVec3, target: glam::DVec3) -> glam::DQuat {
    let back = (eye - target).normalize();
    let right = glam::DVec3::Y.cross(back).normalize();
    let up = back.cross(right);
    glam::DQuat::from_mat3(&glam::DMat3::from_cols(right, up, back)).normalize()
}

/// Appends `bytes` to the binary chunk as a new buffer view starting on a 4-byte boundary.
fn push_view(
    root: &mut json::Root,
    bin: &mut Vec<u8>,
    bytes: &[u8],
    target: json::buffer::Target,
) -> json::Index<json::buffer::View> {
    while bin.len() % 4 != 0 {
        bin.push(0);
    }
    let offset = bin.len();
    bin.extend_from_slice(bytes);
    root.push(json::buffer::View {
        buffer: json::Index::new(0),
        byte_length: USize64::from(bytes.len()),
        byte_offset: Some(USize64::from(offset)),
        byte_stride: None,
        name: None,
        target: Some(Checked::Valid(target)),
        extensions: None,
        extras: Default::default(),
    })
}

fn accessor(
    view: json::Index<json::buffer::View>,
    count: usize,
    component: json::accessor::ComponentType,
    type_: json::accessor::Type,
    bounds: Option<([f32; 3], [f32; 3])>,
) -> json::Accessor {
    let value = |v: [f32; 3]| json::Value::from(v.iter().map(|&x| x as f64).collect::<Vec<_>>());
    json::Accessor {
        buffer_view: Some(view),
        byte_offset: None,
        count: USize64::from(count),
        component_type: Checked::Valid(json::accessor::GenericComponentType(component)),
        extensions: None,
        extras: Default::default(),
        type_: Checked::Valid(type_),
        min: bounds.map(|b| value(b.0)),
        max: bounds.map(|b| value(b.1)),
        name: None,
        normalized: false,
        sparse: None,
    }
}

fn f32_bytes(v: &[[f32; 3]]) -> Vec<u8> {
    v.iter()
        .flat_map(|p| p.iter().flat_map(|x| x.to_le_bytes()))
        .collect()
}

/// The glTF JSON document and binary chunk for `scene`.
pub fn to_gltf(scene: &Scene) -> Result<(json::Root, Vec<u8>), GlbError> {
    let mut root = json::Root {
        asset: json::Asset {
            copyright: None,
            extensions: None,
            extras: Default::default(),
            generator: Some(format!("hce-samples {}", env!("CARGO_PKG_VERSION"))),
            min_version: None,
            version: "2.0".to_string(),
        },
        ..Default::default()
    };
    let mut bin = Vec::new();
    let mut uses_strength = false;

    for m in &scene.materials {
        let max = m.emission.iter().copied().fold(0.0, f64::max);
        let (factor, strength) = if max > 1.0 {
            (m.emission.map(|e| e / max), Some(max))
        } else {
            (m.emission, None)
        };
        uses_strength |= strength.is_some();
        let [r, g, b] = m.base_color.map(|c| c as f32);
        root.push(json::Material {
            name: Some(m.name.clone()),
            pbr_metallic_roughness: json::material::PbrMetallicRoughness {
                base_color_factor: json::material::PbrBaseColorFactor([r, g, b, 1.0]),
                metallic_factor: json::material::StrengthFactor(0.0),
                roughness_factor: json::material::StrengthFactor(1.0),
                ..Default::default()
            },
            emissive_factor: json::material::EmissiveFactor(factor.map(|e| e as f32)),
            extensions: strength.map(|s| json::extensions::material::Material {
                emissive_strength: Some(json::extensions::material::EmissiveStrength {
                    emissive_strength: json::extensions::material::EmissiveStrengthFactor(s as f32),
                }),
                ..Default::default()
            }),
            ..Default::default()
        });
    }

    let mut nodes = Vec::new();
    for object in &scene.objects {
        let mut primitives = Vec::new();
        for (k, prim) in object.primitives.iter().enumerate() {
            if prim.mesh.triangles.is_empty() {
                return Err(GlbError::EmptyPrimitive {
                    object: object.name.clone(),
                    primitive: k,
                });
            }
            if prim.material >= scene.materials.len() {
                return Err(GlbError::MissingMaterial {
                    object: object.name.clone(),
                    primitive: k,
                    material: prim.material,
                    count: scene.materials.len(),
                });
            }
            let split = split_vertices(prim, &object.name, k)?;
            let mut lo = [f32::INFINITY; 3];
            let mut hi = [f32::NEG_INFINITY; 3];
            for p in &split.positions {
                for a in 0..3 {
                    lo[a] = lo[a].min(p[a]);
                    hi[a] = hi[a].max(p[a]);
                }
            }
            use json::accessor::{ComponentType, Type};
            use json::buffer::Target;
            let count = split.positions.len();
            let view = push_view(
                &mut root,
                &mut bin,
                &f32_bytes(&split.positions),
                Target::ArrayBuffer,
            );
            let pos = root.push(accessor(
                view,
                count,
                ComponentType::F32,
                Type::Vec3,
                Some((lo, hi)),
            ));
            let view = push_view(
                &mut root,
                &mut bin,
                &f32_bytes(&split.normals),
                Target::ArrayBuffer,
            );
            let nor = root.push(accessor(view, count, ComponentType::F32, Type::Vec3, None));
            // 16-bit indices when they fit; 65535 is the primitive-restart value, so never use it.
            let (bytes, component) = if count < 65535 {
                let b = split.indices.iter().flat_map(|&i| (i as u16).to_le_bytes());
                (b.collect::<Vec<u8>>(), ComponentType::U16)
            } else {
                let b = split.indices.iter().flat_map(|&i| i.to_le_bytes());
                (b.collect::<Vec<u8>>(), ComponentType::U32)
            };
            let view = push_view(&mut root, &mut bin, &bytes, Target::ElementArrayBuffer);
            let idx = root.push(accessor(
                view,
                split.indices.len(),
                component,
                Type::Scalar,
                None,
            ));
            let mut attributes = BTreeMap::new();
            attributes.insert(Checked::Valid(json::mesh::Semantic::Positions), pos);
            attributes.insert(Checked::Valid(json::mesh::Semantic::Normals), nor);
            primitives.push(json::mesh::Primitive {
                attributes,
                extensions: None,
                extras: Default::default(),
                indices: Some(idx),
                material: Some(json::Index::new(prim.material as u32)),
                mode: Checked::Valid(json::mesh::Mode::Triangles),
                targets: None,
            });
        }
        let mesh = root.push(json::Mesh {
            extensions: None,
            extras: Default::default(),
            name: Some(object.name.clone()),
            primitives,
            weights: None,
        });
        // Translations are literal constants, so no platform-dependent rounding to guard against.
        let t = object.translation.as_vec3().to_array();
        let extras = if object.multires {
            Some(
                json::extras::RawValue::from_string(r#"{"hce":{"multires":true}}"#.to_string())
                    .expect("a constant, valid JSON text"),
            )
        } else {
            None
        };
        nodes.push(root.push(json::Node {
            mesh: Some(mesh),
            name: Some(object.name.clone()),
            translation: (t != [0.0; 3]).then_some(t),
            extras,
            ..Default::default()
        }));
    }
    if let Some(camera) = &scene.camera {
        let index = root.push(json::Camera {
            name: Some(camera.name.clone()),
            orthographic: None,
            perspective: Some(json::camera::Perspective {
                aspect_ratio: None,
                yfov: camera.yfov_degrees.to_radians() as f32,
                zfar: None,
                znear: 0.01,
                extensions: None,
                extras: Default::default(),
            }),
            type_: Checked::Valid(json::camera::Type::Perspective),
            extensions: None,
            extras: Default::default(),
        });
        nodes.push(
            root.push(json::Node {
                camera: Some(index),
                name: Some(camera.name.clone()),
                translation: Some(camera.eye.as_vec3().to_array()),
                rotation: Some(json::scene::UnitQuaternion(
                    look_rotation(camera.eye, camera.target)
                        .as_quat()
                        .to_array(),
                )),
                ..Default::default()
            }),
        );
    }
    while bin.len() % 4 != 0 {
        bin.push(0);
    }
    if bin.len() as u64 > u32::MAX as u64 - 1024 {
        return Err(GlbError::TooLarge(bin.len() as u64));
    }
    if !bin.is_empty() {
        root.push(json::Buffer {
            byte_length: USize64::from(bin.len()),
            name: None,
            uri: None,
            extensions: None,
            extras: Default::default(),
        });
    }
    let scene_index = root.push(json::Scene {
        extensions: None,
        extras: Default::default(),
        name: Some(scene.name.clone()),
        nodes,
    });
    root.scene = Some(scene_index);
    if uses_strength {
        root.extensions_used
            .push("KHR_materials_emissive_strength".to_string());
    }
    Ok((root, bin))
}

/// Serialises `scene` as GLB bytes.
pub fn write_glb(scene: &Scene) -> Result<Vec<u8>, GlbError> {
    let (root, bin) = to_gltf(scene)?;
    let mut json_bytes = root.to_vec()?;
    while json_bytes.len() % 4 != 0 {
        json_bytes.push(b' ');
    }
    let total = 12 + 8 + json_bytes.len() + if bin.is_empty() { 0 } else { 8 + bin.len() };
    let total = u32::try_from(total).map_err(|_| GlbError::TooLarge(total as u64))?;
    let mut out = Vec::with_capacity(total as usize);
    out.extend_from_slice(b"glTF");
    out.extend_from_slice(&2u32.to_le_bytes());
    out.extend_from_slice(&total.to_le_bytes());
    out.extend_from_slice(&(json_bytes.len() as u32).to_le_bytes());
    out.extend_from_slice(b"JSON");
    out.extend_from_slice(&json_bytes);
    if !bin.is_empty() {
        out.extend_from_slice(&(bin.len() as u32).to_le_bytes());
        out.extend_from_slice(b"BIN\0");
        out.extend_from_slice(&bin);
    }
    Ok(out)
}

/// The JSON and BIN chunks of a GLB file, for tests and tools that read back what we wrote.
pub fn split_glb(bytes: &[u8]) -> Option<(&[u8], &[u8])> {
    let word = |at: usize| -> Option<u32> {
        Some(u32::from_le_bytes(bytes.get(at..at + 4)?.try_into().ok()?))
    };
    if bytes.get(0..4)? != b"glTF" || word(4)? != 2 || word(8)? as usize != bytes.len() {
        return None;
    }
    let json_len = word(12)? as usize;
    if bytes.get(16..20)? != b"JSON" {
        return None;
    }
    let json = bytes.get(20..20usize.checked_add(json_len)?)?;
    let rest = 20 + json_len;
    if rest == bytes.len() {
        return Some((json, &[]));
    }
    let bin_len = word(rest)? as usize;
    if bytes.get(rest + 4..rest + 8)? != b"BIN\0" {
        return None;
    }
    let bin = bytes.get(rest + 8..(rest + 8).checked_add(bin_len)?)?;
    Some((json, bin))
}
