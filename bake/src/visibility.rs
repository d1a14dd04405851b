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
    /// The triangles that are not part of the scene's outer boundary, for
    /// [`Occluders::shaft_clear`].
    inner: InnerTriangles,
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
        // The slower build (triangles split before building, finer sorting) traces the bake's
        // rays faster: 5-8% of the scaling scene's bake, for a build of milliseconds.
        let bvh = (!tris.is_empty()).then(|| {
            build_cwbvh_from_tris(
                &tris,
                BvhBuildParams::slow_build(),
                &mut Duration::default(),
            )
        });
        let eps = diag.max(1e-6) * 1e-5;
        let inner = InnerTriangles::new(&tris, eps);
        Occluders {
            tris,
            bvh,
            eps,
            inner,
        }
    }

    /// Whether every segment between a point of the receiver triangle `recv` and a point of
    /// the source, each point on a triangle of the scene, with the source point in front of
    /// `recv`'s plane (and, given `src_plane`, the receiver point in front of the source's),
    /// is certainly clear: no triangle can cross one. The source lies in the box `src_lo` to
    /// `src_hi`; `recv_normal` and `src_plane` (unit normal, point) are the planes of the two
    /// ends. False says nothing: cast rays.
    ///
    /// Such a segment lies in the box around both ends and, but for its ends, strictly in
    /// front of both planes. A triangle of the scene's outer boundary, whose plane has the
    /// whole scene on or in front of it (a wall of a closed room), cannot cross a segment
    /// between two points of the scene; neither can a triangle outside the box, nor one with
    /// no vertex in front of either plane. What is left are the other triangles in the box:
    /// when there are none (a wall seeing a wall past no object, an object's convex side seeing
    /// the room), the link needs no rays.
    pub fn shaft_clear(
        &self,
        recv: [Vec3; 3],
        recv_normal: Vec3,
        src_lo: Vec3,
        src_hi: Vec3,
        src_plane: Option<(Vec3, Vec3)>,
    ) -> bool {
        let lo = recv.iter().fold(src_lo, |a, v| a.min(*v));
        let hi = recv.iter().fold(src_hi, |a, v| a.max(*v));
        let mut planes = [(recv_normal, recv_normal.dot(recv[0])); 2];
        let count = match src_plane {
            Some((n, p)) => {
                planes[1] = (n, n.dot(p));
                2
            }
            None => 1,
        };
        !self.inner.any_in_front(lo, hi, &planes[..count], self.eps)
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
    /// leaves along its edge (`tests/furnace_property.rs`, `wedge`).
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
        let ray = bvh_ray(a.into(), dir.into(), t0, t1);
        bvh.ray_traverse_miss(ray, |r, id| {
            self.hit_but(r, bvh.primitive_indices[id], &ignore)
        })
    }

    /// The distance at which `ray` meets triangle `t`, infinite where it misses or where
    /// `ignore(t)`.
    fn hit_but(&self, ray: &Ray, t: u32, ignore: &impl Fn(usize) -> bool) -> f32 {
        if ignore(t as usize) {
            f32::INFINITY
        } else {
            self.tris[t as usize].intersect(ray)
        }
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
        let ray = bvh_ray(a.into(), dir.into(), t0, max_t);
        let mut hit = RayHit::none();
        bvh.ray_traverse(ray, &mut hit, |r, id| {
            self.hit_but(r, bvh.primitive_indices[id], &ignore)
        })
        .then_some(hit.t)
    }

    /// Whether the ray that leaves `a`, on a surface of unit normal `na`, along unit `dir`
    /// first meets the front of a triangle (the side its counter-clockwise winding faces):
    /// false when it meets a back or nothing. The start is kept clear of `a`'s own surface as
    /// in [`Occluders::first_hit_from`].
    pub fn meets_front_from(&self, a: Vec3, na: Vec3, dir: Vec3) -> bool {
        let Some(bvh) = &self.bvh else { return false };
        let t0 = (self.eps / na.dot(dir).abs().max(1e-6)).max(self.eps);
        let ray = bvh_ray(a.into(), dir.into(), t0, f32::INFINITY);
        let mut hit = RayHit::none();
        let front = |t: &Triangle| (t.v1 - t.v0).cross(t.v2 - t.v0).dot(Vec3A::from(dir)) < 0.0;
        // A back met as near as a front is the edge where the two meet (a ray that grazes a
        // convex object's silhouette): the front is what the ray sees there.
        if !bvh.ray_traverse(ray, &mut hit, |r, id| {
            let t = &self.tris[bvh.primitive_indices[id] as usize];
            let (d, _) = intersect_sealed(t, r);
            if front(t) {
                d
            } else {
                d * (1.0 + SEAL)
            }
        }) {
            return false;
        }
        // So is a back met at its edge, where the front beside it missed by a rounding.
        let t = &self.tris[bvh.primitive_indices[hit.primitive_id as usize] as usize];
        front(t) || intersect_sealed(t, &ray).1 < EDGE
    }

    /// Whether the ray from `origin` along unit `dir` first meets the back of a triangle (the
    /// side its counter-clockwise winding does not face); false when it meets nothing.
    pub fn first_hit_is_back(&self, origin: Vec3, dir: Vec3) -> bool {
        let Some(bvh) = &self.bvh else { return false };
        let ray = bvh_ray(origin.into(), dir.into(), self.eps, f32::INFINITY);
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
        let ray = bvh_ray(origin.into(), dir.into(), self.eps, max_t);
        bvh.ray_traverse_miss(ray, |r, id| {
            self.tris[bvh.primitive_indices[id] as usize].intersect(r)
        })
    }
}

/// Barycentric slack of [`intersect_sealed`].
const SEAL: f32 = 1e-5;

/// How near an edge (barycentric) a back that [`Occluders::meets_front_from`] meets counts as
/// the edge.
const EDGE: f32 = 1e-3;

/// The distance at which `ray` meets triangle `t` (Möller & Trumbore), infinite where it
/// misses, and the least barycentric coordinate of the point met. Each edge is widened by
/// [`SEAL`] of the triangle: a ray through the edge shared by two triangles meets one of them. The plain test (`Triangle::intersect`) lets such a ray
/// through both where rounding puts it a hair outside each, and a room's grid of faces, met
/// along its lines by a regular set of directions, then seemed to leak.
fn intersect_sealed(t: &Triangle, ray: &Ray) -> (f32, f32) {
    let e1 = t.v0 - t.v1;
    let e2 = t.v2 - t.v0;
    let n = e1.cross(e2);
    let det = n.dot(ray.direction);
    if det == 0.0 {
        return (f32::INFINITY, 0.0);
    }
    let inv_det = 1.0 / det;
    let c = t.v0 - ray.origin;
    let r = ray.direction.cross(c);
    let u = r.dot(e2) * inv_det;
    let v = r.dot(e1) * inv_det;
    let w = 1.0 - u - v;
    let least = u.min(v).min(w);
    if least < -SEAL {
        return (f32::INFINITY, least);
    }
    let d = n.dot(c) * inv_det;
    if d >= ray.tmin && d <= ray.tmax {
        (d, least)
    } else {
        (f32::INFINITY, least)
    }
}

/// A ray for the BVH from `origin` along `dir`, between `t0` and `t1`. A negative zero in
/// `dir` is made positive (`-0.0 + 0.0` is `+0.0`): its reciprocal is `-inf`, for which the
/// BVH's slab test misses every box, so a ray along a negated axis-aligned normal met nothing.
pub(crate) fn bvh_ray(origin: Vec3A, dir: Vec3A, t0: f32, t1: f32) -> Ray {
    Ray::new(origin, dir + Vec3A::ZERO, t0, t1)
}

/// The triangles of a scene that lie off its outer boundary, in a bounding volume hierarchy of
/// axis-aligned boxes (median splits, at most [`LEAF_SIZE`] triangles a leaf).
struct InnerTriangles {
    tris: Vec<[Vec3; 3]>,
    nodes: Vec<BoxNode>,
}

/// A node of [`InnerTriangles`]: its box, and either, when `count` is not zero, the triangles
/// `first .. first + count`, or two children: the next node, and node `first`.
struct BoxNode {
    lo: Vec3,
    hi: Vec3,
    first: u32,
    count: u32,
}

const LEAF_SIZE: usize = 4;

impl InnerTriangles {
    /// Keeps the triangles of `all` that have a vertex of the scene more than `eps` behind
    /// their plane (those that do not bound it).
    fn new(all: &[Triangle], eps: f32) -> Self {
        let tris: Vec<[Vec3; 3]> = all
            .iter()
            .map(|t| [t.v0.into(), t.v1.into(), t.v2.into()])
            .collect();
        let everything = Self::build(tris.clone());
        let inner = tris
            .into_iter()
            .filter(|t| {
                let n = (t[1] - t[0]).cross(t[2] - t[0]);
                let len = n.length();
                if len <= 0.0 || !len.is_finite() {
                    return true; // No plane: no claim.
                }
                let n = n / len;
                everything.any_vertex_behind(n, n.dot(t[0]) - eps)
            })
            .collect();
        Self::build(inner)
    }

    fn build(mut tris: Vec<[Vec3; 3]>) -> Self {
        let mut nodes = Vec::with_capacity(2 * tris.len() / LEAF_SIZE + 1);
        if !tris.is_empty() {
            let n = tris.len();
            Self::build_node(&mut tris, 0, n, &mut nodes);
        }
        InnerTriangles { tris, nodes }
    }

    /// Appends the node over `tris[first..end]` and its subtree; returns its index.
    fn build_node(
        tris: &mut [[Vec3; 3]],
        first: usize,
        end: usize,
        nodes: &mut Vec<BoxNode>,
    ) -> usize {
        let (mut lo, mut hi) = (Vec3::splat(f32::MAX), Vec3::splat(f32::MIN));
        for t in &tris[first..end] {
            for v in t {
                lo = lo.min(*v);
                hi = hi.max(*v);
            }
        }
        let at = nodes.len();
        nodes.push(BoxNode {
            lo,
            hi,
            first: first as u32,
            count: (end - first) as u32,
        });
        if end - first <= LEAF_SIZE {
            return at;
        }
        let axis = (hi - lo).max_position();
        let key = |t: &[Vec3; 3]| t[0][axis] + t[1][axis] + t[2][axis];
        let mid = (first + end) / 2;
        tris[first..end].select_nth_unstable_by(mid - first, |a, b| key(a).total_cmp(&key(b)));
        Self::build_node(tris, first, mid, nodes);
        let right = Self::build_node(tris, mid, end, nodes);
        nodes[at].first = right as u32;
        nodes[at].count = 0;
        at
    }

    /// Whether some triangle has a vertex with `n·v < d`.
    fn any_vertex_behind(&self, n: Vec3, d: f32) -> bool {
        self.search(
            |lo, hi| n.dot(Vec3::select(n.cmpge(Vec3::ZERO), lo, hi)) < d,
            |t| t.iter().any(|v| n.dot(*v) < d),
        )
    }

    /// Whether some triangle whose box meets the box `lo` to `hi` has, for each of `planes`
    /// (unit normal, offset), a vertex more than `eps` in front of it.
    fn any_in_front(&self, lo: Vec3, hi: Vec3, planes: &[(Vec3, f32)], eps: f32) -> bool {
        self.search(
            |a, b| {
                a.cmple(hi).all()
                    && b.cmpge(lo).all()
                    && planes
                        .iter()
                        .all(|(n, d)| n.dot(Vec3::select(n.cmpge(Vec3::ZERO), b, a)) > d + eps)
            },
            |t| {
                let (tlo, thi) = (t[0].min(t[1]).min(t[2]), t[0].max(t[1]).max(t[2]));
                tlo.cmple(hi).all()
                    && thi.cmpge(lo).all()
                    && planes
                        .iter()
                        .all(|(n, d)| t.iter().any(|v| n.dot(*v) > d + eps))
            },
        )
    }

    /// Depth-first search for a triangle that `hit` accepts, entering only the nodes whose
    /// box `enter` accepts.
    fn search(&self, enter: impl Fn(Vec3, Vec3) -> bool, hit: impl Fn(&[Vec3; 3]) -> bool) -> bool {
        if self.nodes.is_empty() {
            return false;
        }
        let mut stack = Vec::with_capacity(64);
        stack.push(0usize);
        while let Some(i) = stack.pop() {
            let node = &self.nodes[i];
            if !enter(node.lo, node.hi) {
                continue;
            }
            if node.count > 0 {
                let (a, b) = (node.first as usize, (node.first + node.count) as usize);
                if self.tris[a..b].iter().any(&hit) {
                    return true;
                }
            } else {
                stack.push(node.first as usize);
                stack.push(i + 1);
            }
        }
        false
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

    /// A closed box room from `lo` to `hi` with `n × n` quads a face, facing in (`inward`) or
    /// out (a block standing in the room).
    fn box_faces(lo: Vec3, hi: Vec3, n: u32, inward: bool, out: &mut Vec<[Vec3; 3]>) {
        let size = hi - lo;
        for axis in 0..3 {
            let (u, v) = ((axis + 1) % 3, (axis + 2) % 3);
            for side in 0..2 {
                for j in 0..n {
                    for i in 0..n {
                        let at = |a: u32, b: u32| {
                            let mut p = lo;
                            p[axis] += size[axis] * side as f32;
                            p[u] += size[u] * a as f32 / n as f32;
                            p[v] += size[v] * b as f32 / n as f32;
                            p
                        };
                        let q = [at(i, j), at(i + 1, j), at(i + 1, j + 1), at(i, j + 1)];
                        // Counter-clockwise about +axis on the far side, seen from outside.
                        let outward_ccw = side == 1;
                        let (a, b) = if outward_ccw != inward {
                            ([q[0], q[1], q[2]], [q[0], q[2], q[3]])
                        } else {
                            ([q[0], q[2], q[1]], [q[0], q[3], q[2]])
                        };
                        out.push(a);
                        out.push(b);
                    }
                }
            }
        }
    }

    fn normal(t: &[Vec3; 3]) -> Vec3 {
        (t[1] - t[0]).cross(t[2] - t[0]).normalize()
    }

    fn point_on(t: &[Vec3; 3], rng: &mut crate::radiosity::element::Rng) -> Vec3 {
        crate::radiosity::element::jittered_point(*t, 0, 1, rng)
    }

    #[test]
    fn the_outer_boundary_is_left_out_of_the_inner_triangles() {
        let mut tris = Vec::new();
        box_faces(Vec3::ZERO, Vec3::splat(4.0), 3, true, &mut tris);
        let walls = tris.len();
        box_faces(Vec3::splat(1.0), Vec3::splat(2.0), 1, false, &mut tris);
        let occ = Occluders::new(tris.iter().copied());
        // Every wall has the whole scene in front of it; every face of the block has the
        // rest of the block behind it.
        assert_eq!(occ.inner.tris.len(), tris.len() - walls);
        assert!(normal(&tris[0]).dot(Vec3::splat(2.0) - tris[0][0]) > 0.0);
    }

    /// Over generated rooms with blocks, every pair of triangles `shaft_clear` certifies is
    /// clear along every segment a ray test checks, and it certifies some pairs and refuses
    /// some that rays find blocked.
    #[test]
    fn a_certified_shaft_is_clear_along_every_segment() {
        let mut rng = crate::radiosity::element::Rng::new(20, 11, 26);
        let (mut certified, mut refused_blocked) = (0, 0);
        for scene in 0..6 {
            let mut tris = Vec::new();
            box_faces(Vec3::ZERO, Vec3::splat(4.0), 2 + scene % 3, true, &mut tris);
            for _ in 0..1 + scene % 3 {
                let lo = Vec3::new(0.2 + 2.5 * rng.next_f32(), 0.0, 0.2 + 2.5 * rng.next_f32());
                let size = Vec3::new(0.3, 0.3 + 1.5 * rng.next_f32(), 0.3) + 0.6 * rng.next_f32();
                box_faces(lo, (lo + size).min(Vec3::splat(3.9)), 1, false, &mut tris);
            }
            let occ = Occluders::new(tris.iter().copied());
            for _ in 0..400 {
                let r = &tris[(rng.next_u64() % tris.len() as u64) as usize];
                let s = &tris[(rng.next_u64() % tris.len() as u64) as usize];
                let (rn, sn) = (normal(r), normal(s));
                let (lo, hi) = (s[0].min(s[1]).min(s[2]), s[0].max(s[1]).max(s[2]));
                // As an element source (with its plane) and as a cluster's box (without).
                let clear = occ.shaft_clear(*r, rn, lo, hi, Some((sn, s[0])))
                    || occ.shaft_clear(*r, rn, lo, hi, None);
                let mut blocked = false;
                for _ in 0..32 {
                    let (p, q) = (point_on(r, &mut rng), point_on(s, &mut rng));
                    if rn.dot(q - p) <= 1e-4 || sn.dot(p - q) <= 1e-4 {
                        continue;
                    }
                    if !occ.segment_clear_between(p, rn, q, sn) {
                        blocked = true;
                        assert!(
                            !clear,
                            "scene {scene}: a certified shaft {r:?} → {s:?} is blocked"
                        );
                    }
                }
                certified += usize::from(clear);
                refused_blocked += usize::from(blocked);
            }
        }
        assert!(certified > 100, "only {certified} shafts certified");
        assert!(
            refused_blocked > 20,
            "only {refused_blocked} blocked pairs met"
        );
    }

    /// A direction with a negative zero (a negated axis-aligned normal) meets what the same
    /// direction with positive zeros meets: the open-fraction probe along a ceiling's normal
    /// computed `(-0.0, -1.0, -0.0)` and found nothing.
    #[test]
    fn rays_with_negative_zeros_meet_the_panel() {
        let panel = [[
            Vec3::new(-1.0, -1.0, 1.0),
            Vec3::new(0.0, 2.0, 1.0),
            Vec3::new(2.0, -1.0, 1.0),
        ]];
        let occ = Occluders::new(panel);
        let up = Vec3::new(-0.0, -0.0, 1.0);
        let down = Vec3::new(-0.0, -0.0, -1.0);
        assert!(!occ.ray_clear(Vec3::ZERO, up, 2.0));
        assert!(occ.first_hit_is_back(Vec3::new(0.0, 0.0, 2.0), down));
        assert_eq!(
            occ.first_hit_from(Vec3::ZERO, Vec3::Z, up, 5.0, |_| false),
            Some(1.0)
        );
        assert!(!occ.segment_clear_between(
            Vec3::ZERO,
            Vec3::Z,
            Vec3::new(-0.0, -0.0, 2.0),
            Vec3::NEG_Z
        ));
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
