//! Links: a receiver element, a source (an element or a cluster), and the coefficients that carry
//! the source's radiance to the receiver, linear over the receiver.

use glam::Vec3;

use super::cluster::READ_PARTS;
use super::element::ElemKey;
use super::tree::Tree;

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

/// A link inside a root's tree; `k_start` is where its coefficients start in the tree's `k`
/// (`CORNERS × nn` form factors, visibility included, and on a refined surface `CORNERS` more:
/// [`Ctx::link_coefficients`](super::context::Ctx::link_coefficients)).
pub(super) struct Link {
    /// The receiver's index in the tree.
    pub(super) recv: u32,
    pub(super) src: SrcIdx,
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

/// What a link joins, by key: its receiver and its source.
pub(super) type Ends = (ElemKey, Source);

/// One root's links as refinement makes them, before the trees that index their ends exist:
/// `ends[i]` names the ends of `links[i]`, whose `recv` and element `src` wait for
/// [`RawLinks::resolve`]. The links are made once, in the form the solve reads, with their
/// keys beside them; a keyed copy converted into a resolved one held both at the bake's memory
/// peak (72 and 60 bytes a link).
#[derive(Default)]
pub(super) struct RawLinks {
    pub(super) links: Vec<Link>,
    pub(super) ends: Vec<Ends>,
    pub(super) k: Vec<f32>,
}

impl RawLinks {
    /// Appends `link` with its ends and coefficients; sets its `k_start`.
    pub(super) fn push(&mut self, mut link: Link, ends: Ends, k: &[f32]) {
        link.k_start = self.k.len() as u32;
        self.k.extend_from_slice(k);
        self.links.push(link);
        self.ends.push(ends);
    }

    /// Appends every link of `other`, in order.
    pub(super) fn append(&mut self, other: RawLinks) {
        let offset = self.k.len() as u32;
        self.links.extend(other.links.into_iter().map(|mut l| {
            l.k_start += offset;
            l
        }));
        self.ends.extend(other.ends);
        self.k.extend(other.k);
    }

    pub(super) fn with_capacity(links: usize, k: usize) -> Self {
        RawLinks {
            links: Vec::with_capacity(links),
            ends: Vec::with_capacity(links),
            k: Vec::with_capacity(k),
        }
    }

    /// Gives back the slack of vectors grown by doubling: a root's links are held for every
    /// root at once until the trees are built.
    pub(super) fn shrink_to_fit(&mut self) {
        self.links.shrink_to_fit();
        self.ends.shrink_to_fit();
        self.k.shrink_to_fit();
    }

    /// The links and coefficients of root `r`'s tree, their ends found in `trees` (which hold
    /// every key a link names).
    pub(super) fn resolve(self, r: usize, trees: &[Tree]) -> (Vec<Link>, Vec<f32>) {
        let RawLinks { mut links, ends, k } = self;
        for (l, (recv, src)) in links.iter_mut().zip(ends) {
            l.recv = trees[r].index_of(recv).expect("receiver present");
            if let Source::Elem(k) = src {
                l.src = SrcIdx::Node {
                    root: k.root,
                    node: trees[k.root as usize].index_of(k).expect("source present"),
                };
            }
        }
        (links, k)
    }
}

/// A link's source in the trees. While a link waits for [`RawLinks::resolve`], an element
/// source's `node` is not yet known.
#[derive(Clone, Copy)]
pub(super) enum SrcIdx {
    Cluster(u32),
    Node { root: u32, node: u32 },
}
