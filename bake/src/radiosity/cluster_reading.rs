//! What a link to a cluster reads of it: per cluster the radiance its faces send towards each
//! axis direction ([`ClusterLight`]), and for a near cluster its parts apart, each by its share
//! of what the receiver sees. A cluster's light is its roots' as
//! [`source_radiance`](super::source_radiance) reads them, so the radiance of any source, element
//! or cluster ([`Ctx::src_radiance`]), is read here.

use glam::Vec3;

use super::cluster::{ClusterChild, READ_PARTS};
use super::context::Ctx;
use super::links::Source;
use super::tree::Tree;

/// A cluster whose radius is at least this fraction of its distance from the receiver is read
/// in parts ([`Ctx::reads_deep`]).
pub(super) const DEEP_READ: f32 = 0.25;

/// What a cluster radiates (normal 0): its faces' radiance times their open area, summed
/// separately for the faces turned towards each of +x, −x, +y, −y, +z, −z (weighed by the
/// cosine), and those weights. Seen from a direction, a cluster shows the faces turned that
/// way: a plain area average also counted the faces turned away or edge-on (the ceiling's own
/// triangles in a cluster that a ceiling element gathers from, the dark undersides of objects),
/// and rooms came out 2-6% darker than a path tracer shows them (`tests/objects_reference.rs`).
#[derive(Clone, Copy, Debug, Default)]
pub(super) struct ClusterLight {
    pub(super) radiance: [Vec3; 6],
    pub(super) weight: [f32; 6],
    /// Plain sums over the open area, for a direction no face is turned to.
    pub(super) all: Vec3,
    pub(super) area: f32,
}

impl ClusterLight {
    pub(super) fn add(&mut self, o: &ClusterLight) {
        for i in 0..6 {
            self.radiance[i] += o.radiance[i];
            self.weight[i] += o.weight[i];
        }
        self.all += o.all;
        self.area += o.area;
    }

    pub(super) fn add_face(&mut self, l: Vec3, area: f32, n: Vec3) {
        for (a, c) in n.to_array().into_iter().enumerate() {
            let i = if c >= 0.0 { 2 * a } else { 2 * a + 1 };
            self.radiance[i] += l * (area * c.abs());
            self.weight[i] += area * c.abs();
        }
        self.all += l * area;
        self.area += area;
    }

    /// The radiance leaving in unit direction `w`: the faces turned towards `w`, each axis
    /// weighed by how much `w` lies along it (zero `w`: every face alike).
    pub(super) fn toward(&self, w: Vec3) -> Vec3 {
        let (mut l, mut a) = (Vec3::ZERO, 0.0f32);
        for (axis, c) in w.to_array().into_iter().enumerate() {
            let i = if c >= 0.0 { 2 * axis } else { 2 * axis + 1 };
            l += self.radiance[i] * c.abs();
            a += self.weight[i] * c.abs();
        }
        if a > 0.0 {
            l / a
        } else if self.area > 0.0 {
            self.all / self.area
        } else {
            Vec3::ZERO
        }
    }
}

impl Ctx<'_> {
    /// Cluster radiances (normal 0), bottom-up: per cluster the sums of radiance times open
    /// area turned towards each of ±x, ±y, ±z ([`ClusterLight`]).
    pub(super) fn cluster_radiance(&self, trees: &[Tree]) -> Vec<ClusterLight> {
        let cs = &self.clusters.clusters;
        let mut out = vec![ClusterLight::default(); cs.len()];
        // Children are created after their parent, so reverse order is bottom-up.
        for c in (0..cs.len()).rev() {
            let mut sum = ClusterLight::default();
            for ch in cs[c].children {
                match ch {
                    ClusterChild::Cluster(x) => sum.add(&out[x as usize]),
                    ClusterChild::Root(x) => {
                        let t = &trees[x as usize];
                        // Its radiance is that of its open surface, as for an element (see
                        // `source_radiance`).
                        let root = &self.roots[x as usize];
                        sum.add_face(
                            self.source_radiance(x, t, 0),
                            t.open[0] * root.area,
                            root.normal,
                        );
                    }
                }
            }
            out[c] = sum;
        }
        out
    }

    /// Radiance (normal 0) of a source in the previous solution.
    /// `at` is the receiver's point: a cluster's radiance is that of its faces turned towards it.
    pub(super) fn src_radiance(
        &self,
        trees: &[Tree],
        cl: &[ClusterLight],
        s: Source,
        at: Vec3,
    ) -> Vec3 {
        match s {
            Source::Cluster(c) => cl[c as usize].toward(self.leaving(c, at)),
            Source::Elem(k) => {
                let t = &trees[k.root as usize];
                self.source_radiance(k.root, t, t.deepest_toward(k) as usize)
            }
        }
    }

    /// The unit direction in which light leaves cluster `c` towards the point `at`.
    pub(super) fn leaving(&self, c: u32, at: Vec3) -> Vec3 {
        (at - self.clusters.clusters[c as usize].centre).normalize_or_zero()
    }

    /// Whether a link from cluster `c` to a receiver centred at `p` reads the cluster in its
    /// [`READ_DEPTH`](super::cluster::READ_DEPTH)-level parts rather than its two children: a
    /// cluster near enough for its
    /// radius to be [`DEEP_READ`] of its distance or more. Linked whole up to
    /// `cluster_opening` (a half), it read its two children's mean where the receiver sees one
    /// part of them most: a closed room lit from the middle of its ceiling is brightest in
    /// the middle of its floor, which the ceiling's middle sees square on, and the power the
    /// room's surfaces sent through their links fell 0.6% short of what they reflect (walls
    /// and ceiling 0.7% dark against a path tracer; read by parts, 0.35%:
    /// `tests/solver.rs`, `a_lit_closed_room_agrees_with_the_path_tracer`).
    pub(super) fn reads_deep(&self, c: u32, p: Vec3) -> bool {
        let cluster = &self.clusters.clusters[c as usize];
        cluster.radius() >= DEEP_READ * (cluster.centre - p).length()
    }

    /// The parts of cluster `c` a link reads apart, and how many there are: its
    /// [`READ_DEPTH`](super::cluster::READ_DEPTH)-level descendants where it reads `deep`
    /// ([`read_parts`](super::cluster::read_parts)), else its two
    /// children.
    pub(super) fn cluster_parts(&self, c: u32, deep: bool) -> ([ClusterChild; READ_PARTS], usize) {
        if deep {
            let (parts, count) = self.read_parts[c as usize];
            (parts, usize::from(count))
        } else {
            let [a, b] = self.clusters.clusters[c as usize].children;
            let mut parts = [a; READ_PARTS];
            parts[1] = b;
            (parts, 2)
        }
    }

    /// How much of what a receiver at `p` with normal `n` sees of cluster `c` is each of its
    /// parts' ([`Ctx::cluster_parts`]; `deep`, as [`Ctx::reads_deep`] says): each part as a
    /// disc of its front-facing open area at its centre (`cos A / (π d² + A)`), for
    /// [`Ctx::cluster_seen`]. Alike where it sees none.
    pub(super) fn cluster_share(
        &self,
        trees: &[Tree],
        c: u32,
        p: Vec3,
        n: Vec3,
        deep: bool,
    ) -> [f32; READ_PARTS] {
        let weigh = |ch: ClusterChild| {
            let (centre, area) = match ch {
                ClusterChild::Cluster(x) => {
                    let centre = self.clusters.clusters[x as usize].centre;
                    let w = (p - centre).normalize_or_zero();
                    (centre, self.clusters.projected_area(x, w))
                }
                ClusterChild::Root(x) => {
                    let root = &self.roots[x as usize];
                    let centre = (root.corners[0] + root.corners[1] + root.corners[2]) / 3.0;
                    let w = (p - centre).normalize_or_zero();
                    let open = trees[x as usize].open[0];
                    (centre, root.area * open * root.normal.dot(w).max(0.0))
                }
            };
            let v = centre - p;
            let d2 = v.length_squared().max(1e-20);
            n.dot(v / d2.sqrt()).max(0.0) * area / (std::f32::consts::PI * d2 + area)
        };
        let (parts, count) = self.cluster_parts(c, deep);
        let mut w = [0.0f32; READ_PARTS];
        for (x, part) in w.iter_mut().zip(&parts[..count]) {
            *x = weigh(*part);
        }
        let sum: f32 = w.iter().sum();
        if sum > 0.0 {
            w.map(|x| x / sum)
        } else {
            let mut even = [0.0f32; READ_PARTS];
            even[..count].fill(1.0 / count as f32);
            even
        }
    }

    /// The radiance (normal 0) a link gathers from cluster `c` in direction `w`: its parts'
    /// ([`Ctx::cluster_parts`]; [`ClusterLight::toward`], a root triangle's own), each by its
    /// `share` of the receiver's view ([`Ctx::cluster_share`]). The cluster's own average weighs
    /// its
    /// triangles by their areas turned towards `w` alone, which is right from afar; from a
    /// receiver that sees one child closer, or square on, the other edge-on, that child
    /// brings more (a lit room's walls and ceiling gathered 0.3% too little from clusters of
    /// the floor, `tests/gathered_light.rs`).
    pub(super) fn cluster_seen(
        &self,
        trees: &[Tree],
        cl: &[ClusterLight],
        c: u32,
        w: Vec3,
        share: &[f32; READ_PARTS],
        deep: bool,
    ) -> Vec3 {
        let radiance = |ch: ClusterChild| match ch {
            ClusterChild::Cluster(x) => cl[x as usize].toward(w),
            ClusterChild::Root(x) => self.source_radiance(x, &trees[x as usize], 0),
        };
        let (parts, count) = self.cluster_parts(c, deep);
        parts[..count]
            .iter()
            .zip(share)
            .fold(Vec3::ZERO, |sum, (part, s)| sum + radiance(*part) * *s)
    }
}
