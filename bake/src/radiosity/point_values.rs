//! Values where they are read: the radiance at every leaf's corners, the points a renderer
//! reads the field at (SPEC.md G.2), gathered there rather than averaged over the leaf.
//!
//! A leaf's colour is the mean of the light over its area. A renderer that fits its corners to
//! those means draws, in the corner of a room or along the edge of a shadow, a value between
//! the means of the leaves around the point, where the light itself goes beyond them. Every
//! link is linear over its receiver (its form factors and visibility at the three corners), so
//! evaluated at a corner the links give the light at that point; punctual lights are sampled
//! there by a shadow ray of their own. A corner's links see in all what the leaf's see on
//! average, the difference made up with the radiance of what the corner sees most, and a closed
//! leaf's rule ([`Ctx::enclosure`]) applies at each corner, so a closed furnace stays exact at
//! every point.
//!
//! Measured on the Cornell box against Cycles at its level-2 vertices (BENCHMARKS.md): the
//! corners' links alone drew the feet of the blocks a quarter dark; scaled to the leaf's sum,
//! the ceiling along the walls 7-10% bright; made up from the dominant source, 1.18% in all
//! against the leaf means' 1.84%.

use glam::Vec3;

use super::cluster_reading::ClusterLight;
use super::context::Ctx;
use super::enclosure::{closed_sum, missing_view, rest_radiance};
use super::gather::Gathered;
use super::links::CORNERS;
use super::tree::{corner_mean, Tree};

/// The child of a split node that holds its corner `c` as its own corner `c`
/// ([`super::tree::CHILD_CORNERS`]: Top, Left and Right hold corners 0, 1 and 2).
const CHILD_AT_CORNER: [usize; CORNERS] = [0, 1, 3];

impl Ctx<'_> {
    /// The radiance shown at each corner of each node of root `r`'s tree, per normal,
    /// corner-major (`out[(i * CORNERS + c) * nn + j]`): at a leaf, what its links and the
    /// punctual lights bring to that point, reflected, with its open part's radiance as
    /// [`Ctx::shown`] gives the leaf; at a split node, the value of the leaf that holds the
    /// corner. Read after a solve, from the radiance `trees` and `cl` hold.
    pub(super) fn corner_values(&self, r: u32, trees: &[Tree], cl: &[ClusterLight]) -> Vec<Vec3> {
        let t = &trees[r as usize];
        let nn = self.nn(r);
        let n = t.keys.len();
        let Gathered {
            mut q,
            mut lit,
            g0,
            g0_rest,
            g0_dominant,
            w_dominant,
        } = self.gathered(r, trees, cl, true);
        let (ff, ff_lit) = self.form_factor_corners(r, t);
        let closure = self.closure_corners(r, t);
        let le = self.roots[r as usize].emission;
        let mut out = vec![Vec3::ZERO; n * CORNERS * nn];
        for i in (0..n).filter(|&i| t.child[i] == u32::MAX) {
            let points = self.elem_corners(t.keys[i]);
            let view = |j: usize| t.self_view.get(i * nn + j).copied().unwrap_or(0.0);
            for (c, &p) in points.iter().enumerate() {
                let at = (i * CORNERS + c) * nn;
                if !self.scene.lights.is_empty() {
                    for (j, d) in self.direct_at(r, p).into_iter().enumerate() {
                        q[at + j] += d;
                        lit[at + j] += d;
                    }
                }
                // A refined patch gathers its own radiance where it sees itself; apart, so
                // that the sums below scale what the links bring alone.
                let own = |j: usize| {
                    if closure.is_empty() {
                        Vec3::ZERO
                    } else {
                        t.l[i * nn] * t.self_view[i * nn + j]
                    }
                };
                let f = |j: usize| ff[at + j];
                let f_lit = |j: usize| ff_lit[at + j];
                let mean = |v: &[f32], j: usize| corner_mean(v, i, j, nn);
                let f0 = f(0);
                let enclosed = t.enclosed[i];
                if f0 > 0.0 {
                    // What a corner's links see in all is known best as their mean over the
                    // leaf: at a corner their linear functions are extrapolated, and where one
                    // source fills much of the view and its form factor is far from linear
                    // (a face where it meets the floor it stands on, a ceiling along a wall)
                    // they fall short of it, by a quarter at the foot of a block. What the
                    // corner lacks or has too much against the leaf's sum is of the source it
                    // sees most ([`Gathered::g0_dominant`]): the lights' links stay as they are.
                    let w = w_dominant[i * CORNERS + c];
                    let dominant = if w > 0.0 {
                        g0_dominant[i * CORNERS + c] / w
                    } else {
                        Vec3::ZERO
                    };
                    for j in 0..nn {
                        let seen = f(j) - f_lit(j);
                        let want = mean(&ff, j) - mean(&ff_lit, j);
                        q[at + j] = (q[at + j] + dominant * (want - seen)).max(Vec3::ZERO);
                    }
                }
                if f0 > 0.0 && enclosed >= 0.0 {
                    // Then the closed leaf's rule ([`closed_sum`]) with the leaf's sums:
                    // the lights' links as they are, the rest scaled or filled to the
                    // enclosure.
                    let rest0 = f0 - f_lit(0);
                    let m_rest =
                        rest_radiance(g0_rest[i * CORNERS + c], rest0, g0[i * CORNERS + c], f0);
                    for j in 0..nn {
                        let from_lights = mean(&ff_lit, j);
                        q[at + j] = closed_sum(
                            lit[at + j],
                            q[at + j] + own(j),
                            from_lights,
                            mean(&ff, j) - from_lights + view(j),
                            enclosed,
                            m_rest,
                        );
                    }
                } else {
                    for j in 0..nn {
                        q[at + j] += own(j);
                    }
                    if f0 > 0.0 && (nn > 1 || !closure.is_empty()) {
                        // A tilted normal's missing form factors, filled as
                        // `Ctx::iterate_root` fills them.
                        let m = g0[i * CORNERS + c] / f0;
                        let (full, first) = match t.closure.get(i) {
                            Some(&full) => (full, 0),
                            None => (mean(&ff, 0), 1),
                        };
                        for j in first..nn {
                            q[at + j] += m * missing_view(full, mean(&ff, j), view(j));
                        }
                    }
                }
                // A leaf partly shut in (under a block on the floor, inside a spout where it
                // meets a body) shows its open part's radiance ([`Ctx::shown`]): its links'
                // visibility, at a corner too, is weighed from rays of points all over it, the
                // shut ones dark, so an open corner's value is scaled up as the leaf's mean is
                // (without it the teapot's handle, where it meets the body, came out dark). A
                // shut corner (of any leaf open somewhere: the corner of a handle's leaf inside
                // the body), which is never drawn, shows the open part's mean, so that the fit
                // at a point by the shut region does not darken what is drawn.
                let o = t.open[i];
                let shut = o > 0.0 && self.shut_at(r, p);
                for j in 0..nn {
                    let l = if shut {
                        t.l[i * nn + j]
                    } else {
                        le + t.rho[i] * q[at + j]
                    };
                    out[at + j] = if o > 0.0 && o < 1.0 {
                        le + (l - le) / o
                    } else {
                        l
                    };
                }
            }
        }
        // Breadth-first: children come after their parent, so reverse is bottom-up.
        for i in (0..n).rev() {
            let first = t.child[i];
            if first == u32::MAX {
                continue;
            }
            for (c, ch) in CHILD_AT_CORNER.into_iter().enumerate() {
                let from = ((first as usize + ch) * CORNERS + c) * nn;
                let to = (i * CORNERS + c) * nn;
                out.copy_within(from..from + nn, to);
            }
        }
        out
    }
}
