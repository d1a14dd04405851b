//! A link's visibility: jittered rays between the receiver and the source, each normal of the
//! receiver weighing them by the form-factor kernel, read as a fraction linear over the
//! receiver; and how many rays a link takes.

use glam::Vec3;

use super::context::Ctx;
use super::element::{barycentric_of, jittered_point, ElemKey, Rng};
use super::links::CORNERS;

/// What the noise of one link's visibility rays may move its receiver's radiance by, as a
/// fraction of that radiance (one standard deviation, at worst): links that bring a large share
/// of their receiver's light take more rays than `visibility_rays`. Eight rays for every link
/// left the dark undersides of curved objects blotchy (the visibility of the few links that
/// light them read to ±18%): spot 2.49% against path-traced images, 2.38% at 2%, 2.36% at 1%,
/// for 1.0x, 1.0x and 1.35x on the scaling scene.
pub(super) const VISIBILITY_NOISE: f32 = 0.02;

/// At most this many times `visibility_rays` for one link ([`VISIBILITY_NOISE`]).
pub(super) const MAX_RAY_FACTOR: u32 = 4;

/// [`MAX_RAY_FACTOR`] for a link from a light ([`Ctx::lights`]) to a receiver of
/// `detail_level` or deeper: in a penumbra its visibility is most of what its receiver gets.
pub(super) const LIGHT_RAY_FACTOR: u32 = 16;

/// A link bringing less than this share of its receiver's radiance is faint: a few rays bound
/// what its visibility can put wrong.
pub(super) const FAINT_LINK: f32 = 0.01;

/// The kernel-weighted fraction of `n` rays that are clear, for each receiver normal (and the
/// refined surface's own normal after them) into `vis`, and the same fraction as a linear
/// function over the receiver, its value at each corner, into `at_corner` (`[j * CORNERS + c]`
/// for slot `j` of `vis`). `ray(i, w)` fills `w` with ray `i`'s weight per normal (`None`
/// where that normal's plane hides its source point: it does not count) and casts it,
/// returning whether it is clear and the barycentric coordinates of its receiver point, or
/// returns `None` when no normal counts it.
///
/// Each normal weighs the rays by its own kernel and counts only those its plane lets through.
/// One fraction for all, the geometric normal's, left a tilted normal with the visibility of
/// rays it does not see along (and with none at all, read as wholly clear, where the source
/// lies behind the geometric plane): under spot's muzzle, normals facing the chest and the
/// floor came out too bright. A normal no ray counts takes the fraction of all the
/// rays cast.
///
/// Every ray is cast and weighed by the kernel. Stopping after four that agreed made the
/// estimate lean to whole visibility for links mostly visible (a link 90% visible read 93%),
/// and counting the rays alike, points spread evenly over a large source, read the part of it
/// straight above the receiver no heavier than the part at its horizon: next to an object
/// resting on a floor, which hides the first, floor leaves in a closed furnace summed form
/// factors to 1.07 (`tests/furnace_property.rs`).
///
/// The linear function: the rays weighed also by their point's barycentric coordinate of
/// corner `c` read, for rays spread evenly over the receiver, a linear visibility at the point
/// a quarter of the way from the centroid to corner `c` (`∫ b_c V / ∫ b_c`), so the value at
/// the corner is the mean plus four times that reading's difference from the mean of the
/// three readings: the least-squares linear fit. Its mean is the fraction in `vis`, and a
/// slope that would take a corner outside [0, 1] is flattened until it does not, keeping the
/// mean (`a_soft_shadow_across_a_receiver_is_linear_over_it` below).
pub(super) fn visible_fractions(
    n: u32,
    vis: &mut [f32],
    at_corner: &mut [f32],
    mut ray: impl FnMut(u32, &mut [Option<f32>]) -> Option<(bool, [f32; CORNERS])>,
) {
    let m = vis.len();
    debug_assert_eq!(at_corner.len(), m * CORNERS);
    // Per normal: clear weight, total weight, clear rays, rays; and per normal and corner the
    // clear and total weights times the barycentric coordinate. On the stack for the normal
    // counts of the default sets: every link comes here, and three allocations a link were
    // most of the bake's time in malloc.
    const ON_STACK: usize = 10;
    let (mut acc_s, mut by_corner_s, mut w_s);
    let (mut acc_h, mut by_corner_h, mut w_h);
    let (acc, by_corner, w): (&mut [_], &mut [_], &mut [Option<f32>]) = if m <= ON_STACK {
        acc_s = [(0.0f64, 0.0f64, 0u32, 0u32); ON_STACK];
        by_corner_s = [(0.0f64, 0.0f64); ON_STACK * CORNERS];
        w_s = [None; ON_STACK];
        (
            &mut acc_s[..m],
            &mut by_corner_s[..m * CORNERS],
            &mut w_s[..m],
        )
    } else {
        acc_h = vec![(0.0f64, 0.0f64, 0u32, 0u32); m];
        by_corner_h = vec![(0.0f64, 0.0f64); m * CORNERS];
        w_h = vec![None; m];
        (&mut acc_h[..], &mut by_corner_h[..], &mut w_h[..])
    };
    let (mut cast, mut clear_rays) = (0u32, 0u32);
    for i in 0..n {
        let Some((clear, at)) = ray(i, w) else {
            continue;
        };
        cast += 1;
        clear_rays += u32::from(clear);
        for (j, (a, x)) in acc.iter_mut().zip(w.iter()).enumerate() {
            if let Some(x) = *x {
                let x = f64::from(x);
                a.0 += if clear { x } else { 0.0 };
                a.1 += x;
                a.2 += u32::from(clear);
                a.3 += 1;
                for (c, b) in at.iter().enumerate() {
                    let e = &mut by_corner[j * CORNERS + c];
                    let xb = x * f64::from(b.clamp(0.0, 1.0));
                    e.0 += if clear { xb } else { 0.0 };
                    e.1 += xb;
                }
            }
        }
    }
    for (j, (v, a)) in vis.iter_mut().zip(acc.iter()).enumerate() {
        *v = if a.1 > 0.0 {
            (a.0 / a.1) as f32
        } else if a.3 > 0 {
            a.2 as f32 / a.3 as f32
        } else if cast > 0 {
            clear_rays as f32 / cast as f32
        } else {
            1.0
        };
        let reading: [f32; CORNERS] = std::array::from_fn(|c| {
            let e = by_corner[j * CORNERS + c];
            if a.1 > 0.0 && e.1 > 0.0 {
                (e.0 / e.1) as f32
            } else {
                *v
            }
        });
        let mean = (reading[0] + reading[1] + reading[2]) / 3.0;
        let slope = reading.map(|r| 4.0 * (r - mean));
        let mut scale = 1.0f32;
        for d in slope {
            if *v + d > 1.0 {
                scale = scale.min((1.0 - *v) / d);
            } else if *v + d < 0.0 {
                scale = scale.min(*v / -d);
            }
        }
        for (c, d) in slope.iter().enumerate() {
            at_corner[j * CORNERS + c] = (*v + d * scale.max(0.0)).clamp(0.0, 1.0);
        }
    }
}

/// The form-factor kernel `cos θp cos θq / r²` between a receiver point `p` (normal `np`) and
/// a source point `q` (normal `nq`), the distance kept above a twentieth of `size` (the two
/// elements' sizes together) so that one pair next to a contact cannot outweigh all others.
pub(super) fn kernel(p: Vec3, np: Vec3, q: Vec3, nq: Vec3, size: f32) -> f32 {
    let d = q - p;
    let r2 = d.length_squared();
    let floor = (0.05 * size).powi(2);
    let inv = 1.0 / r2.max(1e-30).sqrt();
    (np.dot(d) * inv).max(0.0) * (-nq.dot(d) * inv).max(0.0) / r2.max(floor)
}

impl Ctx<'_> {
    /// Whether nothing can hide any part of a source in the box `src_box` (with its plane, when
    /// one) from receiver `recv` (corners `rt`): its root is unobstructed, or the shaft between
    /// them is empty ([`Occluders::shaft_clear`](crate::visibility::Occluders::shaft_clear)).
    pub(super) fn certainly_clear(
        &self,
        recv: ElemKey,
        rt: [Vec3; 3],
        (lo, hi): (Vec3, Vec3),
        src_plane: Option<(Vec3, Vec3)>,
    ) -> bool {
        let r = recv.root as usize;
        self.unobstructed[r]
            || self
                .occ
                .shaft_clear(rt, self.roots[r].normal, lo, hi, src_plane)
    }

    /// Casts the `nv` visibility rays of the link from receiver `recv` (corners `rt`) to a source
    /// and puts into `vis` the fraction each receiver normal sees clear, and after them, on a
    /// refined surface, that of the surface's own normal ([`visible_fractions`]). Ray `i` runs
    /// from a jittered point of the receiver's stratum `i` to `source(i, rng)`, a root and a
    /// point on it, both carried onto their refined surfaces; each normal weighs it by the
    /// form-factor kernel (`size`: the two elements' sizes together) where light passes from
    /// the source point across that normal's plane, and does not count it where it cannot. A
    /// ray that no normal counts is not cast.
    pub(super) fn cast_visibility(
        &self,
        (recv, rt): (ElemKey, [Vec3; 3]),
        src_id: u64,
        size: f32,
        nv: u32,
        (vis, at_corner): (&mut [f32], &mut [f32]),
        source: impl Fn(u32, &mut Rng) -> (u32, Vec3),
    ) {
        let normals = &self.roots[recv.root as usize].normals;
        visible_fractions(nv, vis, at_corner, |i, w| {
            let mut rng = Rng::new(recv.id(), src_id, u64::from(i));
            let p = jittered_point(rt, i, nv, &mut rng);
            let at = barycentric_of(rt, p);
            let (t, q) = source(i, &mut rng);
            let (a, na) = self.on_surface(recv.root, p);
            let (b, nb) = self.on_surface(t, q);
            let d = b - a;
            if nb.dot(-d) <= self.plane_eps {
                return None;
            }
            // The refined surface's own normal follows the receiver's normals where `w` has
            // a slot for it.
            let own = [na];
            let mut any = false;
            for (x, n) in w.iter_mut().zip(normals.iter().chain(&own)) {
                *x = (n.dot(d) > self.plane_eps).then(|| kernel(a, *n, b, nb, size));
                any |= x.is_some();
            }
            any.then(|| (self.occ.segment_clear_between(a, na, b, nb), at))
        });
    }
}

/// How many rays a link takes (`nv`, the default): all of them where the link brings a visible
/// share of the scene's power (`est` against `eps_power`) or of its receiver's light (`share`
/// against the receiver's radiance `recv_l`); two where it brings little of either, the error it
/// can add being a fraction of that. Judged by the scene's power alone, every link of a small
/// leaf was faint and took two rays, and next to an object resting on a floor the noise of a
/// dozen half-hidden links left leaves 8% off in a closed furnace.
///
/// In the `last_pass`, whose links make the file, a link that brings much of its receiver's
/// light takes enough rays that their noise cannot move the receiver by more than
/// [`VISIBILITY_NOISE`] of its radiance: n rays read a visible fraction to within 0.5/√n (one
/// standard deviation), so n ≥ (share / 2τ)², up to `ray_factor` times the default. Chosen
/// before any ray is cast, so the estimate stays unbiased (stopping or going on by what the
/// rays found does not). Earlier passes only judge where to refine, and take the default.
pub(super) fn rays_for(
    nv: u32,
    ray_factor: u32,
    last_pass: bool,
    (share, recv_l): (f32, f32),
    (est, eps_power): (f32, f32),
) -> u32 {
    let need = if last_pass {
        (share / recv_l.max(f32::MIN_POSITIVE) / (2.0 * VISIBILITY_NOISE))
            .powi(2)
            .ceil()
            .min((nv * ray_factor) as f32) as u32
    } else {
        0
    };
    if need > nv {
        need
    } else if est >= 0.05 * eps_power || share >= FAINT_LINK * recv_l {
        nv
    } else {
        nv.min(2)
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn a_link_that_brings_much_of_its_receivers_light_takes_more_rays() {
        let rays = |share: f32, last_pass| {
            rays_for(8, MAX_RAY_FACTOR, last_pass, (share, 1.0), (0.0, 1.0))
        };
        // A link bringing 12% of its receiver's light needs (0.12 / 0.04)² = 9 rays.
        let r = rays(0.12, true);
        assert!(r > 8 && r <= 10, "{r}");
        // Half of it: many, up to four times the default; sixteen times from a light.
        assert_eq!(rays(0.5, true), 32);
        assert_eq!(
            rays_for(8, LIGHT_RAY_FACTOR, true, (0.5, 1.0), (0.0, 1.0)),
            128
        );
        // Earlier passes take the default; a faint link two.
        assert_eq!(rays(0.5, false), 8);
        assert_eq!(rays(0.011, true), 8);
        assert_eq!(rays(0.009, true), 2);
        // Faint against its receiver, but a visible share of the scene's power.
        assert_eq!(
            rays_for(8, MAX_RAY_FACTOR, true, (0.009, 1.0), (0.05, 1.0)),
            8
        );
    }

    #[test]
    fn each_normal_weighs_the_rays_its_plane_lets_through() {
        // Rays 0-3 reach a source point above the geometric normal's plane and are clear;
        // rays 4-7 reach one only a tilted normal sees, and are hidden; the third slot (a
        // normal no ray reaches) takes the fraction of all rays cast.
        let mid = [1.0 / 3.0; CORNERS];
        let mut vis = [0.5f32; 3];
        let mut at = [0.5f32; 9];
        visible_fractions(8, &mut vis, &mut at, |i, w| {
            w[0] = (i < 4).then_some(1.0);
            w[1] = Some(if i < 4 { 1.0 } else { 3.0 });
            w[2] = None;
            Some((i < 4, mid))
        });
        assert_eq!(vis[0], 1.0);
        assert!((vis[1] - 4.0 / 16.0).abs() < 1e-6, "{}", vis[1]);
        assert_eq!(vis[2], 0.5);
        // Every ray at the centroid: no slope, each corner the mean.
        for j in 0..3 {
            for c in 0..CORNERS {
                assert!(
                    (at[j * CORNERS + c] - vis[j]).abs() < 1e-6,
                    "{j} {c} {at:?}"
                );
            }
        }
        // No ray any normal counts: nothing hides the source.
        let mut vis = [0.0f32; 2];
        let mut at = [0.0f32; 6];
        visible_fractions(8, &mut vis, &mut at, |_, w| {
            w.iter_mut().for_each(|x| *x = None);
            None
        });
        assert_eq!(vis, [1.0, 1.0]);
        assert_eq!(at, [1.0; 6]);
        // No rays at all (occlusion off).
        let mut vis = [0.0f32; 2];
        let mut at = [0.0f32; 6];
        visible_fractions(0, &mut vis, &mut at, |_, _| unreachable!());
        assert_eq!(vis, [1.0, 1.0]);
        assert_eq!(at, [1.0; 6]);
    }

    #[test]
    fn a_soft_shadow_across_a_receiver_is_linear_over_it() {
        // A visibility linear over the receiver, 1 at corner 0 and 0.2 at corners 1 and 2,
        // sampled by many rays spread evenly over it (each ray clear with that probability,
        // a fixed pattern): the corners come back to within the sampling's noise, and their
        // mean is the fraction of clear rays.
        let n = 4096u32;
        let truth = |b: [f32; 3]| b[0] * 1.0 + (b[1] + b[2]) * 0.2;
        let mut rng = Rng::new(1, 2, 3);
        let rays: Vec<([f32; 3], bool)> = (0..n)
            .map(|i| {
                let p = jittered_point([Vec3::ZERO, Vec3::X, Vec3::Y], i, n, &mut rng);
                let b = barycentric_of([Vec3::ZERO, Vec3::X, Vec3::Y], p);
                (b, rng.next_f32() < truth(b))
            })
            .collect();
        let mut vis = [0.0f32];
        let mut at = [0.0f32; 3];
        visible_fractions(n, &mut vis, &mut at, |i, w| {
            w[0] = Some(1.0);
            let (b, clear) = rays[i as usize];
            Some((clear, b))
        });
        let clear = rays.iter().filter(|r| r.1).count() as f32 / n as f32;
        assert!((vis[0] - clear).abs() < 1e-6);
        assert!(
            ((at[0] + at[1] + at[2]) / 3.0 - vis[0]).abs() < 1e-5,
            "{at:?}"
        );
        assert!((at[0] - 1.0).abs() < 0.06, "{at:?}");
        assert!(
            (at[1] - 0.2).abs() < 0.06 && (at[2] - 0.2).abs() < 0.06,
            "{at:?}"
        );
        // A step: clear only where corner 0's coordinate is over a half. The slope that
        // would take corner 0 above 1 is flattened, the mean kept, every corner in [0, 1].
        let mut vis = [0.0f32];
        let mut at = [0.0f32; 3];
        visible_fractions(n, &mut vis, &mut at, |i, w| {
            w[0] = Some(1.0);
            let b = rays[i as usize].0;
            Some((b[0] > 0.5, b))
        });
        assert!(at.iter().all(|v| (0.0..=1.0).contains(v)), "{at:?}");
        assert!(
            ((at[0] + at[1] + at[2]) / 3.0 - vis[0]).abs() < 1e-5,
            "{at:?}"
        );
        assert!(
            at[0] > 0.5 && at[1] < vis[0] && at[2] < vis[0],
            "{at:?} {vis:?}"
        );
    }
}
