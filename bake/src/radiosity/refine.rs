//! Link refinement of one root: a depth-first walk over (receiver, source) pairs from (the root,
//! the scene's top cluster). Each pair goes through the rules in turn (the receiver's own rules,
//! the culls, the rules for an element or a cluster source, the power rule, then those judged by
//! the link's visibility); the first that asks for it splits the receiver or the source, and a
//! pair no rule splits becomes a link. The receivers the narrow shadow rule split then take their
//! other links down with them.

use std::collections::{HashMap, HashSet};
use std::sync::Mutex;

use glam::Vec3;
use rayon::prelude::*;

use super::bend::bend_splits;
use super::cluster::ClusterChild;
use super::cluster_reading::ClusterLight;
use super::coefficients::{inset_corners, Coefficients, KnownFactors};
use super::context::{lum, Ctx, Root};
use super::element::{split, ElemKey};
use super::factor_variation::factor_variation_splits;
use super::formfactor::{disc_estimate, point_to_polygon, point_to_polygon_each};
use super::link_visibility::{rays_for, LIGHT_RAY_FACTOR, MAX_RAY_FACTOR};
use super::links::{Ends, Link, PackedSrc, RawLinks, Source, SrcIdx, CORNERS};
use super::narrow_shadow::taken_down_with;
use super::parallel_walk::{refine_in_parallel, REFINE_STEPS};
use super::power::{power_split, Split};
use super::shadow_edge::shadow_edge_splits;
use super::source_variation::{receivers_sharing, source_variation_splits};
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

/// A receiver (its key and corners), a source (with its corners, for an element), and whether
/// the receiver's own rules ([`near_occluder`](super::near_occluder),
/// [`self_shade`](super::self_shade)) are known to leave it whole:
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

/// The previous pass's links of one root, by (receiver, source): where their coefficients start
/// in the previous tree's `k`, their visible fraction and the bend the refinement judged.
type Cache = HashMap<(ElemKey, Source), (usize, f32, f32)>;

/// What the rules for a pair's source found, for the power rule and the link.
struct Estimate {
    /// The power the link would carry, bounded (as [`power`](super::power) judges it).
    est: f32,
    s_area: f32,
    s_splittable: bool,
    /// The geometric normal's form factors the rules computed, which the link reuses.
    known: KnownFactors,
    /// A cluster link's bend, as in [`Link::bend`].
    bend: f32,
}

/// The point form factors of a near element source at a receiver's centre and inset corners.
struct NearFactors {
    fmax: f32,
    fmin: f32,
    /// How far the form factor bends away from the plane through the corner samples.
    bend: f32,
    /// The geometric normal's values at the inset corners.
    corners: [f32; CORNERS],
}

/// One root's refinement: what its walk reads, found once.
struct RootRefinement<'c, 'a> {
    ctx: &'c Ctx<'a>,
    r: u32,
    root: &'c Root,
    nn: usize,
    trees: &'c [Tree],
    cl: &'c [ClusterLight],
    spreads: &'c [Vec<f32>],
    eps_power: f32,
    judge: Judge,
    /// Per link: its coefficients, and on a refined surface those of the surface's own normal
    /// ([`Ctx::link_coefficients`]).
    link_len: usize,
    /// The coefficients of the root's links in the previous pass, which `cache` points into.
    prev_k: Vec<f32>,
    /// Coefficients are a pure function of the pair: those of the previous pass, reused.
    cache: Cache,
    /// Radius and area of the clusters of its own object holding this root, largest first: the
    /// receivers around it ([`source_variation`](super::source_variation)).
    neighbourhood: Vec<(f32, f32)>,
    /// The receivers the narrow shadow rule split ([`Ctx::narrow_shadow_splittable`]).
    narrow: Mutex<HashSet<ElemKey>>,
}

impl Ctx<'_> {
    /// Refines the links arriving at root `r` against the previous solution: a depth-first
    /// walk over (receiver, source) pairs from (the root, the scene's top cluster), whose
    /// pairs left after [`REFINE_STEPS`] go on in parallel ([`refine_in_parallel`]); then the
    /// receivers the narrow shadow rule split take their other links down with them.
    #[allow(clippy::too_many_arguments)]
    pub(super) fn refine_root(
        &self,
        r: u32,
        prev: (Vec<Link>, Vec<f32>),
        trees: &[Tree],
        cl: &[ClusterLight],
        spreads: &[Vec<f32>],
        eps_power: f32,
        judge: Judge,
    ) -> RawLinks {
        let refinement = RootRefinement::new(self, r, prev, trees, cl, spreads, eps_power, judge);
        let links = refine_in_parallel(
            &|stack| refinement.walk(stack),
            vec![refinement.first_pair()],
        );
        let mut links = refinement.take_narrow_receivers_down(links);
        // Where the walk's slack was, it was a third of the bake's memory peak.
        links.shrink_to_fit();
        links
    }
}

impl<'c, 'a> RootRefinement<'c, 'a> {
    #[allow(clippy::too_many_arguments)]
    fn new(
        ctx: &'c Ctx<'a>,
        r: u32,
        (prev_links, prev_k): (Vec<Link>, Vec<f32>),
        trees: &'c [Tree],
        cl: &'c [ClusterLight],
        spreads: &'c [Vec<f32>],
        eps_power: f32,
        judge: Judge,
    ) -> Self {
        let nn = ctx.nn(r);
        let link_len = CORNERS * nn
            + if ctx.surface[r as usize].is_empty() {
                0
            } else {
                CORNERS
            };
        let prev = &trees[r as usize];
        let cache: Cache = prev_links
            .iter()
            .enumerate()
            .map(|(i, l)| {
                let src = match l.src.get() {
                    SrcIdx::Cluster(c) => Source::Cluster(c),
                    SrcIdx::Node { root, node } => {
                        Source::Elem(trees[root as usize].keys[node as usize])
                    }
                };
                (
                    (prev.keys[l.recv as usize], src),
                    (i * link_len, l.visible, l.bend),
                )
            })
            .collect();
        let root = &ctx.roots[r as usize];
        let (own, first) = &ctx.object_clusters[root.object];
        let neighbourhood: Vec<(f32, f32)> = own
            .ancestors(r - first)
            .iter()
            .map(|&c| {
                let c = &own.clusters[c as usize];
                (c.radius(), c.area)
            })
            .collect();
        RootRefinement {
            ctx,
            r,
            root,
            nn,
            trees,
            cl,
            spreads,
            eps_power,
            judge,
            link_len,
            prev_k,
            cache,
            neighbourhood,
            narrow: Default::default(),
        }
    }

    /// (The root, the scene's top cluster), where the walk starts.
    fn first_pair(&self) -> Pair {
        let top = match self.ctx.clusters.top {
            ClusterChild::Cluster(c) => Source::Cluster(c),
            ClusterChild::Root(x) => Source::Elem(ElemKey::root(x)),
        };
        (
            ElemKey::root(self.r),
            self.root.corners,
            top,
            self.corners_of(top),
            false,
        )
    }

    /// The corners of an element source, carried down with a pair as it splits.
    fn corners_of(&self, s: Source) -> [Vec3; 3] {
        match s {
            Source::Elem(k) => self.ctx.elem_corners(k),
            Source::Cluster(_) => [Vec3::ZERO; 3],
        }
    }

    /// The receiver's radiance in the previous solution (normal 0), which the rules judged
    /// against the receiver weigh their errors by.
    fn receiver_radiance(&self, recv: ElemKey) -> f32 {
        let t = &self.trees[self.r as usize];
        lum(t.l[t.deepest_toward(recv) as usize * self.nn])
    }

    /// What the bend rules judge a receiver's error against: its radiance, but in a first pass
    /// of several at least `dark_floor`. Before any light has bounced, a receiver in the dark of
    /// the direct light has none, and every bend split it (the scaling scene's ball, pass 1:
    /// 97,000 elements, of which the second pass kept 54,000).
    fn bend_radiance(&self, recv: ElemKey) -> f32 {
        self.receiver_radiance(recv).max(self.judge.dark_floor)
    }

    /// Pushes the pairs of `recv` with the children of cluster `c`.
    fn open(&self, c: u32, recv: ElemKey, rt: [Vec3; 3], stack: &mut Vec<Pair>) {
        for ch in self.ctx.clusters.clusters[c as usize].children.iter().rev() {
            let s = match *ch {
                ClusterChild::Cluster(c) => Source::Cluster(c),
                ClusterChild::Root(x) => Source::Elem(ElemKey::root(x)),
            };
            stack.push((recv, rt, s, self.corners_of(s), true));
        }
    }

    /// Refines the pairs on `stack` depth-first for at most [`REFINE_STEPS`] pairs; returns the
    /// links, their coefficients and the pairs left.
    fn walk(&self, mut stack: Vec<Pair>) -> (RawLinks, Vec<Pair>) {
        let mut links = RawLinks::default();
        let mut steps = 0;
        while let Some(pair) = stack.pop() {
            if steps == REFINE_STEPS {
                stack.push(pair);
                break;
            }
            steps += 1;
            self.refine_pair(pair, &mut stack, &mut links);
        }
        (links, stack)
    }

    /// One pair through the rules: split (its children pushed on `stack`), dropped, or made a
    /// link (pushed on `links`).
    fn refine_pair(
        &self,
        (recv, rt, src, st, judged): Pair,
        stack: &mut Vec<Pair>,
        links: &mut RawLinks,
    ) {
        let ctx = self.ctx;
        let r_area = self.root.area / 4f32.powi(recv.level as i32);
        if !judged && (ctx.near_occluder_splits(recv, r_area) || ctx.self_shade_splits(recv)) {
            split_receiver(stack, recv, rt, src, st);
            return;
        }
        let rc = (rt[0] + rt[1] + rt[2]) / 3.0;
        let judged = match src {
            Source::Elem(sk) => self.element_source(recv, rt, rc, r_area, (sk, st), stack),
            Source::Cluster(c) => self.cluster_source(recv, rt, rc, r_area, c, stack),
        };
        let Some(Estimate {
            est,
            s_area,
            s_splittable,
            known,
            bend,
        }) = judged
        else {
            return;
        };
        let receiver_splittable = ctx.splittable(recv, r_area);
        match power_split(
            est,
            self.eps_power,
            (receiver_splittable, r_area),
            (s_splittable, s_area),
        ) {
            Some(Split::Receiver) => {
                split_receiver(stack, recv, rt, src, st);
                return;
            }
            Some(Split::Source) => {
                match src {
                    Source::Cluster(c) => self.open(c, recv, rt, stack),
                    Source::Elem(sk) => split_source(stack, recv, rt, sk, st),
                }
                return;
            }
            None => {}
        }
        let share = est / (r_area * std::f32::consts::PI) * lum(ctx.reflectance(recv));
        let (k, visible) = self.coefficients((recv, rt), (src, st), est, share, known);
        if k.iter().all(|&v| v <= 0.0) {
            return;
        }
        let partly_hidden = visible > 0.0 && visible < 1.0;
        if partly_hidden
            && !ctx.detail_splittable(recv, r_area)
            && ctx.lights(src)
            && ctx.narrow_shadow_splittable(recv, r_area, rt, st)
        {
            self.narrow
                .lock()
                .unwrap_or_else(|e| e.into_inner())
                .insert(recv);
            split_receiver(stack, recv, rt, src, st);
            return;
        }
        if partly_hidden && ctx.detail_splittable(recv, r_area) {
            let nn = self.nn;
            let gathered = lum(ctx.reflectance(recv))
                * lum(ctx.src_radiance(self.trees, self.cl, src, rc))
                * (k[0] + k[nn] + k[2 * nn])
                / 3.0;
            if shadow_edge_splits(gathered, visible, self.receiver_radiance(recv)) {
                split_receiver(stack, recv, rt, src, st);
                return;
            }
        }
        let (link, ends) = self.make_link(recv, rc, src, st, visible, bend);
        links.push(link, ends, &k);
    }

    /// The culls and rules for a pair whose source is element `sk` (corners `st`): `None` where
    /// the pair is dropped (the receiver cannot see the source) or split.
    fn element_source(
        &self,
        recv: ElemKey,
        rt: [Vec3; 3],
        rc: Vec3,
        r_area: f32,
        (sk, st): (ElemKey, [Vec3; 3]),
        stack: &mut Vec<Pair>,
    ) -> Option<Estimate> {
        let ctx = self.ctx;
        let (r, root, src) = (self.r, self.root, Source::Elem(sk));
        if sk.root == r {
            return None; // A planar triangle does not see itself.
        }
        let source_root = &ctx.roots[sk.root as usize];
        if self.nn == 1 && ctx.sees_none_of_own(r, source_root.object) {
            return None;
        }
        let sn = source_root.normal;
        // Two parts of one refined surface may see each other where their coarse triangles are
        // coplanar or turned apart: the link's form factors, on the refined surface, judge
        // that.
        let refined_pair = source_root.object == root.object && !ctx.surface[r as usize].is_empty();
        // Receiver entirely behind the source, or source behind every normal.
        if !refined_pair && rt.iter().all(|&v| sn.dot(v - st[0]) <= ctx.plane_eps) {
            return None;
        }
        let sees = |n: &Vec3| {
            st.iter()
                .any(|&s| rt.iter().any(|&v| n.dot(s - v) > ctx.plane_eps))
        };
        if !refined_pair && !root.normals.iter().any(sees) {
            return None;
        }
        let s_area = source_root.area / 4f32.powi(sk.level as i32);
        let s_splittable = ctx.splittable(sk, s_area);
        let sc = (st[0] + st[1] + st[2]) / 3.0;
        let d2 = (sc - rc).length_squared();
        let l = lum(ctx.src_radiance(self.trees, self.cl, src, rc));
        let mut known = KnownFactors::default();
        let est;
        let f_bound;
        if !near_pair(d2, r_area, s_area) {
            let w = (sc - rc) / d2.sqrt();
            let cos_r = root.normals.iter().map(|n| n.dot(w)).fold(0.0, f32::max);
            let f = disc_estimate(cos_r, (-w).dot(sn), s_area, d2);
            est = f * l * r_area * std::f32::consts::PI;
            f_bound = f;
        } else {
            let near = self.near_factors(rt, rc, sk, st, refined_pair);
            known.corners = Some(near.corners);
            est = near.fmax * l * r_area * std::f32::consts::PI;
            f_bound = near.fmax;
            // What a link linear over the receiver cannot follow (the form factor bends, next
            // to the edge a wall shares with the floor), judged as the radiance it puts wrong
            // into the receiver against the radiance the receiver has: every leaf is drawn, so
            // a small one next to an edge matters as much as a large one.
            if bend_splits(
                near.bend,
                l,
                lum(ctx.reflectance(recv)),
                ctx.bend_tolerance(recv, src),
                self.bend_radiance(recv),
            ) && ctx.bend_splittable(recv, r_area, sk)
            {
                split_receiver(stack, recv, rt, src, st);
                return None;
            }
            // The form factor varies over the receiver: only a smaller receiver resolves that
            // (splitting the source would only share the same error among four links), unless
            // the receiver is as small as it gets.
            if factor_variation_splits(near.fmax, near.fmin, l, r_area, self.eps_power) {
                if ctx.splittable(recv, r_area) {
                    split_receiver(stack, recv, rt, src, st);
                    return None;
                }
                if s_splittable {
                    split_source(stack, recv, rt, sk, st);
                    return None;
                }
            }
        }
        // A source is split as deep as its tree goes (below `max_level` where a shadow's edge
        // crosses it: the floor in front of a block), or the dark and the lit sides of the edge
        // reach a receiver next to it as one mean.
        if ctx.detail_splittable(sk, s_area) {
            let spread = ctx.src_spread(self.trees, self.spreads, sk);
            let s_radius = st.iter().map(|v| (*v - sc).length()).fold(0.0, f32::max);
            let reach = ctx.params.cluster_opening * d2.sqrt().max(s_radius);
            let sharing = receivers_sharing(&self.neighbourhood, reach, root.area);
            if source_variation_splits(
                f_bound * spread * sharing * std::f32::consts::PI,
                self.eps_power,
                self.receiver_radiance(recv),
                self.judge.mean_radiance,
            ) {
                split_source(stack, recv, rt, sk, st);
                return None;
            }
        }
        Some(Estimate {
            est,
            s_area,
            s_splittable,
            known,
            bend: f32::NAN,
        })
    }

    /// The point form factor from the receiver's centre and near each corner to near source
    /// `sk` (corners `st`), which bounds both its size and its variation over the receiver; on
    /// the refined surface for a `refined_pair`.
    fn near_factors(
        &self,
        rt: [Vec3; 3],
        rc: Vec3,
        sk: ElemKey,
        st: [Vec3; 3],
        refined_pair: bool,
    ) -> NearFactors {
        let ctx = self.ctx;
        let (mut fmax, mut fmin) = (0.0f32, f32::MAX);
        let mut bend = 0.0f32;
        let mut corners = [0.0f32; CORNERS];
        let inset = inset_corners(rt);
        let mut buf = [st; 4];
        let polys: &[[Vec3; 3]] = if refined_pair {
            ctx.source_shape(sk, st, true, &mut buf)
        } else {
            &buf[..1]
        };
        // The points, carried onto the refined surface for a refined pair.
        let lift = |p: Vec3| {
            if refined_pair {
                ctx.on_surface(self.r, p).0
            } else {
                p
            }
        };
        let (lc, li) = (lift(rc), inset.map(lift));
        let normals = &self.root.normals;
        let nn = normals.len();
        // Per point (the inset corners, then the centre) and normal, summed over the polygons
        // in order.
        let mut per_poly = vec![0.0f32; polys.len() * nn];
        let mut values = vec![0.0f32; (CORNERS + 1) * nn];
        for (i, p) in li.iter().chain([&lc]).enumerate() {
            for (t, poly) in polys.iter().enumerate() {
                point_to_polygon_each(*p, normals, poly, |j, v| per_poly[t * nn + j] = v);
            }
            for j in 0..nn {
                values[i * nn + j] = (0..polys.len()).map(|t| per_poly[t * nn + j]).sum::<f32>();
            }
        }
        for (j, n) in normals.iter().enumerate() {
            let f = |p: Vec3| {
                polys
                    .iter()
                    .map(|t| point_to_polygon(p, *n, t))
                    .sum::<f32>()
            };
            let centre = values[CORNERS * nn + j];
            let at: [f32; CORNERS] = std::array::from_fn(|c| values[c * nn + j]);
            for v in at.into_iter().chain([centre]) {
                fmax = fmax.max(v);
                fmin = fmin.min(v);
            }
            // Against the plane through the three corner samples: at the centre, and between
            // each two corners (a source corner touching the receiver's side peaks there). The
            // bend is the geometry's, alike for every normal: the geometric one judges it.
            if j == 0 {
                corners = at;
                bend = (centre - (at[0] + at[1] + at[2]) / 3.0).abs();
                for (a, b) in [(0, 1), (1, 2), (2, 0)] {
                    let mid = f(lift((inset[a] + inset[b]) * 0.5));
                    bend = bend.max((mid - (at[a] + at[b]) * 0.5).abs());
                }
            }
        }
        NearFactors {
            fmax,
            fmin,
            bend,
            corners,
        }
    }

    /// The culls and rules for a pair whose source is cluster `c`: `None` where the pair is
    /// dropped, the cluster opened, or the receiver split.
    fn cluster_source(
        &self,
        recv: ElemKey,
        rt: [Vec3; 3],
        rc: Vec3,
        r_area: f32,
        c: u32,
        stack: &mut Vec<Pair>,
    ) -> Option<Estimate> {
        let ctx = self.ctx;
        let (r, root, src) = (self.r, self.root, Source::Cluster(c));
        if self.nn == 1
            && ctx.cluster_object[c as usize].is_some_and(|o| ctx.sees_none_of_own(r, o as usize))
        {
            return None;
        }
        let cluster = &ctx.clusters.clusters[c as usize];
        if ctx.clusters.holds(c, r) || rt.iter().any(|&v| cluster.contains_point(v)) {
            self.open(c, recv, rt, stack);
            return None;
        }
        let r_radius = rt.iter().map(|v| (*v - rc).length()).fold(0.0, f32::max);
        if cluster.faces_away_from(rc, r_radius) {
            return None;
        }
        let corners = cluster.corners();
        let sees = |n: &Vec3| {
            corners
                .iter()
                .any(|&s| rt.iter().any(|&v| n.dot(s - v) > ctx.plane_eps))
        };
        if !root.normals.iter().any(sees) {
            return None;
        }
        let d = cluster.centre - rc;
        let d2 = d.length_squared().max(1e-20);
        let dist = d2.sqrt();
        let w = d / dist;
        if cluster.radius() >= dist * ctx.params.cluster_opening || ctx.mixes_emitters[c as usize] {
            self.open(c, recv, rt, stack);
            return None;
        }
        let proj = ctx.clusters.projected_area(c, -w);
        let f = proj / (std::f32::consts::PI * d2 + proj);
        let l = lum(ctx.src_radiance(self.trees, self.cl, src, rc));
        let est = f * l * r_area * std::f32::consts::PI;
        let mut known = KnownFactors::default();
        let mut link_bend = f32::NAN;
        // As for near elements: split a receiver over which the cluster's form factor bends
        // more than a linear link follows.
        if ctx.splittable(recv, r_area) {
            // With the geometric normal: the bend is the geometry's, judged in the previous pass
            // where that made this link.
            let bend = match self.cache.get(&(recv, src)) {
                Some(&(_, _, bend)) if !bend.is_nan() => bend,
                _ => {
                    let (centre, at) = ctx.cluster_factors_over(c, recv, rt, root.normal);
                    known = KnownFactors {
                        centre: Some(centre),
                        corners: Some(at),
                    };
                    (centre - (at[0] + at[1] + at[2]) / 3.0).abs()
                }
            };
            link_bend = bend;
            if bend_splits(
                bend,
                l,
                lum(ctx.reflectance(recv)),
                ctx.bend_tolerance(recv, src),
                self.bend_radiance(recv),
            ) {
                split_receiver(stack, recv, rt, src, self.corners_of(src));
                return None;
            }
        }
        Some(Estimate {
            est,
            s_area: cluster.area,
            s_splittable: true,
            known,
            bend: link_bend,
        })
    }

    /// A link's coefficients and visible fraction, with as many rays as what it brings asks
    /// (`est`, the power bound the rules judged; `share`, the radiance it brings its receiver:
    /// [`rays_for`]); a previous pass's coefficients, where they took as many rays.
    fn coefficients(
        &self,
        (recv, rt): (ElemKey, [Vec3; 3]),
        (src, st): (Source, [Vec3; 3]),
        est: f32,
        share: f32,
        known: KnownFactors,
    ) -> (Coefficients, f32) {
        let ctx = self.ctx;
        let nv = ctx.params.visibility_rays;
        // A light's link to a receiver as small as the shadow rule goes carries most of its
        // light, and the shadow edges there are what the narrow shadow rule finds and draws: it
        // may take more rays.
        let r_area = self.root.area / 4f32.powi(recv.level as i32);
        let ray_factor = if ctx.lights(src) && !ctx.detail_splittable(recv, r_area) {
            LIGHT_RAY_FACTOR
        } else {
            MAX_RAY_FACTOR
        };
        let rays = rays_for(
            nv,
            ray_factor,
            self.judge.last_pass,
            (share, self.receiver_radiance(recv)),
            (est, self.eps_power),
        );
        match self.cache.get(&(recv, src)) {
            Some(&(at, visible, _)) if rays <= nv => (
                Coefficients::from_slice(&self.prev_k[at..at + self.link_len]),
                visible,
            ),
            _ => ctx.link_coefficients((recv, rt), (src, st), rays, known),
        }
    }

    /// The link from `src` (corners `st`) to `recv` (centre `rc`), its coefficients at
    /// `k_start`.
    #[allow(clippy::too_many_arguments)]
    fn make_link(
        &self,
        recv: ElemKey,
        rc: Vec3,
        src: Source,
        st: [Vec3; 3],
        visible: f32,
        bend: f32,
    ) -> (Link, Ends) {
        let ctx = self.ctx;
        let normal = self.root.normal;
        // The last pass's links read near clusters by their deeper parts ([`Ctx::reads_deep`]):
        // an earlier pass's solve only judges where to refine, and reading them in every solve
        // cost 15-20% of the scaling scene's bake.
        let deep =
            self.judge.last_pass && matches!(src, Source::Cluster(c) if ctx.reads_deep(c, rc));
        let (share, facing, depth) = match src {
            Source::Cluster(c) => (ctx.cluster_share(self.trees, c, rc, normal, deep), 0, 0),
            Source::Elem(sk) => {
                let (depth, foot) = ctx.footprint(rc, normal, sk, st);
                let aim = if depth > 0 {
                    foot
                } else {
                    ctx.kernel_centre(rc, normal, sk, st)
                };
                let share = [aim.x, aim.y, aim.z, 0.0];
                (share, ctx.facing_normal(sk, rc), depth)
            }
        };
        // The ends are indices in trees not built yet ([`RawLinks::resolve`]).
        let src_idx = match src {
            Source::Cluster(c) => SrcIdx::Cluster(c),
            Source::Elem(sk) => SrcIdx::Node {
                root: sk.root,
                node: u32::MAX,
            },
        };
        let link = Link {
            recv: u32::MAX,
            src: PackedSrc::new(src_idx),
            share,
            deep,
            facing,
            depth,
            visible,
            bend,
        };
        (link, (recv, src))
    }

    /// Takes every link of a receiver the narrow shadow rule split down with the light's
    /// ([`taken_down_with`]), recomputing the coefficients of the links it becomes.
    fn take_narrow_receivers_down(&self, raw: RawLinks) -> RawLinks {
        let ctx = self.ctx;
        let narrow = std::mem::take(&mut *self.narrow.lock().unwrap_or_else(|e| e.into_inner()));
        if narrow.is_empty() {
            return raw;
        }
        let (above, graded) = taken_down_with(&narrow);
        let nn = self.nn;
        let link_len = self.link_len;
        let near = |recv: ElemKey, src: Source| match src {
            Source::Elem(sk) => {
                let (rt, st) = (ctx.elem_corners(recv), ctx.elem_corners(sk));
                let d = (st[0] + st[1] + st[2] - rt[0] - rt[1] - rt[2]) / 3.0;
                let r_area = self.root.area / 4f32.powi(recv.level as i32);
                let s_area = ctx.roots[sk.root as usize].area / 4f32.powi(sk.level as i32);
                near_pair(d.length_squared(), r_area, s_area)
            }
            Source::Cluster(_) => false,
        };
        let goes_down = |recv: ElemKey, src: Source| {
            narrow.contains(&recv)
                || graded.contains(&recv)
                || above.contains(&recv) && near(recv, src)
        };
        let ends: Vec<Ends> = raw.ends().collect();
        let RawLinks { links, k: ks, .. } = raw;
        // Per link: the links it became, where it went down.
        type Expanded = Option<Vec<(Link, Ends, Coefficients)>>;
        let expand = |(i, &(l_recv, l_src)): (usize, &Ends)| -> Expanded {
            if !goes_down(l_recv, l_src) {
                return None;
            }
            let k = &ks[i * link_len..(i + 1) * link_len];
            let lt = ctx.elem_corners(l_recv);
            let share = lum(ctx.reflectance(l_recv))
                * lum(ctx.src_radiance(self.trees, self.cl, l_src, (lt[0] + lt[1] + lt[2]) / 3.0))
                * (k[0] + k[nn] + k[2 * nn])
                / 3.0;
            let st = self.corners_of(l_src);
            let mut out = Vec::new();
            let mut stack = vec![(l_recv, lt)];
            while let Some((recv, rt)) = stack.pop() {
                if goes_down(recv, l_src) {
                    let children = split(rt);
                    for c in (0..4).rev() {
                        stack.push((recv.child(c), children[c as usize]));
                    }
                    continue;
                }
                let (k, visible) = self.coefficients(
                    (recv, rt),
                    (l_src, st),
                    f32::INFINITY,
                    share,
                    KnownFactors::default(),
                );
                if k.iter().all(|&v| v <= 0.0) {
                    continue;
                }
                let rc = (rt[0] + rt[1] + rt[2]) / 3.0;
                let (link, ends) = self.make_link(recv, rc, l_src, st, visible, f32::NAN);
                out.push((link, ends, k));
            }
            Some(out)
        };
        let expanded: Vec<Expanded> = ends.par_iter().enumerate().map(expand).collect();
        let mut out = RawLinks::with_capacity(links.len(), ks.len());
        for (i, ((l, l_ends), e)) in links.into_iter().zip(ends).zip(expanded).enumerate() {
            match e {
                None => {
                    out.push(l, l_ends, &ks[i * link_len..(i + 1) * link_len]);
                }
                Some(v) => {
                    for (nl, nl_ends, k) in v {
                        out.push(nl, nl_ends, &k);
                    }
                }
            }
        }
        out
    }
}
