//! # hce-wasm
//!
//! The browser runtime's reader, validator and table builder: hce's own Rust
//! (`hce_runtime::asset`, `hce_format`, `hce_geometry`) compiled to `wasm32-unknown-unknown`, so
//! that web/ never restates the format in JavaScript. JavaScript keeps the WebGPU work and the
//! page; it calls the functions below through `web/src/native.js`.
//!
//! # Interface
//!
//! Plain `extern "C"` functions over the module's memory, no bindings generator:
//!
//! * `hce_alloc(bytes) -> ptr` and `hce_free(ptr, bytes)`: word-aligned buffers the
//!   caller fills with a request frame and frees again.
//! * `hce_load(ptr, bytes) -> result`: a `.glb`, `.gltf` or `.hce` file, read and checked as
//!   `hce_runtime::Asset::from_bytes` does (the same checks and messages as the CLI), and a
//!   glTF's root rules as `hce validate` words them; a glTF without baked lighting as
//!   `hce_runtime::Asset::plain_preview` draws it, with a warning that says so.
//! * `hce_tables(ptr, bytes) -> result`: one object's kernel tables and lighting table, as
//!   the native runtime's kernels' `upload` builds them.
//! * `hce_refine(ptr, bytes) -> result`: one object refined on the CPU with its baked light, as
//!   `hce subdivide` refines it (a flat object adaptively or uniformly, as asked), for pages
//!   without WebGPU.
//! * `hce_geometry_hash(ptr, bytes) -> result`: the geometry hash (SPEC.md 2.5).
//!
//! A result is a word buffer `[words, status, payload…]`: `words` its length in words (free it
//! with `hce_free(result, 4 * words)`), `status` 0 for success or 1 for an error, whose payload
//! is the error's text. Bad input is an error value, never a trap.
//!
//! # Frames
//!
//! Requests and results are sequences of little-endian 32-bit words, read in the order each
//! function documents, of these items:
//!
//! * `u32`; `u64` as two words, low first; `f32` as its bits.
//! * `words` and `floats`: a count `n`, then `n` words.
//! * `bytes` and `str` (UTF-8): a byte count `n`, then `ceil(n / 4)` words holding the bytes,
//!   zero padded.
#![deny(unsafe_code)]

use std::path::Path;

use hce_format::root_problems;
use hce_format::{ControlMesh, Object, ObjectKind, TriangleRecord};
use hce_geometry::adaptive_flat::refine_adaptive_flat;
use hce_geometry::flat::FlatTopology;
use hce_geometry::lighting::{LightingTable, Reconstruction};
use hce_geometry::loop_tables::LoopKernelTables;
use hce_geometry::refine::FlatRefinement;
use hce_geometry::split::SplitTables;
use hce_geometry::tables::validate_tables;
use hce_runtime::asset::{AssetFormat, GltfSource, OpenOptions};
use hce_runtime::{Asset, AssetError};

mod frame;
mod refine;

pub use frame::{Reader, Writer};
pub use refine::refine;

/// `node` of an instance without one (a `.hce` file's).
pub const NO_NODE: u32 = u32::MAX;

/// Reads an asset. Request: `str` name (names the file in messages, its extension helps tell
/// the format), `u32` strict (1: refuse bad primitive links, SPEC.md 3.5), `bytes` file, `u32`
/// count of external buffers, then per buffer `str` uri and `bytes` data (what a `.gltf`'s
/// buffers name; any other uri is an error).
///
/// Result: `u32` format (0 `.hce`, 1 GLB, 2 `.gltf`), `str` generator, `u32` count and `str`
/// per warning, `u32` has-camera then, when 1: `str` name, `floats` eye, forward, up (3 each),
/// `f32` vertical field of view in degrees, `u32` has-aspect and `f32` aspect ratio; `u32`
/// object count, then per object: `u32` index, `str` name, `u32` kind (0 multiresolution, 1
/// flat), `u64` geometry hash, `u64` bit length, `u32` deepest tree, `floats` positions, `words`
/// triangles, ring offsets, ring, vertex flags, spoke flags, corner spokes, neighbours, edges,
/// records (4 per triangle), `floats` normals (3 per normal), `words` bits, colours, corner colours; `floats`
/// bounds (min, max), `f32` mean edge length, `u32` instance count and per instance `u32` node
/// ([`NO_NODE`] for none), `str` name, `floats` transform (16, column-major).
pub fn load(request: &[u32]) -> Result<Vec<u32>, String> {
    let mut r = Reader::new(request);
    let name = r.string()?;
    let strict = r.u32()? != 0;
    let bytes = r.bytes()?;
    let n = r.u32()?;
    let mut external = Vec::new();
    for _ in 0..n {
        external.push((r.string()?, r.bytes()?));
    }
    let path = Path::new(&name);
    let shown = |e: &dyn std::fmt::Display| {
        let text = e.to_string();
        // The page names the file itself: the message without the CLI's `name: ` prefix.
        text.strip_prefix(&format!("{name}: "))
            .map(str::to_string)
            .unwrap_or(text)
    };
    let format = AssetFormat::detect(path, &bytes)
        .ok_or_else(|| shown(&AssetError::UnknownFormat { path: name.clone() }))?;
    let resolve = |uri: &str| {
        external
            .iter()
            .find(|(u, _)| u == uri)
            .map(|(_, data)| data.clone())
            .ok_or_else(|| {
                "the external buffer cannot be loaded here; open the .glb, or the .gltf by URL"
                    .to_string()
            })
    };
    let options = OpenOptions { strict };
    let asset = match format {
        AssetFormat::Hce => Asset::from_bytes(path, format, &bytes, resolve, &options),
        AssetFormat::Glb | AssetFormat::Gltf => {
            let source = GltfSource::parse(&bytes, resolve).map_err(|error| {
                shown(&AssetError::Gltf {
                    path: name.clone(),
                    error,
                })
            })?;
            // A file that says nothing of the extension lost its baked lighting to an optimiser
            // that drops unknown extensions (or was never baked): drawn from its COLOR_0,
            // saying so (the first warning).
            if !hce_format::mentions_extension(&source.json) {
                Asset::plain_preview(path, &source)
            } else if let Some(problem) = root_problems(&source.json).first() {
                // The root rules the native loader leaves to `hce validate` (SPEC.md 3.2,
                // 3.3): a page has no validator beside it, so it refuses such a file with its
                // first one.
                return Err(problem.to_string());
            } else {
                Asset::from_gltf(path, &source, &options)
            }
        }
    }
    .map_err(|e| shown(&e))?;
    Ok(write_asset(&asset))
}

fn write_asset(asset: &Asset) -> Vec<u32> {
    let mut w = Writer::default();
    w.u32(match asset.format {
        AssetFormat::Hce => 0,
        AssetFormat::Glb => 1,
        AssetFormat::Gltf => 2,
    });
    w.string(&asset.metadata.generator);
    w.u32(asset.warnings.len() as u32);
    for warning in &asset.warnings {
        w.string(warning);
    }
    match &asset.camera {
        None => w.u32(0),
        Some(c) => {
            w.u32(1);
            w.string(&c.name);
            w.floats(&c.eye);
            w.floats(&c.forward);
            w.floats(&c.up);
            w.f32(c.fov_y_degrees);
            w.u32(u32::from(c.aspect_ratio.is_some()));
            w.f32(c.aspect_ratio.unwrap_or(0.0));
        }
    }
    w.u32(asset.objects.len() as u32);
    for o in &asset.objects {
        w.u32(o.index);
        write_object(&mut w, &o.object);
        w.u32(o.tree_depth);
        w.floats(&[o.bounds.min, o.bounds.max].concat());
        w.f32(o.mean_edge_length);
        w.u32(o.instances.len() as u32);
        for i in &o.instances {
            w.u32(i.node.map_or(NO_NODE, |n| n as u32));
            w.string(&i.name);
            w.floats(&i.transform.to_cols_array());
        }
    }
    w.finish()
}

/// An object as [`load`] writes it and [`tables`] reads it, from `name` to `corner_colours`.
fn write_object(w: &mut Writer, o: &Object) {
    w.string(&o.name);
    w.u32(kind_code(o.kind));
    w.u64(o.geometry_hash);
    w.u64(o.bit_len);
    let m = &o.mesh;
    w.floats(&m.positions);
    for table in [
        &m.triangles,
        &m.ring_offsets,
        &m.ring,
        &m.vertex_flags,
        &m.spoke_flags,
        &m.corner_spokes,
        &m.neighbours,
        &m.edges,
    ] {
        w.words(table);
    }
    let records: Vec<u32> = o
        .triangles
        .iter()
        .flat_map(|r| [r.bits_start, r.colour_start, r.normal_start, r.normal_count])
        .collect();
    w.words(&records);
    w.floats(o.normals.as_flattened());
    w.words(&o.bits);
    w.words(&o.colours);
    w.words(&o.corner_colours);
}

fn kind_code(kind: ObjectKind) -> u32 {
    match kind {
        ObjectKind::Multiresolution => 0,
        ObjectKind::Flat => 1,
    }
}

/// A reconstruction word: 0 smooth, 1 nearest normal, 2 Gouraud.
fn read_reconstruction(r: &mut Reader) -> Result<Reconstruction, String> {
    Ok(match r.u32()? {
        0 => Reconstruction::Smooth,
        1 => Reconstruction::NearestNormal,
        2 => Reconstruction::Gouraud,
        k => return Err(format!("reconstruction {k} is not 0, 1 or 2")),
    })
}

/// A flat refinement word (SPEC.md F.7): 0 adaptive (F.7.1), 1 uniform (F.7.2).
fn read_flat_refinement(r: &mut Reader) -> Result<FlatRefinement, String> {
    Ok(match r.u32()? {
        0 => FlatRefinement::Adaptive,
        1 => FlatRefinement::Uniform,
        k => {
            return Err(format!(
                "flat refinement {k} is neither 0 (adaptive) nor 1 (uniform)"
            ))
        }
    })
}

fn read_object(r: &mut Reader) -> Result<Object, String> {
    let name = r.string()?;
    let kind = match r.u32()? {
        0 => ObjectKind::Multiresolution,
        1 => ObjectKind::Flat,
        k => return Err(format!("object kind {k} is neither 0 nor 1")),
    };
    let geometry_hash = r.u64()?;
    let bit_len = r.u64()?;
    let mesh = ControlMesh {
        positions: r.floats()?,
        triangles: r.words()?,
        ring_offsets: r.words()?,
        ring: r.words()?,
        vertex_flags: r.words()?,
        spoke_flags: r.words()?,
        corner_spokes: r.words()?,
        neighbours: r.words()?,
        edges: r.words()?,
    };
    let records = r.words()?;
    if records.len() % 4 != 0 {
        return Err(format!(
            "{} record words are not 4 per triangle",
            records.len()
        ));
    }
    let normals = r.floats()?;
    if normals.len() % 3 != 0 {
        return Err(format!(
            "{} normal floats are not 3 per normal",
            normals.len()
        ));
    }
    Ok(Object {
        name,
        kind,
        geometry_hash,
        mesh,
        triangles: records
            .chunks_exact(4)
            .map(|c| TriangleRecord {
                bits_start: c[0],
                colour_start: c[1],
                normal_start: c[2],
                normal_count: c[3],
            })
            .collect(),
        normals: normals
            .chunks_exact(3)
            .map(|c| [c[0], c[1], c[2]])
            .collect(),
        bits: r.words()?,
        bit_len,
        colours: r.words()?,
        corner_colours: r.words()?,
    })
}

/// The tables the kernels read of one object, checked first as the native runtime's upload
/// checks them. Request: `u32` index (names the object in messages), the object as [`load`]
/// writes it from `name` to `corner_colours`, `u32` reconstruction (0 smooth, 1 nearest: no lighting
/// table, 2 Gouraud), `u32` flat refinement (0 adaptive, 1 uniform; read for every object, used
/// for flat ones).
///
/// Result: `u32` deepest tree; the incidence: `u32` vertex, triangle and edge counts, `words`
/// edge end points; the split (SPEC.md F.5): `u32` copies and split edges, `words` edge slot
/// offsets, edge slot sides, corner slot offsets, corner slot corners, corner copy, edge copy,
/// slot split; `u32` has-Loop then, when 1, `words` triangle flags, crease spokes, weights and
/// `u32` largest valence and ring points; `words` lighting table (one zero word for nearest);
/// `u32` has-adaptive then, when 1 (a flat object asked for adaptively), the adaptive refinement
/// (SPEC.md F.7.1) as the flat kernel reads it: `u32` vertex and triangle counts, `words`
/// sources, faces, indices, use offsets, uses
/// ([`hce_geometry::adaptive_flat::AdaptiveFlat::kernel_lists`]) and triangle starts (per
/// coarse triangle its first triangle, then the count).
pub fn tables(request: &[u32]) -> Result<Vec<u32>, String> {
    let mut r = Reader::new(request);
    let index = r.u32()?;
    let object = read_object(&mut r).map_err(|e| format!("objects[{index}]: {e}"))?;
    let reconstruction = read_reconstruction(&mut r)?;
    let refinement = read_flat_refinement(&mut r)?;
    let at = |e: &dyn std::fmt::Display| format!("objects[{index}]: {e}");
    let summary = validate_tables(&object).map_err(|e| at(&e))?;
    let mesh = &object.mesh;
    let loop_tables = match object.kind {
        ObjectKind::Multiresolution => Some(
            LoopKernelTables::new(mesh).map_err(|e| at(&format!("object {}: {e}", object.name)))?,
        ),
        ObjectKind::Flat => None,
    };
    let topology = FlatTopology::new(&object.name, mesh).map_err(|e| at(&e))?;
    let split = SplitTables::from_topology(mesh, &topology, object.kind);
    let light = if reconstruction == Reconstruction::NearestNormal {
        vec![0]
    } else {
        LightingTable::build_with(&object, reconstruction)
            .map_err(|e| at(&e))?
            .to_words()
            .ok_or_else(|| at(&"the lighting table is too large for 32-bit word indices"))?
    };
    let mut w = Writer::default();
    w.u32(summary.max_depth);
    w.u32(topology.vertex_count);
    w.u32(topology.triangle_count);
    w.u32(topology.edge_count);
    w.words(&topology.edge_verts);
    w.u32(split.copies);
    w.u32(split.split_edges);
    for table in split.tables() {
        w.words(table);
    }
    match &loop_tables {
        None => w.u32(0),
        Some(t) => {
            w.u32(1);
            w.words(&t.tri_flags);
            w.words(&t.crease);
            w.words(&t.weights);
            w.u32(t.max_valence);
            w.u32(t.ring_points);
        }
    }
    w.words(&light);
    if object.kind == ObjectKind::Flat && refinement == FlatRefinement::Adaptive {
        let adaptive = refine_adaptive_flat(&object).map_err(|e| at(&e))?;
        let lists = adaptive.kernel_lists();
        w.u32(1);
        w.u32(lists.vertices);
        w.u32(lists.triangles);
        for section in &lists.sections {
            w.words(section);
        }
        w.words(&adaptive.triangle_start);
    } else {
        w.u32(0);
    }
    Ok(w.finish())
}

/// The geometry hash (SPEC.md 2.5) of the corners `triangles` pick from `positions`. Request:
/// `floats` positions (3 per vertex), `words` triangles. Result: `u64` hash.
pub fn geometry_hash(request: &[u32]) -> Result<Vec<u32>, String> {
    let mut r = Reader::new(request);
    let positions = r.floats()?;
    let triangles = r.words()?;
    let vertices = positions.len() / 3;
    if let Some(&v) = triangles.iter().find(|&&v| v as usize >= vertices) {
        return Err(format!("index {v} is out of range for {vertices} vertices"));
    }
    let hash = hce_format::geometry_hash(triangles.iter().map(|&v| {
        let v = 3 * v as usize;
        [positions[v], positions[v + 1], positions[v + 2]]
    }));
    let mut w = Writer::default();
    w.u64(hash);
    Ok(w.finish())
}

/// A result buffer: `[words, status, payload…]`.
fn result(out: Result<Vec<u32>, String>) -> Vec<u32> {
    let (status, payload) = match out {
        Ok(words) => (0, words),
        Err(message) => {
            let mut w = Writer::default();
            w.string(&message);
            (1, w.finish())
        }
    };
    let mut v = Vec::with_capacity(payload.len() + 2);
    v.push((payload.len() + 2) as u32);
    v.push(status);
    v.extend_from_slice(&payload);
    v
}

#[allow(unsafe_code)]
mod ffi;
