//! Gather and solve: each node gathers what its links bring, pushed down to the leaves, a closed
//! leaf's sum of form factors filled or scaled to its enclosure, then pulled up as area means;
//! Jacobi iterations until the solution stops changing.

use glam::Vec3;
use rayon::prelude::*;

use super::cluster_reading::ClusterLight;
use super::context::Ctx;
use super::enclosure::{closed_sum, missing_view, rest_radiance};
use super::formfactor::point_to_polygon_each;
use super::links::{Link, SrcIdx, CORNERS};
use super::tree::{corner_mean, push_linear, Tree};

/// What a root's nodes gather, at each node's corners (the links are linear over their
/// receivers) and pushed down from every receiver above: per corner and normal
/// (`[(i * CORNERS + c) * nn + j]`) direct light plus all links (`q`) and what comes from the
/// lights, directly or through links from their elements (`lit`); per corner, what the
/// geometric normal gathers from all links (`g0`) and from the rest (`g0_rest`). A closed
/// leaf's sum leaves `lit` alone and fills or scales the rest.
pub(super) struct Gathered {
    pub(super) q: Vec<Vec3>,
    pub(super) lit: Vec<Vec3>,
    pub(super) g0: Vec<Vec3>,
    pub(super) g0_rest: Vec<Vec3>,
    /// For points only (empty otherwise): per corner, what the geometric normal gathers from
    /// the links that are not the lights', each weighed by its own form factor there again,
    /// and the sum of those weights: their mean is the radiance of what the corner sees most.
    pub(super) g0_dominant: Vec<Vec3>,
    pub(super) w_dominant: Vec<f32>,
}

impl Ctx<'_> {
    /// [`Tree::closure`] and [`Tree::self_view`] of tree `t` (root `r`), from its links.
    pub(super) fn closure(&self, r: u32, t: &Tree) -> (Vec<f32>, Vec<f32>) {
        if self.surface[r as usize].is_empty() {
            return (Vec::new(), Vec::new());
        }
        let n = t.keys.len();
        let f = self.closure_corners(r, t);
        let mut closure: Vec<f32> = (0..n)
            .map(|i| (f[i * CORNERS] + f[i * CORNERS + 1] + f[i * CORNERS + 2]) / 3.0)
            .collect();
        // A refined patch sees itself where it curves inwards, which no link carries (the
        // coarse triangle under it is flat): from each leaf's centre, the form factors of its
        // own root's refined triangles, for its normals and the surface's.
        let nn = self.nn(r);
        let surf = &self.surface[r as usize];
        let root = &self.roots[r as usize];
        let mut view = vec![0.0f32; n * nn];
        // The root's normals and the refined surface's own after them; per refined triangle
        // and normal, their form factors from one leaf's centre.
        let mut normals = root.normals.clone();
        normals.push(Vec3::ZERO);
        let mut per_tri = vec![0.0f32; surf.len() * (nn + 1)];
        for i in (0..n).filter(|&i| t.child[i] == u32::MAX) {
            let c = self.elem_corners(t.keys[i]);
            let (p, pn) = self.on_surface(r, (c[0] + c[1] + c[2]) / 3.0);
            normals[nn] = pn;
            for (t, tri) in surf.iter().enumerate() {
                point_to_polygon_each(p, &normals, tri, |j, v| per_tri[t * (nn + 1) + j] = v);
            }
            let f = |j: usize| {
                (0..surf.len())
                    .map(|t| per_tri[t * (nn + 1) + j])
                    .sum::<f32>()
            };
            for j in 0..nn {
                view[i * nn + j] = f(j);
            }
            closure[i] += f(nn);
        }
        (closure, view)
    }

    /// The form factors [`Tree::closure`] averages, at each node's corners
    /// (`[i * CORNERS + c]`; empty where root `r` has no refined surface).
    pub(super) fn closure_corners(&self, r: u32, t: &Tree) -> Vec<f32> {
        if self.surface[r as usize].is_empty() {
            return Vec::new();
        }
        let block = CORNERS * self.nn(r);
        let mut f = vec![0.0f32; t.keys.len() * CORNERS];
        for (link, k) in t.links_with_k() {
            for c in 0..CORNERS {
                f[link.recv as usize * CORNERS + c] += k[block + c];
            }
        }
        push_linear(t, &mut f, 1);
        f
    }

    /// Per node and normal of root `r`'s tree (`out[i * nn + j]`), the sum of the form factors
    /// its links give it, pushed down from every receiver above it and averaged over its
    /// corners ([`push_linear`]): of all its links, and of those from the lights'
    /// ([`Ctx::is_light`]) elements alone. They depend on the links alone, so every iteration
    /// of a solve reads them ([`Ctx::iterate_root`]).
    pub(super) fn form_factor_sums(&self, r: u32, t: &Tree) -> Vec<[f32; 2]> {
        let nn = self.nn(r);
        let (ff, ff_lit) = self.form_factor_corners(r, t);
        (0..t.keys.len() * nn)
            .map(|x| {
                let (i, j) = (x / nn, x % nn);
                [corner_mean(&ff, i, j, nn), corner_mean(&ff_lit, i, j, nn)]
            })
            .collect()
    }

    /// The sums of [`Ctx::form_factor_sums`] at each node's corners, before their mean:
    /// corner-major (`[(i * CORNERS + c) * nn + j]`), of all links and of the lights' alone.
    pub(super) fn form_factor_corners(&self, r: u32, t: &Tree) -> (Vec<f32>, Vec<f32>) {
        let nn = self.nn(r);
        let n = t.keys.len();
        let mut ff = vec![0.0f32; n * CORNERS * nn];
        let mut ff_lit = vec![0.0f32; n * CORNERS * nn];
        for (link, k) in t.links_with_k() {
            let base = link.recv as usize * CORNERS * nn;
            let ks = &k[..CORNERS * nn];
            for (x, &k) in ks.iter().enumerate() {
                ff[base + x] += k;
            }
            if self.brings_light(link) {
                for (x, &k) in ks.iter().enumerate() {
                    ff_lit[base + x] += k;
                }
            }
        }
        push_linear(t, &mut ff, nn);
        push_linear(t, &mut ff_lit, nn);
        (ff, ff_lit)
    }

    /// Whether `link` brings a light's own light: its source is an element of a light
    /// ([`Ctx::is_light`]).
    pub(super) fn brings_light(&self, link: &Link) -> bool {
        matches!(link.src.get(), SrcIdx::Node { root, .. } if self.is_light(root))
    }

    /// What root `r`'s nodes gather at their corners from `trees` and `cl`, pushed down to
    /// every node ([`Gathered`]): for the elements (with their direct light, [`Tree::direct`]),
    /// or `for_points`, for their corners ([`Ctx::corner_values`]).
    pub(super) fn gathered(
        &self,
        r: u32,
        trees: &[Tree],
        cl: &[ClusterLight],
        for_points: bool,
    ) -> Gathered {
        let t = &trees[r as usize];
        let nn = self.nn(r);
        let n = t.keys.len();
        let mut q = vec![Vec3::ZERO; n * CORNERS * nn];
        // An element's direct light is its mean over the element, at each corner alike; a
        // point's comes from its own shadow rays ([`Ctx::direct_at`]), added by the caller.
        if !for_points {
            for i in 0..n {
                for c in 0..CORNERS {
                    let at = (i * CORNERS + c) * nn;
                    q[at..at + nn].copy_from_slice(&t.direct[i * nn..(i + 1) * nn]);
                }
            }
        }
        let mut lit = q.clone();
        let mut g0 = vec![Vec3::ZERO; n * CORNERS];
        let mut g0_rest = vec![Vec3::ZERO; n * CORNERS];
        let width = if for_points { n * CORNERS } else { 0 };
        let mut g0_dominant = vec![Vec3::ZERO; width];
        let mut w_dominant = vec![0.0f32; width];
        for (link, k) in t.links_with_k() {
            let ls = match link.src.get() {
                SrcIdx::Cluster(c) => {
                    let aim = self.leaving(c, t.centre[link.recv as usize]);
                    self.cluster_seen(trees, cl, c, aim, &link.share, link.deep)
                }
                SrcIdx::Node { root, node } => self.seen_radiance(
                    root,
                    &trees[root as usize],
                    (node as usize, link.depth),
                    link.aim_over_source(),
                    link.facing as usize,
                ),
            };
            let base = link.recv as usize * CORNERS * nn;
            let ks = &k[..CORNERS * nn];
            for (x, &k) in ks.iter().enumerate() {
                q[base + x] += ls * k;
            }
            let from_light = self.brings_light(link);
            if from_light {
                for (x, &k) in ks.iter().enumerate() {
                    lit[base + x] += ls * k;
                }
            }
            for c in 0..CORNERS {
                let g = ls * ks[c * nn];
                g0[link.recv as usize * CORNERS + c] += g;
                if !from_light {
                    g0_rest[link.recv as usize * CORNERS + c] += g;
                    if for_points {
                        g0_dominant[link.recv as usize * CORNERS + c] += g * ks[c * nn];
                        w_dominant[link.recv as usize * CORNERS + c] += ks[c * nn] * ks[c * nn];
                    }
                }
            }
        }
        push_linear(t, &mut q, nn);
        push_linear(t, &mut lit, nn);
        push_linear(t, &mut g0, 1);
        push_linear(t, &mut g0_rest, 1);
        if for_points {
            push_linear(t, &mut g0_dominant, 1);
            push_linear(t, &mut w_dominant, 1);
        }
        Gathered {
            q,
            lit,
            g0,
            g0_rest,
            g0_dominant,
            w_dominant,
        }
    }

    /// One Jacobi step for root `r`: its nodes' new radiance from what its links gather from
    /// `trees` and `cl`; `sums` are its [`Ctx::form_factor_sums`].
    pub(super) fn iterate_root(
        &self,
        r: u32,
        trees: &[Tree],
        cl: &[ClusterLight],
        sums: &[[f32; 2]],
    ) -> Vec<Vec3> {
        let t = &trees[r as usize];
        let nn = self.nn(r);
        let n = t.keys.len();
        let Gathered {
            q,
            lit,
            g0,
            g0_rest,
            ..
        } = self.gathered(r, trees, cl, false);
        // What each leaf gathers: the mean of its linear function, the value at its centroid.
        let mut q_leaf = vec![Vec3::ZERO; n * nn];
        for i in 0..n {
            if t.child[i] != u32::MAX {
                continue;
            }
            for j in 0..nn {
                q_leaf[i * nn + j] = corner_mean(&q, i, j, nn);
            }
            // A refined patch gathers its own radiance where it sees itself.
            let closure = t.closure.get(i).copied();
            if closure.is_some() {
                for j in 0..nn {
                    q_leaf[i * nn + j] += t.l[i * nn] * t.self_view[i * nn + j];
                }
            }
            // The form factors of all the leaf's links, and of the lights' alone.
            let ff = |j: usize| sums[i * nn + j][0];
            let ff_lit = |j: usize| sums[i * nn + j][1];
            let f0 = ff(0);
            if f0 <= 0.0 {
                continue;
            }
            let view = |j: usize| t.self_view.get(i * nn + j).copied().unwrap_or(0.0);
            let avg = |g: &[Vec3]| (g[i * CORNERS] + g[i * CORNERS + 1] + g[i * CORNERS + 2]) / 3.0;
            let enclosed = t.enclosed[i];
            if enclosed >= 0.0 {
                // A closed leaf: its form factors sum to its enclosure ([`closed_sum`]).
                let rest0 = f0 - ff_lit(0);
                let m_rest = rest_radiance(avg(&g0_rest), rest0, avg(&g0), f0);
                for j in 0..nn {
                    let at = i * nn + j;
                    let from_lights = ff_lit(j);
                    q_leaf[at] = closed_sum(
                        corner_mean(&lit, i, j, nn),
                        q_leaf[at],
                        from_lights,
                        ff(j) - from_lights + view(j),
                        enclosed,
                        m_rest,
                    );
                }
            } else if nn > 1 || closure.is_some() {
                // Elsewhere every form factor a tilted normal lacks against the geometric one
                // is filled with the mean radiance the geometric normal gathers; on a refined
                // surface every normal, the geometric one too, is filled against the surface's
                // own normal at the receiver's points ([`Tree::closure`]).
                let m = avg(&g0) / f0;
                let (full, first) = match closure {
                    Some(f) => (f, 0),
                    None => (f0, 1),
                };
                for j in first..nn {
                    q_leaf[i * nn + j] += m * missing_view(full, ff(j), view(j));
                }
            }
        }
        let q = q_leaf;
        let le = self.roots[r as usize].emission;
        let mut l = vec![Vec3::ZERO; n * nn];
        // Pull: leaves reflect, interior nodes average their children by area.
        for i in (0..n).rev() {
            let c = t.child[i];
            if c == u32::MAX {
                for j in 0..nn {
                    l[i * nn + j] = le + t.rho[i] * q[i * nn + j];
                }
            } else {
                let c = c as usize;
                let a: f32 = (c..c + 4).map(|ch| t.area[ch]).sum();
                for j in 0..nn {
                    let mut s = Vec3::ZERO;
                    for ch in c..c + 4 {
                        s += l[ch * nn + j] * t.area[ch];
                    }
                    l[i * nn + j] = s / a;
                }
            }
        }
        l
    }

    pub(super) fn solve(
        &self,
        trees: &mut [Tree],
        cl: &mut Vec<ClusterLight>,
        max_iterations: u32,
        report: &dyn Fn(usize),
    ) -> (u32, f32) {
        let mut change = f32::INFINITY;
        let mut it = 0;
        let sums: Vec<Vec<[f32; 2]>> = (0..trees.len() as u32)
            .into_par_iter()
            .map(|r| self.form_factor_sums(r, &trees[r as usize]))
            .collect();
        while it < max_iterations {
            it += 1;
            report(it as usize);
            let new: Vec<Vec<Vec3>> = (0..trees.len() as u32)
                .into_par_iter()
                .map(|r| self.iterate_root(r, trees, cl, &sums[r as usize]))
                .collect();
            let (mut num, mut den) = (0.0f64, 0.0f64);
            for (t, l) in trees.iter_mut().zip(new) {
                for (a, b) in t.l.iter().zip(&l) {
                    num += f64::from((*a - *b).abs().element_sum());
                    den += f64::from(b.abs().element_sum());
                }
                t.l = l;
            }
            *cl = self.cluster_radiance(trees);
            change = if den > 0.0 { (num / den) as f32 } else { 0.0 };
            if change < self.params.tolerance {
                break;
            }
        }
        (it, change)
    }
}
