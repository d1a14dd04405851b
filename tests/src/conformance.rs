//! The conformance suite's generator (`conformance/`, described in its README): valid files from
//! the format's examples and a bundled sample, invalid files made by breaking exactly one rule
//! of a valid one, and `manifest.json` with each file's expected `hce validate` outcome and
//! problems, and for valid files the refined positions, normals and colours (both
//! reconstructions) of probe vertices at levels 1 to 3.
//!
//! Everything is deterministic: the same sources give the same bytes. Run
//! `cargo run -p hce-tests --bin gen-conformance` to rewrite the directory.

use std::path::Path;

use hce_format::{
    example, rgb9e5, validate_bytes, write, Container, Problem, RULE_CORNER, RULE_CREASE,
    RULE_SMOOTH, SPOKE_SHARP, VERTEX_BOUNDARY, VERTEX_RULE_SHIFT,
};
use hce_format::{validate_asset_report, GltfAsset as Asset, EXTENSION_NAME};
use hce_geometry::colour::{apply_baked_colours_with, Reconstruction};
use hce_geometry::refine::{refine_object, RefinedObject};
use serde_json::{json, Value};

/// Levels whose probes the manifest records.
pub const PROBE_LEVELS: [u32; 3] = [1, 2, 3];

/// One file of the suite.
pub struct Case {
    /// Path inside `conformance/`, e.g. `invalid/trailing-bytes.hce`.
    pub file: String,
    pub bytes: Vec<u8>,
    /// What the file shows, for people.
    pub description: String,
    /// The program whose output the bytes are, when it is not this generator: `hce bake`, or a
    /// glTF tool's command (their exact bytes follow that program; the regeneration check
    /// compares only their expectations).
    pub generated_by: Option<String>,
}

/// What a probe field reads: one object refined to one level, with its colours under both
/// reconstructions (SPEC.md Appendix G).
pub struct Probed {
    /// The refinement and its smooth colours, as `hce subdivide` computes them.
    pub refined: RefinedObject,
    /// The same vertices' colours with [`Reconstruction::NearestNormal`].
    pub nearest: Vec<[f32; 3]>,
}

/// A probe column: the name of a field and how to compute it for vertex `v`.
type ProbeField = (&'static str, fn(&Probed, usize) -> Value);

/// The fields recorded per probe vertex.
pub const PROBE_FIELDS: &[ProbeField] = &[
    ("position", |p, v| vector(p.refined.mesh.positions[v])),
    ("normal", |p, v| vector(p.refined.mesh.normals[v])),
    ("colour_smooth", |p, v| vector(p.refined.colours[v])),
    ("colour_nearest", |p, v| vector(p.nearest[v])),
];

/// `[x, y, z]` as shortest round-trip decimals plus the exact `f32` bits in hex.
fn vector(p: [f32; 3]) -> Value {
    json!({
        "xyz": p,
        "bits": p.map(|x| format!("{:08x}", x.to_bits())),
    })
}

/// `example::grid(3, 2)` with the interior line `x = 1` made a crease: both spokes of each of
/// its edges sharp, the vertex rules as Appendix C rule 3 ties them to the spokes (crease inside,
/// corner where the line meets the boundary). Refined, its vertices split per side (SPEC.md F.5).
fn creased_grid() -> Container {
    let mut c = example::grid(3, 2);
    let m = &mut c.objects[0].mesh;
    let on_line = |m: &hce_format::ControlMesh, v: u32| m.positions[3 * v as usize] == 1.0;
    for v in 0..m.vertex_count() {
        let (a, b) = (m.ring_offsets[v] as usize, m.ring_offsets[v + 1] as usize);
        for s in a..b {
            if on_line(m, v as u32) && on_line(m, m.ring[s]) {
                m.spoke_flags[s] |= SPOKE_SHARP;
            }
        }
        let sharp = (a..b)
            .filter(|&s| m.spoke_flags[s] & SPOKE_SHARP != 0)
            .count();
        let boundary = m.vertex_flags[v] & VERTEX_BOUNDARY != 0;
        let rule = if (boundary && b - a == 2) || sharp >= 3 {
            RULE_CORNER
        } else if sharp == 2 {
            RULE_CREASE
        } else {
            RULE_SMOOTH
        };
        m.vertex_flags[v] = (m.vertex_flags[v] & VERTEX_BOUNDARY) | (rule << VERTEX_RULE_SHIFT);
    }
    c
}

/// The unit normal `(p1 − p0) × (p2 − p0)` of a triangle, in `f64`.
fn face_normal(p: [[f32; 3]; 3]) -> [f64; 3] {
    let p = p.map(|c| c.map(f64::from));
    let (u, v) = (
        [0, 1, 2].map(|k| p[1][k] - p[0][k]),
        [0, 1, 2].map(|k| p[2][k] - p[0][k]),
    );
    let n = [
        u[1] * v[2] - u[2] * v[1],
        u[2] * v[0] - u[0] * v[2],
        u[0] * v[1] - u[1] * v[0],
    ];
    let l = (n[0] * n[0] + n[1] * n[1] + n[2] * n[2]).sqrt();
    n.map(|x| x / l)
}

/// A flat strip of three unit squares (six triangles) along `x`: the first lies in `z = 0`, the
/// second rises 5 degrees from it (a fold under 10 degrees: joined, its vertices shared), the
/// third turns up 90 degrees from the second (a fold that splits, SPEC.md F.5, G.2). Every
/// triangle has its geometric normal; the even ones a tree one level deep, the odd ones a
/// single node; each square its own light, the upturned one dark.
fn flat_fold() -> Container {
    use hce_format::{geometry_hash, BitWriter, Metadata, Object, ObjectKind, TriangleRecord};
    let (s5, c5) = 5f64.to_radians().sin_cos();
    // Where the strip is at x = 0, 1, 2, 3 (in the xz plane).
    let xz = [
        [0.0, 0.0],
        [1.0, 0.0],
        [1.0 + c5, s5],
        [1.0 + c5 - s5, s5 + c5],
    ];
    let mut positions = Vec::new();
    for y in 0..2 {
        for p in xz {
            positions.extend([p[0] as f32, y as f32, p[1] as f32]);
        }
    }
    let id = |x: u32, y: u32| y * 4 + x;
    let mut triangles = Vec::new();
    for x in 0..3 {
        triangles.extend([id(x, 0), id(x + 1, 0), id(x + 1, 1)]);
        triangles.extend([id(x, 0), id(x + 1, 1), id(x, 1)]);
    }
    let corner = |v: u32| {
        let i = 3 * v as usize;
        [positions[i], positions[i + 1], positions[i + 2]]
    };
    let hash = geometry_hash(triangles.iter().map(|&v| corner(v)));
    let mut w = BitWriter::new();
    let (mut records, mut normals, mut colours) = (Vec::new(), Vec::new(), Vec::new());
    for (t, tri) in triangles.chunks_exact(3).enumerate() {
        let flags: &[bool] = if t % 2 == 0 {
            &[true, false, false, false, false]
        } else {
            &[false]
        };
        let bits_start = w.push_tree(flags).expect("a small tree") as u32;
        records.push(TriangleRecord {
            bits_start,
            colour_start: colours.len() as u32,
            normal_start: normals.len() as u32,
            normal_count: 1,
        });
        normals.push(face_normal([0, 1, 2].map(|c| corner(tri[c]))).map(|x| x as f32));
        let light = [[0.8, 0.7, 0.6], [0.6, 0.55, 0.5], [0.05, 0.04, 0.03]][t / 2];
        for k in 0..flags.len() {
            let f = 1.0 + 0.1 * k as f32;
            colours.push(rgb9e5::encode(light.map(|c| c * f)));
        }
    }
    let (bits, bit_len) = w.finish();
    Container {
        metadata: Metadata {
            generator: "hce conformance flat fold".into(),
            bake_parameters: String::new(),
            source_hash: hash,
        },
        objects: vec![Object {
            name: "fold".into(),
            kind: ObjectKind::Flat,
            geometry_hash: hash,
            mesh: example::control_mesh(positions, triangles),
            triangles: records,
            normals,
            bits,
            bit_len,
            colours,
            corner_colours: Vec::new(),
        }],
    }
}

/// A multiresolution fan of four triangles of different areas around an apex (vertex 0), with
/// 1, 2, 3 and 4 normals in their sets and trees 0, 1, 2 and 1 deep: the leaves meeting at the
/// apex and along the fan's edges differ in area, depth and normal count, so the probes'
/// colours pin the weights of SPEC.md G.3 (a sample weighs its leaf's area over its triangle's
/// normal count).
fn uneven_normals() -> Container {
    use hce_format::{geometry_hash, BitWriter, Metadata, Object, ObjectKind, TriangleRecord};
    let positions = vec![
        0.0, 0.0, 0.5, // the apex
        1.0, 0.0, 0.0, 0.0, 1.5, 0.0, -0.8, 0.0, 0.0, 0.0, -1.2, 0.0,
    ];
    let triangles = vec![0, 1, 2, 0, 2, 3, 0, 3, 4, 0, 4, 1];
    let corner = |v: u32| {
        let i = 3 * v as usize;
        [positions[i], positions[i + 1], positions[i + 2]]
    };
    let hash = geometry_hash(triangles.iter().map(|&v| corner(v)));
    let unit = |n: [f64; 3]| {
        let l = (n[0] * n[0] + n[1] * n[1] + n[2] * n[2]).sqrt();
        n.map(|x| (x / l) as f32)
    };
    // Directions the extra normals lean towards, one more per triangle.
    let tilts = [[0.4, 0.0, 0.0], [0.0, 0.4, 0.1], [-0.3, -0.2, 0.3]];
    let trees: [&[bool]; 4] = [
        &[false],
        &[true, false, false, false, false],
        &[true, false, false, true, false, false, false, false, false],
        &[true, false, false, false, false],
    ];
    let mut w = BitWriter::new();
    let (mut records, mut normals, mut colours) = (Vec::new(), Vec::new(), Vec::new());
    for (t, tri) in triangles.chunks_exact(3).enumerate() {
        let g = face_normal([0, 1, 2].map(|c| corner(tri[c])));
        let set: Vec<[f32; 3]> = std::iter::once(unit(g))
            .chain(
                tilts[..t]
                    .iter()
                    .map(|d| unit([g[0] + d[0], g[1] + d[1], g[2] + d[2]])),
            )
            .collect();
        let bits_start = w.push_tree(trees[t]).expect("a small tree") as u32;
        records.push(TriangleRecord {
            bits_start,
            colour_start: colours.len() as u32,
            normal_start: normals.len() as u32,
            normal_count: set.len() as u32,
        });
        for k in 0..trees[t].len() {
            for (j, n) in set.iter().enumerate() {
                // Brighter towards +x and up, with a step per node and per normal.
                let base = 0.3 + 0.2 * t as f32 + 0.05 * k as f32;
                let lean = 0.5 * n[0] + 0.3 * n[2] + 0.1 * j as f32;
                colours.push(rgb9e5::encode([
                    base + lean,
                    0.5 * base + 0.2 * lean,
                    0.25 + 0.1 * lean,
                ]));
            }
        }
        normals.extend(set);
    }
    let (bits, bit_len) = w.finish();
    Container {
        metadata: Metadata {
            generator: "hce conformance uneven normals".into(),
            bake_parameters: String::new(),
            source_hash: hash,
        },
        objects: vec![Object {
            name: "fan".into(),
            kind: ObjectKind::Multiresolution,
            geometry_hash: hash,
            mesh: example::control_mesh(positions, triangles),
            triangles: records,
            normals,
            bits,
            bit_len,
            colours,
            corner_colours: Vec::new(),
        }],
    }
}

/// Every case, valid ones first. `cornell` is the bundled Cornell box, already baked.
pub fn cases(cornell_baked: Vec<u8>) -> Vec<Case> {
    let case = |file: &str, bytes: Vec<u8>, description: &str| Case {
        file: file.into(),
        bytes,
        description: description.into(),
        generated_by: None,
    };
    let hce = |c: &Container| write(c).expect("example containers are consistent");
    let mut out = vec![
        case(
            "valid/triangle.hce",
            hce(&example::single_triangle()),
            "SPEC.md Appendix D: one multiresolution triangle, a 9-node tree",
        ),
        case(
            "valid/two-triangles.hce",
            hce(&example::two_triangles()),
            "two triangles sharing an interior edge",
        ),
        case(
            "valid/grid.hce",
            hce(&example::grid(3, 2)),
            "a 3 x 3 grid (18 triangles), trees 2 deep",
        ),
        case(
            "valid/creased-grid.hce",
            hce(&creased_grid()),
            "the grid with the line x = 1 a crease: its refined vertices split per side \
             (SPEC.md F.5), the last probes are copies",
        ),
        case(
            "valid/flat-fold.hce",
            hce(&flat_fold()),
            "a flat strip folded 5 degrees (joined: vertices shared) and 90 degrees (split: \
             the refined vertices on the fold are drawn once per side, SPEC.md F.5, G.2), the \
             last probes are copies",
        ),
        case(
            "valid/uneven-normals.hce",
            hce(&uneven_normals()),
            "SPEC.md G.3: a multiresolution fan whose triangles have 1 to 4 normals and trees 0 to \
             2 deep; probe 0 is the apex, where leaves of every area, depth and normal count \
             meet (a sample weighs its leaf's area over its triangle's normal count)",
        ),
        case(
            "valid/triangle.glb",
            example::triangle_glb(),
            "the Appendix D container in a GLB, linked from one primitive",
        ),
        Case {
            file: "valid/cornell-box.glb".into(),
            bytes: cornell_baked,
            description: "samples/cornell-box.glb baked by hce bake (flat objects)".into(),
            generated_by: Some("hce bake".into()),
        },
    ];

    // Container mutations: each breaks one rule (SPEC.md Appendix C).
    let mut c = example::two_triangles();
    c.objects[0].mesh.positions[0] = 0.25;
    out.push(case(
        "invalid/geometry-hash-mismatch.hce",
        hce(&c),
        "rule 11: POSN edited after baking, the object's geometry_hash no longer matches",
    ));
    let mut c = example::two_triangles();
    let m = &mut c.objects[0].mesh;
    if let Some(s) = (0..m.ring.len()).find(|&s| m.spoke_flags[s] == 0) {
        m.spoke_flags[s] |= SPOKE_SHARP;
    }
    out.push(case(
        "invalid/sharp-one-end.hce",
        hce(&c),
        "rule 3: the sharp bit on one spoke of the interior edge only",
    ));
    let mut c = example::two_triangles();
    c.objects[0].mesh.spoke_flags[0] |= 4;
    out.push(case(
        "invalid/spoke-flag-unknown-bit.hce",
        hce(&c),
        "rule 3 and A.5: spoke flag bit 2 set; new spoke-flag bits are a major-version change",
    ));
    let mut b = hce(&example::single_triangle());
    b.extend_from_slice(&[0u8; 256]);
    let len = b.len() as u64;
    b[16..24].copy_from_slice(&len.to_le_bytes());
    reseal_header(&mut b);
    out.push(case(
        "invalid/trailing-bytes.hce",
        b,
        "A.1: 256 zero bytes after the last section, counted in file_length",
    ));
    let mut b = hce(&example::single_triangle());
    flip_last_byte(&mut b);
    out.push(case(
        "invalid/section-checksum.hce",
        b,
        "A.4: one bit flipped in COLR, its CRC-32 no longer matches",
    ));
    let mut b = hce(&example::single_triangle());
    b[0] = 0x09;
    out.push(case(
        "invalid/high-bit-stripped.hce",
        b,
        "A.2: the identifier's first byte lost its high bit (7-bit transfer)",
    ));
    let mut c = example::single_triangle();
    c.metadata.bake_parameters = "levels=3".into();
    out.push(case(
        "invalid/bake-parameters-not-json.hce",
        hce(&c),
        "A.6: bake_parameters is neither empty nor a JSON object",
    ));

    // The validation stages (SPEC.md Appendix C): what a failure leaves unchecked.
    let mut c = example::two_triangles();
    c.objects[0].mesh.positions[0] = 0.25;
    let mut b = hce(&c);
    wrong_edge_count(&mut b);
    flip_last_byte(&mut b);
    out.push(case(
        "invalid/stages-sections.hce",
        b,
        "Appendix C stage 2: a COLR checksum mismatch (reported), edge_count one too large (a \
         decoding failure, reported at file) and POSN edited (rule 11, skipped after the \
         decoding failure)",
    ));

    // glTF mutations of the valid GLB (SPEC.md Section 3): its JSON edited, and the bytes of
    // its embedded container.
    let view = |j: &Value| {
        j["extensions"][EXTENSION_NAME]["bufferView"]
            .as_u64()
            .unwrap_or(0) as usize
    };
    let damaged_glb =
        |file: &str, description: &str, edit: &dyn Fn(&mut Value), damage: &dyn Fn(&mut [u8])| {
            let a = Asset::from_glb(&example::triangle_glb()).expect("the example GLB parses");
            let mut j = a.json;
            let mut bin = a.bin.unwrap_or_default();
            let v = &j["bufferViews"][view(&j)];
            let at = v["byteOffset"].as_u64().unwrap_or(0) as usize;
            let len = v["byteLength"].as_u64().unwrap_or(0) as usize;
            damage(&mut bin[at..at + len]);
            edit(&mut j);
            let bytes = hce_format::write_glb(&j, &bin).expect("a small GLB");
            case(file, bytes, description)
        };
    let glb = |file: &str, description: &str, edit: &dyn Fn(&mut Value)| {
        damaged_glb(file, description, edit, &|_| {})
    };
    let link = "/meshes/0/primitives/0/extensions/EXT_hce_baked_lighting";
    out.extend([
        glb(
            "invalid/extension-not-used.glb",
            "3.2: EXT_hce_baked_lighting missing from extensionsUsed",
            &|j| j["extensionsUsed"] = json!([]),
        ),
        glb(
            "invalid/extension-required.glb",
            "3.2: EXT_hce_baked_lighting listed in extensionsRequired",
            &|j| j["extensionsRequired"] = json!([EXTENSION_NAME]),
        ),
        glb(
            "invalid/buffer-view-stride-target.glb",
            "3.3: the container's buffer view has byteStride and target",
            &|j| {
                let v = view(j);
                j["bufferViews"][v]["byteStride"] = json!(4);
                j["bufferViews"][v]["target"] = json!(34962);
            },
        ),
        glb(
            "invalid/bad-version.glb",
            "3.3: version \"1\" does not match ^[0-9]+\\.[0-9]+$",
            &|j| j["extensions"][EXTENSION_NAME]["version"] = json!("1"),
        ),
        glb(
            "invalid/uppercase-geometry-hash.glb",
            "3.3: geometryHash in uppercase: one problem at the property",
            &|j| {
                let h = j
                    .pointer(&format!("{link}/geometryHash"))
                    .and_then(Value::as_str)
                    .unwrap_or("")
                    .to_uppercase();
                if let Some(x) = j.pointer_mut(&format!("{link}/geometryHash")) {
                    *x = json!(h);
                }
            },
        ),
        moved_vertex_glb(
            "invalid/stale-primitive-hash.glb",
            "2.6, 3.5: geometryHash differs from the primitive's triangles and vertex 2 moved \
             off the plane by half the triangle's size, far beyond the tolerance (edited after \
             baking; a differing hash alone is no edit)",
        ),
        glb(
            "invalid/object-out-of-range.glb",
            "3.5: the primitive names object 4 of a 1-object container",
            &|j| {
                if let Some(x) = j.pointer_mut(&format!("{link}/object")) {
                    *x = json!(4);
                }
            },
        ),
        damaged_glb(
            "invalid/stages-layout.glb",
            "Appendix C stage 1: the container's header checksum broken (reported at file; the \
             container is not read further); a second primitive with an uppercase geometryHash \
             (rule 14, reported); the first primitive's geometryHash stale (rule 15, reported: \
             it needs no container) and its object 4 (not judged without the container)",
            &|j| {
                let mut second = j["meshes"][0]["primitives"][0].clone();
                let upper = second["extensions"][EXTENSION_NAME]["geometryHash"]
                    .as_str()
                    .unwrap_or("")
                    .to_uppercase();
                second["extensions"][EXTENSION_NAME]["geometryHash"] = json!(upper);
                if let Some(p) = j["meshes"][0]["primitives"].as_array_mut() {
                    p.push(second);
                }
                stale_link_to_object_4(j, link);
            },
            &|b| b[28] ^= 1,
        ),
        damaged_glb(
            "invalid/stages-sections.glb",
            "Appendix C stage 2: the container's COLR checksum broken (reported) and its \
             edge_count one too large (a decoding failure, reported at file); the primitive's \
             geometryHash stale (rule 15, reported: it needs no container) and its object 4 (not \
             judged without the container)",
            &|j| stale_link_to_object_4(j, link),
            &|b| {
                wrong_edge_count(b);
                flip_last_byte(b);
            },
        ),
    ]);
    out.extend(optimised_cases());
    out
}

/// The example GLB (one triangle) with vertex 2 moved to z = 0.5 and its geometryHash stale.
fn moved_vertex_glb(file: &str, description: &str) -> Case {
    let a = Asset::from_glb(&example::triangle_glb()).expect("the example GLB parses");
    let mut j = a.json;
    let mut bin = a.bin.unwrap_or_default();
    // POSITION is the first buffer view: vertex 2's z is bytes 32..36.
    bin[32..36].copy_from_slice(&0.5f32.to_le_bytes());
    j["meshes"][0]["primitives"][0]["extensions"][EXTENSION_NAME]["geometryHash"] =
        json!("0123456789abcdef");
    j["accessors"][0]["max"] = json!([1.0, 1.0, 0.5]);
    Case {
        file: file.into(),
        bytes: hce_format::write_glb(&j, &bin).expect("a small GLB"),
        description: description.into(),
        generated_by: None,
    }
}

/// A primitive as an optimiser may leave it: positions, triangles, and how positions are stored.
struct Rewritten {
    positions: Vec<[f32; 3]>,
    triangles: Vec<[u32; 3]>,
    /// Normalized SHORTs of `bits` bits over the box, the dequantization in the node (what
    /// gltf-transform's `quantize` writes), instead of `FLOAT`.
    quantized_bits: Option<u32>,
}

impl Rewritten {
    /// The grid as `hce bake` writes a primitive: three vertices per triangle, in the object's
    /// triangle and corner order.
    fn unwelded(c: &Container) -> Self {
        let m = &c.objects[0].mesh;
        let p = |v: u32| {
            let i = 3 * v as usize;
            [m.positions[i], m.positions[i + 1], m.positions[i + 2]]
        };
        Rewritten {
            positions: m.triangles.iter().map(|&v| p(v)).collect(),
            triangles: (0..m.triangle_count() as u32)
                .map(|t| [3 * t, 3 * t + 1, 3 * t + 2])
                .collect(),
            quantized_bits: None,
        }
    }

    /// The grid welded: the object's own vertices and triangles.
    fn welded(c: &Container) -> Self {
        let m = &c.objects[0].mesh;
        Rewritten {
            positions: m
                .positions
                .chunks_exact(3)
                .map(|p| [p[0], p[1], p[2]])
                .collect(),
            triangles: m
                .triangles
                .chunks_exact(3)
                .map(|t| [t[0], t[1], t[2]])
                .collect(),
            quantized_bits: None,
        }
    }
}

/// `example::grid(3, 2)` in a GLB whose one primitive is `prim`, linked to object 0 with the
/// object's (baked) geometry hash: what an optimiser leaves of a baked GLB that it kept the
/// extension of.
fn grid_glb(c: &Container, prim: &Rewritten) -> Vec<u8> {
    let mut bin = Vec::new();
    let lo = (0..3).map(|a| prim.positions.iter().map(|p| p[a]).fold(f32::MAX, f32::min));
    let hi = (0..3).map(|a| prim.positions.iter().map(|p| p[a]).fold(f32::MIN, f32::max));
    let (lo, hi): (Vec<f32>, Vec<f32>) = (lo.collect(), hi.collect());
    let mut node = json!({ "mesh": 0 });
    let position = match prim.quantized_bits {
        None => {
            for p in &prim.positions {
                for x in p {
                    bin.extend_from_slice(&x.to_le_bytes());
                }
            }
            json!({ "bufferView": 0, "componentType": 5126, "count": prim.positions.len(),
                    "type": "VEC3", "min": lo, "max": hi })
        }
        Some(bits) => {
            // One scale for every axis, the box's centre as offset; `bits` levels stored in the
            // top bits of a SHORT, as gltf-transform does for fewer than 16 bits.
            let centre: Vec<f32> = (0..3).map(|a| (lo[a] + hi[a]) / 2.0).collect();
            let half = (0..3).map(|a| (hi[a] - lo[a]) / 2.0).fold(0.0, f32::max);
            let levels = ((1u32 << (bits - 1)) - 1) as f32;
            let step = 1 << (16 - bits);
            let (mut qlo, mut qhi) = ([i16::MAX; 3], [i16::MIN; 3]);
            for p in &prim.positions {
                for a in 0..3 {
                    let q = (((p[a] - centre[a]) / half * levels).round() as i32 * step) as i16;
                    (qlo[a], qhi[a]) = (qlo[a].min(q), qhi[a].max(q));
                    bin.extend_from_slice(&q.to_le_bytes());
                }
                bin.extend_from_slice(&0i16.to_le_bytes());
            }
            let scale = half * 32767.0 / (levels * step as f32);
            node["translation"] = json!(centre);
            node["scale"] = json!([scale, scale, scale]);
            json!({ "bufferView": 0, "componentType": 5122, "normalized": true,
                    "count": prim.positions.len(), "type": "VEC3",
                    "min": qlo.map(|q| f32::from(q) / 32767.0), "max": qhi.map(|q| f32::from(q) / 32767.0) })
        }
    };
    let positions_len = bin.len();
    for t in &prim.triangles {
        for v in t {
            bin.extend_from_slice(&v.to_le_bytes());
        }
    }
    let stride = if prim.quantized_bits.is_some() {
        json!(8)
    } else {
        Value::Null
    };
    let mut view0 =
        json!({ "buffer": 0, "byteOffset": 0, "byteLength": positions_len, "target": 34962 });
    if !stride.is_null() {
        view0["byteStride"] = stride;
    }
    let mut j = json!({
        "asset": { "version": "2.0", "generator": "hce conformance" },
        "scene": 0,
        "scenes": [{ "nodes": [0] }],
        "nodes": [node],
        "meshes": [{ "primitives": [{ "attributes": { "POSITION": 0 }, "indices": 1 }] }],
        "accessors": [
            position,
            { "bufferView": 1, "componentType": 5125, "count": 3 * prim.triangles.len(), "type": "SCALAR" }
        ],
        "bufferViews": [
            view0,
            { "buffer": 0, "byteOffset": positions_len, "byteLength": bin.len() - positions_len, "target": 34963 }
        ],
        "buffers": [{ "byteLength": bin.len() }],
    });
    if prim.quantized_bits.is_some() {
        j["extensionsUsed"] = json!(["KHR_mesh_quantization"]);
        j["extensionsRequired"] = json!(["KHR_mesh_quantization"]);
    }
    let container = write(c).expect("example containers are consistent");
    hce_format::embed_container(&mut j, &mut bin, &container).expect("a fresh asset");
    hce_format::link_primitive(
        &mut j,
        &hce_format::PrimitiveLink {
            mesh: 0,
            primitive: 0,
            object: 0,
            geometry_hash: c.objects[0].geometry_hash,
            first_triangle: 0,
        },
    )
    .expect("the primitive exists");
    hce_format::write_glb(&j, &bin).expect("a small GLB")
}

/// The same-geometry rule (SPEC.md 2.6) on the grid in a GLB: what optimisers do without
/// changing the surface (valid, the geometryHash left stale as they leave it), and edits.
fn optimised_cases() -> Vec<Case> {
    let c = example::grid(3, 2);
    let case = |file: &str, prim: &Rewritten, description: &str| Case {
        file: file.into(),
        bytes: grid_glb(&c, prim),
        description: description.into(),
        generated_by: None,
    };
    let base = Rewritten::unwelded(&c);
    // Triangles in reverse order, each one's corners rotated by its index, vertices renumbered
    // from the end (gltf-transform `reorder`).
    let mut reordered = Rewritten::unwelded(&c);
    let n = reordered.positions.len() as u32;
    reordered.triangles = base
        .triangles
        .iter()
        .enumerate()
        .rev()
        .map(|(t, tri)| {
            let mut r = tri.map(|v| n - 1 - v);
            r.rotate_left(t % 3);
            r
        })
        .collect();
    reordered.positions.reverse();
    let welded = Rewritten::welded(&c);
    let quantized = Rewritten {
        quantized_bits: Some(14),
        ..Rewritten::welded(&c)
    };
    // Vertex (1, 1) raised by 0.25, 30 times the tolerance D/512.
    let mut moved = Rewritten::welded(&c);
    moved.positions[5][2] += 0.25;
    // Vertex (1, 1) collapsed into (2, 1), its two degenerate triangles removed.
    let mut simplified = Rewritten::welded(&c);
    simplified.triangles = simplified
        .triangles
        .iter()
        .map(|t| t.map(|v| if v == 5 { 6 } else { v }))
        .filter(|t| t[0] != t[1] && t[1] != t[2] && t[2] != t[0])
        .collect();
    let mut flipped = Rewritten::welded(&c);
    flipped.triangles[4].swap(1, 2);
    // The first quad's two triangles re-triangulated across its other diagonal: every corner
    // where it was, the (non-planar) surface changed.
    let mut retriangulated = Rewritten::welded(&c);
    let [t0, t1] = [retriangulated.triangles[0], retriangulated.triangles[1]];
    let o0 = t0
        .iter()
        .position(|v| !t1.contains(v))
        .expect("quad triangles share an edge");
    let [o0, p, q] = [t0[o0], t0[(o0 + 1) % 3], t0[(o0 + 2) % 3]];
    let o1 = *t1
        .iter()
        .find(|v| !t0.contains(v))
        .expect("quad triangles share an edge");
    retriangulated.triangles[0] = [o0, p, o1];
    retriangulated.triangles[1] = [o0, o1, q];
    vec![
        case(
            "valid/grid.glb",
            &base,
            "example::grid(3, 2) in a GLB, its primitive as hce bake writes one (three \
             vertices per triangle, the object's order): the hash fast path of 2.6",
        ),
        case(
            "valid/optimised-reordered.glb",
            &reordered,
            "2.6: the grid's triangles reversed, their corners rotated, vertices renumbered \
             (gltf-transform reorder); geometryHash stale, the surface the same",
        ),
        case(
            "valid/optimised-welded.glb",
            &welded,
            "2.6: the grid welded (gltf-transform weld: 16 vertices for 54 corners); \
             geometryHash stale, the surface the same",
        ),
        case(
            "valid/optimised-quantized.glb",
            &quantized,
            "2.6: the welded grid quantized to 14 bits in normalized SHORTs, the \
             dequantization in the node's scale and translation (gltf-transform quantize); \
             the placement M undoes it",
        ),
        case(
            "invalid/edited-moved-vertex.glb",
            &moved,
            "2.6: the welded grid with vertex (1, 1) raised by 0.25, beyond the tolerance \
             D / 512 = 0.0083",
        ),
        case(
            "invalid/edited-simplified.glb",
            &simplified,
            "2.6: the welded grid with vertex (1, 1) collapsed into (2, 1): 16 triangles for \
             the object's 18 (gltf-transform simplify)",
        ),
        Case {
            file: "valid/optimised-instanced.glb".into(),
            bytes: gpu_instanced(grid_glb(&c, &base)),
            description: "2.6: valid/grid.glb with its node's mesh drawn three times by \
                          EXT_mesh_gpu_instancing (translations 0, 4 and 8 along x), which leaves \
                          the primitive alone: the fast path holds, and every instance is drawn \
                          with the object's light"
                .into(),
            generated_by: None,
        },
        case(
            "invalid/edited-retriangulated.glb",
            &retriangulated,
            "2.6: the welded grid with its first quad split across the other diagonal: every \
             corner where it was, two triangles that match none of the object's",
        ),
        case(
            "invalid/edited-flipped.glb",
            &flipped,
            "2.6: the welded grid with triangle 4's winding reversed: its corners match under \
             a reflection, not a rotation",
        ),
    ]
}

/// Cases that glTF Transform wrote from `valid/grid.glb`, kept as it wrote them (the
/// compressors are theirs, not ours): file, command (from the repository root, with
/// `@gltf-transform/cli` 4.5.1 of `web/gltf-transform`'s lockfile), description. The gltf-transform
/// tests run each command again and compare the bytes; the conformance test checks that each
/// still carries `valid/grid.glb`'s container.
pub const TOOL_CASES: [(&str, &str, &str); 2] = [
    (
        "valid/optimised-meshopt.glb",
        "gltf-transform meshopt conformance/valid/grid.glb conformance/valid/optimised-meshopt.glb \
         --config web/gltf-transform/hce.config.mjs",
        "2.6: valid/grid.glb through gltf-transform meshopt: positions quantized to normalized \
         SHORTs (the dequantization in the node), indices and positions EXT_meshopt_compression \
         streams (TRIANGLES and ATTRIBUTES), read from buffer 0 in place of buffer 1, a fallback \
         buffer without data; geometryHash stale, the surface the same",
    ),
    (
        "valid/optimised-draco.glb",
        "gltf-transform draco conformance/valid/grid.glb conformance/valid/optimised-draco.glb \
         --config web/gltf-transform/hce.config.mjs",
        "2.6: valid/grid.glb through gltf-transform draco: its primitive KHR_draco_mesh_compression, \
         which hce's readers cannot decode: valid, the primitive not checked (a warning), drawn \
         without the baked lighting",
    ),
];

/// The [`TOOL_CASES`], their bytes read by `read` (a path inside `conformance/`).
pub fn tool_cases(read: impl Fn(&str) -> std::io::Result<Vec<u8>>) -> std::io::Result<Vec<Case>> {
    TOOL_CASES
        .iter()
        .map(|(file, command, description)| {
            Ok(Case {
                file: (*file).into(),
                bytes: read(file)?,
                description: (*description).into(),
                generated_by: Some(format!("@gltf-transform/cli 4.5.1: {command}")),
            })
        })
        .collect()
}

/// `glb` with its one node's mesh drawn at x = 0, 4 and 8 by `EXT_mesh_gpu_instancing`.
fn gpu_instanced(glb: Vec<u8>) -> Vec<u8> {
    let a = Asset::parse(&glb).expect("a suite GLB");
    let (mut j, mut bin) = (a.json, a.bin.expect("a GLB has its BIN chunk"));
    bin.resize(bin.len().next_multiple_of(4), 0);
    let at = bin.len();
    for x in [0.0f32, 4.0, 8.0] {
        for v in [x, 0.0, 0.0] {
            bin.extend_from_slice(&v.to_le_bytes());
        }
    }
    let push = |list: &mut Value, item: Value| {
        let a = list
            .as_array_mut()
            .expect("the grid GLB has views and accessors");
        a.push(item);
        a.len() - 1
    };
    let view = push(
        &mut j["bufferViews"],
        json!({ "buffer": 0, "byteOffset": at, "byteLength": 36 }),
    );
    let accessor = push(
        &mut j["accessors"],
        json!({ "bufferView": view, "componentType": 5126, "count": 3, "type": "VEC3",
                "min": [0.0, 0.0, 0.0], "max": [8.0, 0.0, 0.0] }),
    );
    j["buffers"][0]["byteLength"] = json!(bin.len());
    j["nodes"][0]["extensions"] = json!({ "EXT_mesh_gpu_instancing": {
        "attributes": { "TRANSLATION": accessor } } });
    if let Some(used) = j["extensionsUsed"].as_array_mut() {
        used.push(json!("EXT_mesh_gpu_instancing"));
    }
    hce_format::write_glb(&j, &bin).expect("a small GLB")
}

/// Gives the primitive extension object at JSON pointer `link` a geometryHash that matches
/// nothing and object 4 (of a one-object container).
fn stale_link_to_object_4(j: &mut Value, link: &str) {
    if let Some(x) = j.pointer_mut(&format!("{link}/geometryHash")) {
        *x = json!("0123456789abcdef");
    }
    if let Some(x) = j.pointer_mut(&format!("{link}/object")) {
        *x = json!(4);
    }
}

/// Makes object 0's `edge_count` one too large and reseals the `OBJS` checksum (directory
/// entry 1, as the writer lays the file out) and the header's: a decoding failure (A.7).
fn wrong_edge_count(b: &mut [u8]) {
    let entry = 32 + 32;
    let u64_at =
        |b: &[u8], at: usize| u64::from_le_bytes(b[at..at + 8].try_into().expect("8 bytes"));
    let (offset, length) = (
        u64_at(b, entry + 8) as usize,
        u64_at(b, entry + 16) as usize,
    );
    let at = offset + 8 + 36;
    let e = u32::from_le_bytes(b[at..at + 4].try_into().expect("4 bytes"));
    b[at..at + 4].copy_from_slice(&(e + 1).to_le_bytes());
    let crc = crc32fast::hash(&b[offset..offset + length]);
    b[entry + 24..entry + 28].copy_from_slice(&crc.to_le_bytes());
    reseal_header(b);
}

/// Flips a bit of the last byte, in the last section (`COLR`), whose checksum then fails.
fn flip_last_byte(b: &mut [u8]) {
    if let Some(x) = b.last_mut() {
        *x ^= 1;
    }
}

/// Recomputes the header CRC (A.3) after an edit of the header.
fn reseal_header(b: &mut [u8]) {
    let n = u32::from_le_bytes([b[12], b[13], b[14], b[15]]) as usize;
    let mut h = crc32fast::Hasher::new();
    h.update(&b[..28]);
    h.update(&b[32..32 + 32 * n]);
    let crc = h.finalize();
    b[28..32].copy_from_slice(&crc.to_le_bytes());
}

/// What `hce validate` reports for a file, from the library it calls: its problems and its
/// warnings.
pub fn expected_problems(file: &str, bytes: &[u8]) -> (Vec<Problem>, Vec<Problem>) {
    if file.ends_with(".hce") {
        return (validate_bytes(bytes), Vec::new());
    }
    let a = Asset::parse(bytes).expect("suite GLBs parse");
    let buffers = a
        .buffers(|_| Err("no external buffers".into()))
        .expect("GLB buffers");
    let r = validate_asset_report(&a.json, &buffers);
    (r.problems, r.warnings)
}

/// The containers' objects of a valid file, in container order.
pub fn objects(file: &str, bytes: &[u8]) -> Vec<hce_format::Object> {
    let container = if file.ends_with(".hce") {
        bytes.to_vec()
    } else {
        let a = Asset::parse(bytes).expect("suite GLBs parse");
        let buffers = a.buffers(|_| Err("none".into())).expect("GLB buffers");
        hce_format::container_bytes(&a.json, &buffers)
            .ok()
            .flatten()
            .expect("a container")
            .to_vec()
    };
    hce_format::read(&container).expect("valid").objects
}

/// Probe vertices of a refined object: the first, one in the middle and the last.
fn probe_vertices(count: usize) -> Vec<usize> {
    let mut v = vec![0, count / 2, count.saturating_sub(1)];
    v.dedup();
    v
}

/// Per object and level, the probe vertices and their fields.
pub fn probes(file: &str, bytes: &[u8]) -> Value {
    let objects = objects(file, bytes);
    let mut out = Vec::new();
    for (k, o) in objects.iter().enumerate() {
        for level in PROBE_LEVELS {
            let refined = refine_object(o, level).expect("valid objects refine");
            let nearest =
                apply_baked_colours_with(o, &refined.mesh, level, Reconstruction::NearestNormal)
                    .expect("valid objects colour");
            let r = Probed { refined, nearest };
            let vertices: Vec<Value> = probe_vertices(r.refined.mesh.positions.len())
                .into_iter()
                .map(|v| {
                    let mut entry = json!({ "vertex": v });
                    for (name, f) in PROBE_FIELDS {
                        entry[*name] = f(&r, v);
                    }
                    entry
                })
                .collect();
            out.push(json!({
                "object": k,
                "name": o.name,
                "level": level,
                "vertex_count": r.refined.mesh.positions.len(),
                "triangle_count": r.refined.mesh.indices.len(),
                "probes": vertices,
            }));
        }
    }
    json!(out)
}

/// The level of the `scene` entry of baked glTF cases.
pub const SCENE_LEVEL: u32 = 1;

/// What `hce subdivide FILE -l SCENE_LEVEL -o out.glb` writes for a baked glTF case (SPEC.md
/// F.10): per linked primitive, its object, vertex count, output vertex order, and the `NORMAL`
/// and `COLOR_0` (after the scene's one exposure) of probe vertices, numbered as the output
/// numbers them (flat objects' vertices split per coarse triangle).
pub fn scene(file: &str, bytes: &[u8]) -> Value {
    use hce_runtime::asset::{Asset as RuntimeAsset, GltfSource, OpenOptions};
    let scratch = tempfile::tempdir().expect("a scratch folder");
    let input = scratch
        .path()
        .join(Path::new(file).file_name().expect("a file name"));
    std::fs::write(&input, bytes).expect("the scratch copy");
    let source = GltfSource::open_baked(&input)
        .expect("suite GLBs open")
        .expect("baked");
    let asset = RuntimeAsset::from_gltf(&input, &source, &OpenOptions::default()).expect("valid");
    let refined: Vec<RefinedObject> = asset
        .objects
        .iter()
        .map(|o| refine_object(&o.object, SCENE_LEVEL).expect("valid objects refine"))
        .collect();
    let output = scratch.path().join("scene.glb");
    let objects: Vec<&hce_format::Object> = asset.objects.iter().map(|o| &o.object).collect();
    hce_refined::write_refined_scene(
        &output,
        &objects,
        Some((&source.json, source.buffers.as_slice())),
        &refined,
    )
    .expect("the scene writes");
    let (doc, buffers, _) =
        gltf::import_slice(std::fs::read(&output).expect("the scene")).expect("the scene reads");
    let links = hce_format::primitive_links(&source.json).expect("suite GLBs are valid");
    let mut out = Vec::new();
    for mesh in doc.meshes() {
        for prim in mesh.primitives() {
            let reader = prim.reader(|b| Some(&buffers[b.index()][..]));
            let (Some(normals), Some(colours)) = (reader.read_normals(), reader.read_colors(0))
            else {
                continue;
            };
            let normals: Vec<[f32; 3]> = normals.collect();
            let colours: Vec<[f32; 3]> = colours.into_rgb_f32().collect();
            let probes: Vec<Value> = probe_vertices(normals.len())
                .into_iter()
                .map(|v| json!({ "vertex": v, "normal": vector(normals[v]), "colour": vector(colours[v]) }))
                .collect();
            // The suite's scenes keep every mesh and primitive, so the output's numbers are the
            // input's.
            let link = links
                .iter()
                .find(|l| l.mesh == mesh.index() && l.primitive == prim.index())
                .expect("every refined primitive is linked");
            let k = link.object as usize;
            let order = output_vertices(asset.objects[k].kind(), &refined[k].mesh);
            assert_eq!(order.len(), normals.len(), "{file}: output vertices");
            out.push(json!({
                "mesh": mesh.index(),
                "primitive": prim.index(),
                "object": k,
                "vertex_count": normals.len(),
                "refined_vertices": order,
                "probes": probes,
            }));
        }
    }
    json!({ "level": SCENE_LEVEL, "primitives": out })
}

/// The refined vertex (SPEC.md F.5) that each output vertex of `hce subdivide`'s scene is, in
/// output order (SPEC.md F.10): the refined mesh as it is for a multiresolution object; for a
/// flat one, per coarse triangle, each refined vertex at its first use by the triangle's fine
/// triangles, in fine-triangle and corner order.
fn output_vertices(
    kind: hce_format::ObjectKind,
    mesh: &hce_geometry::subdivide::Refined,
) -> Vec<u32> {
    if kind == hce_format::ObjectKind::Multiresolution {
        return (0..mesh.positions.len() as u32).collect();
    }
    let per = 1usize << (2 * mesh.level);
    let mut order = Vec::new();
    for fine in mesh.indices.chunks(per) {
        let mut met = std::collections::HashSet::new();
        order.extend(fine.iter().flatten().filter(|&&i| met.insert(i)));
    }
    order
}

/// The manifest of `cases`.
pub fn manifest(cases: &[Case]) -> Value {
    let entries: Vec<Value> = cases
        .iter()
        .map(|c| {
            let (problems, warnings) = expected_problems(&c.file, &c.bytes);
            let valid = problems.is_empty();
            let listed = |list: &[Problem]| -> Vec<Value> {
                list.iter()
                    .map(|p| json!({ "location": p.location, "message": p.message }))
                    .collect()
            };
            let mut e = json!({
                "file": c.file,
                "description": c.description,
                "valid": valid,
                "exit_status": if valid { 0 } else { 3 },
                "problems": listed(&problems),
            });
            if !warnings.is_empty() {
                e["warnings"] = json!(listed(&warnings));
            }
            if let Some(by) = &c.generated_by {
                e["generated_by"] = json!(by);
            }
            if valid {
                e["refined"] = probes(&c.file, &c.bytes);
                // A primitive that cannot be checked (a warning) keeps `hce subdivide` from
                // applying its lighting, so it refuses the file: no scene to record.
                if !c.file.ends_with(".hce") && warnings.is_empty() {
                    e["scene"] = scene(&c.file, &c.bytes);
                }
            }
            e
        })
        .collect();
    json!({
        "suite": "hce conformance",
        "spec": "SPEC.md, container 1.0",
        "probe_levels": PROBE_LEVELS,
        "cases": entries,
    })
}

/// Bakes the bundled Cornell box at low settings (a moment in the dev profile).
pub fn bake_cornell(samples: &Path, scratch: &Path) -> Vec<u8> {
    use hce_bake::{bake_file, PipelineOptions};
    let output = scratch.join("cornell-box.glb");
    let options = PipelineOptions {
        levels: 2,
        bake: hce_bake::BakeParams {
            bf_epsilon: 5e-2,
            ..hce_bake::BakeParams::default()
        },
        output: output.clone(),
        ..PipelineOptions::default()
    };
    bake_file(
        &samples.join("cornell-box.glb"),
        &options,
        &|_: &str, _: usize, _: usize| {},
    )
    .expect("the sample bakes");
    std::fs::read(&output).expect("the baked sample")
}

/// Writes every case and `manifest.json` under `dir`.
pub fn generate(dir: &Path, cases: &[Case]) -> std::io::Result<()> {
    for c in cases {
        let path = dir.join(&c.file);
        if let Some(p) = path.parent() {
            std::fs::create_dir_all(p)?;
        }
        std::fs::write(path, &c.bytes)?;
    }
    let mut text = serde_json::to_string_pretty(&manifest(cases)).map_err(std::io::Error::other)?;
    text.push('\n');
    std::fs::write(dir.join("manifest.json"), text)
}
