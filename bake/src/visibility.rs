//! Ray-cast visibility through a BVH of every triangle of the scene, built with `obvhs`
//! (a compressed wide BVH8, Ylitie et al. 2017, from a PLOC BVH2, Meister & Bittner 2018).

use std::time::Duration;

use glam::{Vec3, Vec3A};
use obvhs::{
    cwbvh::{builder::build_cwbvh_from_tris, CwBvh},
    ray::{Ray, RayHit},
    triangle::Triangle,
    BvhBuildParams,
};

/// The scene's occluders.
pub struct Occluders {
    tris: Vec<Triangle>,
    bvh: Option<CwBvh>,
    /// Distance kept clear at both ends of a segment so that the surfaces it joins do not
    /// occlude it (relative to the scene size).
    eps: f32,
}

impl Occluders {
    pub fn new(triangles: impl IntoIterator<Item = [Vec3; 3]>) -> Self {
        let tris: Vec<Triangle> = triangles
            .into_iter()
            .map(|[a, b, c]| Triangle {
                v0: a.into(),
                v1: b.into(),
                v2: c.into(),
            })
            .collect();
        let (mut lo, mut hi) = (Vec3A::splat(f32::MAX), Vec3A::splat(f32::MIN));
        for t in &tris {
            for v in [t.v0, t.v1, t.v2] {
                lo = lo.min(v);
                hi = hi.max(v);
            }
        }
        let diag = if tris.is_empty() {
            1.0
        } else {
            (hi - lo).length()
        };
        let bvh = (!tris.is_empty()).then(|| {
            build_cwbvh_from_tris(
                &tris,
                BvhBuildParams::medium_build(),
                &mut Duration::default(),
            )
        });
        Occluders {
            tris,
            bvh,
            eps: diag.max(1e-6) * 1e-5,
        }
    }

    /// Whether the open segment from `a` to `b` crosses no triangle.
    pub fn segment_clear(&self, a: Vec3, b: Vec3) -> bool {
        let d = b - a;
        let len = d.length();
        if len <= 2.0 * self.eps {
            return true;
        }
        self.ray_clear(a, d / len, len - self.eps)
    }

    /// Whether the segment from `a`, on a surface of unit normal `na`, to `b`, on a surface of
    /// unit normal `nb`, crosses no triangle on its way. Near each end the segment is kept
    /// clear for as long as it stays within the tolerance of that end's own plane: a segment
    /// that leaves or meets its surface at a grazing angle (between two faces meeting at a
    /// sharp edge, or along a wall from a point next to it) runs within rounding distance of
    /// that plane for a long way, and met the neighbouring triangles of its own surface
    /// there. A fixed gap at each end let a closed 30-degree wedge lose 4% of its light at the
    /// leaves along its edge (issue 20).
    pub fn segment_clear_between(&self, a: Vec3, na: Vec3, b: Vec3, nb: Vec3) -> bool {
        self.segment_clear_between_but(a, na, b, nb, |_| false)
    }

    /// [`Occluders::segment_clear_between`], the triangles (by index) for which `ignore` is
    /// true left out.
    pub fn segment_clear_between_but(
        &self,
        a: Vec3,
        na: Vec3,
        b: Vec3,
        nb: Vec3,
        ignore: impl Fn(usize) -> bool,
    ) -> bool {
        let d = b - a;
        let len = d.length();
        if len <= 2.0 * self.eps {
            return true;
        }
        let dir = d / len;
        // The distance along the segment over which it rises `eps` above each end's plane,
        // never more than a quarter of the segment (a grazing ray carries almost no light:
        // the form factor weighs it by the cosine).
        let gap = |n: Vec3| {
            (self.eps / n.dot(dir).abs().max(1e-6))
                .max(self.eps)
                .min(0.25 * len)
        };
        let (t0, t1) = (gap(na), len - gap(nb));
        let Some(bvh) = &self.bvh else { return true };
        if t0 >= t1 {
            return true;
        }
        let ray = Ray::new(a.into(), dir.into(), t0, t1);
        bvh.ray_traverse_miss(ray, |r, id| {
            let t = bvh.primitive_indices[id] as usize;
            if ignore(t) {
                f32::INFINITY
            } else {
                self.tris[t].intersect(r)
            }
        })
    }

    /// Distance to the first triangle met by the ray that leaves `a`, on a surface of unit
    /// normal `na`, along unit `dir`, within `max_t`; the start is kept clear of `a`'s own
    /// surface as in [`Occluders::segment_clear_between`].
    pub fn first_hit_from(
        &self,
        a: Vec3,
        na: Vec3,
        dir: Vec3,
        max_t: f32,
        ignore: impl Fn(usize) -> bool,
    ) -> Option<f32> {
        let bvh = self.bvh.as_ref()?;
        let t0 = (self.eps / na.dot(dir).abs().max(1e-6))
            .max(self.eps)
            .min(0.25 * max_t);
        if t0 >= max_t {
            return None;
        }
        let ray = Ray::new(a.into(), dir.into(), t0, max_t);
        let mut hit = RayHit::none();
        bvh.ray_traverse(ray, &mut hit, |r, id| {
            let t = bvh.primitive_indices[id] as usize;
            if ignore(t) {
                f32::INFINITY
            } else {
                self.tris[t].intersect(r)
            }
        })
        .then_some(hit.t)
    }

    /// Whether the ray from `origin` along unit `dir` first meets the back of a triangle (the
    /// side its counter-clockwise winding does not face); false when it meets nothing.
    pub fn first_hit_is_back(&self, origin: Vec3, dir: Vec3) -> bool {
        let Some(bvh) = &self.bvh else { return false };
        let ray = Ray::new(origin.into(), dir.into(), self.eps, f32::INFINITY);
        let mut hit = RayHit::none();
        if !bvh.ray_traverse(ray, &mut hit, |r, id| {
            self.tris[bvh.primitive_indices[id] as usize].intersect(r)
        }) {
            return false;
        }
        let t = &self.tris[bvh.primitive_indices[hit.primitive_id as usize] as usize];
        let n = (t.v1 - t.v0).cross(t.v2 - t.v0);
        n.dot(Vec3A::from(dir)) > 0.0
    }

    /// Whether the ray from `origin` along unit `dir` meets no triangle before `max_t`.
    pub fn ray_clear(&self, origin: Vec3, dir: Vec3, max_t: f32) -> bool {
        let Some(bvh) = &self.bvh else { return true };
        let ray = Ray::new(origin.into(), dir.into(), self.eps, max_t);
        bvh.ray_traverse_miss(ray, |r, id| {
            self.tris[bvh.primitive_indices[id] as usize].intersect(r)
        })
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn a_wall_blocks_only_segments_through_it() {
        let wall = [
            [
                Vec3::new(1.0, -1.0, -1.0),
                Vec3::new(1.0, 1.0, -1.0),
                Vec3::new(1.0, 1.0, 1.0),
            ],
            [
                Vec3::new(1.0, -1.0, -1.0),
                Vec3::new(1.0, 1.0, 1.0),
                Vec3::new(1.0, -1.0, 1.0),
            ],
        ];
        let occ = Occluders::new(wall);
        assert!(!occ.segment_clear(Vec3::ZERO, Vec3::new(2.0, 0.1, 0.2)));
        assert!(occ.segment_clear(Vec3::ZERO, Vec3::new(0.9, 0.1, 0.2)));
        assert!(occ.segment_clear(Vec3::ZERO, Vec3::new(2.0, 3.0, 0.0)));
        // A segment ending on the wall is not blocked by it.
        assert!(occ.segment_clear(Vec3::ZERO, Vec3::new(1.0, 0.5, 0.5)));
    }

    #[test]
    fn first_hit_tells_the_back_of_a_panel_from_its_front() {
        // A panel in z = 1 facing down (counter-clockwise seen from below).
        let panel = [[
            Vec3::new(-1.0, -1.0, 1.0),
            Vec3::new(0.0, 2.0, 1.0),
            Vec3::new(2.0, -1.0, 1.0),
        ]];
        let occ = Occluders::new(panel);
        // From below the ray meets its front; from above, going down, its back.
        assert!(!occ.first_hit_is_back(Vec3::ZERO, Vec3::Z));
        assert!(occ.first_hit_is_back(Vec3::new(0.0, 0.0, 2.0), Vec3::NEG_Z));
        // A ray that misses meets nothing.
        assert!(!occ.first_hit_is_back(Vec3::ZERO, Vec3::NEG_Z));
    }
}
