//! The narrow shadow rule: a flat receiver in a light's shadow is split below `detail_level`
//! where the shadow may be narrower than the receiver (a surface met between the receiver and
//! the light close enough that its penumbra is narrower than the receiver), and the receiver's
//! other links go down with the light's. Shown by Teatime's spoon and the base of its teapot
//! (`samples/teatime.glb`).

use glam::Vec3;
use hce_format::MAX_TREE_DEPTH;

use super::coefficients::inset_corners;
use super::context::Ctx;
use super::element::ElemKey;

/// How many levels below [`BakeParams::detail_level`] an emitter's narrow shadow splits a
/// flat receiver ([`Ctx::narrow_shadow_splittable`]).
pub(super) const NARROW_SHADOW_LEVELS: u32 = 2;

/// The least area [`Ctx::narrow_shadow_splittable`] splits to, as a fraction of the object's
/// least element area.
pub(super) const NARROW_SHADOW_AREA: f32 = 16.0;

impl Ctx<'_> {
    /// Whether the shadow that a light `st` ([`Ctx::lights`]) casts across flat receiver `k`
    /// (corners `rt`), which the link's rays found partly hidden, may be narrower than the
    /// receiver, which then draws it blurred over its whole width: below
    /// [`BakeParams::detail_level`] (down to [`NARROW_SHADOW_LEVELS`] more levels and a
    /// sixteenth of the least area), a surface met between the receiver and the light nearer
    /// than `s·D/W` (receiver size `s`, light distance `D` and width `W`), where its penumbra
    /// is narrower than `s`. Judged by the geometry, from the receiver's centre and inset
    /// corners towards the light's centre and corners, and with no threshold on the light the
    /// link brings, so that the receivers along one shadow edge split alike. Split where that
    /// light passed a threshold (the thirteenth round), a thin shadow (Teatime's spoon) was
    /// drawn as dashes, sharp where a receiver passed and blurred between; kept to where the
    /// light was a quarter to three quarters hidden, a contact shadow's outline was ragged
    /// (BENCHMARKS.md, fourteenth round). `refine_root` takes the receiver's other links down
    /// with the light's.
    pub(super) fn narrow_shadow_splittable(
        &self,
        k: ElemKey,
        area: f32,
        rt: [Vec3; 3],
        st: [Vec3; 3],
    ) -> bool {
        let object = self.roots[k.root as usize].object;
        if self.scene.objects[object].multires
            || k.level >= (self.params.detail_level + NARROW_SHADOW_LEVELS).min(MAX_TREE_DEPTH)
            || area * 0.25 * NARROW_SHADOW_AREA < self.min_area_of(k)
        {
            return false;
        }
        // Part of it shut in (under a block standing on it): the shadow's edge there is the
        // footprint's, which the open fraction already draws ([`Ctx::shown`]).
        if self.memo(k, |m| &mut m.open, || self.open_fraction(k)) < 1.0 {
            return false;
        }
        let longest = |t: [Vec3; 3]| {
            (0..3)
                .map(|i| (t[(i + 1) % 3] - t[i]).length())
                .fold(0.0, f32::max)
        };
        let rc = (rt[0] + rt[1] + rt[2]) / 3.0;
        let sc = (st[0] + st[1] + st[2]) / 3.0;
        let (size, width, dist) = (longest(rt), longest(st), (sc - rc).length());
        if width <= 0.0 {
            return false;
        }
        let reach = size * dist / width;
        let n = self.roots[k.root as usize].normal;
        let [c0, c1, c2] = inset_corners(rt);
        [rc, c0, c1, c2].iter().any(|&p| {
            [sc, st[0], st[1], st[2]].iter().any(|&q| {
                let d = q - p;
                let len = d.length();
                len > 0.0
                    && n.dot(d) > 0.0
                    && self
                        .occ
                        .first_hit_from(p, n, d / len, reach.min(len * 0.99), |_| false)
                        .is_some()
            })
        })
    }
}
