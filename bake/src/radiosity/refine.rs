//! Link refinement of one root: a depth-first walk over (receiver, source) pairs from (the root,
//! the scene's top cluster). Each pair goes through the rules in turn (the receiver's own rules,
//! the culls, the rules for an element or a cluster source, the power rule, then those judged by
//! the link's visibility); the first that asks for it splits the receiver or the source, and a
//! pair no rule splits becomes a link. The receivers the narrow shadow rule split then take their
//! other links down with them.

use std::collections::HashSet;
use std::sync::Mutex;

use glam::Vec3;
use rayon::prelude::*;

use super::cluster::ClusterChild;
use super::cluster_reading::{ClusterLight, READ_PARTS};
use super::coefficients::{inset_corners, KnownFactors};
use super::context::{lum, Ctx};
use super::element::{split, ElemKey};
use super::formfactor::{disc_estimate, point_to_polygon};
use super::link_visibility::{FAINT_LINK, LIGHT_RAY_FACTOR, MAX_RAY_FACTOR, VISIBILITY_NOISE};
use super::links::{RawLink, Source, SrcIdx, CORNERS};
use super::schedule::{refine_in_parallel, REFINE_STEPS};
use super::shadow_edge::SHADOW_TOLERANCE;
use super::source_variation::DIM_RECEIVER_FLOOR;
use super::tree::Tree;

/// What a refinement pass judges the rules weighed against a receiver's own radiance by: the
/// mean radiance of the surfaces that emit nothing (`DIM_RECEIVER_FLOOR`), and the least
/// radiance the bend rules count a receiver as having (in a first pass of several, before any
/// light has bounced, a fraction of that mean; else zero).
#[derive(Clone, Copy)]
pub(super) struct Judge {
    pub(super) mean_radiance: f32,
    pub(super) dark_floor: f32,
    /// Whether this pass's links make the file.
    pub(super) last_pass: bool,
}

/// A receiver and a source that may exchange light, with the corners of the receiver and of the
/// source (when an element).
/// A receiver (its key and corners), a source (with its corners, for an element), and whether
/// the receiver's own rules (`near_shadow`, `self_shade_varies`) are known to leave it whole:
/// so a pair that splits or opens its source, keeping the receiver, does not ask again.
pub(super) type Pair = (ElemKey, [Vec3; 3], Source, [Vec3; 3], bool);

/// Whether a receiver and a source element of areas `r_area` and `s_area`, their centres `d2`
/// apart (squared), are near: within six times the root of their summed areas, where the
/// form factor is bounded at points of the receiver, not by a disc from afar.
pub(super) fn near_pair(d2: f32, r_area: f32, s_area: f32) -> bool {
    d2 <= 36.0 * (r_area + s_area)
}

/// Pushes the pairs of the four children of receiver `recv` (corners `rt`) with `src`.
pub(super) fn split_receiver(
    stack: &mut Vec<Pair>,
    recv: ElemKey,
    rt: [Vec3; 3],
    src: Source,
    st: [Vec3; 3],
) {
    let children = split(rt);
    for c in (0..4).rev() {
        stack.push((recv.child(c), children[c as usize], src, st, false));
    }
}

/// Pushes the pairs of `recv` with the four children of source element `sk` (corners `st`).
pub(super) fn split_source(
    stack: &mut Vec<Pair>,
    recv: ElemKey,
    rt: [Vec3; 3],
    sk: ElemKey,
    st: [Vec3; 3],
) {
    let children = split(st);
    for c in (0..4).rev() {
        stack.push((
            recv,
            rt,
            Source::Elem(sk.child(c)),
            children[c as usize],
            true,
        ));
    }
}

impl Ctx<'_> {
    /// Refines the links arriving at root `r` against the previous solution: a depth-first
    /// walk over (receiver, source) pairs from (the root, the scene's top cluster), whose
    /// pairs left after [`REFINE_STEPS`] go on in parallel ([`refine_in_parallel`]).
    pub(super) fn refine_root(
        &self,
        r: u32,
        trees: &[Tree],
        cl: &[ClusterLight],
        spreads: &[Vec<f32>],
        eps_power: f32,
        judge: Judge,
    ) -> (Vec<RawLink>, Vec<f32>) {
        let Judge {
            mean_radiance,
            dark_floor,
            last_pass,
        } = judge;
        let nn = self.nn(r);
        // Per link: its coefficients, and on a refined surface those of the surface's own
        // normal ([`Ctx::link_coefficients`]).
        let link_len = CORNERS * nn
            + if self.surface[r as usize].is_empty() {
                0
            } else {
                CORNERS
            };
        // Coefficients are a pure function of the pair: reuse those of the previous pass.
        let prev = &trees[r as usize];
        let cache: std::collections::HashMap<(ElemKey, Source), (usize, f32, f32)> = prev
            .links
            .iter()
            .map(|l| {
                let src = match l.src {
                    SrcIdx::Cluster(c) => Source::Cluster(c),
                    SrcIdx::Node { root, node } => {
                        Source::Elem(trees[root as usize].keys[node as usize])
                    }
                };
                (
                    (prev.keys[l.recv as usize], src),
                    (l.k_start as usize, l.visible, l.bend),
                )
            })
            .collect();
        let top = match self.clusters.top {
            ClusterChild::Cluster(c) => Source::Cluster(c),
            ClusterChild::Root(x) => Source::Elem(ElemKey::root(x)),
        };
        let corners_of = |s: Source| match s {
            Source::Elem(k) => self.elem_corners(k),
            Source::Cluster(_) => [Vec3::ZERO; 3],
        };
        // Each pair with the corners of its receiver and (an element) source, carried down as
        // they split.
        let stack: Vec<Pair> = vec![(
            ElemKey::root(r),
            self.roots[r as usize].corners,
            top,
            corners_of(top),
            false,
        )];
        let root = &self.roots[r as usize];
        // Radius and area of the clusters of its own object holding this root, largest
        // first: the receivers around it (see the source variation rule below).
        let (own, first) = &self.object_clusters[root.object];
        let neighbourhood: Vec<(f32, f32)> = own
            .ancestors(r - first)
            .iter()
            .map(|&c| {
                let c = &own.clusters[c as usize];
                (c.radius(), c.area)
            })
            .collect();
        // The receiver's radiance in the previous solution (normal 0), which the rules judged
        // against the receiver weigh their errors by.
        let receiver_radiance = |recv: ElemKey| {
            let t = &trees[r as usize];
            lum(t.l[t.deepest_toward(recv) as usize * nn])
        };
        // What the bend rules judge a receiver's error against: its radiance, but in a first
        // pass of several at least `dark_floor`. Before any light has bounced, a receiver
        // in the dark of the direct light has none, and every bend split it (the scaling
        // scene's ball, pass 1: 97,000 elements, of which the second pass kept 54,000).
        let bend_radiance = |recv: ElemKey| receiver_radiance(recv).max(dark_floor);
        // A link's coefficients and visible fraction, with as many rays as what it brings asks
        // (`est`, the power bound the rules judged; `share`, the radiance it brings its
        // receiver).
        let coefficients = |(recv, rt): (ElemKey, [Vec3; 3]),
                            (src, st): (Source, [Vec3; 3]),
                            est: f32,
                            share: f32,
                            known: KnownFactors| {
            // All the rays where the link brings a visible share of the scene's power or of
            // its receiver's light; a few where it brings little of either (the error it can
            // add is a fraction of that). Judged by the scene's power alone, every link of a
            // small leaf was faint and took two rays, and next to an object resting on a floor
            // the noise of a dozen half-hidden links left leaves 8% off in a closed furnace.
            let nv = self.params.visibility_rays;
            let recv_l = receiver_radiance(recv);
            // In the last pass, whose links make the file, a link that brings much of its
            // receiver's light takes enough rays that their noise cannot move the receiver by
            // more than `VISIBILITY_NOISE` of its radiance: n rays read a visible fraction to
            // within 0.5/√n (one standard deviation), so n ≥ (share / 2τ)², up to
            // `MAX_RAY_FACTOR` times the default. Chosen before any ray is cast, so the
            // estimate stays unbiased (stopping or going on by what the rays found does not).
            // Earlier passes only judge where to refine, and take the default.
            // A light's link to a receiver as small as the shadow rule goes carries most of
            // its light, and the shadow edges there are what the narrow shadow rule finds
            // and draws: it may take more rays.
            let r_area = root.area / 4f32.powi(recv.level as i32);
            let ray_factor = if self.lights(src) && !self.detail_splittable(recv, r_area) {
                LIGHT_RAY_FACTOR
            } else {
                MAX_RAY_FACTOR
            };
            let need = if last_pass {
                (share / recv_l.max(f32::MIN_POSITIVE) / (2.0 * VISIBILITY_NOISE))
                    .powi(2)
                    .ceil()
                    .min((nv * ray_factor) as f32) as u32
            } else {
                0
            };
            let rays = if need > nv {
                need
            } else if est >= 0.05 * eps_power || share >= FAINT_LINK * recv_l {
                nv
            } else {
                nv.min(2)
            };
            // A previous pass's coefficients, where they took as many rays.
            match cache.get(&(recv, src)) {
                Some(&(at, visible, _)) if rays <= nv => {
                    (prev.k[at..at + link_len].to_vec(), visible)
                }
                _ => self.link_coefficients((recv, rt), (src, st), rays, known),
            }
        };
        // The link from `src` (corners `st`) to `recv` (centre `rc`), its coefficients at
        // `k_start`.
        let make_link = |recv: ElemKey,
                         rc: Vec3,
                         src: Source,
                         st: [Vec3; 3],
                         k_start: u32,
                         visible: f32,
                         bend: f32| {
            // The last pass's links read near clusters by their deeper parts
            // ([`Ctx::reads_deep`]): an earlier pass's solve only judges where to refine, and
            // reading them in every solve cost 15-20% of the scaling scene's bake.
            let deep = last_pass && matches!(src, Source::Cluster(c) if self.reads_deep(c, rc));
            let (aim, share, facing, depth) = match src {
                Source::Cluster(c) => (
                    self.leaving(c, rc),
                    self.cluster_share(trees, c, rc, root.normal, deep),
                    0,
                    0,
                ),
                Source::Elem(sk) => {
                    let (depth, foot) = self.footprint(rc, root.normal, sk, st);
                    let aim = if depth > 0 {
                        foot
                    } else {
                        self.kernel_centre(rc, root.normal, sk, st)
                    };
                    (aim, [0.0; READ_PARTS], self.facing_normal(sk, rc), depth)
                }
            };
            RawLink {
                recv,
                src,
                aim,
                share,
                deep,
                facing,
                depth,
                k_start,
                visible,
                bend,
            }
        };
        // The receivers the narrow shadow rule split ([`Ctx::narrow_shadow_splittable`]).
        let narrow: Mutex<HashSet<ElemKey>> = Default::default();
        // Refines the pairs on `stack` depth-first for at most `REFINE_STEPS` pairs; returns the
        // links, their coefficients and the pairs left.
        let run = |mut stack: Vec<Pair>| {
            let mut links = Vec::new();
            let mut ks = Vec::new();
            let mut steps = 0;
            while let Some((recv, rt, src, st, judged)) = stack.pop() {
                if steps == REFINE_STEPS {
                    stack.push((recv, rt, src, st, judged));
                    break;
                }
                steps += 1;
                let r_area = root.area / 4f32.powi(recv.level as i32);
                if !judged
                    && self.detail_splittable(recv, r_area)
                    && self.memo(recv, |m| &mut m.near_shadow, || self.near_shadow(recv))
                {
                    split_receiver(&mut stack, recv, rt, src, st);
                    continue;
                }
                if !judged
                    && self.self_shade_splittable(recv)
                    && self.memo(
                        recv,
                        |m| &mut m.shade_varies,
                        || self.self_shade_varies(recv),
                    )
                {
                    split_receiver(&mut stack, recv, rt, src, st);
                    continue;
                }
                let rc = (rt[0] + rt[1] + rt[2]) / 3.0;
                let open = |c: u32, stack: &mut Vec<Pair>| {
                    for ch in self.clusters.clusters[c as usize].children.iter().rev() {
                        let s = match *ch {
                            ClusterChild::Cluster(c) => Source::Cluster(c),
                            ClusterChild::Root(x) => Source::Elem(ElemKey::root(x)),
                        };
                        stack.push((recv, rt, s, corners_of(s), true));
                    }
                };
                let est;
                let s_area;
                let s_splittable;
                // The geometric normal's form factors the split rules below computed, which the
                // link's coefficients reuse.
                let mut known = KnownFactors::default();
                let mut link_bend = f32::NAN;
                match src {
                    Source::Elem(sk) => {
                        if sk.root == r {
                            continue; // A planar triangle does not see itself.
                        }
                        if nn == 1 && self.sees_none_of_own(r, self.roots[sk.root as usize].object)
                        {
                            continue;
                        }
                        let sn = self.roots[sk.root as usize].normal;
                        // Two parts of one refined surface may see each other where their coarse
                        // triangles are coplanar or turned apart: the link's form factors, on the
                        // refined surface, judge that.
                        let refined_pair = self.roots[sk.root as usize].object == root.object
                            && !self.surface[r as usize].is_empty();
                        // Receiver entirely behind the source, or source behind every normal.
                        if !refined_pair && rt.iter().all(|&v| sn.dot(v - st[0]) <= self.plane_eps)
                        {
                            continue;
                        }
                        let sees = |n: &Vec3| {
                            st.iter()
                                .any(|&s| rt.iter().any(|&v| n.dot(s - v) > self.plane_eps))
                        };
                        if !refined_pair && !root.normals.iter().any(sees) {
                            continue;
                        }
                        s_area = self.roots[sk.root as usize].area / 4f32.powi(sk.level as i32);
                        s_splittable = self.splittable(sk, s_area);
                        let sc = (st[0] + st[1] + st[2]) / 3.0;
                        let d2 = (sc - rc).length_squared();
                        let l = lum(self.src_radiance(trees, cl, src, rc));
                        let far = !near_pair(d2, r_area, s_area);
                        let f_bound;
                        if far {
                            let w = (sc - rc) / d2.sqrt();
                            let cos_r = root.normals.iter().map(|n| n.dot(w)).fold(0.0, f32::max);
                            let f = disc_estimate(cos_r, (-w).dot(sn), s_area, d2);
                            est = f * l * r_area * std::f32::consts::PI;
                            f_bound = f;
                        } else {
                            // Near pairs: the point form factor at the centre and near each
                            // corner of the receiver bounds both its size and its variation.
                            let (mut fmax, mut fmin) = (0.0f32, f32::MAX);
                            let mut bend = 0.0f32;
                            let inset = inset_corners(rt);
                            let mut buf = [st; 4];
                            let polys: &[[Vec3; 3]] = if refined_pair {
                                self.source_shape(sk, st, true, &mut buf)
                            } else {
                                &buf[..1]
                            };
                            // The points, carried onto the refined surface for a refined pair.
                            let lift = |p: Vec3| {
                                if refined_pair {
                                    self.on_surface(r, p).0
                                } else {
                                    p
                                }
                            };
                            let (lc, li) = (lift(rc), inset.map(lift));
                            for (j, n) in root.normals.iter().enumerate() {
                                let f = |p: Vec3| {
                                    polys
                                        .iter()
                                        .map(|t| point_to_polygon(p, *n, t))
                                        .sum::<f32>()
                                };
                                let centre = f(lc);
                                let at = li.map(f);
                                for v in at.into_iter().chain([centre]) {
                                    fmax = fmax.max(v);
                                    fmin = fmin.min(v);
                                }
                                // Against the plane through the three corner samples: at the
                                // centre, and between each two corners (a source corner touching
                                // the receiver's side peaks there). The bend is the geometry's,
                                // alike for every normal: the geometric one judges it.
                                if j == 0 {
                                    known.corners = Some(at);
                                    bend = (centre - (at[0] + at[1] + at[2]) / 3.0).abs();
                                    for (a, b) in [(0, 1), (1, 2), (2, 0)] {
                                        let mid = f(lift((inset[a] + inset[b]) * 0.5));
                                        bend = bend.max((mid - (at[a] + at[b]) * 0.5).abs());
                                    }
                                }
                            }
                            est = fmax * l * r_area * std::f32::consts::PI;
                            f_bound = fmax;
                            // What a link linear over the receiver cannot follow (the form factor
                            // bends, next to the edge a wall shares with the floor), judged as the
                            // radiance it puts wrong into the receiver against the radiance the
                            // receiver has: every leaf is drawn, so a small one next to an edge
                            // matters as much as a large one.
                            let recv_l = bend_radiance(recv);
                            if bend * l * lum(self.reflectance(recv))
                                > self.bend_tolerance(recv, src) * recv_l
                                && self.bend_splittable(recv, r_area, sk)
                            {
                                split_receiver(&mut stack, recv, rt, src, st);
                                continue;
                            }
                            // The form factor varies over the receiver: only a smaller receiver
                            // resolves that (splitting the source would only share the same error
                            // among four links), unless the receiver is as small as it gets.
                            let var = (fmax - fmin) * l * r_area * std::f32::consts::PI;
                            if var > eps_power * 0.2 {
                                if self.splittable(recv, r_area) {
                                    split_receiver(&mut stack, recv, rt, src, st);
                                    continue;
                                }
                                if s_splittable {
                                    split_source(&mut stack, recv, rt, sk, st);
                                    continue;
                                }
                            }
                        }
                        // The source's radiance varies (a lit wall with a shadow on it): a link
                        // gathers its average, and only a smaller source resolves that. The
                        // estimate is the power the error would carry into every receiver that
                        // makes the same error, not into this element alone: receivers are split
                        // finely near sources (the rule above), and with their own small areas
                        // every piece would pass while the error, the same in each, stayed. The
                        // same holds across coarse triangles: the many small ones of a curved
                        // object all gather the mean of a floor they see from about the same
                        // place, although they mostly see its bright middle under the light
                        // (weighed against one coarse triangle, the sides of the objects in
                        // `gen-samples room` came out 5% too dark; `tests/small_receivers.rs`).
                        // So the error is weighed against the largest cluster of the receiver's
                        // own object around it whose radius is below `cluster_opening` times the
                        // larger of the source's distance and radius (the receivers that see the
                        // source from about the same place, as the opening criterion judges a
                        // cluster of sources), or against the coarse triangle if that is larger.
                        // A source is split as deep as its tree goes (below `max_level` where a
                        // shadow's edge crosses it: the floor in front of a block), or the dark
                        // and the lit sides of the edge reach a receiver next to it as one mean.
                        // A receiver darker than the scene's mean is judged against a threshold
                        // lowered with its radiance (see `DIM_RECEIVER_FLOOR`).
                        if self.detail_splittable(sk, s_area) {
                            let spread = self.src_spread(trees, spreads, sk);
                            let s_radius =
                                st.iter().map(|v| (*v - sc).length()).fold(0.0, f32::max);
                            let reach = self.params.cluster_opening * d2.sqrt().max(s_radius);
                            let sharing = neighbourhood
                                .iter()
                                .find(|(radius, _)| *radius < reach)
                                .map_or(root.area, |&(_, area)| area.max(root.area));
                            let svar = f_bound * spread * sharing * std::f32::consts::PI;
                            let dim = (receiver_radiance(recv)
                                / mean_radiance.max(f32::MIN_POSITIVE))
                            .clamp(DIM_RECEIVER_FLOOR, 1.0);
                            if svar > eps_power * dim {
                                split_source(&mut stack, recv, rt, sk, st);
                                continue;
                            }
                        }
                    }
                    Source::Cluster(c) => {
                        if nn == 1
                            && self.cluster_object[c as usize]
                                .is_some_and(|o| self.sees_none_of_own(r, o as usize))
                        {
                            continue;
                        }
                        let cluster = &self.clusters.clusters[c as usize];
                        if self.clusters.holds(c, r)
                            || rt.iter().any(|&v| cluster.contains_point(v))
                        {
                            open(c, &mut stack);
                            continue;
                        }
                        let r_radius = rt.iter().map(|v| (*v - rc).length()).fold(0.0, f32::max);
                        if cluster.faces_away_from(rc, r_radius) {
                            continue;
                        }
                        let corners = cluster.corners();
                        let sees = |n: &Vec3| {
                            corners
                                .iter()
                                .any(|&s| rt.iter().any(|&v| n.dot(s - v) > self.plane_eps))
                        };
                        if !root.normals.iter().any(sees) {
                            continue;
                        }
                        s_area = cluster.area;
                        s_splittable = true;
                        let d = cluster.centre - rc;
                        let d2 = d.length_squared().max(1e-20);
                        let dist = d2.sqrt();
                        let w = d / dist;
                        if cluster.radius() >= dist * self.params.cluster_opening
                            || self.mixes_emitters[c as usize]
                        {
                            open(c, &mut stack);
                            continue;
                        }
                        let proj = self.clusters.projected_area(c, -w);
                        let f = proj / (std::f32::consts::PI * d2 + proj);
                        let l = lum(self.src_radiance(trees, cl, src, rc));
                        est = f * l * r_area * std::f32::consts::PI;
                        // As for near elements below: split a receiver over which the cluster's
                        // form factor bends more than a linear link follows.
                        if self.splittable(recv, r_area) {
                            // With the geometric normal: the bend is the geometry's, judged in
                            // the previous pass where that made this link.
                            let bend = match cache.get(&(recv, src)) {
                                Some(&(_, _, bend)) if !bend.is_nan() => bend,
                                _ => {
                                    let (centre, at) =
                                        self.cluster_factors_over(c, recv, rt, root.normal);
                                    known = KnownFactors {
                                        centre: Some(centre),
                                        corners: Some(at),
                                    };
                                    (centre - (at[0] + at[1] + at[2]) / 3.0).abs()
                                }
                            };
                            link_bend = bend;
                            let recv_l = bend_radiance(recv);
                            if bend * l * lum(self.reflectance(recv))
                                > self.bend_tolerance(recv, src) * recv_l
                            {
                                split_receiver(&mut stack, recv, rt, src, st);
                                continue;
                            }
                        }
                    }
                }
                if est > eps_power {
                    let r_split = self.splittable(recv, r_area);
                    let split_recv = r_split && (r_area >= s_area || !s_splittable);

                    if split_recv {
                        split_receiver(&mut stack, recv, rt, src, st);
                        continue;
                    }
                    if s_splittable {
                        match src {
                            Source::Cluster(c) => open(c, &mut stack),
                            Source::Elem(sk) => {
                                split_source(&mut stack, recv, rt, sk, st);
                            }
                        }
                        continue;
                    }
                }
                let k_start = ks.len() as u32;
                let share = est / (r_area * std::f32::consts::PI) * lum(self.reflectance(recv));
                let (k, visible) = coefficients((recv, rt), (src, st), est, share, known);
                if k.iter().all(|&v| v <= 0.0) {
                    continue;
                }
                // Part of the source hidden from part of the receiver: a shadow's edge crosses the
                // receiver (under a block standing on the floor, or a face in the block's shadow),
                // and the link spreads its light evenly over both sides. Split the receiver while
                // the light put on the wrong side is a visible fraction of what the receiver
                // gets. Judged against the light this link brings as well as the receiver's own
                // radiance, so that the first pass, before any light has arrived, resolves the
                // shadows the emitters cast.
                if visible > 0.0
                    && visible < 1.0
                    && !self.detail_splittable(recv, r_area)
                    && self.lights(src)
                    && self.narrow_shadow_splittable(recv, r_area, rt, st)
                {
                    narrow
                        .lock()
                        .unwrap_or_else(|e| e.into_inner())
                        .insert(recv);
                    split_receiver(&mut stack, recv, rt, src, st);
                    continue;
                }
                if visible > 0.0 && visible < 1.0 && self.detail_splittable(recv, r_area) {
                    let gathered = lum(self.reflectance(recv))
                        * lum(self.src_radiance(trees, cl, src, rc))
                        * (k[0] + k[nn] + k[2 * nn])
                        / 3.0;
                    let wrong = gathered * (1.0 - visible).min(visible) / visible;
                    let recv_l = receiver_radiance(recv);
                    if wrong > SHADOW_TOLERANCE * recv_l.max(gathered) {
                        split_receiver(&mut stack, recv, rt, src, st);
                        continue;
                    }
                }
                ks.extend(k);
                links.push(make_link(recv, rc, src, st, k_start, visible, link_bend));
            }
            (links, ks, stack)
        };
        let (links, ks) = refine_in_parallel(&run, stack);
        let narrow = narrow.into_inner().unwrap_or_else(|e| e.into_inner());
        if narrow.is_empty() {
            return (links, ks);
        }
        // Every other link of a receiver the narrow shadow rule split goes down with the
        // light's, to the same leaves: the links of one leaf sum to what it sees only at one
        // resolution. In a closed furnace the walls' links, split beside an object resting on
        // the floor, saw the object hide them leaf by leaf, while the object's own link, on
        // the larger receiver, spread its share linearly, and the leaves at the point of
        // contact read -13% to +10%.
        // So does a link to a near source (the object casting the shadow) on a larger
        // receiver above one of them: near the point of contact its form factor is far from
        // linear over that receiver.
        let mut above: HashSet<ElemKey> = HashSet::new();
        for k in &narrow {
            let mut k = k.parent();
            while let Some(x) = k {
                if !above.insert(x) {
                    break;
                }
                k = x.parent();
            }
        }
        // Graded along a narrow shadow's edge: the elements beside a receiver the rule split
        // exist at its level, their links taken down with it, so that the dark side of the
        // edge is as fine as the lit side. Otherwise the leaves just inside the umbra, whose
        // light link every ray found hidden and which no rule splits, stayed two or three levels
        // larger than the split ones beside them, and the field drawn along the edge followed
        // their sides: a serrated outline, and the lit leaves' corners pulled dark at the
        // T-vertices on those sides (BENCHMARKS.md, seventeenth and eighteenth rounds).
        let mut graded: HashSet<ElemKey> = HashSet::new();
        for k in &narrow {
            for beside in k.edge_neighbours() {
                let mut x = beside.parent();
                while let Some(a) = x {
                    if !graded.insert(a) {
                        break;
                    }
                    x = a.parent();
                }
            }
        }
        let near = |recv: ElemKey, src: Source| match src {
            Source::Elem(sk) => {
                let (rt, st) = (self.elem_corners(recv), self.elem_corners(sk));
                let d = (st[0] + st[1] + st[2] - rt[0] - rt[1] - rt[2]) / 3.0;
                let r_area = root.area / 4f32.powi(recv.level as i32);
                let s_area = self.roots[sk.root as usize].area / 4f32.powi(sk.level as i32);
                near_pair(d.length_squared(), r_area, s_area)
            }
            Source::Cluster(_) => false,
        };
        let goes_down = |recv: ElemKey, src: Source| {
            narrow.contains(&recv)
                || graded.contains(&recv)
                || above.contains(&recv) && near(recv, src)
        };
        let expand = |l: &RawLink| -> Option<Vec<(RawLink, Vec<f32>)>> {
            if !goes_down(l.recv, l.src) {
                return None;
            }
            let at = l.k_start as usize;
            let k = &ks[at..at + link_len];
            let lt = self.elem_corners(l.recv);
            let share = lum(self.reflectance(l.recv))
                * lum(self.src_radiance(trees, cl, l.src, (lt[0] + lt[1] + lt[2]) / 3.0))
                * (k[0] + k[nn] + k[2 * nn])
                / 3.0;
            let st = corners_of(l.src);
            let mut out = Vec::new();
            let mut stack = vec![(l.recv, lt)];
            while let Some((recv, rt)) = stack.pop() {
                if goes_down(recv, l.src) {
                    let children = split(rt);
                    for c in (0..4).rev() {
                        stack.push((recv.child(c), children[c as usize]));
                    }
                    continue;
                }
                let (k, visible) = coefficients(
                    (recv, rt),
                    (l.src, st),
                    f32::INFINITY,
                    share,
                    KnownFactors::default(),
                );
                if k.iter().all(|&v| v <= 0.0) {
                    continue;
                }
                let rc = (rt[0] + rt[1] + rt[2]) / 3.0;
                out.push((make_link(recv, rc, l.src, st, 0, visible, f32::NAN), k));
            }
            Some(out)
        };
        // Per link: the links it became, where it went down.
        type Expanded = Option<Vec<(RawLink, Vec<f32>)>>;
        let expanded: Vec<Expanded> = links.par_iter().map(expand).collect();
        let mut out_links = Vec::with_capacity(links.len());
        let mut out_ks = Vec::with_capacity(ks.len());
        for (l, e) in links.into_iter().zip(expanded) {
            match e {
                None => {
                    let at = l.k_start as usize;
                    let k_start = out_ks.len() as u32;
                    out_ks.extend_from_slice(&ks[at..at + link_len]);
                    out_links.push(RawLink { k_start, ..l });
                }
                Some(v) => {
                    for (mut nl, k) in v {
                        nl.k_start = out_ks.len() as u32;
                        out_ks.extend(k);
                        out_links.push(nl);
                    }
                }
            }
        }
        (out_links, out_ks)
    }
}
