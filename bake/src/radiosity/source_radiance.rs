//! The radiance a link reads from a source element: the light it sends from its open part only,
//! read where the receiver looks (the kernel's centre, or the node under the receiver's
//! footprint for a near, large source) and with the normal of its set that faces the receiver.

use glam::Vec3;

use super::context::Ctx;
use super::element::{child_toward, ElemKey};
use super::formfactor::stratified_16;
use super::tree::Tree;

impl Ctx<'_> {
    /// Radiance (normal 0) that node `i` of root `r`'s tree sends out. Its stored value is
    /// the area average that a viewer sees; but light leaves only from the open part of the
    /// element (see [`Ctx::open_fraction`]): the part of a floor element under a block
    /// standing on it receives nothing and sends nothing. Links already give that part no
    /// weight (a receiver finds it behind the block or behind its own plane), so the power
    /// the element reflects must be spread over the open part alone, or the light it sends
    /// is cut once by the dark part in the average and again by the link. Emission is
    /// uniform over the element and is not diluted.
    pub(super) fn source_radiance(&self, r: u32, t: &Tree, i: usize) -> Vec3 {
        self.source_radiance_for(r, t, i, 0)
    }

    /// [`Ctx::source_radiance`] for normal `j` of the root's set.
    pub(super) fn source_radiance_for(&self, r: u32, t: &Tree, i: usize, j: usize) -> Vec3 {
        let o = t.open[i];
        if o <= 0.0 {
            return Vec3::ZERO;
        }
        let le = self.roots[r as usize].emission;
        le + (t.l[i * self.nn(r) + j] - le) / o
    }

    /// The radiance (normal 0) a link gathers from node `i` of root `r`'s tree, looking at the
    /// point with barycentric coordinates `aim` over it ([`Ctx::kernel_centre`]): the node's
    /// own ([`Ctx::source_radiance`]) where it is a leaf; else the linear function over it
    /// whose corner children have their radiances, read there, held between its children's
    /// least and greatest. A link to a large source whose radiance varies gathered its mean,
    /// where the receiver sees one part of it more than another: a lit room's floor is
    /// brightest under the light, which the ceiling above sees most of, and the room's walls
    /// and ceiling came out 1-2% too dark against a path tracer
    /// (`tests/objects_reference.rs`).
    ///
    /// With `aᵢ` the corner children's (Top, Left, Right) radiances and `m` the node's, a
    /// linear function with those child means is `m + 2 Σ (bᵢ − 1/3) aᵢ` at `b`.
    pub(super) fn seen_radiance(
        &self,
        r: u32,
        t: &Tree,
        (mut i, depth): (usize, u8),
        mut aim: Vec3,
        j: usize,
    ) -> Vec3 {
        // Down to the node under the receiver's footprint ([`Ctx::footprint`]).
        for _ in 0..depth {
            let c = t.child[i];
            if c == u32::MAX {
                break;
            }
            let (k, local) = child_toward(aim);
            i = c as usize + k;
            aim = local;
        }
        let mean = self.source_radiance_for(r, t, i, j);
        let c = t.child[i];
        if c == u32::MAX {
            return mean;
        }
        let c = c as usize;
        let kids = [c, c + 1, c + 2, c + 3].map(|k| self.source_radiance_for(r, t, k, j));
        let (lo, hi) = kids
            .iter()
            .fold((mean, mean), |(lo, hi), k| (lo.min(*k), hi.max(*k)));
        let tilt = (kids[0] * (aim.x - 1.0 / 3.0)
            + kids[1] * (aim.y - 1.0 / 3.0)
            + kids[3] * (aim.z - 1.0 / 3.0))
            * 2.0;
        (mean + tilt).clamp(lo, hi)
    }

    /// Where in source element `sk` (corners `st`) a receiver at `p` with normal `n` looks:
    /// the barycentric coordinates over the source of its children's centroids, each weighed
    /// by its form factor from `p` as a disc (`A cos cos / (π d² + A)`), for
    /// [`Ctx::seen_radiance`]. The source's centroid where none is in front of `p`.
    pub(super) fn kernel_centre(&self, p: Vec3, n: Vec3, sk: ElemKey, st: [Vec3; 3]) -> Vec3 {
        let sn = self.roots[sk.root as usize].normal;
        let area = self.roots[sk.root as usize].area / 4f32.powi(sk.level as i32 + 1);
        // The children's centroids in the split order (Top, Left, Center, Right), as
        // barycentric coordinates of the source.
        const CENTROIDS: [[f32; 3]; 4] = [
            [4.0 / 6.0, 1.0 / 6.0, 1.0 / 6.0],
            [1.0 / 6.0, 4.0 / 6.0, 1.0 / 6.0],
            [1.0 / 3.0, 1.0 / 3.0, 1.0 / 3.0],
            [1.0 / 6.0, 1.0 / 6.0, 4.0 / 6.0],
        ];
        let (mut sum, mut total) = (Vec3::ZERO, 0.0f32);
        for b in CENTROIDS {
            let b = Vec3::from(b);
            let q = st[0] * b.x + st[1] * b.y + st[2] * b.z;
            let v = q - p;
            let d2 = v.length_squared();
            let w = n.dot(v).max(0.0) * (-sn.dot(v)).max(0.0)
                / (d2 * (std::f32::consts::PI * d2 + area)).max(f32::MIN_POSITIVE);
            sum += b * w;
            total += w;
        }
        if total > 0.0 && sum.is_finite() {
            sum / total
        } else {
            Vec3::splat(1.0 / 3.0)
        }
    }

    /// How far below source element `sk` (corners `st`) a receiver centred at `p` with normal
    /// `n` reads its radiance, and where: a receiver whose view of the source is centred
    /// nearer than a quarter of the source's size sees mostly the part of it around that
    /// centre (seen from a height `d`, a plane sends 80% of what a point gathers from it from
    /// within `2d` of the foot), so its link reads the node of about four times that distance
    /// there, `depth` levels down, at the centre's barycentric coordinates (the kernel
    /// `cos cos / r²` weighed over sixteen stratified points of the source, clamped into it).
    /// `(0, _)` otherwise.
    ///
    /// A link to a large near source gathered its mean, where its receiver sees the part in
    /// front of it: under a slab floating 10 cm above a lit floor, the floor saw the slab's
    /// whole underside, rim lit by the floor around it, where it looks at the dark middle,
    /// and came out 21% too bright (`tests/contact_shadows.rs`). Refinement does not split
    /// such a source: its variation comes from light that has bounced, which the last pass
    /// judges by the previous solution, where the source was still one leaf.
    pub(super) fn footprint(&self, p: Vec3, n: Vec3, sk: ElemKey, st: [Vec3; 3]) -> (u8, Vec3) {
        let sn = self.roots[sk.root as usize].normal;
        let size = (st[1] - st[0])
            .length()
            .max((st[2] - st[1]).length())
            .max((st[0] - st[2]).length());
        if sn.dot(p - st[0]).abs() * 4.0 >= size || size <= 0.0 {
            return (0, Vec3::ZERO);
        }
        // The kernel's centre over sixteen stratified points of the source.
        let (mut sum, mut total) = (Vec3::ZERO, 0.0f32);
        for q in stratified_16(st) {
            let v = q - p;
            let d2 = v.length_squared().max(f32::MIN_POSITIVE);
            let w = n.dot(v).max(0.0) * (-sn.dot(v)).max(0.0) / (d2 * d2);
            sum += q * w;
            total += w;
        }
        if total <= 0.0 || !sum.is_finite() {
            return (0, Vec3::ZERO);
        }
        let q = sum / total;
        let dist = (q - p).length();
        if dist * 4.0 >= size {
            return (0, Vec3::ZERO);
        }
        let depth = (size / (4.0 * dist.max(size * 1e-4)))
            .log2()
            .floor()
            .clamp(0.0, 15.0) as u8;
        // Barycentric coordinates of the centre over the source.
        let area2 = (st[1] - st[0]).cross(st[2] - st[0]).dot(sn);
        if depth == 0 || area2.abs() <= f32::MIN_POSITIVE {
            return (0, Vec3::ZERO);
        }
        let b = Vec3::new(
            (st[1] - q).cross(st[2] - q).dot(sn),
            (st[2] - q).cross(st[0] - q).dot(sn),
            (st[0] - q).cross(st[1] - q).dot(sn),
        ) / area2;
        let b = b.max(Vec3::ZERO);
        let sum = b.x + b.y + b.z;
        (
            depth,
            if sum > 0.0 {
                b / sum
            } else {
                Vec3::splat(1.0 / 3.0)
            },
        )
    }
}
