//! glTF 2.0 accessors (glTF 2.0 specification, section 3.6.2 and 5.1), read as optimisers write
//! them: any component type `KHR_mesh_quantization` allows, `normalized` values dequantized
//! (section 3.11), buffer views with `byteStride`, `sparse` substitutions, and views in any
//! buffer. Every size read from the asset is checked before anything is allocated, and an
//! accessor never yields more elements than the asset's buffers can justify; nothing panics on
//! any input.
//!
//! A buffer view compressed with `EXT_meshopt_compression` is read decoded ([`crate::meshopt`]);
//! the view's own `buffer` is then the extension's fallback, possibly without data.

use crate::gltf_json::{buffer_view_bytes, GltfError};
use serde_json::Value;

/// An accessor's values, converted to `f64` (exact for every glTF component type), with what
/// the same-geometry rule needs to know of its quantization.
#[derive(Clone, Debug, PartialEq)]
pub struct AccessorValues {
    /// Values per element: 1 for `SCALAR`, 2–4 for `VECn`.
    pub components: usize,
    /// `count · components` values, element after element.
    pub values: Vec<f64>,
    /// The spacing of representable values in the accessor's own units (SPEC.md 2.6, `g`):
    /// `1 / (2^(b−1) − 1)` or `1 / (2^b − 1)` for normalized signed or unsigned `b`-bit
    /// integers, 1 for other integers, 0 for `FLOAT`.
    pub grid: f64,
}

impl AccessorValues {
    /// The number of elements.
    pub fn count(&self) -> usize {
        self.values.len() / self.components.max(1)
    }
}

/// A glTF component type (section 3.6.2.2).
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
enum Component {
    I8,
    U8,
    I16,
    U16,
    U32,
    F32,
}

impl Component {
    fn from_code(code: u64) -> Option<Self> {
        Some(match code {
            5120 => Self::I8,
            5121 => Self::U8,
            5122 => Self::I16,
            5123 => Self::U16,
            5125 => Self::U32,
            5126 => Self::F32,
            _ => return None,
        })
    }

    fn size(self) -> usize {
        match self {
            Self::I8 | Self::U8 => 1,
            Self::I16 | Self::U16 => 2,
            Self::U32 | Self::F32 => 4,
        }
    }

    /// The value at the start of `b` (which holds at least [`Component::size`] bytes),
    /// dequantized when `normalized` (section 3.11: `max(c / (2^(b−1) − 1), −1)` signed,
    /// `c / (2^b − 1)` unsigned).
    fn read(self, b: &[u8], normalized: bool) -> f64 {
        let raw = match self {
            Self::I8 => f64::from(b[0] as i8),
            Self::U8 => f64::from(b[0]),
            Self::I16 => f64::from(i16::from_le_bytes([b[0], b[1]])),
            Self::U16 => f64::from(u16::from_le_bytes([b[0], b[1]])),
            Self::U32 => f64::from(u32::from_le_bytes([b[0], b[1], b[2], b[3]])),
            Self::F32 => f64::from(f32::from_le_bytes([b[0], b[1], b[2], b[3]])),
        };
        match (normalized, self.max()) {
            (true, Some(max)) => (raw / max).max(-1.0),
            _ => raw,
        }
    }

    /// The largest value of an integer type whose normalized form is 1; `None` for `FLOAT`.
    fn max(self) -> Option<f64> {
        match self {
            Self::I8 => Some(127.0),
            Self::U8 => Some(255.0),
            Self::I16 => Some(32767.0),
            Self::U16 => Some(65535.0),
            Self::U32 => Some(4_294_967_295.0),
            Self::F32 => None,
        }
    }

    fn grid(self, normalized: bool) -> f64 {
        match (self.max(), normalized) {
            (None, _) => 0.0,
            (Some(max), true) => 1.0 / max,
            (Some(_), false) => 1.0,
        }
    }
}

fn err(message: String) -> GltfError {
    GltfError::Json(message)
}

fn item<'a>(json: &'a Value, array: &str, i: usize) -> Result<&'a Value, GltfError> {
    json.get(array)
        .and_then(Value::as_array)
        .and_then(|a| a.get(i))
        .ok_or_else(|| err(format!("{array}[{i}] does not exist")))
}

fn index(v: &Value, key: &str, loc: &str) -> Result<usize, GltfError> {
    v.get(key)
        .and_then(Value::as_u64)
        .and_then(|x| usize::try_from(x).ok())
        .ok_or_else(|| err(format!("{loc}.{key} is missing or not an index")))
}

/// The bytes of buffer view `view`, decoded first when it is compressed with
/// `EXT_meshopt_compression`, and its byte stride (`None` when it has none).
pub fn view_bytes<'a>(
    json: &Value,
    buffers: &'a [Vec<u8>],
    view: usize,
) -> Result<(std::borrow::Cow<'a, [u8]>, Option<u64>), GltfError> {
    let v = item(json, "bufferViews", view)?;
    let stride = v.get("byteStride").and_then(Value::as_u64);
    if let Some(ext) = v.get("extensions").and_then(|e| e.get(MESHOPT)) {
        let decoded = crate::meshopt::decode_view(buffers, view, ext)?;
        return Ok((std::borrow::Cow::Owned(decoded), stride));
    }
    Ok((
        std::borrow::Cow::Borrowed(buffer_view_bytes(json, buffers, view)?),
        stride,
    ))
}

/// The total bytes of every buffer: no accessor may describe more elements than that (an
/// accessor without a buffer view is all zeros plus its sparse values, so its `count` is not
/// otherwise bounded by the input).
fn input_bytes(buffers: &[Vec<u8>]) -> u64 {
    buffers.iter().map(|b| b.len() as u64).sum()
}

/// Reads accessor `accessor` of the asset (section 3.6.2, with `sparse`, section 3.6.2.3).
pub fn read_accessor(
    json: &Value,
    buffers: &[Vec<u8>],
    accessor: usize,
) -> Result<AccessorValues, GltfError> {
    let loc = format!("accessors[{accessor}]");
    let a = item(json, "accessors", accessor)?;
    let count = a
        .get("count")
        .and_then(Value::as_u64)
        .ok_or_else(|| err(format!("{loc}.count is missing")))?;
    let components = match a.get("type").and_then(Value::as_str) {
        Some("SCALAR") => 1usize,
        Some("VEC2") => 2,
        Some("VEC3") => 3,
        Some("VEC4") => 4,
        t => return Err(err(format!("{loc}.type {t:?} is not SCALAR or VECn"))),
    };
    let component = a
        .get("componentType")
        .and_then(Value::as_u64)
        .and_then(Component::from_code)
        .ok_or_else(|| {
            err(format!(
                "{loc}.componentType {:?} is not a glTF component type",
                a.get("componentType")
            ))
        })?;
    let normalized = a
        .get("normalized")
        .and_then(Value::as_bool)
        .unwrap_or(false);
    let element = (component.size() * components) as u64;
    if count > input_bytes(buffers) {
        return Err(err(format!(
            "{loc}: count {count} is more than the asset's buffers can hold"
        )));
    }
    let total = count as usize * components;
    let mut values = Vec::with_capacity(total.min(1 << 24));
    match a.get("bufferView") {
        None => values.resize(total, 0.0),
        Some(_) => {
            let view = index(a, "bufferView", &loc)?;
            let (data, stride) = view_bytes(json, buffers, view)?;
            let stride = stride.unwrap_or(element);
            let offset = a.get("byteOffset").and_then(Value::as_u64).unwrap_or(0);
            // The last element must end inside the view; checked before allocating.
            let needed = match count {
                0 => 0,
                _ => (count - 1)
                    .checked_mul(stride)
                    .and_then(|x| x.checked_add(offset))
                    .and_then(|x| x.checked_add(element))
                    .unwrap_or(u64::MAX),
            };
            if needed > data.len() as u64 || stride < element {
                return Err(err(format!(
                    "{loc}: {count} elements of {element} bytes at stride {stride} do not fit in bufferViews[{view}] ({} bytes)",
                    data.len()
                )));
            }
            for i in 0..count {
                let base = (offset + i * stride) as usize;
                for c in 0..components {
                    let at = base + c * component.size();
                    values.push(component.read(&data[at..], normalized));
                }
            }
        }
    }
    if let Some(sparse) = a.get("sparse") {
        apply_sparse(
            json,
            buffers,
            &loc,
            sparse,
            count,
            components,
            component,
            normalized,
            &mut values,
        )?;
    }
    Ok(AccessorValues {
        components,
        values,
        grid: component.grid(normalized),
    })
}

/// Substitutes the sparse values of an accessor (section 3.6.2.3): `sparse.count` indices,
/// each below the accessor's `count`, and as many elements of the accessor's type.
#[allow(clippy::too_many_arguments)]
fn apply_sparse(
    json: &Value,
    buffers: &[Vec<u8>],
    loc: &str,
    sparse: &Value,
    count: u64,
    components: usize,
    component: Component,
    normalized: bool,
    values: &mut [f64],
) -> Result<(), GltfError> {
    let loc = format!("{loc}.sparse");
    let n = sparse
        .get("count")
        .and_then(Value::as_u64)
        .ok_or_else(|| err(format!("{loc}.count is missing")))?;
    let part = |key: &str| {
        sparse
            .get(key)
            .ok_or_else(|| err(format!("{loc}.{key} is missing")))
    };
    let (indices, vals) = (part("indices")?, part("values")?);
    let index_type = indices
        .get("componentType")
        .and_then(Value::as_u64)
        .and_then(Component::from_code)
        .filter(|c| matches!(c, Component::U8 | Component::U16 | Component::U32))
        .ok_or_else(|| {
            err(format!(
                "{loc}.indices.componentType is not an unsigned integer type"
            ))
        })?;
    // Sparse data is tightly packed: byteStride does not apply (section 3.6.2.3).
    let packed = |at: &Value, what: &str, element: u64| -> Result<(Vec<u8>, u64), GltfError> {
        let view = index(at, "bufferView", &format!("{loc}.{what}"))?;
        let (data, _) = view_bytes(json, buffers, view)?;
        let offset = at.get("byteOffset").and_then(Value::as_u64).unwrap_or(0);
        let end = n
            .checked_mul(element)
            .and_then(|x| x.checked_add(offset))
            .filter(|&e| e <= data.len() as u64)
            .ok_or_else(|| {
                err(format!(
                    "{loc}.{what}: {n} elements of {element} bytes do not fit in bufferViews[{view}]"
                ))
            })?;
        Ok((data[offset as usize..end as usize].to_vec(), element))
    };
    let (index_bytes, index_size) = packed(indices, "indices", index_type.size() as u64)?;
    let (value_bytes, value_size) = packed(vals, "values", (component.size() * components) as u64)?;
    for k in 0..n as usize {
        let i = index_type.read(&index_bytes[k * index_size as usize..], false) as u64;
        if i >= count {
            return Err(err(format!(
                "{loc}.indices[{k}]: {i} is out of range ({count} elements)"
            )));
        }
        for c in 0..components {
            let at = k * value_size as usize + c * component.size();
            values[i as usize * components + c] = component.read(&value_bytes[at..], normalized);
        }
    }
    Ok(())
}

/// A triangle primitive as the same-geometry rule reads it (SPEC.md 2.6): positions before any
/// node transform, decoded and dequantized, and triangles through its indices.
#[derive(Clone, Debug, PartialEq)]
pub struct PrimitiveMesh {
    pub positions: Vec<[f64; 3]>,
    pub triangles: Vec<[u32; 3]>,
    /// The `POSITION` accessor's grid step ([`AccessorValues::grid`]).
    pub grid: f64,
}

impl PrimitiveMesh {
    /// The corners of every triangle, in triangle order, as `f32` (SPEC.md 2.5).
    pub fn corners_f32(&self) -> impl Iterator<Item = [f32; 3]> + '_ {
        self.triangles.iter().flatten().map(|&v| {
            let p = self.positions[v as usize];
            [p[0] as f32, p[1] as f32, p[2] as f32]
        })
    }
}

/// The buffer-view compression hce's readers decode (SPEC.md 2.6).
pub const MESHOPT: &str = crate::meshopt::EXTENSION;

/// The primitive's extension that hce's readers cannot decode: its positions cannot be checked.
pub const DRACO: &str = "KHR_draco_mesh_compression";

/// Reads mesh `mesh`'s primitive `primitive`: mode 4, a `VEC3` `POSITION`, indices (or
/// consecutive vertices) in whole triangles and in range. A Draco-compressed primitive is
/// [`GltfError::Compressed`].
pub fn read_primitive(
    json: &Value,
    buffers: &[Vec<u8>],
    mesh: usize,
    primitive: usize,
) -> Result<PrimitiveMesh, GltfError> {
    let loc = format!("meshes[{mesh}].primitives[{primitive}]");
    let prim = item(json, "meshes", mesh)?
        .get("primitives")
        .and_then(Value::as_array)
        .and_then(|p| p.get(primitive))
        .ok_or_else(|| err(format!("{loc} does not exist")))?;
    if prim.get("mode").and_then(Value::as_u64).unwrap_or(4) != 4 {
        return Err(err(format!("{loc}: mode is not 4 (triangles)")));
    }
    if prim.get("extensions").and_then(|e| e.get(DRACO)).is_some() {
        return Err(GltfError::Compressed {
            location: loc,
            extension: DRACO.into(),
        });
    }
    let position =
        prim.get("attributes")
            .and_then(|a| a.get("POSITION"))
            .and_then(Value::as_u64)
            .ok_or_else(|| err(format!("{loc} has no POSITION attribute")))? as usize;
    let p = read_accessor(json, buffers, position)?;
    if p.components != 3 {
        return Err(err(format!("{loc}: the POSITION accessor is not VEC3")));
    }
    let positions: Vec<[f64; 3]> = p
        .values
        .chunks_exact(3)
        .map(|c| [c[0], c[1], c[2]])
        .collect();
    let vertex_count = positions.len();
    let indices: Vec<u32> = match prim.get("indices") {
        Some(i) => {
            let i = i
                .as_u64()
                .ok_or_else(|| err(format!("{loc}.indices is not an index")))?;
            let values = read_accessor(json, buffers, i as usize)?;
            if values.components != 1 {
                return Err(err(format!("{loc}: the indices accessor is not SCALAR")));
            }
            let mut out = Vec::with_capacity(values.values.len());
            for &x in &values.values {
                if !(0.0..vertex_count as f64).contains(&x) || x.fract() != 0.0 {
                    return Err(err(format!(
                        "{loc}: index {x} is out of range ({vertex_count} vertices)"
                    )));
                }
                out.push(x as u32);
            }
            out
        }
        None => {
            let n = u32::try_from(vertex_count)
                .map_err(|_| err(format!("{loc}: {vertex_count} vertices are too many")))?;
            (0..n).collect()
        }
    };
    if indices.len() % 3 != 0 {
        return Err(err(format!(
            "{loc}: {} indices are not whole triangles",
            indices.len()
        )));
    }
    Ok(PrimitiveMesh {
        positions,
        triangles: indices
            .chunks_exact(3)
            .map(|t| [t[0], t[1], t[2]])
            .collect(),
        grid: p.grid,
    })
}
