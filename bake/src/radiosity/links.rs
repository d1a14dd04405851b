//! Links: a receiver element, a source (an element or a cluster), and the coefficients that carry
//! the source's radiance to the receiver, linear over the receiver.

use glam::Vec3;

use super::cluster::READ_PARTS;
use super::element::ElemKey;

/// A link's coefficients are a linear function over its receiver, stored as its values at the
/// receiver's three corners (per normal: `k[c * nn + j]`). A constant per link, pushed down to
/// every leaf below its receiver, gives a leaf near the edge of a large receiver that
/// receiver's average form factor rather than its own: next to a wall, where the form factor to
/// the wall rises towards one half and those to everything else fall, the leaves summed up to
/// 10% more than the whole hemisphere in a closed furnace and came out 13% too bright (issue
/// 20). With the first-order variation of every link kept, the push hands each child the
/// coefficient over its own part of the receiver, and what remains is curvature.
pub(super) const CORNERS: usize = 3;

/// A link source.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Hash)]
pub(super) enum Source {
    Cluster(u32),
    Elem(ElemKey),
}

/// A link as refinement produces it; `k[nn]` form factors (visibility included) per normal.
pub(super) struct RawLink {
    pub(super) recv: ElemKey,
    pub(super) src: Source,
    /// Where the link looks: for a cluster source, the direction light leaves it towards the
    /// receiver; for an element source, the barycentric coordinates over the source of the
    /// centre of the receiver's view of it
    /// ([`Ctx::kernel_centre`](super::context::Ctx::kernel_centre)).
    pub(super) aim: Vec3,
    /// For a cluster source, the share of each of its parts in what the receiver sees of it
    /// ([`Ctx::cluster_share`](super::context::Ctx::cluster_share)); unused for an element source.
    pub(super) share: [f32; READ_PARTS],
    /// For a cluster source: whether its parts are its
    /// [`READ_DEPTH`](super::cluster::READ_DEPTH)-level descendants
    /// ([`Ctx::reads_deep`](super::context::Ctx::reads_deep)) rather than its two children.
    pub(super) deep: bool,
    /// For an element source: which of its normals' radiance it sends towards the receiver
    /// ([`Ctx::facing_normal`](super::context::Ctx::facing_normal)); 0 for a cluster.
    pub(super) facing: u8,
    /// For an element source: how many levels below it the receiver's view is read
    /// ([`Ctx::footprint`](super::context::Ctx::footprint)); 0 for a cluster.
    pub(super) depth: u8,
    pub(super) k_start: u32,
    /// Fraction of the visibility rays that were clear.
    pub(super) visible: f32,
    /// For a cluster source on a receiver that may split: how far its form factor bends over
    /// the receiver, as the refinement judged it
    /// ([`Ctx::cluster_factors_over`](super::context::Ctx::cluster_factors_over)); NaN where it
    /// was not judged. The geometry's alone, so the next pass reads it here and does not walk
    /// the cluster again (a tenth of the scaling scene's bake).
    pub(super) bend: f32,
}

/// A resolved link inside a root's tree.
pub(super) struct Link {
    pub(super) recv: u32,
    pub(super) src: SrcIdx,
    /// As in [`RawLink`].
    pub(super) aim: Vec3,
    pub(super) share: [f32; READ_PARTS],
    pub(super) deep: bool,
    pub(super) facing: u8,
    pub(super) depth: u8,
    pub(super) k_start: u32,
    pub(super) visible: f32,
    pub(super) bend: f32,
}

#[derive(Clone, Copy)]
pub(super) enum SrcIdx {
    Cluster(u32),
    Node { root: u32, node: u32 },
}
