//! The Loop subdivision kernel (`hce_runtime::gpu::LoopKernel`) against its CPU reference,
//! `hce_geometry::subdivide` followed by `hce_geometry::colour::apply_baked_colours`: indices
//! identical, positions within 1e-5 of the bounding-box diagonal, normals close, vertex colours
//! within 1e-3 relative, on built-in meshes (valences 3 to 9, boundaries, creases) and on the
//! shared real meshes when `HCE_EXTRA_MESHES` names their folder. Colours come from random but
//! real HCE trees (depth up to 4, up to 5 representative normals per triangle).
//!
//! Runs on any adapter, Mesa lavapipe included. Without one the tests skip with a message,
//! unless `HCE_REQUIRE_GPU=1`, which makes them fail.
#![cfg(feature = "gpu")]
#![allow(clippy::needless_range_loop)]

// The meshes and helpers of hce-geometry's tests, shared rather than copied.
#[path = "../../geometry/tests/common/mod.rs"]
mod common;

use std::path::Path;

use hce_format::{ControlMesh, Object, ObjectKind};
use hce_geometry::colour::apply_baked_colours_with;
use hce_geometry::lighting::Reconstruction;
use hce_geometry::refine::subdivide_split;
use hce_geometry::refine::FlatRefinement;
use hce_geometry::subdivide::subdivide;
use hce_geometry::topology::{build_control_mesh, Creases, Topology, TopologyConfig};
use hce_runtime::gpu::testing::{context_or_skip, random_object, RandomTrees};
use hce_runtime::gpu::{AdapterKind, GpuContext, LoopKernel, PatchScheme};

fn data_mesh(name: &str, creases: Creases) -> Topology {
    common::control_mesh(
        &Path::new(env!("CARGO_MANIFEST_DIR")).join(format!("../geometry/tests/data/{name}.obj")),
        &TopologyConfig {
            creases,
            ..Default::default()
        },
    )
}

/// A bipyramid over an `n`-gon: two apexes of valence `n`, rim vertices of valence 4.
fn bipyramid(n: u32) -> Topology {
    let mut p = vec![[0.0, 0.0, 0.8], [0.0, 0.0, -0.7]];
    for k in 0..n {
        let a = std::f32::consts::TAU * k as f32 / n as f32;
        // A wobble in height so no two fine normals coincide by symmetry.
        p.push([a.cos(), a.sin(), 0.1 * (3.0 * a).sin()]);
    }
    let mut t = Vec::new();
    for k in 0..n {
        let (a, b) = (2 + k, 2 + (k + 1) % n);
        t.push([0, a, b]);
        t.push([1, b, a]);
    }
    build_control_mesh(&p, &t, None, &TopologyConfig::default()).unwrap()
}

/// The 2x2-per-face cube with flat-shading normals (each corner takes its triangle's normal),
/// so `Creases::Auto` makes exactly the cube's 12 edges hard: 24 crease edges.
fn flat_shaded_cube() -> Topology {
    let path =
        Path::new(env!("CARGO_MANIFEST_DIR")).join("../geometry/tests/data/cube_creased.obj");
    let input = hce_meshio::load_mesh(&path).unwrap();
    let w = hce_geometry::weld(&input.positions, 0.0);
    let tris = w.triangles(&input.triangles);
    let normals: Vec<[f32; 3]> = tris
        .iter()
        .flat_map(|t| {
            let p = t.map(|i| w.positions[i as usize]);
            let u = [0, 1, 2].map(|k| p[1][k] - p[0][k]);
            let v = [0, 1, 2].map(|k| p[2][k] - p[0][k]);
            let n = [
                u[1] * v[2] - u[2] * v[1],
                u[2] * v[0] - u[0] * v[2],
                u[0] * v[1] - u[1] * v[0],
            ];
            let l = (n[0] * n[0] + n[1] * n[1] + n[2] * n[2]).sqrt();
            // `+ 0.0` turns -0.0 into 0.0: Auto compares normals bit for bit.
            [n.map(|x| x / l + 0.0); 3]
        })
        .collect();
    let t = build_control_mesh(
        &w.positions,
        &tris,
        Some(&normals),
        &TopologyConfig {
            creases: Creases::Auto,
            ..Default::default()
        },
    )
    .unwrap();
    assert_eq!(
        t.report.crease_edges, 24,
        "auto creases on the cube's edges"
    );
    t
}

/// An object over `mesh` with random HCE trees; the first normal of each triangle is its
/// geometric normal, as a baker writes it.
fn baked(name: &str, mesh: &ControlMesh, seed: u64) -> Object {
    baked_to_depth(name, mesh, seed, RandomTrees::default().max_depth)
}

/// [`baked`] with trees at most `max_depth` deep.
fn baked_to_depth(name: &str, mesh: &ControlMesh, seed: u64, max_depth: u32) -> Object {
    let trees = RandomTrees {
        max_depth,
        ..RandomTrees::default()
    };
    let mut o = random_object(
        name,
        mesh.positions.clone(),
        mesh.triangles.clone(),
        trees,
        seed,
    );
    o.kind = ObjectKind::Multiresolution;
    o.mesh = mesh.clone();
    o
}

/// What one comparison found, for the test's report.
#[derive(Clone, Default, Debug)]
struct Report {
    max_position: f64,
    positions_bitwise: usize,
    positions: usize,
    max_normal: f32,
    max_colour: f64,
    colours_over: usize,
}

/// Refines `object` on the GPU at each of `levels` (reusing one output across levels, as a
/// viewer does) and compares with the CPU reference.
/// Every reconstruction is compared; the report is the smooth one's (the default).
fn compare(ctx: &GpuContext, object: &Object, levels: &[u32]) -> Report {
    let kernel = LoopKernel::new(ctx);
    for other in [Reconstruction::NearestNormal, Reconstruction::Gouraud] {
        compare_with(ctx, &[&kernel], object, levels, other);
    }
    compare_with(ctx, &[&kernel], object, levels, Reconstruction::Smooth)
        .pop()
        .unwrap()
}

/// [`compare`] for several kernels at once, against one CPU reference per level.
fn compare_with(
    ctx: &GpuContext,
    kernels: &[&LoopKernel],
    object: &Object,
    levels: &[u32],
    reconstruction: Reconstruction,
) -> Vec<Report> {
    let uploaded: Vec<_> = kernels
        .iter()
        .map(|k| k.upload(ctx, object, reconstruction).unwrap())
        .collect();
    let mut outs: Vec<_> = kernels.iter().map(|_| None).collect();
    let mut reports = vec![Report::default(); kernels.len()];
    for &level in levels {
        // The drawn mesh: Loop subdivision split at sharp edges (SPEC.md F.5).
        let cpu = subdivide_split(&object.name, &object.mesh, level).unwrap();
        let cpu_colours = apply_baked_colours_with(object, &cpu, level, reconstruction).unwrap();
        let brightest = cpu_colours.iter().flatten().fold(0f32, |a, &b| a.max(b));
        for (k, kernel) in kernels.iter().enumerate() {
            let report = &mut reports[k];
            let name = format!("{} level {level}, kernel {k}", object.name);
            kernel
                .refine_into(ctx, &uploaded[k], level, &mut outs[k], false)
                .unwrap();
            let o = outs[k].as_ref().unwrap();
            let gpu = o.read_back(ctx).unwrap();
            let gpu_normals = o.read_back_normals(ctx).unwrap();
            assert_eq!(gpu.level, level);
            assert_eq!(gpu.vertex_count(), cpu.positions.len(), "{name}");
            assert_eq!(gpu.triangle_count(), cpu.indices.len(), "{name}");
            assert!(
                gpu.indices == cpu.indices.as_flattened(),
                "{name}: indices differ"
            );

            let diag = common::bbox_diagonal(&cpu.positions);
            for (v, c) in cpu.positions.iter().enumerate() {
                let g = &gpu.positions[3 * v..3 * v + 3];
                let d = (0..3)
                    .map(|k| (f64::from(g[k]) - f64::from(c[k])).powi(2))
                    .sum::<f64>()
                    .sqrt()
                    / diag;
                assert!(d <= 1e-5, "{name}: vertex {v}: {g:?} vs {c:?}");
                report.max_position = report.max_position.max(d);
                report.positions_bitwise += usize::from(g == c.as_slice());
                report.positions += 1;

                let gn = &gpu_normals[3 * v..3 * v + 3];
                let dn = (0..3)
                    .map(|k| (gn[k] - cpu.normals[v][k]).abs())
                    .fold(0.0, f32::max);
                assert!(
                    dn <= 1e-3,
                    "{name}: vertex {v}: normal {gn:?} vs {:?}",
                    cpu.normals[v]
                );
                report.max_normal = report.max_normal.max(dn);
            }

            // Colours: relative 1e-3 of the channel (absolute 1e-3 of the largest channel for
            // dark ones). A fine triangle on a near tie between two representative normals may pick
            // the other one on the GPU (f32 dot products against the CPU's f64); that moves its
            // three vertices, so a handful of vertices are allowed to differ.
            for (v, c) in cpu_colours.iter().enumerate() {
                let g = &gpu.colours[4 * v..4 * v + 4];
                assert_eq!(g[3], 1.0);
                let scale = c.iter().fold(0f32, |a, &b| a.max(b.abs())).max(1e-6);
                // The smooth field (c + G n, blended) is computed in f32 on both sides from the
                // same table; where c and G n nearly cancel, a channel far below the vertex's
                // brightest keeps only the absolute precision of the terms: 1e-4 of the
                // brightest channel (at least 1e-2 of the object's brightest, for vertices the
                // clamp at zero darkens) is the stated tolerance there.
                let (d, limit) = match reconstruction {
                    Reconstruction::Smooth | Reconstruction::Gouraud => (
                        (0..3)
                            .map(|k| f64::from((g[k] - c[k]).abs() / scale.max(1e-2 * brightest)))
                            .fold(0.0, f64::max),
                        1e-4,
                    ),
                    Reconstruction::NearestNormal => (
                        (0..3)
                            .map(|k| f64::from((g[k] - c[k]).abs() / c[k].abs().max(1e-3 * scale)))
                            .fold(0.0, f64::max),
                        1e-3,
                    ),
                };
                if d > limit {
                    if reconstruction == Reconstruction::Smooth && report.colours_over < 5 {
                        eprintln!("{name}: smooth vertex {v}: GPU {g:?}, CPU {c:?}");
                    }
                    report.colours_over += 1;
                } else {
                    report.max_colour = report.max_colour.max(d);
                }
            }
            // The smooth field has no choice to tip: every vertex agrees to f32 rounding.
            assert!(
                reconstruction == Reconstruction::NearestNormal || report.colours_over == 0,
                "{name}: {} smooth vertex colours differ by more than 1e-4 of their brightest channel",
                report.colours_over
            );
            assert!(
                report.colours_over * 2000 <= cpu_colours.len(),
                "{name}: {} of {} vertex colours differ by more than 1e-3 relative",
                report.colours_over,
                cpu_colours.len()
            );
        }
    }
    for report in &reports {
        eprintln!("{}: {report:?}", object.name);
    }
    reports
}

#[test]
fn gpu_loop_matches_cpu_on_built_in_meshes() {
    let Some(ctx) = context_or_skip("gpu_loop_matches_cpu_on_built_in_meshes") else {
        return;
    };
    // Valences 3 (tetrahedron), 4 (octahedron), 5 (icosahedron), 6 and open boundaries
    // (grid_open), 7 (bifan7, and fan7_open with a boundary), 8 (bipyramid), 9 (bipyramid9),
    // and crease and corner vertices (cube_creased with angle creases).
    let mut meshes: Vec<(String, ControlMesh)> = [
        ("tetrahedron", Creases::None),
        ("octahedron", Creases::None),
        ("icosahedron", Creases::None),
        ("grid_open", Creases::None),
        ("bifan7", Creases::None),
        ("fan7_open", Creases::None),
        ("bipyramid9", Creases::None),
        ("cube_creased", Creases::Angle(45.0)),
    ]
    .into_iter()
    .map(|(n, c)| {
        let t = data_mesh(n, c);
        if c != Creases::None {
            assert!(t.report.crease_edges > 0, "{n}: no crease edges tagged");
        }
        (n.to_string(), t.mesh)
    })
    .collect();
    meshes.push(("bipyramid8".into(), bipyramid(8).mesh));
    meshes.push(("cube_auto_creases".into(), flat_shaded_cube().mesh));
    let mut total = Report::default();
    for (i, (name, mesh)) in meshes.iter().enumerate() {
        let object = baked(name, mesh, 100 + i as u64);
        // Down and up again: a lower level reuses the larger buffers.
        let r = compare(&ctx, &object, &[0, 1, 2, 3, 4, 2, 5]);
        total.max_position = total.max_position.max(r.max_position);
        total.positions_bitwise += r.positions_bitwise;
        total.positions += r.positions;
    }
    // The highest level, 6 (patch scratch of about 105 KiB per triangle), on the creased cube
    // (48 triangles: crease and corner vertices at the deepest level).
    let object = baked("cube_creased", &meshes[7].1, 77);
    let r = compare(&ctx, &object, &[6]);
    total.max_position = total.max_position.max(r.max_position);
    eprintln!(
        "built-in meshes: max position error {:.3e} of the diagonal, {} of {} positions bitwise equal",
        total.max_position, total.positions_bitwise, total.positions
    );
}

#[test]
fn workgroup_and_scratch_patches_match_cpu_bitwise_at_levels_0_to_5() {
    let Some(ctx) =
        context_or_skip("workgroup_and_scratch_patches_match_cpu_bitwise_at_levels_0_to_5")
    else {
        return;
    };
    // Boundaries (grid_open, fan7_open), valence 9, and crease and corner vertices: every branch
    // of the patch kernels, through both of them.
    let meshes = [
        ("grid_open", Creases::None),
        ("fan7_open", Creases::None),
        ("bipyramid9", Creases::None),
        ("cube_creased", Creases::Angle(45.0)),
    ];
    let workgroup = LoopKernel::with_scheme(&ctx, PatchScheme::Workgroup);
    let scratch = LoopKernel::with_scheme(&ctx, PatchScheme::Scratch);
    let auto = LoopKernel::new(&ctx);
    // The default takes workgroup memory wherever it fits on hardware, and the scratch kernel
    // on software adapters, where it is faster.
    let preferred = if ctx.description.kind == AdapterKind::Software {
        PatchScheme::Scratch
    } else {
        PatchScheme::Workgroup
    };
    for (i, (name, creases)) in meshes.into_iter().enumerate() {
        let object = baked(name, &data_mesh(name, creases).mesh, 300 + i as u64);
        let uploaded = auto
            .upload(&ctx, &object, Reconstruction::default())
            .unwrap();
        for level in 1..=5 {
            assert_eq!(
                auto.scheme_for(&ctx, &uploaded, level).unwrap(),
                preferred,
                "{name} level {level}"
            );
            assert_eq!(
                workgroup.scheme_for(&ctx, &uploaded, level).unwrap(),
                PatchScheme::Workgroup
            );
            assert_eq!(
                scratch.scheme_for(&ctx, &uploaded, level).unwrap(),
                PatchScheme::Scratch
            );
        }
        // Level 6 does not fit workgroup memory: the default falls back, a forced workgroup
        // kernel refuses with an error.
        assert_eq!(
            auto.scheme_for(&ctx, &uploaded, 6).unwrap(),
            PatchScheme::Scratch
        );
        assert!(workgroup.scheme_for(&ctx, &uploaded, 6).is_err());
        let reports = compare_with(
            &ctx,
            &[&workgroup, &scratch],
            &object,
            &[0, 1, 2, 3, 4, 5, 3],
            Reconstruction::Smooth,
        );
        for (scheme, r) in ["workgroup", "scratch"].into_iter().zip(reports) {
            assert_eq!(
                r.positions_bitwise, r.positions,
                "{name}, {scheme} patches: positions must equal the CPU's bit for bit"
            );
        }
    }
}

#[test]
fn gpu_loop_matches_cpu_on_real_meshes() {
    let Some(dir) = std::env::var_os("HCE_EXTRA_MESHES") else {
        eprintln!(
            "SKIPPED gpu_loop_matches_cpu_on_real_meshes: HCE_EXTRA_MESHES is unset \
             (point it at the shared meshes folder to run this test)"
        );
        return;
    };
    let Some(ctx) = context_or_skip("gpu_loop_matches_cpu_on_real_meshes") else {
        return;
    };
    // The bunny (69,451 triangles) only to level 2, to keep the test within its time budget in
    // the dev profile; the other meshes to level 4. Suzanne is non-manifold and is split into
    // manifold pieces by the default topology configuration. Fandisk gets angle creases.
    let workgroup = LoopKernel::with_scheme(&ctx, PatchScheme::Workgroup);
    let scratch = LoopKernel::with_scheme(&ctx, PatchScheme::Scratch);
    let cases: &[(&str, Creases, u32)] = &[
        ("spot", Creases::None, 4),
        ("fandisk", Creases::Angle(40.0), 4),
        ("teapot", Creases::None, 4),
        ("suzanne", Creases::None, 4),
        ("stanford-bunny", Creases::None, 2),
    ];
    for (i, &(name, creases, top)) in cases.iter().enumerate() {
        let t = common::control_mesh(
            &Path::new(&dir).join(format!("{name}.obj")),
            &TopologyConfig {
                creases,
                ..Default::default()
            },
        );
        // The cases exist for their features: make sure the mesh still has them.
        if creases != Creases::None {
            assert!(t.report.crease_edges > 0, "{name}: no crease edges tagged");
        }
        let max_valence = t.mesh.ring_offsets.windows(2).map(|w| w[1] - w[0]).max();
        if name == "suzanne" {
            assert!(
                t.report.non_manifold_edges > 0,
                "suzanne: no non-manifold edge split"
            );
        }
        if name == "teapot" {
            assert!(
                max_valence >= Some(40),
                "teapot: max valence {max_valence:?}"
            );
            assert!(t.report.boundary_edges > 0);
        }
        // Random trees of depth 4 on every one of the bunny's 69,451 triangles (about 40 leaves
        // each, far more than a bake makes) would need a lighting table beyond the 128 MiB a
        // storage binding is guaranteed; depth 3 keeps it within.
        let depth = if name == "stanford-bunny" { 3 } else { 4 };
        let object = baked_to_depth(name, &t.mesh, 200 + i as u64, depth);
        let levels: Vec<u32> = (1..=top).collect();
        // Both patch kernels: the default picks only one of them on a given adapter.
        let reports = compare_with(
            &ctx,
            &[&workgroup, &scratch],
            &object,
            &levels,
            Reconstruction::Smooth,
        );
        for (scheme, r) in ["workgroup", "scratch"].into_iter().zip(reports) {
            eprintln!(
                "{name}, {scheme} patches (max valence {max_valence:?}, {} crease edges): max position error {:.3e} of the diagonal, {} of {} positions bitwise equal",
                t.report.crease_edges, r.max_position, r.positions_bitwise, r.positions
            );
        }
    }
}

#[test]
fn reusing_outputs_keeps_buffers_when_the_level_does_not_grow() {
    let Some(ctx) = context_or_skip("reusing_outputs_keeps_buffers_when_the_level_does_not_grow")
    else {
        return;
    };
    let object = baked(
        "icosahedron",
        &data_mesh("icosahedron", Creases::None).mesh,
        5,
    );
    let kernel = LoopKernel::new(&ctx);
    let uploaded = kernel
        .upload(&ctx, &object, Reconstruction::default())
        .unwrap();
    let mut out = None;
    kernel
        .refine_into(&ctx, &uploaded, 3, &mut out, false)
        .unwrap();
    let size3 = out.as_ref().unwrap().positions.size();
    kernel
        .refine_into(&ctx, &uploaded, 1, &mut out, false)
        .unwrap();
    let o = out.as_ref().unwrap();
    assert_eq!(
        o.positions.size(),
        size3,
        "level 1 must reuse the level 3 buffers"
    );
    assert_eq!(o.vertex_count, 42);
    assert_eq!(o.triangle_count, 80);
    let cpu = subdivide(&object.mesh, 1).unwrap();
    let gpu = o.read_back(&ctx).unwrap();
    assert_eq!(gpu.positions, cpu.positions.as_flattened());
    assert!(kernel
        .refine_into(&ctx, &uploaded, 7, &mut out, false)
        .is_err());
}

#[test]
fn malformed_tables_are_upload_errors() {
    let Some(ctx) = context_or_skip("malformed_tables_are_upload_errors") else {
        return;
    };
    let good = baked(
        "octahedron",
        &data_mesh("octahedron", Creases::None).mesh,
        9,
    );
    let kernel = LoopKernel::new(&ctx);
    assert!(kernel
        .upload(&ctx, &good, Reconstruction::default())
        .is_ok());
    type Damage = fn(&mut Object);
    let damages: &[(&str, Damage)] = &[
        ("spoke out of range", |o| o.mesh.ring[3] = 1000),
        ("ring offsets past the ring", |o| {
            o.mesh.ring_offsets[1] = 10_000
        }),
        ("ring offsets decreasing", |o| o.mesh.ring_offsets[2] = 1),
        ("corner spoke out of range", |o| {
            o.mesh.corner_spokes[4] = 99
        }),
        ("corner spoke wrong", |o| {
            o.mesh.corner_spokes[4] = (o.mesh.corner_spokes[4] + 1) % 4
        }),
        ("neighbour out of range", |o| o.mesh.neighbours[2] = 77),
        ("triangle vertex out of range", |o| o.mesh.triangles[5] = 6),
        ("edge id skips", |o| o.mesh.edges[7] = 500),
        ("spoke flags truncated", |o| {
            o.mesh.spoke_flags.pop();
        }),
        ("crease rule without two sharp spokes", |o| {
            o.mesh.vertex_flags[0] = hce_format::RULE_CREASE << hce_format::VERTEX_RULE_SHIFT
        }),
        ("boundary edge not marked sharp", |o| {
            o.mesh.neighbours[0] = hce_format::NO_NEIGHBOUR
        }),
        ("record normals outside", |o| {
            o.triangles[3].normal_start = 10_000
        }),
        ("tree past the bitstream", |o| o.bit_len = 3),
        ("record missing", |o| {
            o.triangles.pop();
        }),
    ];
    for (what, damage) in damages {
        let mut bad = good.clone();
        damage(&mut bad);
        match kernel.upload(&ctx, &bad, Reconstruction::default()) {
            Ok(_) => panic!("{what}: upload accepted a damaged object"),
            Err(e) => {
                let msg = e.to_string();
                assert!(msg.contains("octahedron"), "{what}: {msg}");
            }
        }
    }
}

#[test]
fn flat_and_loop_refinements_number_vertices_alike() {
    use hce_geometry::flat::{refine_flat_cpu, FlatTopology};
    // CPU twins only: the GPU kernels are compared with them elsewhere (gpu_kernels.rs here).
    for name in ["octahedron", "grid_open", "fan7_open"] {
        let object = baked(name, &data_mesh(name, Creases::None).mesh, 3);
        let topo = FlatTopology::new(name, &object.mesh).unwrap();
        for level in 1..=4 {
            let flat = refine_flat_cpu(&object, &topo, level);
            let loop_ = subdivide(&object.mesh, level).unwrap();
            assert_eq!(
                flat.indices,
                loop_.indices.as_flattened(),
                "{name} level {level}"
            );
        }
    }
}

/// More than 65,535 workgroups in one dispatch take the second dispatch dimension: a 400 × 400
/// grid (320,000 triangles) at level 2, four triangles per workgroup, is 80,000 workgroups. The
/// two patch kernels must agree bit for bit with each other and the CPU. About a minute on
/// lavapipe, hence ignored by default (`cargo test -p hce-runtime --test gpu_loop -- --ignored`).
#[test]
#[ignore]
fn workgroup_kernel_spans_two_dispatch_dimensions() {
    let Some(ctx) = context_or_skip("workgroup_kernel_spans_two_dispatch_dimensions") else {
        return;
    };
    let (p, t) = hce_runtime::gpu::testing::grid(400, 400);
    let p: Vec<[f32; 3]> = p.chunks_exact(3).map(|c| [c[0], c[1], c[2]]).collect();
    let t: Vec<[u32; 3]> = t.chunks_exact(3).map(|c| [c[0], c[1], c[2]]).collect();
    let mesh = build_control_mesh(&p, &t, None, &TopologyConfig::default())
        .unwrap()
        .mesh;
    // Shallow trees, so the colours stay within lavapipe's 128 MiB storage bindings.
    let mut object = random_object(
        "grid400",
        mesh.positions.clone(),
        mesh.triangles.clone(),
        RandomTrees {
            max_depth: 2,
            max_extra_normals: 2,
            ..Default::default()
        },
        17,
    );
    object.kind = ObjectKind::Multiresolution;
    object.mesh = mesh.clone();
    let limit = ctx.device.limits().max_compute_workgroups_per_dimension;
    assert!(mesh.triangle_count() / 4 > limit as usize);
    let workgroup = LoopKernel::with_scheme(&ctx, PatchScheme::Workgroup);
    let scratch = LoopKernel::with_scheme(&ctx, PatchScheme::Scratch);
    let reports = compare_with(
        &ctx,
        &[&workgroup, &scratch],
        &object,
        &[2],
        Reconstruction::Smooth,
    );
    for r in reports {
        assert_eq!(r.positions_bitwise, r.positions);
    }
}

/// Every output word of a refinement as bits, for comparisons that must be exact.
fn mesh_bits(m: &hce_runtime::gpu::RefinedMesh) -> Vec<Vec<u32>> {
    let bits = |v: &[f32]| v.iter().map(|x| x.to_bits()).collect::<Vec<u32>>();
    vec![
        bits(&m.positions),
        bits(&m.colours),
        m.indices.clone(),
        bits(&m.face_colours),
    ]
}

/// Records `job` in pieces of `piece` fine triangles, one submission each, and returns how many
/// submissions it took.
fn refine_in_pieces(ctx: &GpuContext, job: &mut hce_runtime::gpu::RefineJob, piece: u64) -> usize {
    let total = job.total_work();
    let mut submissions = 0;
    while !job.is_done() {
        let before = job.work_left();
        let mut encoder = ctx.device.create_command_encoder(&Default::default());
        let done = job.encode(ctx, &mut encoder, piece, None).unwrap();
        ctx.queue.submit([encoder.finish()]);
        submissions += 1;
        assert_eq!(done.work, before - job.work_left());
        assert!(done.work > 0, "a piece records at least one item");
        assert!(submissions as u64 <= 3 * total + 3, "the job does not end");
    }
    assert_eq!(job.work_left(), 0);
    submissions
}

/// A refinement recorded in pieces, one submission each (as a viewer spreads a large level
/// change over frames), writes exactly the bytes of the same refinement recorded whole: Loop
/// (workgroup and scratch patches) and flat, pieces from one item to most of a step, on meshes
/// with boundaries, extraordinary vertices and creases. The whole refinement is the one the
/// other tests compare with the CPU reference.
#[test]
fn refinement_in_pieces_writes_the_bytes_of_one_submission() {
    use hce_runtime::gpu::FlatKernel;
    let Some(ctx) = context_or_skip("refinement_in_pieces_writes_the_bytes_of_one_submission")
    else {
        return;
    };
    let loops = [
        (
            "workgroup",
            LoopKernel::with_scheme(&ctx, PatchScheme::Workgroup),
        ),
        (
            "scratch",
            LoopKernel::with_scheme(&ctx, PatchScheme::Scratch),
        ),
    ];
    let flat = FlatKernel::new(&ctx);
    for (i, (name, creases)) in [
        ("grid_open", Creases::None),
        ("bipyramid9", Creases::None),
        ("cube_creased", Creases::Angle(45.0)),
    ]
    .into_iter()
    .enumerate()
    {
        let object = baked(name, &data_mesh(name, creases).mesh, 500 + i as u64);
        let coarse = object.mesh.triangle_count() as u64;
        for level in [1, 3, 4] {
            let fine = coarse << (2 * level);
            // One item (level 1 only: one submission per fine triangle), one coarse
            // triangle's fine triangles, an odd size, and most of a step.
            let one = if level == 1 { 1 } else { 1 << (2 * level) };
            let pieces = [
                one,
                1 << (2 * level),
                3 * (1 << (2 * level)) + 5,
                fine * 2 / 3,
            ];
            for (scheme, kernel) in &loops {
                let uploaded = kernel
                    .upload(&ctx, &object, Reconstruction::default())
                    .unwrap();
                let mut whole = None;
                kernel
                    .refine_into(&ctx, &uploaded, level, &mut whole, false)
                    .unwrap();
                let whole = whole.unwrap();
                let expected = mesh_bits(&whole.read_back(&ctx).unwrap());
                let normals = whole.read_back_normals(&ctx).unwrap();
                for piece in pieces {
                    let mut out = None;
                    let mut job = kernel.begin(&ctx, &uploaded, level, &mut out).unwrap();
                    assert_eq!(job.total_work(), 3 * fine);
                    let submissions = refine_in_pieces(&ctx, &mut job, piece);
                    assert!(
                        submissions as u64 >= (3 * fine).div_ceil(piece.max(1)).min(3),
                        "{name} {scheme} level {level}: {submissions} submissions for pieces of {piece}"
                    );
                    let out = out.unwrap();
                    assert_eq!(
                        mesh_bits(&out.read_back(&ctx).unwrap()),
                        expected,
                        "{name} {scheme} level {level}, pieces of {piece}"
                    );
                    let n = out.read_back_normals(&ctx).unwrap();
                    assert!(
                        n.iter()
                            .zip(&normals)
                            .all(|(a, b)| a.to_bits() == b.to_bits()),
                        "{name} {scheme} level {level}, pieces of {piece}: normals"
                    );
                }
            }
            let uploaded = flat
                .upload(
                    &ctx,
                    &object,
                    Reconstruction::default(),
                    FlatRefinement::Uniform,
                )
                .unwrap();
            let mut whole = None;
            flat.refine_into(&ctx, &uploaded, level, &mut whole, false)
                .unwrap();
            let expected = mesh_bits(&whole.unwrap().read_back(&ctx).unwrap());
            for piece in pieces {
                let mut out = None;
                let mut job = flat.begin(&ctx, &uploaded, level, &mut out).unwrap();
                let submissions = refine_in_pieces(&ctx, &mut job, piece);
                assert!(
                    submissions >= 3 || piece >= fine,
                    "{name} flat: {submissions}"
                );
                assert_eq!(
                    mesh_bits(&out.unwrap().read_back(&ctx).unwrap()),
                    expected,
                    "{name} flat level {level}, pieces of {piece}"
                );
            }
        }
    }
}
