//! Batched refinement (`SceneOptions::batch`, runtime/src/gpu/batch.rs): the small objects that
//! `GpuScene::refine_batch` refines whole are refined together, one dispatch per step for all
//! the flat ones and one for all the multiresolution ones, and must write exactly the bytes of
//! each object refined alone with its own dispatches, at any mix of levels, with either colour
//! reconstruction, as the levels change (the pooled outputs reused and grown) and beside
//! objects refined in pieces: flat objects with both refinements (SPEC.md F.7.1, whose
//! triangles do not depend on the level, and F.7.2), multiresolution ones whose own refinement
//! may build its patches with the other patch kernel.
//!
//! Runs on any adapter, Mesa lavapipe included. Without one the tests skip with a message,
//! unless `HCE_REQUIRE_GPU=1`, which makes them fail.
#![cfg(feature = "gpu")]

use hce_format::ObjectKind;
use hce_geometry::lighting::Reconstruction;
use hce_runtime::asset::Asset;
use hce_runtime::gpu::testing::{context_or_skip, small_flat_scene, small_scene};
use hce_runtime::gpu::{FlatRefinement, GpuContext, GpuScene, ObjectMesh, SceneOptions};

/// A mesh's bytes, so that equal means bit-identical (and a NaN equals itself).
fn bytes(m: &ObjectMesh) -> Vec<u8> {
    let mut out = Vec::new();
    out.extend_from_slice(&m.level.to_le_bytes());
    out.extend_from_slice(bytemuck::cast_slice(&m.positions));
    out.extend_from_slice(bytemuck::cast_slice(&m.colours));
    out.extend_from_slice(bytemuck::cast_slice(&m.indices));
    if let Some(normals) = &m.normals {
        out.extend_from_slice(bytemuck::cast_slice(normals));
    }
    out
}

fn scene(
    ctx: &GpuContext,
    asset: &Asset,
    reconstruction: Reconstruction,
    batch: bool,
    flat: FlatRefinement,
) -> GpuScene {
    GpuScene::new(
        ctx,
        asset,
        &SceneOptions {
            reconstruction,
            batch,
            flat_refinement: flat,
            ..SceneOptions::default()
        },
    )
    .unwrap()
}

/// The scenes the tests batch: small flat objects with either refinement, and small
/// multiresolution objects (whose refinement does not depend on the flat one).
const SCENES: [(ObjectKind, FlatRefinement); 3] = [
    (ObjectKind::Flat, FlatRefinement::Adaptive),
    (ObjectKind::Flat, FlatRefinement::Uniform),
    (ObjectKind::Multiresolution, FlatRefinement::Adaptive),
];

/// Every object of `reference` refined alone to `levels[i]` (one object per call: its own
/// dispatches), read back.
fn alone(ctx: &GpuContext, reference: &mut GpuScene, levels: &[u32]) -> Vec<Vec<u8>> {
    (0..levels.len())
        .map(|i| {
            reference.refine(ctx, i, levels[i]).unwrap();
            bytes(&reference.read_back(ctx, i).unwrap())
        })
        .collect()
}

#[test]
fn a_batch_writes_the_bytes_of_each_object_refined_alone() {
    let Some(ctx) = context_or_skip("a_batch_writes_the_bytes_of_each_object_refined_alone") else {
        return;
    };
    let runs = SCENES.into_iter().flat_map(|scene| {
        [Reconstruction::Smooth, Reconstruction::NearestNormal].map(|r| (scene, r))
    });
    for ((kind, flat), reconstruction) in runs {
        let asset = small_scene(14, 5, kind).unwrap();
        let n = asset.objects.len();
        let mut batched = scene(&ctx, &asset, reconstruction, true, flat);
        let mut reference = scene(&ctx, &asset, reconstruction, false, flat);
        // Levels 0 to 3 mixed, then each object to another (reusing the pooled outputs), then
        // each one level up (growing them), with object 0 refined in pieces beside the batch.
        // Every object changes level in every round.
        let rounds: [Vec<u32>; 3] = [
            (0..n).map(|i| (i % 4) as u32).collect(),
            (0..n).map(|i| ((i + 1) % 4) as u32).collect(),
            (0..n).map(|i| ((i + 1) % 4) as u32 + 1).collect(),
        ];
        for (round, levels) in rounds.iter().enumerate() {
            let mut work = Vec::new();
            for (i, &level) in levels.iter().enumerate() {
                assert!(batched.begin_refine(&ctx, i, level).unwrap());
                work.push((i, u64::MAX));
            }
            let pieces = round == 2;
            if pieces {
                let (_, _, total) = batched.refine_progress(0).unwrap();
                work[0].1 = total / 3;
            }
            let mut reports = batched.refine_batch(&ctx, &work, false).unwrap();
            let together: Vec<usize> = reports
                .iter()
                .filter(|r| r.batched)
                .map(|r| r.object)
                .collect();
            // Every object given all its work went in the batch.
            let expected: Vec<usize> = (0..n).filter(|&i| !(pieces && i == 0)).collect();
            assert_eq!(
                together, expected,
                "{kind:?} {flat:?} {reconstruction:?}, round {round}"
            );
            assert_eq!(reports.len(), n);
            assert!(reports
                .iter()
                .all(|r| r.finished || (pieces && r.object == 0)));
            while batched.refine_progress(0).is_some() {
                reports = batched.refine_batch(&ctx, &[(0, 1 << 20)], false).unwrap();
                assert!(
                    reports.iter().all(|r| !r.batched),
                    "one object is not a batch"
                );
            }
            let want = alone(&ctx, &mut reference, levels);
            for (i, want) in want.iter().enumerate() {
                let got = bytes(&batched.read_back(&ctx, i).unwrap());
                assert_eq!(batched.level(i), Some(levels[i]));
                assert!(
                    got == *want,
                    "{kind:?} {flat:?} {reconstruction:?}, round {round}: object {i} at level {} \
                     differs from its refinement alone",
                    levels[i]
                );
            }
        }
    }
}

/// A call refining more fine triangles than one batch holds refines them in several batches
/// (all but the last submitted at once, each with its own table) and still writes the bytes of
/// each object refined alone.
#[test]
fn several_batches_in_one_call_write_the_bytes_of_each_object_alone() {
    let Some(ctx) =
        context_or_skip("several_batches_in_one_call_write_the_bytes_of_each_object_alone")
    else {
        return;
    };
    for (kind, flat) in SCENES {
        let asset = small_scene(12, 3, kind).unwrap();
        let n = asset.objects.len();
        let levels: Vec<u32> = (0..n).map(|i| 2 + (i % 2) as u32).collect();
        let mut reference = scene(&ctx, &asset, Reconstruction::Smooth, false, flat);
        // A batch of a third of the scene, at least its largest object.
        let fine: Vec<u64> = (0..n)
            .map(|i| reference.triangles_at(i, levels[i]))
            .collect();
        let batch_fine = (fine.iter().sum::<u64>() / 3).max(*fine.iter().max().unwrap());
        several_batches(
            &ctx,
            &asset,
            &mut reference,
            &levels,
            (kind, flat),
            batch_fine,
        );
    }
}

fn several_batches(
    ctx: &GpuContext,
    asset: &Asset,
    reference: &mut GpuScene,
    levels: &[u32],
    (kind, flat): (ObjectKind, FlatRefinement),
    batch_fine: u64,
) {
    let n = levels.len();
    let options = SceneOptions {
        batch_fine,
        flat_refinement: flat,
        ..SceneOptions::default()
    };
    let mut batched = GpuScene::new(ctx, asset, &options).unwrap();
    let work: Vec<(usize, u64)> = levels
        .iter()
        .enumerate()
        .map(|(i, &level)| {
            assert!(batched.begin_refine(ctx, i, level).unwrap());
            (i, u64::MAX)
        })
        .collect();
    let fine: Vec<u64> = (0..n).map(|i| batched.triangles_at(i, levels[i])).collect();
    let total: u64 = fine.iter().sum();
    assert!(
        total > 2 * batch_fine,
        "{kind:?} {flat:?}: the scene ({total} fine triangles) must take three batches or more"
    );
    let reports = batched.refine_batch(ctx, &work, false).unwrap();
    assert_eq!(reports.len(), n);
    assert!(reports.iter().all(|r| r.finished));
    let together = reports.iter().filter(|r| r.batched).count();
    assert!(
        together >= n - 1,
        "{kind:?}: only {together} of {n} objects went in batches"
    );
    let want = alone(ctx, reference, levels);
    for (i, want) in want.iter().enumerate() {
        let got = bytes(&batched.read_back(ctx, i).unwrap());
        assert!(
            got == *want,
            "{kind:?} {flat:?}: object {i} at level {} differs from its refinement alone",
            levels[i]
        );
    }
}

#[test]
fn a_scene_without_batching_refines_each_object_alone() {
    let Some(ctx) = context_or_skip("a_scene_without_batching_refines_each_object_alone") else {
        return;
    };
    let asset = small_flat_scene(4, 9).unwrap();
    let mut s = scene(
        &ctx,
        &asset,
        Reconstruction::Smooth,
        false,
        FlatRefinement::Adaptive,
    );
    let work: Vec<(usize, u64)> = (0..4)
        .map(|i| {
            assert!(s.begin_refine(&ctx, i, 2).unwrap());
            (i, u64::MAX)
        })
        .collect();
    let reports = s.refine_batch(&ctx, &work, false).unwrap();
    assert_eq!(reports.len(), 4);
    assert!(reports.iter().all(|r| r.finished && !r.batched));
}

#[test]
fn objects_too_large_for_a_batch_keep_their_own_dispatches() {
    let Some(ctx) = context_or_skip("objects_too_large_for_a_batch_keep_their_own_dispatches")
    else {
        return;
    };
    // At level 5 of the uniform refinement and of Loop subdivision an octahedron is 8,192 fine
    // triangles (batched), a grid of 8 to 50 triangles 8,192 to 51,200: the larger ones exceed
    // 16,384 and are refined alone.
    for kind in [ObjectKind::Flat, ObjectKind::Multiresolution] {
        let asset = small_scene(9, 3, kind).unwrap();
        let n = asset.objects.len();
        let levels = vec![5; n];
        let uniform = FlatRefinement::Uniform;
        let mut batched = scene(&ctx, &asset, Reconstruction::Smooth, true, uniform);
        let mut reference = scene(&ctx, &asset, Reconstruction::Smooth, false, uniform);
        let work: Vec<(usize, u64)> = (0..n)
            .map(|i| {
                assert!(batched.begin_refine(&ctx, i, 5).unwrap());
                (i, u64::MAX)
            })
            .collect();
        let reports = batched.refine_batch(&ctx, &work, false).unwrap();
        assert_eq!(reports.len(), n);
        let small = |i: usize| batched.triangles_at(i, 5) <= 16_384;
        for r in &reports {
            assert!(r.finished);
            assert_eq!(r.batched, small(r.object), "{kind:?}: object {}", r.object);
        }
        let together = (0..n).filter(|&i| small(i)).count();
        assert!(
            together >= 2 && together < n,
            "{kind:?}: {together} of {n} batched"
        );
        for (i, want) in alone(&ctx, &mut reference, &levels).iter().enumerate() {
            assert!(
                bytes(&batched.read_back(&ctx, i).unwrap()) == *want,
                "{kind:?}: object {i}"
            );
        }
    }
}
