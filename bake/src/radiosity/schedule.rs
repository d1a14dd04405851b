//! The bake's passes: direct light, then `refine_passes` times link refinement and a solve,
//! each pass's work run in parallel per root (within a root's refinement, in the parts of
//! [`parallel_walk`](super::parallel_walk)), so that the result does not depend on the thread
//! count.

use std::time::Instant;

use glam::Vec3;
use rayon::prelude::*;

use super::cluster_reading::ClusterLight;
use super::context::{lum, Ctx};
use super::element::ElemKey;
use super::links::{Link, RawLinks, Source, CORNERS};
use super::params::BakeParams;
use super::refine::Judge;
use super::solution::{BakeResult, BakeStats, ObjectSolution, TriangleSolution};
use super::source_variation::DIM_RECEIVER_FLOOR;
use super::tree::Tree;
use crate::scene::Scene;
use crate::BakeError;

/// Progress callback: `(phase, done, total)`, e.g. `("refine 1", 1200, 20000)` coarse
/// triangles, or `("solve 2", 3, 200)` iterations (the total is the iteration cap). Called
/// from worker threads; it only reports and never changes the result.
pub type Progress<'a> = &'a (dyn Fn(&str, usize, usize) + Sync);

/// Bakes the scene: direct light, link refinement, solve, repeated `refine_passes` times.
pub fn bake(scene: &Scene, params: &BakeParams) -> Result<BakeResult, BakeError> {
    bake_with_progress(scene, params, &|_: &str, _: usize, _: usize| {})
}

/// [`bake`] with a progress report per phase (for progress bars).
pub fn bake_with_progress(
    scene: &Scene,
    params: &BakeParams,
    progress: Progress<'_>,
) -> Result<BakeResult, BakeError> {
    scene.validate()?;
    params.validate()?;
    let mut stats = BakeStats::default();
    let t0 = Instant::now();
    let ctx = Ctx::new(scene, params)?;
    stats.coarse_triangles = ctx.roots.len();
    stats
        .phase_seconds
        .push(("setup".into(), t0.elapsed().as_secs_f64()));

    // Direct light, first at the roots to fix the reference power, then refined.
    let t1 = Instant::now();
    let n_roots = ctx.roots.len() as u32;
    let root_q: Vec<Vec<Vec3>> = (0..n_roots)
        .into_par_iter()
        .map(|r| ctx.direct(ElemKey::root(r)))
        .collect();
    let mut ref_power = 0.0f64;
    for (r, (root, q)) in ctx.roots.iter().zip(&root_q).enumerate() {
        let rho = lum(ctx.reflectance(ElemKey::root(r as u32)));
        let r = root;
        ref_power +=
            f64::from(r.area) * std::f64::consts::PI * f64::from(lum(r.emission) + rho * lum(q[0]));
    }
    let eps_power = (ref_power * f64::from(params.bf_epsilon)) as f32;
    let counter = std::sync::atomic::AtomicUsize::new(0);
    let direct: Vec<Vec<(ElemKey, Vec<Vec3>)>> = root_q
        .into_par_iter()
        .enumerate()
        .map(|(r, q)| {
            let out = ctx.direct_tree(r as u32, q, eps_power);
            let done = counter.fetch_add(1, std::sync::atomic::Ordering::Relaxed) + 1;
            progress("direct", done, n_roots as usize);
            out
        })
        .collect();
    let mut trees: Vec<Tree> = (0..n_roots)
        .into_par_iter()
        .map(|r| ctx.build_tree(r, Vec::new(), &direct[r as usize]))
        .collect();
    let mut cl = vec![ClusterLight::default(); ctx.clusters.clusters.len()];
    // Without links one pass gives L = Le + ρ H/π.
    ctx.solve(&mut trees, &mut cl, 1, &|_| {});
    stats
        .phase_seconds
        .push(("direct".into(), t1.elapsed().as_secs_f64()));

    for pass in 0..params.refine_passes.max(1) {
        let t2 = Instant::now();
        let phase = format!("refine {}", pass + 1);
        counter.store(0, std::sync::atomic::Ordering::Relaxed);
        let spreads: Vec<Vec<f32>> = (0..n_roots)
            .into_par_iter()
            .map(|r| ctx.spreads(r, &trees[r as usize]))
            .collect();
        let mean_radiance = ctx.mean_radiance(&trees);
        let judge = Judge {
            mean_radiance,
            dark_floor: if pass == 0 && params.refine_passes > 1 {
                DIM_RECEIVER_FLOOR * mean_radiance
            } else {
                0.0
            },
            last_pass: pass + 1 >= params.refine_passes.max(1),
        };
        // A root's links of the previous pass are read by its own refinement alone (its cache
        // of known links), so they go to it and are freed when it is done: they are not held
        // beside the new pass's links at the bake's memory peak. The solution and the trees'
        // shape stay for the warm start below.
        let prev: Vec<(Vec<Link>, Vec<f32>)> = trees
            .iter_mut()
            .map(|t| (std::mem::take(&mut t.links), std::mem::take(&mut t.k)))
            .collect();
        let refined: Vec<RawLinks> = prev
            .into_par_iter()
            .enumerate()
            .map(|(r, prev)| {
                let r = r as u32;
                let out = ctx.refine_root(r, prev, &trees, &cl, &spreads, eps_power, judge);
                let done = counter.fetch_add(1, std::sync::atomic::Ordering::Relaxed) + 1;
                progress(&phase, done, n_roots as usize);
                out
            })
            .collect();
        // Every source element must exist in its tree: collect keys per root in fixed order.
        let mut needed: Vec<Vec<ElemKey>> = vec![Vec::new(); n_roots as usize];
        // A receiver's links come one after another, and so mostly do a source's: a key is
        // left out when it repeats the last one pushed, which `build_tree` would drop anyway
        // (a key a link names, most of this list, at the memory peak).
        // A root's own key is left out too: `build_tree` adds it to every tree (in a scene of
        // unsplit roots, every key a link names).
        let mut push = |k: ElemKey| {
            let list = &mut needed[k.root as usize];
            if k.level > 0 && list.last() != Some(&k) {
                list.push(k);
            }
        };
        for raw in &refined {
            for (recv, src) in raw.ends() {
                push(recv);
                if let Source::Elem(k) = src {
                    push(k);
                }
            }
        }
        // Each tree starts from the previous solution where it exists, so that the solve
        // converges fast; the previous tree is dropped as soon as it has been read, not held
        // beside the new ones.
        let mut new_trees: Vec<Tree> = needed
            .into_par_iter()
            .zip(std::mem::take(&mut trees))
            .enumerate()
            .map(|(r, (keys, old))| {
                let mut nt = ctx.build_tree(r as u32, keys, &direct[r]);
                let nn = nt.l.len() / nt.keys.len();
                for i in 0..nt.keys.len() {
                    let j = old.deepest_toward(nt.keys[i]) as usize;
                    nt.l[i * nn..(i + 1) * nn].copy_from_slice(&old.l[j * nn..(j + 1) * nn]);
                }
                nt
            })
            .collect();
        stats.links = 0;
        for (r, raw) in refined.into_iter().enumerate() {
            stats.links += raw.links.len();
            let (links, k) = raw.resolve(r, |root, key| {
                new_trees[root]
                    .index_of(key)
                    .expect("a link's ends are in the trees")
            });
            (new_trees[r].links, new_trees[r].k) = (links, k);
            (new_trees[r].closure, new_trees[r].self_view) = ctx.closure(r as u32, &new_trees[r]);
        }
        trees = new_trees;
        stats
            .phase_seconds
            .push((format!("refine {}", pass + 1), t2.elapsed().as_secs_f64()));
        let t3 = Instant::now();
        let phase = format!("solve {}", pass + 1);
        let cap = params.max_iterations as usize;
        let (it, change) = ctx.solve(&mut trees, &mut cl, params.max_iterations, &|i| {
            progress(&phase, i, cap)
        });
        stats.iterations += it;
        stats.final_change = change;
        stats
            .phase_seconds
            .push((format!("solve {}", pass + 1), t3.elapsed().as_secs_f64()));
    }

    stats.elements = trees.iter().map(|t| t.keys.len()).sum();
    let mut objects: Vec<ObjectSolution> = scene
        .objects
        .iter()
        .map(|o| ObjectSolution {
            name: o.name.clone(),
            multires: o.multires,
            triangles: Vec::with_capacity(o.triangles.len()),
        })
        .collect();
    let corners: Vec<Vec<Vec3>> = (0..trees.len() as u32)
        .into_par_iter()
        .map(|r| {
            if params.corner_colours {
                ctx.corner_values(r, &trees, &cl)
            } else {
                Vec::new()
            }
        })
        .collect();
    for ((r, t), corners) in trees.iter().enumerate().zip(corners) {
        let root = &ctx.roots[r];
        let nn = root.normals.len();
        objects[root.object].triangles.push(TriangleSolution {
            corner_colours: (0..corners.len())
                .map(|x| {
                    let (kj, c) = (x / CORNERS, x % CORNERS);
                    corners[((kj / nn) * CORNERS + c) * nn + kj % nn].to_array()
                })
                .collect(),
            normals: root.normals.iter().map(|n| n.to_array()).collect(),
            nodes: t.keys.iter().map(|k| (k.level, k.path)).collect(),
            subdivided: t.child.iter().map(|&c| c != u32::MAX).collect(),
            colours: ctx
                .shown(r as u32, t)
                .iter()
                .map(|v| v.to_array())
                .collect(),
        });
    }
    Ok(BakeResult { objects, stats })
}
