//! The near occluder rule: a receiver is split where an occluder close to it (an object resting
//! on it, the overhang of a fold) hides from one of its points what another sees, a shadow edge
//! every link to it shares. Judged by the geometry alone. Shown by the floor under and beside
//! the objects of `tests/contact_shadows.rs`.

use glam::Vec3;

use super::coefficients::inset_corners;
use super::context::Ctx;
use super::element::ElemKey;
use super::enclosure::cosine_strata;
use crate::visibility::Occluders;

/// How far from a receiver, in receiver radii, an occluder is looked for by
/// [`Ctx::near_shadow`].
pub(super) const NEAR_SHADOW_REACH: f32 = 10.0;

impl Ctx<'_> {
    /// Whether the near occluder rule splits receiver `k` of `area`: a rule judged against the
    /// receiver's own radiance may ([`Ctx::detail_splittable`]) and an occluder beside it casts
    /// a shadow edge across it ([`Ctx::near_shadow`], found once per element).
    pub(super) fn near_occluder_splits(&self, k: ElemKey, area: f32) -> bool {
        self.detail_splittable(k, area)
            && self.memo(k, |m| &mut m.near_shadow, || self.near_shadow(k))
    }

    /// Whether an occluder close to receiver `k` casts a shadow edge across it: from the
    /// receiver's centre and inset corners, rays along fixed cosine-stratified directions of
    /// its hemisphere; in a direction where some ray meets a surface within
    /// [`NEAR_SHADOW_REACH`] times the receiver's radius, each point checks that it sees what
    /// every other point sees along it (the end of that point's ray). A wall or a room corner
    /// next to the receiver is seen alike from all its points; an object standing on it, or
    /// the overhang of a fold, hides from one point what another sees. A link's visibility is
    /// at most linear over its receiver (it was one number when this rule was made), so near
    /// such an occluder each link spreads its shadow's edge over the receiver and the errors of
    /// all of them add up with one sign (in a closed furnace, floor leaves next to a resting
    /// object summed form factors to 1.12).
    pub(super) fn near_shadow(&self, k: ElemKey) -> bool {
        // Nothing but the scene's outer boundary in front: nothing there hides one source
        // from part of the receiver (the convex side of an object in a room).
        if self.unobstructed[k.root as usize] {
            return false;
        }
        let rt = self.elem_corners(k);
        let rc = (rt[0] + rt[1] + rt[2]) / 3.0;
        let radius = rt.iter().map(|v| (*v - rc).length()).fold(0.0, f32::max);
        let reach = NEAR_SHADOW_REACH * radius;
        let n = self.roots[k.root as usize].normal;
        let [c0, c1, c2] = inset_corners(rt);
        let pts = [rc, c0, c1, c2];
        // A multiresolution object's own coarse triangles are not the surface drawn: its folds
        // are shallower once refined, and refining against the coarse ones made the eye
        // sockets of suzanne darker than a path tracer of the refined surface shows them.
        let object = self.roots[k.root as usize].object;
        let own = self.scene.objects[object].multires;
        let ignore = |t: usize| own && self.owner_object(t) == object;
        hides_unevenly(&self.occ, pts, n, reach, ignore)
    }
}

/// Whether, from points `pts` of a receiver with normal `n`, an occluder of `occ` within `reach`
/// along one of the fixed directions of [`Ctx::near_shadow`] hides from one point what another
/// sees along it; triangles for which `ignore` holds do not count.
pub(super) fn hides_unevenly(
    occ: &Occluders,
    pts: [Vec3; 4],
    n: Vec3,
    reach: f32,
    ignore: impl Fn(usize) -> bool + Copy,
) -> bool {
    for d in cosine_strata(n, 3, 4, 0.0) {
        let hits = pts.map(|p| occ.first_hit_from(p, n, d, reach, ignore));
        if hits.iter().all(Option::is_none) {
            continue;
        }
        // What each point sees along `d`, stopped short of the surface it meets.
        let ends: Vec<Vec3> = pts
            .iter()
            .zip(&hits)
            .map(|(&p, h)| p + d * (h.unwrap_or(reach) * 0.95))
            .collect();
        for (i, &p) in pts.iter().enumerate() {
            for (j, &e) in ends.iter().enumerate() {
                if i != j && !occ.segment_clear_between_but(p, n, e, d, ignore) {
                    return true;
                }
            }
        }
    }
    false
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::radiosity::cluster::tests::box_tris;

    #[test]
    fn a_block_beside_the_receiver_within_reach_shades_it_unevenly() {
        // A receiver on the floor z = 0 of radius about 0.75; a thin block standing at
        // `x` from it, along −x, where the fixed directions look.
        let rt = [Vec3::ZERO, Vec3::X, Vec3::Y];
        let rc = (rt[0] + rt[1] + rt[2]) / 3.0;
        let radius = rt.iter().map(|v| (*v - rc).length()).fold(0.0, f32::max);
        let [c0, c1, c2] = inset_corners(rt);
        let pts = [rc, c0, c1, c2];
        let reach = NEAR_SHADOW_REACH * radius;
        let shades = |x: f32| {
            let occ = Occluders::new(box_tris(
                Vec3::new(-x - 0.1, -0.25, 0.0),
                Vec3::new(-x, 0.25, 10.0),
                false,
            ));
            hides_unevenly(&occ, pts, Vec3::Z, reach, |_| false)
        };
        // Ten radii, 7.45: the block met along the lowest directions (66° from the normal)
        // 4.05 away is within reach, 9.9 away is not.
        assert!((reach - 7.45).abs() < 0.01, "{reach}");
        assert!(shades(0.5));
        assert!(shades(3.7));
        assert!(!shades(9.0));
        // A wall along the whole side is seen alike from every point.
        let wall = Occluders::new(box_tris(
            Vec3::new(-1.1, -50.0, 0.0),
            Vec3::new(-1.0, 50.0, 50.0),
            false,
        ));
        assert!(!hides_unevenly(&wall, pts, Vec3::Z, reach, |_| false));
    }
}
