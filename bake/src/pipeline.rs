//! The whole bake, from a scene file to a baked `.glb`, `.gltf` or `.hce`: what `hce bake` runs.
//!
//! Phases: import → topology (one control mesh per scene object) → normal sets (multiresolution
//! objects: Loop subdivision with the runtime's own CPU reference, then greedy k-centre, see
//! [`crate::normal_sets`]) → hierarchical radiosity ([`crate::bake_with_progress`]) → HCE
//! encoding ([`crate::encode`]) → output.
//!
//! # One container object per scene object, triangle for triangle
//!
//! Every imported object (node instance × primitive) becomes one container object linked from
//! its primitive with `firstTriangle` 0, so SPEC.md 3.3 requires container triangle `t` to be
//! primitive triangle `t`, with the same corners in the same order (the HCE tree paths are
//! relative to the corners). The control mesh is built from the primitive's object-space
//! positions welded bitwise. It is used as is only when it reproduces the primitive corner for
//! corner: same triangle count and order, no triangle flipped by the orientation pass, and every
//! corner at bitwise the primitive's position (so the container's geometry hash is the
//! primitive's). Otherwise (degenerate triangles, inconsistently oriented or non-orientable
//! surfaces, `-0.0` welded with `0.0`) the object is baked **flat** on an unwelded control mesh
//! (three vertices per triangle, which always satisfies the rules) and a warning names it: a
//! multiresolution object loses its smoothing rather than getting colours on the wrong triangles.
//! Non-manifold edges and vertices are fine: the runtime's split keeps triangles and corners.
//!
//! # Normal spaces
//!
//! The container stores normals in the primitive's object space (the space of the control mesh
//! the runtime subdivides and whose subtriangle normals it compares them with). The solver works
//! in world space, so it gets the same sets through the inverse transpose of the node transform,
//! with the geometric normal first taken from its own world triangle.
//!
//! # Mirroring transforms
//!
//! The solver restores the winding of a mirrored instance by swapping corners 1 and 2, which
//! swaps the Left and Right children at every level of its element trees; they are swapped back
//! before encoding so that the trees follow the primitive's own corner order.
//!
//! # Fallback vertex colours
//!
//! `COLOR_0` holds the light arriving at each vertex rather than the outgoing radiosity: per
//! triangle `(B - E) / ρ` (per channel, with `ρ` floored at 0.02), because glTF viewers multiply
//! `COLOR_0` by the base colour; emitting triangles get white so that the emissive material
//! shows. Colours are area-averaged at the primitive's vertices and scaled by one exposure per
//! scene: the reciprocal of the 90th percentile of the vertices' largest channel, so that most of
//! the scene is within [0, 1] and only the brightest tenth saturates.

use std::path::{Path, PathBuf};
use std::time::Instant;

use glam::{Mat3, Vec3};
use hce_format::{Container, ControlMesh, Metadata, Object, ObjectKind};
use hce_geometry::{build_control_mesh, subdivide, weld, Creases, TopologyConfig};

use crate::normal_sets::{select_normal_sets, NormalSetParams};
use crate::output::{bake_gltf, ObjectLink};
use crate::radiosity::{BakeParams, Progress, TriangleSolution};
use hce_meshio::scene::{import_scene, ImportOptions, ImportedScene, ToSolver};

/// Everything `hce bake` can set.
#[derive(Clone, Debug)]
pub struct PipelineOptions {
    pub import: ImportOptions,
    /// Loop subdivision depth the normal sets serve (the deepest level the runtime draws).
    pub levels: u32,
    pub normal_sets: NormalSetParams,
    pub creases: Creases,
    pub bake: BakeParams,
    /// Output file: `.glb`, `.gltf` or `.hce`.
    pub output: PathBuf,
}

impl Default for PipelineOptions {
    fn default() -> Self {
        PipelineOptions {
            import: ImportOptions::default(),
            levels: 3,
            normal_sets: NormalSetParams::default(),
            creases: Creases::None,
            bake: BakeParams::default(),
            output: PathBuf::from("out.glb"),
        }
    }
}

/// Why a bake failed.
#[derive(Debug, thiserror::Error)]
pub enum PipelineError {
    #[error(transparent)]
    Import(#[from] hce_meshio::scene::ImportError),
    #[error(transparent)]
    Bake(#[from] crate::BakeError),
    #[error(transparent)]
    Output(#[from] crate::output::OutputError),
    /// The container could not be encoded.
    #[error(transparent)]
    Write(#[from] hce_format::WriteError),
    #[error(transparent)]
    FileWrite(#[from] hce_meshio::FileWriteError),
    #[error("object {index} '{name}': {message}")]
    Object {
        index: usize,
        name: String,
        message: String,
    },
    #[error("{path}: the output must end in .glb, .gltf or .hce")]
    OutputExtension { path: PathBuf },
    #[error("--max-level {0} is out of range; use 0..=6")]
    Levels(u32),
}

/// Per-object figures of the summary.
#[derive(Clone, Debug, PartialEq)]
pub struct ObjectSummary {
    pub name: String,
    pub kind: ObjectKind,
    pub triangles: usize,
    pub control_vertices: usize,
    /// `histogram[k]`: triangles with `k` normals (multiresolution objects only).
    pub normal_histogram: Vec<usize>,
    pub worst_angle_deg: f32,
}

/// What a bake produced.
#[derive(Clone, Debug)]
pub struct BakeOutcome {
    pub container: Container,
    pub objects: Vec<ObjectSummary>,
    pub coarse_triangles: usize,
    pub elements: usize,
    pub links: usize,
    pub iterations: u32,
    /// Normals-per-triangle histogram over every multiresolution triangle.
    pub normal_histogram: Vec<usize>,
    pub worst_angle_deg: f32,
    /// `(phase, seconds)` in order, the solver's phases included.
    pub phase_seconds: Vec<(String, f64)>,
    /// Bytes written (the `.gltf` JSON plus its `.bin`).
    pub output_bytes: u64,
    /// Import and topology warnings.
    pub warnings: Vec<String>,
    /// What the importer read (units, counts).
    pub import_summary: String,
    pub exposure: f32,
}

/// The control mesh of one object and how it was made.
struct Prepared {
    mesh: ControlMesh,
    kind: ObjectKind,
    /// Object-space normal sets (multiresolution) or geometric normals (flat), per triangle.
    normals: Vec<Vec<[f32; 3]>>,
    histogram: Vec<usize>,
    worst_angle_deg: f32,
    /// Multiresolution: the Loop refinement at [`OCCLUDER_LEVEL`] (object space), each
    /// triangle with its coarse triangle ([`SolverObject::occluder`]).
    ///
    /// [`SolverObject::occluder`]: crate::scene::SolverObject::occluder
    occluder: Vec<([[f32; 3]; 3], u32)>,
}

/// The Loop level of the surface that casts a multiresolution object's shadows in the bake:
/// 16 triangles per coarse one, close to the limit surface a renderer draws (level 3 gave the
/// same images).
const OCCLUDER_LEVEL: u32 = 2;

/// Most triangles of a multiresolution object's occluder: a finer control mesh casts its
/// shadows at a lower level (a fine mesh barely changes when refined, and each level costs the
/// visibility rays four times the triangles), and one finer than this with its own triangles.
const OCCLUDER_TRIANGLES: usize = 1 << 20;

/// The level of the occluder of a control mesh of `triangles` triangles refined to `levels`
/// at most, `None` for none (its own triangles).
fn occluder_level(triangles: usize, levels: u32) -> Option<u32> {
    (1..=OCCLUDER_LEVEL.min(levels))
        .rev()
        .find(|&l| triangles << (2 * l) <= OCCLUDER_TRIANGLES)
}

/// The output format `options` ask for, `glb`, `gltf` or `hce` (from the output's extension),
/// once the options are found acceptable.
pub fn output_format(options: &PipelineOptions) -> Result<&'static str, PipelineError> {
    if options.levels > 6 {
        return Err(PipelineError::Levels(options.levels));
    }
    let ext = options
        .output
        .extension()
        .and_then(|e| e.to_str())
        .map(str::to_ascii_lowercase);
    match ext.as_deref() {
        Some("glb") => Ok("glb"),
        Some("gltf") => Ok("gltf"),
        Some("hce") => Ok("hce"),
        _ => Err(PipelineError::OutputExtension {
            path: options.output.clone(),
        }),
    }
}

/// Bakes `input` and writes `options.output`. `progress` gets `(phase, done, total)`.
pub fn bake_file(
    input: &Path,
    options: &PipelineOptions,
    progress: Progress<'_>,
) -> Result<BakeOutcome, PipelineError> {
    let format = output_format(options)?;
    let mut phases = Vec::new();
    let t = Instant::now();
    progress("import", 0, 1);
    let scene = import_scene(input, &options.import)?;
    progress("import", 1, 1);
    phases.push(("import".to_string(), t.elapsed().as_secs_f64()));
    let mut warnings = scene.warnings.clone();

    let t = Instant::now();
    let n = scene.objects.len();
    let mut prepared = Vec::with_capacity(n);
    for i in 0..n {
        progress("topology and normal sets", i, n);
        prepared.push(prepare_object(&scene, i, options, &mut warnings)?);
    }
    progress("topology and normal sets", n, n);
    phases.push((
        "topology and normal sets".to_string(),
        t.elapsed().as_secs_f64(),
    ));

    let mut solver = scene.solver_scene();
    for (i, (so, p)) in solver.objects.iter_mut().zip(&prepared).enumerate() {
        so.multires = p.kind == ObjectKind::Multiresolution;
        if so.multires {
            let m = scene.objects[i].transform;
            so.occluder = p
                .occluder
                .iter()
                .map(|(tri, t)| {
                    (
                        tri.map(|v| m.transform_point3(Vec3::from(v)).to_array()),
                        *t,
                    )
                })
                .collect();
        }
        if so.multires {
            let inv_t = Mat3::from_mat4(scene.objects[i].transform)
                .inverse()
                .transpose();
            so.normal_sets = p
                .normals
                .iter()
                .enumerate()
                .map(|(t, set)| {
                    let [a, b, c] = so.corners(t);
                    let n0 = (b - a).cross(c - a).try_normalize().unwrap_or(Vec3::Z);
                    let mut w = vec![n0.to_array()];
                    w.extend(set.iter().skip(1).map(|&n| {
                        (inv_t * Vec3::from(n))
                            .try_normalize()
                            .unwrap_or(n0)
                            .to_array()
                    }));
                    w
                })
                .collect();
        }
    }
    let result = crate::bake_with_progress(&solver, &options.bake, progress)?;
    phases.extend(result.stats.phase_seconds.iter().cloned());

    let t = Instant::now();
    let mut container = Container {
        metadata: Metadata {
            generator: format!("hce {}", env!("CARGO_PKG_VERSION")),
            bake_parameters: parameters_json(options),
            source_hash: scene.source_hash(),
        },
        objects: Vec::with_capacity(n),
    };
    let mut summaries = Vec::with_capacity(n);
    let mut histogram = vec![0usize; options.normal_sets.max_normals + 2];
    let mut worst = 0.0f32;
    let mut per_triangle_light: Vec<Vec<[f32; 3]>> = Vec::with_capacity(n);
    for (i, (p, sol)) in prepared.into_iter().zip(&result.objects).enumerate() {
        let o = &scene.objects[i];
        let mirrored = o.mirrored();
        let tris: Vec<TriangleSolution> = sol
            .triangles
            .iter()
            .zip(&p.normals)
            .map(|(ts, normals)| {
                let mut ts = if mirrored {
                    mirror_tree(ts)
                } else {
                    ts.clone()
                };
                ts.normals = normals.clone();
                ts
            })
            .collect();
        per_triangle_light.push(incident_light(&solver.objects[i], &sol.triangles));
        let mut object = Object {
            name: o.name.clone(),
            kind: p.kind,
            geometry_hash: o.geometry_hash(),
            mesh: p.mesh,
            ..Default::default()
        };
        crate::encode::encode_object(&mut object, &tris)?;
        for (k, &c) in p.histogram.iter().enumerate() {
            if k < histogram.len() {
                histogram[k] += c;
            }
        }
        worst = worst.max(p.worst_angle_deg);
        summaries.push(ObjectSummary {
            name: o.name.clone(),
            kind: p.kind,
            triangles: o.triangle_count(),
            control_vertices: object.mesh.vertex_count(),
            normal_histogram: p.histogram,
            worst_angle_deg: p.worst_angle_deg,
        });
        container.objects.push(object);
    }
    let bytes = hce_format::write(&container)?;
    phases.push(("encode".to_string(), t.elapsed().as_secs_f64()));

    let t = Instant::now();
    progress("write", 0, 1);
    let (colours, exposure) = fallback_colours(&scene, &per_triangle_light);
    let output_bytes = if format == "hce" {
        hce_meshio::write_atomic(&options.output, &bytes)?;
        bytes.len() as u64
    } else {
        let links: Vec<Option<ObjectLink>> = (0..n)
            .map(|i| {
                Some(ObjectLink {
                    object: i as u32,
                    first_triangle: 0,
                })
            })
            .collect();
        let asset = bake_gltf(&scene, &colours, &bytes, &links)?;
        asset.write(&options.output)?;
        let mut size = std::fs::metadata(&options.output)
            .map(|m| m.len())
            .unwrap_or(0);
        if format == "gltf" {
            size += std::fs::metadata(options.output.with_extension("bin"))
                .map(|m| m.len())
                .unwrap_or(0);
        }
        size
    };
    progress("write", 1, 1);
    phases.push(("write".to_string(), t.elapsed().as_secs_f64()));

    Ok(BakeOutcome {
        objects: summaries,
        coarse_triangles: result.stats.coarse_triangles,
        elements: result.stats.elements,
        links: result.stats.links,
        iterations: result.stats.iterations,
        normal_histogram: histogram,
        worst_angle_deg: worst,
        phase_seconds: phases,
        output_bytes,
        warnings,
        import_summary: scene.summary.clone(),
        exposure,
        container,
    })
}

/// The bake parameters a container records (its metadata's `bake_parameters`): every solver, normal-set
/// and subdivision parameter that shapes the lighting, as one JSON object.
pub fn parameters_json(options: &PipelineOptions) -> String {
    let mut v: serde_json::Value =
        serde_json::from_str(&options.bake.to_json()).unwrap_or_else(|_| serde_json::json!({}));
    v["levels"] = serde_json::json!(options.levels);
    v["max_normals"] = serde_json::json!(options.normal_sets.max_normals);
    v["normal_tolerance_deg"] = serde_json::json!(options.normal_sets.normal_tolerance_deg);
    v["creases"] = serde_json::json!(match options.creases {
        Creases::None => "none".to_string(),
        Creases::Auto => "auto".to_string(),
        Creases::Angle(d) => format!("angle={d}"),
    });
    v.to_string()
}

/// Builds the control mesh of object `i` (see the module documentation for the policy) and, for
/// a multiresolution object, its object-space normal sets.
fn prepare_object(
    scene: &ImportedScene,
    i: usize,
    options: &PipelineOptions,
    warnings: &mut Vec<String>,
) -> Result<Prepared, PipelineError> {
    let o = &scene.objects[i];
    let obj_err = |message: String| PipelineError::Object {
        index: i,
        name: o.name.clone(),
        message,
    };
    let corners: Vec<[f32; 3]> = o.indices.iter().map(|&v| o.positions[v as usize]).collect();
    let w = weld(&o.positions, 0.0);
    let triangles: Vec<[u32; 3]> = o
        .indices
        .chunks_exact(3)
        .map(|c| [0, 1, 2].map(|k| w.input_to_welded[c[k] as usize]))
        .collect();
    let corner_normals: Option<Vec<[f32; 3]>> = o
        .normals
        .as_ref()
        .map(|n| o.indices.iter().map(|&v| n[v as usize]).collect());
    let config = TopologyConfig {
        creases: options.creases,
        ..Default::default()
    };
    let welded =
        build_control_mesh(&w.positions, &triangles, corner_normals.as_deref(), &config)
            .ok()
            .filter(|top| {
                top.mesh.triangle_count() == triangles.len()
                    && top.triangle_flipped.iter().all(|&f| !f)
                    && top
                        .triangle_source
                        .iter()
                        .enumerate()
                        .all(|(t, &s)| s as usize == t)
                    && top.mesh.triangles.iter().zip(&corners).all(|(&v, c)| {
                        top.mesh.position(v).map(f32::to_bits) == c.map(f32::to_bits)
                    })
            });
    let (mesh, kind) = match welded {
        Some(top) => (
            top.mesh,
            if o.multires {
                ObjectKind::Multiresolution
            } else {
                ObjectKind::Flat
            },
        ),
        None => {
            warnings.push(format!(
                "object '{}': its triangles do not form a control mesh that keeps every triangle \
                 and corner (degenerate or inconsistently oriented triangles); baked flat on \
                 unwelded triangles{}",
                o.name,
                if o.multires {
                    ", without Loop smoothing"
                } else {
                    ""
                }
            ));
            let soup: Vec<[u32; 3]> = (0..triangles.len() as u32)
                .map(|t| [3 * t, 3 * t + 1, 3 * t + 2])
                .collect();
            let top = build_control_mesh(&corners, &soup, None, &TopologyConfig::default())
                .map_err(|e| obj_err(format!("cannot build even an unwelded control mesh: {e}")))?;
            if top.mesh.triangle_count() != soup.len() {
                return Err(obj_err(
                    "it has triangles with repeated corners; remove them and bake again".into(),
                ));
            }
            (top.mesh, ObjectKind::Flat)
        }
    };
    let geometric: Vec<[f32; 3]> = (0..mesh.triangle_count())
        .map(|t| {
            let p = mesh.triangle(t).map(|v| Vec3::from(mesh.position(v)));
            // A zero-area triangle has no normal; any unit vector keeps the file valid, and
            // it receives no light anyway.
            (p[1] - p[0])
                .cross(p[2] - p[0])
                .try_normalize()
                .unwrap_or(Vec3::Z)
                .to_array()
        })
        .collect();
    if kind == ObjectKind::Flat {
        return Ok(Prepared {
            mesh,
            kind,
            normals: geometric.into_iter().map(|n| vec![n]).collect(),
            histogram: Vec::new(),
            worst_angle_deg: 0.0,
            occluder: Vec::new(),
        });
    }
    let refined = match subdivide(&mesh, options.levels) {
        Ok(r) => r,
        Err(e) => {
            warnings.push(format!(
                "object '{}': Loop subdivision failed ({e}); baked with its geometric normals only",
                o.name
            ));
            return Ok(Prepared {
                mesh,
                kind,
                normals: geometric.into_iter().map(|n| vec![n]).collect(),
                histogram: Vec::new(),
                worst_angle_deg: 0.0,
                occluder: Vec::new(),
            });
        }
    };
    let per = 1usize << (2 * options.levels);
    let subs: Vec<([f32; 3], f32)> = refined
        .indices
        .iter()
        .map(|f| {
            let p = f.map(|v| Vec3::from(refined.positions[v as usize]));
            let c = (p[1] - p[0]).cross(p[2] - p[0]);
            (c.normalize_or_zero().to_array(), 0.5 * c.length())
        })
        .collect();
    let (sets, report) = select_normal_sets(
        geometric
            .iter()
            .enumerate()
            .map(|(t, &n0)| (n0, &subs[t * per..(t + 1) * per])),
        &options.normal_sets,
    );
    let level = occluder_level(mesh.triangle_count(), options.levels);
    let occluder = match level.map(|l| (l, subdivide(&mesh, l))) {
        Some((level, Ok(r))) => {
            let per = 1usize << (2 * level);
            r.indices
                .iter()
                .enumerate()
                .map(|(k, f)| (f.map(|v| r.positions[v as usize]), (k / per) as u32))
                .collect()
        }
        _ => Vec::new(),
    };
    Ok(Prepared {
        mesh,
        kind,
        normals: sets.into_iter().map(|s| s.normals).collect(),
        histogram: report.histogram,
        worst_angle_deg: report.worst_angle_deg,
        occluder,
    })
}

/// Swaps the Left (1) and Right (3) children at every level of a breadth-first tree.
fn mirror_tree(ts: &TriangleSolution) -> TriangleSolution {
    let nn = ts.normals.len().max(1);
    // children[k]: first child index of node k in the original breadth-first order.
    let mut first_child = vec![usize::MAX; ts.subdivided.len()];
    let mut next = 1;
    for (k, &s) in ts.subdivided.iter().enumerate() {
        if s {
            first_child[k] = next;
            next += 4;
        }
    }
    let mut order = vec![0usize];
    let mut head = 0;
    while head < order.len() {
        let k = order[head];
        head += 1;
        if ts.subdivided[k] {
            let c = first_child[k];
            order.extend([c, c + 3, c + 2, c + 1]);
        }
    }
    let swap = |path: u32, level: u32| -> u32 {
        (0..level).fold(0, |acc, d| {
            let digit = (path >> (2 * (level - 1 - d))) & 3;
            let digit = [0, 3, 2, 1][digit as usize];
            (acc << 2) | digit
        })
    };
    TriangleSolution {
        normals: ts.normals.clone(),
        nodes: order
            .iter()
            .filter_map(|&k| ts.nodes.get(k).map(|&(l, p)| (l, swap(p, l))))
            .collect(),
        subdivided: order.iter().map(|&k| ts.subdivided[k]).collect(),
        colours: order
            .iter()
            .flat_map(|&k| ts.colours[k * nn..(k + 1) * nn].iter().copied())
            .collect(),
        // Mirrored, a node's corners 1 and 2 trade places.
        corner_colours: if ts.corner_colours.is_empty() {
            Vec::new()
        } else {
            order
                .iter()
                .flat_map(|&k| {
                    (k * nn..(k + 1) * nn).flat_map(|x| {
                        let c = &ts.corner_colours[3 * x..3 * x + 3];
                        [c[0], c[2], c[1]]
                    })
                })
                .collect()
        },
    }
}

/// Per triangle: the light arriving, `(B - E) / ρ` from the root colour (white on emitters).
fn incident_light(o: &crate::scene::SolverObject, sol: &[TriangleSolution]) -> Vec<[f32; 3]> {
    sol.iter()
        .enumerate()
        .map(|(t, ts)| {
            let e = o.emission_of(t);
            if e.iter().any(|&c| c > 0.0) {
                return [f32::INFINITY; 3];
            }
            let b = ts.colours.first().copied().unwrap_or([0.0; 3]);
            let rho = o.reflectance.get(t).copied().unwrap_or([1.0; 3]);
            [0, 1, 2].map(|c| (b[c] - e[c]).max(0.0) / rho[c].max(hce_format::ALBEDO_FLOOR))
        })
        .collect()
}

/// Per object, per primitive vertex `COLOR_0` (area-weighted average of the incident light of
/// its triangles, times one exposure), and the exposure.
fn fallback_colours(scene: &ImportedScene, light: &[Vec<[f32; 3]>]) -> (Vec<Vec<[f32; 3]>>, f32) {
    let mut raw = Vec::with_capacity(scene.objects.len());
    let mut maxima = Vec::new();
    for (o, l) in scene.objects.iter().zip(light) {
        let mut sum = vec![[0.0f64; 4]; o.positions.len()];
        let mut emissive = vec![false; o.positions.len()];
        for (t, c) in o.indices.chunks_exact(3).enumerate() {
            let p = [0, 1, 2].map(|k| Vec3::from(o.world_positions[c[k] as usize]));
            let area = f64::from(0.5 * (p[1] - p[0]).cross(p[2] - p[0]).length());
            let v = l.get(t).copied().unwrap_or([0.0; 3]);
            for &i in c {
                if v[0].is_infinite() {
                    emissive[i as usize] = true;
                    continue;
                }
                let s = &mut sum[i as usize];
                for k in 0..3 {
                    s[k] += area * f64::from(v[k]);
                }
                s[3] += area;
            }
        }
        let colours: Vec<[f32; 3]> = sum
            .iter()
            .zip(&emissive)
            .map(|(s, &e)| {
                if e {
                    [f32::INFINITY; 3]
                } else if s[3] > 0.0 {
                    [0, 1, 2].map(|k| (s[k] / s[3]) as f32)
                } else {
                    [0.0; 3]
                }
            })
            .collect();
        maxima.extend(
            colours
                .iter()
                .filter(|c| c[0].is_finite())
                .map(|c| c[0].max(c[1]).max(c[2])),
        );
        raw.push(colours);
    }
    let exposure = hce_format::colour_exposure(&mut maxima);
    let out = raw
        .into_iter()
        .map(|cs| {
            cs.into_iter()
                .map(|c| {
                    if c[0].is_infinite() {
                        [1.0; 3]
                    } else {
                        c.map(|x| x * exposure)
                    }
                })
                .collect()
        })
        .collect();
    (out, exposure)
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn fine_control_meshes_cast_shadows_at_lower_levels() {
        assert_eq!(occluder_level(1000, 3), Some(2));
        assert_eq!(occluder_level(1000, 1), Some(1));
        assert_eq!(occluder_level(1000, 0), None);
        assert_eq!(occluder_level(OCCLUDER_TRIANGLES / 16, 3), Some(2));
        assert_eq!(occluder_level(OCCLUDER_TRIANGLES / 16 + 1, 3), Some(1));
        assert_eq!(occluder_level(OCCLUDER_TRIANGLES / 4 + 1, 3), None);
    }

    #[test]
    fn mirror_tree_swaps_left_and_right_at_every_level() {
        // Root split, its Left child (node 2) split.
        let mut sub = vec![true, false, true, false, false];
        sub.extend([false; 4]);
        let ts = TriangleSolution {
            normals: vec![[0.0, 0.0, 1.0]],
            nodes: vec![
                (0, 0),
                (1, 0),
                (1, 1),
                (1, 2),
                (1, 3),
                (2, 4),
                (2, 5),
                (2, 6),
                (2, 7),
            ],
            subdivided: sub,
            colours: (0..9).map(|k| [k as f32, 0.0, 0.0]).collect(),
            corner_colours: (0..27).map(|x| [x as f32, 1.0, 0.0]).collect(),
        };
        let m = mirror_tree(&ts);
        // New order: root, Top, Right(old 4), Center, Left(old 2), then old 2's children
        // 5, 8, 7, 6.
        let ids: Vec<f32> = m.colours.iter().map(|c| c[0]).collect();
        assert_eq!(ids, vec![0.0, 1.0, 4.0, 3.0, 2.0, 5.0, 8.0, 7.0, 6.0]);
        assert_eq!(
            m.subdivided,
            vec![true, false, false, false, true, false, false, false, false]
        );
        // Old node 7, path (Left, Center) = 6, becomes (Right, Center) = 14.
        assert_eq!(m.nodes[7], (2, 14));
        // Each node's corners 1 and 2 trade places: the root's (0, 1, 2) become (0, 2, 1), and
        // the Top child's (3, 4, 5) its (3, 5, 4).
        let corners: Vec<f32> = m.corner_colours[..6].iter().map(|c| c[0]).collect();
        assert_eq!(corners, vec![0.0, 2.0, 1.0, 3.0, 5.0, 4.0]);
        assert_eq!(mirror_tree(&m), ts);
    }
}
