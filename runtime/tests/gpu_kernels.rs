//! GPU kernels against their CPU twins: HCE colour decoding on random trees, and flat
//! refinement (positions, indices, fine-triangle and vertex colours) at levels 0 to 4.
//!
//! Runs on any adapter, Mesa lavapipe included. Without one the tests skip with a message,
//! unless `HCE_REQUIRE_GPU=1`, which makes them fail.
#![cfg(feature = "gpu")]

use hce_geometry::adaptive_flat::refine_adaptive_flat;
use hce_geometry::colour::{adaptive_flat_colours, apply_baked_colours};
use hce_geometry::flat::{self, FlatTopology};
use hce_geometry::lighting::Reconstruction;
use hce_geometry::refine::FlatRefinement;
use hce_geometry::split::SplitTables;
use hce_geometry::Refined;
use hce_geometry::{decode, tables};
use hce_runtime::gpu::testing::{
    context_or_skip, decode_colours, grid, octahedron, random_object, ColourQuery, RandomTrees,
    SplitMix,
};
use hce_runtime::gpu::{refine_flat, refine_flat_adaptive, refine_flat_with};

/// `object` with the full adjacency tables of a container's object (neighbours, rings,
/// spokes), so that its refinement splits where the surface folds (SPEC.md F.5, G.2).
fn with_adjacency(mut object: hce_format::Object, name: &str) -> hce_format::Object {
    object.mesh = hce_format::example::control_mesh(
        std::mem::take(&mut object.mesh.positions),
        std::mem::take(&mut object.mesh.triangles),
    );
    object.name = name.into();
    object
}

/// Two objects without adjacency tables (nothing splits) and the same two with them: every
/// edge of the octahedron is a fold of 109 degrees; the bumpy grid folds by more than 10
/// degrees at some edges and less at others.
fn test_objects() -> Vec<hce_format::Object> {
    let (p, t) = octahedron();
    let (gp, gt) = grid(3, 2);
    let plain = vec![
        random_object("octahedron", p, t, RandomTrees::default(), 1),
        random_object(
            "grid",
            gp,
            gt,
            RandomTrees {
                max_depth: 5,
                split_probability: 0.7,
                max_extra_normals: 6,
            },
            2,
        ),
    ];
    let folded: Vec<_> = plain
        .iter()
        .map(|o| with_adjacency(o.clone(), &format!("{} with folds", o.name)))
        .collect();
    plain.into_iter().chain(folded).collect()
}

/// Dot products of the candidate normals, to accept a different choice only on a near tie
/// (the GPU may fuse multiply-adds the CPU rounds separately).
fn near_tie(object: &hce_format::Object, t: u32, a: u32, b: u32, n: [f32; 3]) -> bool {
    let r = object.triangles[t as usize];
    let dot = |j: u32| {
        let m = object.normals[(r.normal_start + j) as usize];
        m[0] * n[0] + m[1] * n[1] + m[2] * n[2]
    };
    (dot(a) - dot(b)).abs() <= 1e-5
}

#[test]
fn gpu_decoding_matches_cpu_on_random_trees() {
    let Some(ctx) = context_or_skip("gpu_decoding_matches_cpu_on_random_trees") else {
        return;
    };
    for object in test_objects() {
        let summary = tables::validate_tables(&object).unwrap();
        assert!(
            summary.max_depth >= 2,
            "random trees should be deep enough to test walking"
        );
        let mut rng = SplitMix(99);
        let queries: Vec<ColourQuery> = (0..4000)
            .map(|_| {
                let level = rng.below(7);
                let n = rng.unit_vector();
                ColourQuery {
                    triangle: rng.below(object.triangles.len() as u32),
                    level,
                    path: (rng.next_u64() % (1u64 << (2 * level))) as u32,
                    _pad: 0,
                    normal: [n[0], n[1], n[2], 0.0],
                }
            })
            .collect();
        let gpu = decode_colours(&ctx, &object, &queries).unwrap();
        assert_eq!(gpu.len(), queries.len());
        let mut deep = 0;
        for (q, g) in queries.iter().zip(&gpu) {
            let n = [q.normal[0], q.normal[1], q.normal[2]];
            let c = decode::decode_colour(&object, q.triangle, q.level, q.path, n);
            assert_eq!(g.node, c.node, "{}: query {q:?}", object.name);
            if g.normal_index != c.normal_index {
                assert!(
                    near_tie(&object, q.triangle, g.normal_index, c.normal_index, n),
                    "{}: query {q:?}: GPU normal {} CPU {}",
                    object.name,
                    g.normal_index,
                    c.normal_index
                );
                continue;
            }
            assert_eq!(g.packed, c.packed);
            // Decoding a power-of-two scaled mantissa is exact on both sides.
            assert_eq!(g.rgb, c.rgb, "{}: query {q:?}", object.name);
            if c.node > 4 {
                deep += 1;
            }
        }
        assert!(
            deep > 100,
            "{}: only {deep} queries reached depth 2",
            object.name
        );
    }
}

#[test]
fn gpu_flat_refinement_matches_cpu() {
    let Some(ctx) = context_or_skip("gpu_flat_refinement_matches_cpu") else {
        return;
    };
    let mut split_objects = 0;
    for object in test_objects() {
        let topo = FlatTopology::new(&object.name, &object.mesh).unwrap();
        let split = SplitTables::new(&object.name, &object.mesh, object.kind).unwrap();
        split_objects += usize::from(!split.is_empty());
        let diag = {
            let p = &object.mesh.positions;
            let mut lo = [f32::MAX; 3];
            let mut hi = [f32::MIN; 3];
            for v in p.chunks_exact(3) {
                for k in 0..3 {
                    lo[k] = lo[k].min(v[k]);
                    hi[k] = hi[k].max(v[k]);
                }
            }
            ((0..3).map(|k| (hi[k] - lo[k]).powi(2)).sum::<f32>()).sqrt()
        };
        for level in 0..=4 {
            let cpu = flat::refine_flat_cpu(&object, &topo, level);
            let gpu =
                refine_flat_with(&ctx, &object, level, Reconstruction::NearestNormal).unwrap();
            let what = format!("{} level {level}", object.name);
            let base = topo.refined_vertex_count(level) as usize;
            assert_eq!(
                gpu.vertex_count(),
                base + split.appended(level) as usize,
                "{what}"
            );
            // Each copy of the split sits on its original, bit for bit (SPEC.md F.5).
            for (j, src) in split.copy_sources(&object.mesh, level).iter().enumerate() {
                let (i, src) = (base + j, *src as usize);
                assert_eq!(
                    gpu.positions[3 * i..3 * i + 3]
                        .iter()
                        .map(|x| x.to_bits())
                        .collect::<Vec<_>>(),
                    gpu.positions[3 * src..3 * src + 3]
                        .iter()
                        .map(|x| x.to_bits())
                        .collect::<Vec<_>>(),
                    "{what}: copy {i} of vertex {src}"
                );
            }
            assert_eq!(
                gpu.triangle_count(),
                object.triangles.len() << (2 * level),
                "{what}"
            );
            assert_eq!(gpu.indices, cpu.indices, "{what}: indices");
            for (i, (g, c)) in gpu.positions.iter().zip(&cpu.positions).enumerate() {
                assert!(
                    (g - c).abs() <= 1e-5 * diag,
                    "{what}: position {i}: {g} vs {c}"
                );
            }
            let close = |g: f32, c: f32| (g - c).abs() <= 1e-3 * c.abs().max(1e-3);
            let mut differing_faces = 0;
            for (f, (g, c)) in gpu
                .face_colours
                .chunks_exact(4)
                .zip(cpu.face_colours.chunks_exact(4))
                .enumerate()
            {
                if !(0..4).all(|k| close(g[k], c[k])) {
                    // Only a near tie in the normal choice may pick another colour.
                    differing_faces += 1;
                    assert!(differing_faces <= 2, "{what}: face {f}: {g:?} vs {c:?}");
                }
            }
            if differing_faces == 0 {
                for (i, (g, c)) in gpu.colours.iter().zip(&cpu.colours).enumerate() {
                    assert!(close(*g, *c), "{what}: vertex colour {}: {g} vs {c}", i / 4);
                }
            }

            // The smooth reconstruction against `apply_baked_colours` on the same refinement:
            // the corner models are the same f32 table on both sides, so the colours differ
            // only by f32 rounding of the blend and of the area weights.
            let smooth = refine_flat_with(&ctx, &object, level, Reconstruction::Smooth).unwrap();
            assert_eq!(smooth.indices, cpu.indices, "{what}: smooth indices");
            let refined = Refined {
                level,
                positions: cpu
                    .positions
                    .chunks_exact(3)
                    .map(|p| [p[0], p[1], p[2]])
                    .collect(),
                normals: vec![[0.0; 3]; cpu.positions.len() / 3],
                indices: cpu
                    .indices
                    .chunks_exact(3)
                    .map(|t| [t[0], t[1], t[2]])
                    .collect(),
                coarse_vertices: object.mesh.vertex_count(),
                coarse_edges: topo.edge_count as usize,
                coarse_triangles: object.triangles.len(),
            };
            let want = apply_baked_colours(&object, &refined, level).unwrap();
            for (v, c) in want.iter().enumerate() {
                let g = &smooth.colours[4 * v..4 * v + 3];
                let scale = c.iter().fold(1e-3f32, |a, &b| a.max(b));
                for k in 0..3 {
                    assert!(
                        (g[k] - c[k]).abs() <= 1e-5 * scale,
                        "{what}: smooth vertex colour {v}: {g:?} vs {c:?}"
                    );
                }
            }
        }
    }
    assert_eq!(split_objects, 2, "both objects with folds split");
}

/// The adaptive refinement (SPEC.md F.7.1) on the GPU against `hce_geometry::adaptive_flat`
/// and `adaptive_flat_colours`: the same indices and position bits, and the same vertex colours
/// up to the f32 rounding of the area-weighted means (the CPU sums in f64), for both
/// reconstructions.
#[test]
fn gpu_adaptive_flat_refinement_matches_cpu() {
    let Some(ctx) = context_or_skip("gpu_adaptive_flat_refinement_matches_cpu") else {
        return;
    };
    for object in test_objects() {
        let cpu = refine_adaptive_flat(&object).unwrap();
        for reconstruction in [Reconstruction::Smooth, Reconstruction::NearestNormal] {
            let what = format!("{} {reconstruction:?}", object.name);
            let gpu = refine_flat_adaptive(&ctx, &object, reconstruction).unwrap();
            assert_eq!(gpu.vertex_count(), cpu.vertex_count(), "{what}");
            assert_eq!(
                gpu.indices,
                cpu.indices.iter().flatten().copied().collect::<Vec<_>>(),
                "{what}: indices"
            );
            for (v, p) in cpu.positions.iter().enumerate() {
                assert_eq!(
                    gpu.positions[3 * v..3 * v + 3]
                        .iter()
                        .map(|x| x.to_bits())
                        .collect::<Vec<_>>(),
                    p.map(f32::to_bits),
                    "{what}: position {v}"
                );
            }
            let want = adaptive_flat_colours(&object, &cpu, reconstruction).unwrap();
            // The nearest-normal rule may pick another normal on a near tie (the GPU may fuse
            // multiply-adds); a vertex of such a triangle then differs.
            let mut differing = 0;
            for (v, c) in want.iter().enumerate() {
                let g = &gpu.colours[4 * v..4 * v + 3];
                let scale = c.iter().fold(1e-3f32, |a, &b| a.max(b));
                if !(0..3).all(|k| (g[k] - c[k]).abs() <= 1e-5 * scale) {
                    differing += 1;
                    assert!(
                        reconstruction == Reconstruction::NearestNormal && differing <= 6,
                        "{what}: vertex colour {v}: {g:?} vs {c:?}"
                    );
                }
            }
        }
    }
}

#[test]
fn refined_closed_mesh_is_watertight_and_single_colours_stay_exact() {
    // One normal, a single-node tree per triangle: every fine triangle and vertex gets that
    // triangle's colour where triangles agree; across the octahedron all equal one colour.
    let (p, t) = octahedron();
    let mut object = random_object(
        "octahedron",
        p,
        t,
        RandomTrees {
            max_depth: 0,
            split_probability: 0.0,
            max_extra_normals: 0,
        },
        3,
    );
    let colour = hce_format::rgb9e5::encode([0.5, 0.25, 2.0]);
    object.colours.iter_mut().for_each(|c| *c = colour);
    let topo = FlatTopology::new("octahedron", &object.mesh).unwrap();
    let level = 3;
    let cpu = flat::refine_flat_cpu(&object, &topo, level);
    // Every fine edge is shared by exactly two fine triangles, in opposite directions.
    let mut directed = std::collections::HashMap::new();
    for tri in cpu.indices.chunks_exact(3) {
        for e in 0..3 {
            *directed.entry((tri[e], tri[(e + 1) % 3])).or_insert(0) += 1;
        }
    }
    for (&(a, b), &count) in &directed {
        assert_eq!(count, 1, "edge ({a}, {b}) used twice in one direction");
        assert_eq!(
            directed.get(&(b, a)),
            Some(&1),
            "edge ({a}, {b}) is a border"
        );
    }
    // V − E + F = 2 for the refined sphere.
    let (v, e, f) = (cpu.vertex_count(), directed.len() / 2, cpu.triangle_count());
    assert_eq!(v as i64 - e as i64 + f as i64, 2);
    for c in cpu.colours.chunks_exact(4) {
        assert_eq!(c, [0.5, 0.25, 2.0, 1.0]);
    }
    let Some(ctx) =
        context_or_skip("refined_closed_mesh_is_watertight_and_single_colours_stay_exact")
    else {
        return;
    };
    let gpu = refine_flat(&ctx, &object, level).unwrap();
    assert_eq!(gpu.indices, cpu.indices);
    for c in gpu.colours.chunks_exact(4) {
        for k in 0..3 {
            assert!((c[k] - [0.5, 0.25, 2.0][k]).abs() < 1e-6, "{c:?}");
        }
    }
}

#[test]
fn malformed_tables_are_rejected_before_upload() {
    let (p, t) = octahedron();
    let good = random_object("octahedron", p, t, RandomTrees::default(), 4);
    let mut bad = good.clone();
    bad.triangles[3].bits_start = bad.bit_len as u32;
    let e = tables::validate_tables(&bad).unwrap_err().to_string();
    assert!(
        e.contains("triangles[3]: bitstream ends inside node 0"),
        "{e}"
    );
    let mut bad = good.clone();
    bad.colours.truncate(bad.colours.len() - 1);
    let e = tables::validate_tables(&bad).unwrap_err().to_string();
    assert!(e.contains("colours"), "{e}");
    let mut bad = good.clone();
    bad.triangles[0].normal_count = 0;
    assert!(tables::validate_tables(&bad).is_err());
    let mut bad = good;
    bad.mesh.edges[5] = 1000;
    let e = FlatTopology::new("octahedron", &bad.mesh)
        .unwrap_err()
        .to_string();
    assert!(e.contains("mesh.edges[5]: id 1000 skips ahead"), "{e}");
}

#[test]
fn gpu_flat_refinement_matches_cpu_on_real_meshes() {
    let Some(dir) = std::env::var_os("HCE_EXTRA_MESHES") else {
        eprintln!(
            "SKIPPED gpu_flat_refinement_matches_cpu_on_real_meshes: HCE_EXTRA_MESHES is unset \
             (point it at the shared meshes folder to run this test)"
        );
        return;
    };
    let Some(ctx) = context_or_skip("gpu_flat_refinement_matches_cpu_on_real_meshes") else {
        return;
    };
    use hce_meshio::plain::load_plain_mesh;
    use hce_runtime::plain::to_flat_object;
    for name in ["teapot.obj", "suzanne.obj"] {
        let path = std::path::Path::new(&dir).join(name);
        let plain = load_plain_mesh(&path).unwrap();
        let (welded, _) = to_flat_object(name, &plain);
        let object = random_object(
            name,
            welded.mesh.positions,
            welded.mesh.triangles,
            RandomTrees::default(),
            11,
        );
        let topo = FlatTopology::new(name, &object.mesh).unwrap();
        for level in 1..=2 {
            let cpu = flat::refine_flat_cpu(&object, &topo, level);
            let gpu =
                refine_flat_with(&ctx, &object, level, Reconstruction::NearestNormal).unwrap();
            assert_eq!(gpu.indices, cpu.indices, "{name} level {level}");
            let max_pos = gpu
                .positions
                .iter()
                .zip(&cpu.positions)
                .map(|(g, c)| (g - c).abs())
                .fold(0f32, f32::max);
            assert!(
                max_pos < 1e-4,
                "{name} level {level}: position error {max_pos}"
            );
            let faces_differing = gpu
                .face_colours
                .chunks_exact(4)
                .zip(cpu.face_colours.chunks_exact(4))
                .filter(|(g, c)| (0..3).any(|k| (g[k] - c[k]).abs() > 1e-3 * c[k].abs().max(1e-3)))
                .count();
            // Near ties in the normal choice are the only admissible difference.
            assert!(
                faces_differing * 10_000 <= gpu.triangle_count(),
                "{name} level {level}: {faces_differing} fine triangles coloured differently"
            );
        }
    }
}

#[test]
fn refining_again_reuses_buffers_and_is_deterministic() {
    let Some(ctx) = context_or_skip("refining_again_reuses_buffers_and_is_deterministic") else {
        return;
    };
    use hce_runtime::gpu::FlatKernel;
    let object = test_objects().remove(1);
    let kernel = FlatKernel::new(&ctx);
    let uploaded = kernel
        .upload(
            &ctx,
            &object,
            Reconstruction::default(),
            FlatRefinement::Uniform,
        )
        .unwrap();
    let mut out = None;
    kernel
        .refine_into(&ctx, &uploaded, 3, &mut out, false)
        .unwrap();
    let level3_size = out.as_ref().unwrap().positions.size();
    // Dropping to level 2 keeps the level-3 buffers and reads back only level 2's part.
    kernel
        .refine_into(&ctx, &uploaded, 2, &mut out, false)
        .unwrap();
    let o = out.as_ref().unwrap();
    assert_eq!(o.positions.size(), level3_size);
    let reused = o.read_back(&ctx).unwrap();
    let fresh = refine_flat(&ctx, &object, 2).unwrap();
    // Same input, same bits: every output element has exactly one writer.
    assert_eq!(reused, fresh);
    assert_eq!(reused.triangle_count(), object.triangles.len() * 16);
}

#[test]
fn write_bandwidth_reference_fills_the_whole_buffer() {
    let Some(ctx) = context_or_skip("write_bandwidth_reference_fills_the_whole_buffer") else {
        return;
    };
    // 1 MiB + 16 bytes: the last word lies past a power of two, so a dispatch that stops
    // short would leave it unwritten and the function would report an error.
    let bw = hce_runtime::gpu::bench::write_bandwidth(&ctx, (1 << 20) + 16, 2).unwrap();
    assert_eq!(bw.bytes, (1 << 20) + 16);
    assert!(bw.seconds > 0.0 && bw.bytes_per_second().is_finite());
    assert!(bw.bytes_per_second() > 1e6, "{bw:?}");
}
