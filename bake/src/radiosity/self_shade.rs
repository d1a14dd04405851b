//! The self-shading rule: an element of an object with a refined surface is split where its
//! parts are shut in by their surroundings unevenly (a fold, a crease, an eye socket, the
//! junction of a spout with its body), which no link sees. Judged by the geometry alone.
//! Shown by `tests/self_shading.rs` and Teatime's spout.

use hce_format::MAX_TREE_DEPTH;

use super::coefficients::inset_corners;
use super::context::Ctx;
use super::element::ElemKey;
use super::enclosure::cosine_strata;
use super::near_occluder::NEAR_SHADOW_REACH;

/// Directions [`Ctx::self_shade_varies`] casts from each point: rings of equal cosine-weighted
/// measure, and directions per ring (24 in all: with 12, the same gain on the teapot took
/// twice the bake time).
pub(super) const SELF_SHADE_RINGS: u32 = 4;

pub(super) const SELF_SHADE_AZIMUTHS: u32 = 6;

/// Largest difference, as a share of the directions, between what two points of an element
/// see open before [`Ctx::self_shade_varies`] splits it: more than 2 of 24. (4 of 24 took the
/// teapot to 4.1% instead of 3.8% against path-traced images, in 80% of the time.)
pub(super) const SELF_SHADE_TOLERANCE: f32 = 0.1;

impl Ctx<'_> {
    /// Whether the self-shading rule splits receiver `k`: it may ([`Ctx::self_shade_splittable`])
    /// and its parts are shut in unevenly ([`Ctx::self_shade_varies`], found once per element).
    pub(super) fn self_shade_splits(&self, k: ElemKey) -> bool {
        self.self_shade_splittable(k)
            && self.memo(k, |m| &mut m.shade_varies, || self.self_shade_varies(k))
    }

    /// Whether the self-shading rule may split `k` ([`Ctx::self_shade_varies`]): an element of
    /// an object with a refined surface, down to a quarter of one of that surface's triangles
    /// (the rays that judge it meet that surface, and resolve nothing finer), whatever its
    /// area: the surface's level bounds the leaves to 4^(level + 1) per coarse triangle, and
    /// `min_area_fraction`, a share of the scene's area in a room, stopped the teapot's spout
    /// junction at leaves of a quarter of its coarse triangles (5.4% against path-traced
    /// images, 3.8% without).
    pub(super) fn self_shade_splittable(&self, k: ElemKey) -> bool {
        self.surface_level(k.root)
            .is_some_and(|level| k.level <= level && k.level < MAX_TREE_DEPTH)
    }

    /// Whether the parts of element `k` of an object with a refined surface are shut in by
    /// their surroundings unevenly: at its centre and inset corners, carried onto the refined
    /// surface, the share of [`SELF_SHADE_RINGS`] × [`SELF_SHADE_AZIMUTHS`] cosine-weighted
    /// directions around the surface's normal that meet nothing within
    /// [`NEAR_SHADOW_REACH`] element radii differs between two points by more than
    /// [`SELF_SHADE_TOLERANCE`].
    ///
    /// A fold, a crease, the rim of an eye socket, the junction of a spout with its body: one
    /// side of the element looks out into the room, the other into the object itself. No link
    /// sees that (a link's visibility is at most linear over its receiver, and
    /// [`Ctx::near_shadow`] leaves the object's own surface out), and the element's area
    /// average, drawn at its corners, is too bright at the bottom of the fold and too dark at
    /// its rim. Judged here by the geometry alone, and so the same in every pass.
    pub(super) fn self_shade_varies(&self, k: ElemKey) -> bool {
        let rt = self.elem_corners(k);
        let rc = (rt[0] + rt[1] + rt[2]) / 3.0;
        let radius = rt.iter().map(|v| (*v - rc).length()).fold(0.0, f32::max);
        let reach = NEAR_SHADOW_REACH * radius;
        let [c0, c1, c2] = inset_corners(rt);
        let (mut lo, mut hi) = (u32::MAX, 0u32);
        for p in [rc, c0, c1, c2] {
            let (q, n) = self.on_surface(k.root, p);
            let open = cosine_strata(n, SELF_SHADE_RINGS, SELF_SHADE_AZIMUTHS, 0.0)
                .filter(|&d| self.occ.first_hit_from(q, n, d, reach, |_| false).is_none())
                .count() as u32;
            lo = lo.min(open);
            hi = hi.max(open);
        }
        open_counts_differ(lo, hi)
    }
}

/// Whether the least and the most open directions (`lo`, `hi`) of an element's points differ by
/// more than [`SELF_SHADE_TOLERANCE`] of all the directions cast.
pub(super) fn open_counts_differ(lo: u32, hi: u32) -> bool {
    (hi - lo) as f32 > SELF_SHADE_TOLERANCE * (SELF_SHADE_RINGS * SELF_SHADE_AZIMUTHS) as f32
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn more_than_two_of_twenty_four_directions_apart_splits() {
        assert!(!open_counts_differ(10, 12));
        assert!(open_counts_differ(10, 13));
        assert!(!open_counts_differ(24, 24));
        assert!(open_counts_differ(0, 24));
    }
}
