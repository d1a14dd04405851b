//! A link's coefficients: the form factor from the receiver to the source per receiver normal,
//! as a linear function over the receiver (its values at the three corners), times the link's
//! visibility. Clusters count as discs from afar and as their triangles from near.

use glam::Vec3;
use smallvec::{smallvec, SmallVec};

use super::cluster::ClusterChild;
use super::context::Ctx;
use super::element::{jittered_point, split, ElemKey};
use super::formfactor::{point_to_polygon, point_to_polygon_each, stratified_16};
use super::links::{Source, CORNERS};

/// A cluster is one disc in a link's coefficient while its radius is below this fraction of
/// its distance ([`Ctx::cluster_form_factors`]).
pub(super) const CLUSTER_DISC_OPENING: f32 = 0.2;

/// Where a receiver's form factor is sampled for its slope: its corners moved a tenth of the
/// way towards the centroid (a corner on an edge shared with the source sits where the kernel
/// is steepest).
pub(super) const CORNER_INSET: f32 = 0.1;

/// Form factors to a link's source with the receiver's geometric normal, already computed by
/// the rules that decided to make the link: at the receiver's centre, and at its inset corners
/// ([`inset_corners`]).
#[derive(Clone, Copy, Default)]
pub(super) struct KnownFactors {
    pub(super) centre: Option<f32>,
    pub(super) corners: Option<[f32; 3]>,
}

/// A link's coefficients ([`Ctx::link_coefficients`]), on the stack for the default normal
/// sets (eight normals and the refined surface's own at three corners): every link makes one,
/// and its two allocations were a share of the bake's time in `malloc` and `free`.
pub(super) type Coefficients = SmallVec<[f32; 32]>;

pub(super) fn inset_corners(t: [Vec3; 3]) -> [Vec3; CORNERS] {
    let c = (t[0] + t[1] + t[2]) / 3.0;
    t.map(|v| v + (c - v) * CORNER_INSET)
}

/// The linear function over the receiver with mean `mean[j]` for each normal (the link's
/// estimate over the whole receiver) and the relative slope of the geometric normal's values
/// `at` sampled at the inset corners (the slope is the geometry's: distance and angle to the
/// source change alike for every normal), as corner values, never below zero. Corner-major:
/// `out[c * nn + j]`.
pub(super) fn linear_over_receiver(mean: &[f32], at: [f32; CORNERS]) -> Coefficients {
    let nn = mean.len();
    let mut out: Coefficients = smallvec![0.0f32; CORNERS * nn];
    let fm = (at[0] + at[1] + at[2]) / 3.0;
    // Relative change at each corner; none when the geometric normal sees nothing (a source
    // below the coarse plane that only tilted normals see).
    let slope = if fm > 0.0 {
        at.map(|v| (v - fm) / (fm * (1.0 - CORNER_INSET)))
    } else {
        [0.0; CORNERS]
    };
    // A slope steep enough to take a corner below zero is flattened until that corner is zero,
    // keeping the mean (clamping the corner alone would add light).
    let low = slope.iter().copied().fold(0.0f32, f32::min);
    let scale = if low < -1.0 { 1.0 / -low } else { 1.0 };
    for (j, &m) in mean.iter().enumerate() {
        for c in 0..CORNERS {
            out[c * nn + j] = (m * (1.0 + slope[c] * scale)).max(0.0);
        }
    }
    out
}

/// Form factor from a point with normal `n` to a disc of projected area `proj` at squared
/// distance `d2` along unit `w` (how a cluster small against its distance counts).
pub(super) fn disc_factor(n: Vec3, w: Vec3, proj: f32, d2: f32) -> f32 {
    (n.dot(w).max(0.0) * proj / (std::f32::consts::PI * d2 + proj)).min(1.0)
}

impl Ctx<'_> {
    /// Form factor times visibility from receiver `recv` to `src`, per receiver normal. A pair
    /// whose form factor is nowhere positive (a cluster whose box reaches above the receiver's
    /// plane while its triangles lie below it) is dropped by the caller, and casts no rays.
    ///
    /// Returns the coefficients (`CORNERS × nn`, corner-major) and the visible fraction. For a
    /// receiver on a refined surface (its points carried onto it, [`Ctx::on_surface`])
    /// `CORNERS` more follow: the same for that surface's own normal at each point, what the
    /// receiver's normals are filled against ([`Tree::closure`](super::tree::Tree::closure)).
    pub(super) fn link_coefficients(
        &self,
        (recv, rt): (ElemKey, [Vec3; 3]),
        (src, st): (Source, [Vec3; 3]),
        nv: u32,
        known: KnownFactors,
    ) -> (Coefficients, f32) {
        let root = &self.roots[recv.root as usize];
        let nn = root.normals.len();
        let rc = (rt[0] + rt[1] + rt[2]) / 3.0;
        let r_size = (rt[1] - rt[0]).length().max((rt[2] - rt[0]).length());
        let src_id = match src {
            Source::Cluster(c) => 0x8000_0000_0000_0000 | u64::from(c),
            Source::Elem(k) => k.id(),
        };
        let mut k: Coefficients = smallvec![0.0f32; nn];
        let lifted = !self.surface[recv.root as usize].is_empty();
        let mut closure = 0.0f32;
        // Every link comes here: the scratch stays on the stack for the default normal sets
        // (at most eight normals, and the refined surface's own), rather than five allocations
        // a link.
        let mut vis: SmallVec<[f32; 10]> = smallvec![1.0f32; nn + usize::from(lifted)];
        // Per slot of `vis`, the visible fraction at each corner (`[j * CORNERS + c]`).
        let mut at_corner: SmallVec<[f32; 30]> = smallvec![1.0f32; vis.len() * CORNERS];
        match src {
            Source::Elem(sk) => {
                let sc = (st[0] + st[1] + st[2]) / 3.0;
                let s_size = (st[1] - st[0]).length().max((st[2] - st[0]).length());
                // Far pairs: the centroid suffices; near pairs: four stratified points.
                let dist = (sc - rc).length();
                let pts: SmallVec<[Vec3; 16]> = if dist > 3.0 * (r_size + s_size) {
                    smallvec![rc]
                } else if dist > r_size + s_size {
                    split(rt)
                        .iter()
                        .map(|t| (t[0] + t[1] + t[2]) / 3.0)
                        .collect()
                } else {
                    SmallVec::from_slice(&stratified_16(rt))
                };
                // Points and source on the refined surfaces where the objects have them.
                let mut buf = [st; 4];
                let polys = self.source_shape(sk, st, pts.len() > 1, &mut buf);
                // The receiver's normals, and the refined surface's own after them.
                let mut normals: SmallVec<[Vec3; 10]> = root.normals.iter().copied().collect();
                normals.push(Vec3::ZERO);
                let m = nn + usize::from(lifted);
                // Per polygon and normal (`[t * m + j]`), summed over the polygons in order.
                let mut f: SmallVec<[f32; 40]> = smallvec![0.0f32; polys.len() * m];
                for p in &pts {
                    let (p, pn) = self.on_surface(recv.root, *p);
                    normals[nn] = pn;
                    for (t, poly) in polys.iter().enumerate() {
                        point_to_polygon_each(p, &normals[..m], poly, |j, v| f[t * m + j] = v);
                    }
                    for (j, kj) in k.iter_mut().enumerate() {
                        *kj += (0..polys.len()).map(|t| f[t * m + j]).sum::<f32>();
                    }
                    if lifted {
                        closure += (0..polys.len()).map(|t| f[t * m + nn]).sum::<f32>();
                    }
                }
                let inv = 1.0 / pts.len() as f32;
                k.iter_mut().for_each(|v| *v *= inv);
                closure *= inv;
                let at_corners = known.corners.unwrap_or_else(|| {
                    inset_corners(rt).map(|p| point_to_polygon(p, root.normal, &st))
                });
                k = linear_over_receiver(&k, at_corners);
                if lifted {
                    k.extend(linear_over_receiver(&[closure], at_corners));
                }
                if k.iter().all(|&v| v <= 0.0) {
                    return (k, 0.0);
                }
                let sn = self.roots[sk.root as usize].normal;
                let (lo, hi) = (st[0].min(st[1]).min(st[2]), st[0].max(st[1]).max(st[2]));
                if self.certainly_clear(recv, rt, (lo, hi), Some((sn, st[0]))) {
                    return (k, 1.0);
                }
                self.cast_visibility(
                    (recv, rt),
                    src_id,
                    r_size + s_size,
                    nv,
                    (&mut vis, &mut at_corner),
                    |i, rng| (sk.root, jittered_point(st, i, nv, rng)),
                );
            }
            Source::Cluster(c) => {
                let c_size = 2.0 * self.clusters.clusters[c as usize].radius();
                let (centre, at_corners) = match (known.centre, known.corners) {
                    (Some(centre), Some(at)) => (centre, at),
                    _ => self.cluster_factors_over(c, recv, rt, root.normal),
                };
                k[0] = centre;
                let (p, pn) = self.on_surface(recv.root, rc);
                self.cluster_form_factors(c, p, &root.normals[1..], &mut k[1..]);
                k = linear_over_receiver(&k, at_corners);
                if lifted {
                    let mut f = [0.0f32];
                    self.cluster_form_factors(c, p, &[pn], &mut f);
                    k.extend(linear_over_receiver(&f, at_corners));
                }
                if k.iter().all(|&v| v <= 0.0) {
                    return (k, 0.0);
                }
                let cluster = &self.clusters.clusters[c as usize];
                if self.certainly_clear(recv, rt, (cluster.lo, cluster.hi), None) {
                    return (k, 1.0);
                }
                self.cast_visibility(
                    (recv, rt),
                    src_id,
                    r_size + c_size,
                    nv,
                    (&mut vis, &mut at_corner),
                    |i, rng| {
                        // Stratified over the cluster's area as the receiver point is over
                        // the receiver.
                        let u = (i as f32 + rng.next_f32()) / nv as f32;
                        let t = self.clusters.pick(c, u.min(1.0 - f32::EPSILON));
                        (t, jittered_point(self.roots[t as usize].corners, 0, 1, rng))
                    },
                );
            }
        };
        // The visible fraction is linear over the receiver, as the form factor is: a soft
        // shadow's gradient across a link's receiver reaches its leaves, where one fraction
        // for the whole receiver left a step at every receiver's edge (the Cornell box's floor
        // beside the short block, blotchy where the path tracer's penumbra is smooth).
        for (c, row) in k.chunks_mut(nn).take(CORNERS).enumerate() {
            for (j, v) in row.iter_mut().enumerate() {
                *v *= at_corner[j * CORNERS + c];
            }
        }
        if lifted {
            for c in 0..CORNERS {
                k[CORNERS * nn + c] *= at_corner[nn * CORNERS + c];
            }
        }
        (k, vis[0])
    }

    /// Unoccluded form factor from a point `p` with normal `n` to the triangles of cluster
    /// `c`. A cluster small against its distance is one disc of its projected area seen from
    /// its centre; a nearer one is the sum of its children, down to triangles, which are
    /// exact. The link oracle lets a cluster stand for its triangles while its radius is below
    /// `cluster_opening` (one half) times its distance from the receiver's centre; a lone disc
    /// there is 10-20% off, and more at the receiver's corners, which can lie closer (in a
    /// closed furnace, leaves near a cube's corners summed to 8% less or more than the
    /// whole hemisphere, `tests/furnace_property.rs`). The link stays one link; only its
    /// coefficient is summed
    /// finer. Adds the form factor for each of `normals` to `out`.
    pub(super) fn cluster_form_factors(&self, c: u32, p: Vec3, normals: &[Vec3], out: &mut [f32]) {
        if normals.is_empty() {
            return;
        }
        let cluster = &self.clusters.clusters[c as usize];
        let d = cluster.centre - p;
        let d2 = d.length_squared().max(1e-20);
        let dist = d2.sqrt();
        if cluster.radius() < dist * CLUSTER_DISC_OPENING {
            let w = d / dist;
            let proj = self.clusters.projected_area(c, -w);
            for (o, n) in out.iter_mut().zip(normals) {
                *o += disc_factor(*n, w, proj, d2);
            }
            return;
        }
        for ch in cluster.children {
            match ch {
                ClusterChild::Cluster(x) => self.cluster_form_factors(x, p, normals, out),
                ClusterChild::Root(x) => {
                    point_to_polygon_each(p, normals, &self.shape[x as usize], |j, v| {
                        if let Some(o) = out.get_mut(j) {
                            *o += v;
                        }
                    });
                }
            }
        }
    }

    /// [`Ctx::cluster_form_factors`] with normal `n` at the centre of receiver triangle `rt` and
    /// at its inset corners, in one walk of the cluster tree: the centre's, and the corners'.
    /// Each point opens the clusters it would open alone and sums in the same order, so the
    /// four values are those of four walks (but for the disc's area, which the points share).
    pub(super) fn cluster_factors_over(
        &self,
        c: u32,
        recv: ElemKey,
        rt: [Vec3; 3],
        n: Vec3,
    ) -> (f32, [f32; CORNERS]) {
        let [a, b, d] = inset_corners(rt);
        let pts = [(rt[0] + rt[1] + rt[2]) / 3.0, a, b, d].map(|p| self.on_surface(recv.root, p).0);
        let mut out = [0.0f32; 4];
        self.cluster_factors_at(c, &pts, n, 0b1111, &mut out);
        (out[0], [out[1], out[2], out[3]])
    }

    /// Adds to `out[i]` the form factor from point `pts[i]` (normal `n`) to cluster `c`, for
    /// every point `i` whose bit is set in `active`.
    pub(super) fn cluster_factors_at(
        &self,
        c: u32,
        pts: &[Vec3; 4],
        n: Vec3,
        active: u8,
        out: &mut [f32; 4],
    ) {
        let cluster = &self.clusters.clusters[c as usize];
        let mut open = 0u8;
        // The disc's area seen from the first point that takes it, for all: the points are a
        // receiver's, within a fifth of the distance of each other (a sixteenth of the bake's
        // time went to computing it four times).
        let mut proj = None;
        for (i, p) in pts.iter().enumerate() {
            if active & (1 << i) == 0 {
                continue;
            }
            let d = cluster.centre - *p;
            let d2 = d.length_squared().max(1e-20);
            let dist = d2.sqrt();
            if cluster.radius() < dist * CLUSTER_DISC_OPENING {
                let w = d / dist;
                let area = *proj.get_or_insert_with(|| self.clusters.projected_area(c, -w));
                out[i] += disc_factor(n, w, area, d2);
            } else {
                open |= 1 << i;
            }
        }
        if open == 0 {
            return;
        }
        for ch in cluster.children {
            match ch {
                ClusterChild::Cluster(x) => self.cluster_factors_at(x, pts, n, open, out),
                ClusterChild::Root(x) => {
                    let tri = &self.shape[x as usize];
                    for (i, p) in pts.iter().enumerate() {
                        if open & (1 << i) != 0 {
                            out[i] += point_to_polygon(*p, n, tri);
                        }
                    }
                }
            }
        }
    }
}
