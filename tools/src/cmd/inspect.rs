//! `hce inspect FILE [--json]`: what a `.hce`, `.glb` or `.gltf` file holds: header and version,
//! sections with checksum status, objects with their counts and histograms, and for glTF assets
//! the primitives linked through `EXT_hce_baked_lighting`. The JSON shape is documented in
//! SPEC.md Appendix E.

use clap::Args;

pub use crate::exit::LoadError;

use hce_format::{
    read_layout, read_with, rgb9e5, triangle_trees, Container, ObjectKind, ReadOptions,
};
use hce_runtime::asset::{buffer_files, GltfSource};
use serde_json::{json, Value};
use std::collections::BTreeMap;
use std::path::{Path, PathBuf};

#[derive(Args, Debug)]
pub struct InspectArgs {
    /// A `.hce` container, or a `.glb` / `.gltf` asset that embeds one.
    pub file: PathBuf,
    /// Print one JSON document (shape in SPEC.md Appendix E) instead of text.
    #[arg(long)]
    pub json: bool,
}

/// A primitive linked to a container object, with the hash recomputed from its geometry.
pub struct LinkedPrimitive {
    pub link: hce_format::PrimitiveLink,
    /// `Ok((hash, triangle count))` or why the geometry could not be read.
    pub computed: Result<(u64, usize), String>,
}

/// The container bytes of a file and, for glTF assets, their links.
pub struct Loaded {
    pub format: &'static str,
    pub container: Vec<u8>,
    pub primitives: Vec<LinkedPrimitive>,
}

/// Reads a `.hce`, `.glb` or `.gltf` file and extracts its container.
pub fn load(path: &Path) -> Result<Loaded, LoadError> {
    let bytes =
        std::fs::read(path).map_err(|e| LoadError::Io(format!("{}: {e}", path.display())))?;
    let is_gltf = bytes.starts_with(b"glTF")
        || path
            .extension()
            .is_some_and(|e| e.eq_ignore_ascii_case("gltf") || e.eq_ignore_ascii_case("glb"));
    if !is_gltf {
        return Ok(Loaded {
            format: "hce",
            container: bytes,
            primitives: Vec::new(),
        });
    }
    let invalid = |e: hce_format::GltfError| LoadError::Invalid(format!("{}: {e}", path.display()));
    let dir = path.parent().map(Path::to_path_buf).unwrap_or_default();
    let source = GltfSource::parse(&bytes, buffer_files(&dir)).map_err(invalid)?;
    let format = if source.glb { "glb" } else { "gltf" };
    let container = source
        .container()
        .map_err(invalid)?
        .ok_or_else(|| {
            LoadError::Invalid(format!(
                "{}: the asset does not use {} (no root extension object); bake it with `hce bake`",
                path.display(),
                hce_format::EXTENSION_NAME
            ))
        })?
        .to_vec();
    // Malformed links are left out here; `hce validate` reports each of them.
    let (links, _) = hce_format::scan_primitive_links(&source.json);
    let geometries = hce_format::linked_geometries(&source.json, &source.buffers, &links);
    let primitives = links
        .into_iter()
        .zip(geometries)
        .map(|(link, computed)| LinkedPrimitive {
            link,
            computed: computed.map_err(|e| e.to_string()),
        })
        .collect();
    Ok(Loaded {
        format,
        container,
        primitives,
    })
}

fn histogram(values: impl IntoIterator<Item = u32>) -> BTreeMap<u32, u64> {
    let mut h = BTreeMap::new();
    for v in values {
        *h.entry(v).or_insert(0) += 1;
    }
    h
}

fn histogram_json(h: &BTreeMap<u32, u64>) -> Value {
    Value::Object(h.iter().map(|(k, v)| (k.to_string(), json!(v))).collect())
}

fn object_json(index: usize, o: &hce_format::Object) -> Value {
    let trees = triangle_trees(o);
    let good: Vec<_> = trees.iter().filter_map(|t| t.as_ref().ok()).collect();
    let nodes: u64 = good.iter().map(|s| u64::from(s.node_count)).sum();
    let leaves: u64 = good
        .iter()
        .map(|s| u64::from(s.node_count - s.subdivided))
        .sum();
    let mut lo = [f32::INFINITY; 3];
    let mut hi = [0f32; 3];
    for &c in &o.colours {
        let rgb = rgb9e5::decode(c);
        for k in 0..3 {
            lo[k] = lo[k].min(rgb[k]);
            hi[k] = hi[k].max(rgb[k]);
        }
    }
    let range = if o.colours.is_empty() {
        Value::Null
    } else {
        json!({ "min": lo, "max": hi })
    };
    json!({
        "index": index,
        "name": o.name,
        "kind": match o.kind { ObjectKind::Multiresolution => "multiresolution", ObjectKind::Flat => "flat" },
        "geometry_hash": hce_format::hash_hex(o.geometry_hash),
        "control_points": o.mesh.positions.len() / 3,
        "triangles": o.triangles.len(),
        "ring_length": o.mesh.ring.len(),
        "edges": o.mesh.edges.iter().max().map_or(0, |&e| u64::from(e) + 1),
        "normals": o.normals.len(),
        "normals_per_triangle": histogram_json(&histogram(o.triangles.iter().map(|t| t.normal_count))),
        "tree_depth": histogram_json(&histogram(good.iter().map(|s| s.depth))),
        "undecodable_trees": trees.len() - good.len(),
        "nodes": nodes,
        "leaves": leaves,
        "bits": o.bit_len,
        "colours": o.colours.len(),
        "corner_colours": o.corner_colours.len(),
        "colour_range": range,
    })
}

/// Builds the `--json` document; `Err` when not even the header can be read.
pub fn inspect_json(path: &Path) -> Result<Value, LoadError> {
    let loaded = load(path)?;
    let bytes = &loaded.container;
    let layout =
        read_layout(bytes).map_err(|e| LoadError::Invalid(format!("{}: {e}", path.display())))?;
    let sections: Vec<Value> = layout
        .sections
        .iter()
        .enumerate()
        .map(|(i, s)| {
            json!({
                "index": i,
                "type": s.kind.to_string(),
                "object": (s.object != hce_format::FILE_LEVEL).then_some(s.object),
                "offset": s.offset,
                "length": s.length,
                "crc32": format!("{:08x}", s.crc32),
                "checksum_ok": s.checksum_ok(bytes),
                "known": s.kind.is_known(),
            })
        })
        .collect();
    let read = read_with(
        bytes,
        &ReadOptions {
            verify_checksums: false,
        },
    );
    let (metadata, objects, read_error) = match &read {
        Ok(c) => (
            metadata_json(c),
            c.objects
                .iter()
                .enumerate()
                .map(|(i, o)| object_json(i, o))
                .collect(),
            Value::Null,
        ),
        Err(e) => (Value::Null, Vec::new(), json!(e.to_string())),
    };
    let primitives: Vec<Value> = loaded
        .primitives
        .iter()
        .map(|p| {
            let (computed, triangles, error) = match &p.computed {
                Ok((h, t)) => (json!(hce_format::hash_hex(*h)), json!(t), Value::Null),
                Err(e) => (Value::Null, Value::Null, json!(e)),
            };
            json!({
                "mesh": p.link.mesh,
                "primitive": p.link.primitive,
                "object": p.link.object,
                "first_triangle": p.link.first_triangle,
                "geometry_hash": hce_format::hash_hex(p.link.geometry_hash),
                "computed_hash": computed,
                "hash_ok": p.computed.as_ref().ok().map(|(h, _)| *h == p.link.geometry_hash),
                "triangles": triangles,
                "error": error,
            })
        })
        .collect();
    Ok(json!({
        "file": path.display().to_string(),
        "format": loaded.format,
        "version": { "major": layout.header.major_version, "minor": layout.header.minor_version },
        "file_length": layout.header.file_length,
        "flags": layout.header.flags,
        "sections": sections,
        "metadata": metadata,
        "objects": objects,
        "primitives": primitives,
        "read_error": read_error,
    }))
}

fn metadata_json(c: &Container) -> Value {
    json!({
        "generator": c.metadata.generator,
        "bake_parameters": c.metadata.bake_parameters,
        "source_hash": hce_format::hash_hex(c.metadata.source_hash),
    })
}

fn text_report(v: &Value) -> String {
    use std::fmt::Write;
    let mut out = String::new();
    let _ = writeln!(
        out,
        "{} ({}), container version {}.{}, {} bytes, flags {}",
        v["file"].as_str().unwrap_or(""),
        v["format"].as_str().unwrap_or(""),
        v["version"]["major"],
        v["version"]["minor"],
        v["file_length"],
        v["flags"]
    );
    if let Some(m) = v["metadata"].as_object() {
        let _ = writeln!(
            out,
            "generator {}, source hash {}, bake parameters {}",
            m["generator"], m["source_hash"], m["bake_parameters"]
        );
    }
    let sections = v["sections"].as_array().map(Vec::as_slice).unwrap_or(&[]);
    let _ = writeln!(out, "sections: {}", sections.len());
    let _ = writeln!(
        out,
        "  {:>4}  {:<10}  {:>6}  {:>10}  {:>10}  {:<8}  checksum",
        "#", "type", "object", "offset", "length", "crc32"
    );
    for s in sections {
        let object = if s["object"].is_null() {
            "-".to_string()
        } else {
            s["object"].to_string()
        };
        let status = match (s["checksum_ok"].as_bool(), s["known"].as_bool()) {
            (Some(true), Some(true)) => "ok",
            (Some(true), _) => "ok (unknown type, skipped)",
            _ => "MISMATCH",
        };
        let _ = writeln!(
            out,
            "  {:>4}  {:<10}  {:>6}  {:>10}  {:>10}  {:<8}  {status}",
            s["index"].to_string(),
            s["type"].as_str().unwrap_or(""),
            object,
            s["offset"].to_string(),
            s["length"].to_string(),
            s["crc32"].as_str().unwrap_or("")
        );
    }
    if let Some(e) = v["read_error"].as_str() {
        let _ = writeln!(out, "content unreadable: {e}");
    }
    let objects = v["objects"].as_array().map(Vec::as_slice).unwrap_or(&[]);
    let _ = writeln!(out, "objects: {}", objects.len());
    for o in objects {
        let _ = writeln!(
            out,
            "  [{}] {} ({}), geometry hash {}",
            o["index"],
            o["name"],
            o["kind"].as_str().unwrap_or(""),
            o["geometry_hash"].as_str().unwrap_or("")
        );
        let _ = writeln!(
            out,
            "      control points {}, triangles {}, ring {}, edges {}, normals {}",
            o["control_points"], o["triangles"], o["ring_length"], o["edges"], o["normals"]
        );
        let _ = writeln!(
            out,
            "      normals per triangle: {}",
            hist_text(&o["normals_per_triangle"])
        );
        let _ = writeln!(
            out,
            "      tree depth: {}{}",
            hist_text(&o["tree_depth"]),
            if o["undecodable_trees"].as_u64().unwrap_or(0) > 0 {
                format!(" ({} undecodable)", o["undecodable_trees"])
            } else {
                String::new()
            }
        );
        let _ = writeln!(
            out,
            "      nodes {} ({} leaves), bits {}, colours {}, corner colours {}",
            o["nodes"], o["leaves"], o["bits"], o["colours"], o["corner_colours"]
        );
        if !o["colour_range"].is_null() {
            let _ = writeln!(
                out,
                "      colour range {} .. {}",
                o["colour_range"]["min"], o["colour_range"]["max"]
            );
        }
    }
    let prims = v["primitives"].as_array().map(Vec::as_slice).unwrap_or(&[]);
    if !prims.is_empty() {
        let _ = writeln!(out, "linked primitives: {}", prims.len());
        for p in prims {
            let status = match p["hash_ok"].as_bool() {
                Some(true) => "geometry hash matches".to_string(),
                Some(false) => format!(
                    "GEOMETRY HASH MISMATCH (now {}): edited after baking",
                    p["computed_hash"].as_str().unwrap_or("")
                ),
                None => format!("geometry unreadable: {}", p["error"].as_str().unwrap_or("")),
            };
            let _ = writeln!(
                out,
                "  meshes[{}].primitives[{}] -> object {} from triangle {}: {status}",
                p["mesh"], p["primitive"], p["object"], p["first_triangle"]
            );
        }
    }
    out
}

fn hist_text(h: &Value) -> String {
    match h.as_object() {
        Some(m) if !m.is_empty() => m
            .iter()
            .map(|(k, v)| format!("{k}: {v}"))
            .collect::<Vec<_>>()
            .join(", "),
        _ => "-".into(),
    }
}

/// Writes to stdout, ignoring a closed pipe (`hce inspect x.hce | head` must not panic).
pub fn emit(text: &str) {
    use std::io::Write;
    let mut stdout = std::io::stdout().lock();
    let _ = stdout
        .write_all(text.as_bytes())
        .and_then(|()| stdout.flush());
}

/// Runs the command. A file that cannot be read is an error; so is one whose container is
/// unreadable, after its report is printed.
pub fn run(args: InspectArgs) -> anyhow::Result<()> {
    match inspect_json(&args.file) {
        Ok(v) => {
            if args.json {
                emit(&(serde_json::to_string_pretty(&v)? + "\n"));
            } else {
                emit(&text_report(&v));
            }
            match v["read_error"].as_str() {
                None => Ok(()),
                Some(e) => {
                    Err(crate::exit::Invalid(format!("{}: {e}", args.file.display())).into())
                }
            }
        }
        Err(e) => {
            if args.json {
                println!(
                    "{}",
                    serde_json::to_string_pretty(&json!({
                        "file": args.file.display().to_string(),
                        "error": e.message(),
                    }))?
                );
            }
            Err(e.into())
        }
    }
}
