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

/// A link inside a root's tree. Its coefficients (`CORNERS × nn` form factors, visibility
/// included, and on a refined surface `CORNERS` more:
/// [`Ctx::link_coefficients`](super::context::Ctx::link_coefficients)) are the tree's `k`, the
/// same number for every link of a root, in the links' order ([`Tree::links_with_k`](super::tree::Tree::links_with_k)).
/// 40 bytes: a million triangles make some eighty million links, so every field counts.
pub(super) struct Link {
    /// The receiver's index in the tree.
    pub(super) recv: u32,
    pub(super) src: PackedSrc,
    /// For a cluster source, the share of each of its parts in what the receiver sees of it
    /// ([`Ctx::cluster_share`](super::context::Ctx::cluster_share)). For an element source, in
    /// its first three, where the link looks ([`Link::aim_over_source`]). A cluster link looks
    /// along the direction light leaves the cluster towards the receiver's centre
    /// ([`Ctx::leaving`](super::context::Ctx::leaving)), found from the tree
    /// ([`Tree::centre`](super::tree::Tree::centre)) rather than held: nine links in ten are cluster links.
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
    /// Fraction of the visibility rays that were clear.
    pub(super) visible: f32,
    /// For a cluster source on a receiver that may split: how far its form factor bends over
    /// the receiver, as the refinement judged it
    /// ([`Ctx::cluster_factors_over`](super::context::Ctx::cluster_factors_over)); NaN where it
    /// was not judged. The geometry's alone, so the next pass reads it here and does not walk
    /// the cluster again (a tenth of the scaling scene's bake).
    pub(super) bend: f32,
}

impl Link {
    /// For an element source: the barycentric coordinates over the source of the centre of the
    /// receiver's view of it ([`Ctx::kernel_centre`](super::context::Ctx::kernel_centre)), or
    /// of its footprint ([`Ctx::footprint`](super::context::Ctx::footprint)).
    pub(super) fn aim_over_source(&self) -> Vec3 {
        Vec3::new(self.share[0], self.share[1], self.share[2])
    }
}

/// What a link joins, by key: its receiver and its source.
pub(super) type Ends = (ElemKey, Source);

/// One root's links as refinement makes them, before the trees that index their ends exist.
/// The links are made once, in the form the solve reads, with their ends' keys beside them
/// until [`RawLinks::resolve`] (their `recv` and element `src` wait for it); a keyed copy
/// converted into a resolved one held both at the bake's memory peak. The keys are held
/// compactly: a receiver's links mostly come one after another, so receivers are runs, and
/// only element sources (a tenth of the links in a large scene) need a key of their own.
#[derive(Default)]
pub(super) struct RawLinks {
    pub(super) links: Vec<Link>,
    /// Per run of links with the same receiver: its key and the run's length.
    recv_runs: Vec<(ElemKey, u32)>,
    /// The keys of the element sources, in the order of their links.
    elem_srcs: Vec<ElemKey>,
    pub(super) k: Vec<f32>,
}

impl RawLinks {
    /// Appends `link` with its ends and coefficients.
    pub(super) fn push(&mut self, link: Link, (recv, src): Ends, k: &[f32]) {
        debug_assert_eq!(
            self.k.len(),
            self.links.len() * k.len(),
            "one length a root"
        );
        self.k.extend_from_slice(k);
        self.links.push(link);
        self.push_recv(recv, 1);
        if let Source::Elem(sk) = src {
            self.elem_srcs.push(sk);
        }
    }

    fn push_recv(&mut self, recv: ElemKey, n: u32) {
        match self.recv_runs.last_mut() {
            Some((k, len)) if *k == recv => *len += n,
            _ => self.recv_runs.push((recv, n)),
        }
    }

    /// Appends every link of `other`, in order.
    pub(super) fn append(&mut self, other: RawLinks) {
        self.links.extend(other.links);
        for (recv, n) in other.recv_runs {
            self.push_recv(recv, n);
        }
        self.elem_srcs.extend(other.elem_srcs);
        self.k.extend(other.k);
    }

    pub(super) fn with_capacity(links: usize, k: usize) -> Self {
        RawLinks {
            links: Vec::with_capacity(links),
            k: Vec::with_capacity(k),
            ..Default::default()
        }
    }

    /// Gives back the slack of vectors grown by doubling: a root's links are held for every
    /// root at once until the trees are built.
    pub(super) fn shrink_to_fit(&mut self) {
        self.links.shrink_to_fit();
        self.recv_runs.shrink_to_fit();
        self.elem_srcs.shrink_to_fit();
        self.k.shrink_to_fit();
    }

    /// Each link's ends, in order.
    pub(super) fn ends(&self) -> impl Iterator<Item = Ends> + '_ {
        let recvs = self
            .recv_runs
            .iter()
            .flat_map(|&(k, n)| std::iter::repeat_n(k, n as usize));
        let mut elems = self.elem_srcs.iter();
        recvs.zip(&self.links).map(move |(recv, l)| {
            let src = match l.src.get() {
                SrcIdx::Cluster(c) => Source::Cluster(c),
                SrcIdx::Node { .. } => {
                    Source::Elem(*elems.next().expect("a key per element source"))
                }
            };
            (recv, src)
        })
    }

    /// The links and coefficients of root `r`'s tree, their ends found by `index_of(root, key)`:
    /// the node of `key` in root `root`'s tree, which holds every key a link names.
    pub(super) fn resolve(
        self,
        r: usize,
        index_of: impl Fn(usize, ElemKey) -> u32,
    ) -> (Vec<Link>, Vec<f32>) {
        let RawLinks {
            mut links,
            recv_runs,
            elem_srcs,
            k,
        } = self;
        let recvs = recv_runs.iter().flat_map(|&(key, n)| {
            let i = index_of(r, key);
            std::iter::repeat_n(i, n as usize)
        });
        let mut elems = elem_srcs.iter();
        for (l, recv) in links.iter_mut().zip(recvs) {
            l.recv = recv;
            if let SrcIdx::Node { root, .. } = l.src.get() {
                let key = elems.next().expect("a key per element source");
                let node = index_of(root as usize, *key);
                l.src = PackedSrc::new(SrcIdx::Node { root, node });
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

/// A [`SrcIdx`] in 8 bytes rather than the enum's 12: a cluster is marked by a root that no
/// scene has (`u32::MAX`; [`Ctx::new`](super::context::Ctx::new) refuses that many roots).
#[derive(Clone, Copy)]
pub(super) struct PackedSrc {
    root: u32,
    index: u32,
}

impl PackedSrc {
    pub(super) fn new(src: SrcIdx) -> Self {
        match src {
            SrcIdx::Cluster(c) => PackedSrc {
                root: u32::MAX,
                index: c,
            },
            SrcIdx::Node { root, node } => PackedSrc { root, index: node },
        }
    }

    pub(super) fn get(self) -> SrcIdx {
        if self.root == u32::MAX {
            SrcIdx::Cluster(self.index)
        } else {
            SrcIdx::Node {
                root: self.root,
                node: self.index,
            }
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn a_link_stays_small() {
        assert_eq!(std::mem::size_of::<Link>(), 40);
    }

    fn link(src: SrcIdx) -> Link {
        Link {
            recv: u32::MAX,
            src: PackedSrc::new(src),
            share: [0.0; READ_PARTS],
            deep: false,
            facing: 0,
            depth: 0,
            visible: 1.0,
            bend: f32::NAN,
        }
    }

    #[test]
    fn raw_links_keep_every_links_ends_through_runs_and_appends() {
        let key = |root, path| ElemKey {
            root,
            level: 1,
            path,
        };
        let ends = [
            (key(0, 0), Source::Cluster(7)),
            (key(0, 0), Source::Elem(key(3, 2))),
            (key(0, 1), Source::Cluster(8)),
            (key(0, 1), Source::Elem(key(4, 1))),
            (key(0, 0), Source::Cluster(9)),
        ];
        let make = |ends: &[Ends]| {
            let mut raw = RawLinks::default();
            for (i, &(recv, src)) in ends.iter().enumerate() {
                let idx = match src {
                    Source::Cluster(c) => SrcIdx::Cluster(c),
                    Source::Elem(k) => SrcIdx::Node {
                        root: k.root,
                        node: u32::MAX,
                    },
                };
                raw.push(link(idx), (recv, src), &[i as f32, 0.5]);
            }
            raw
        };
        let mut raw = make(&ends[..3]);
        raw.append(make(&ends[3..]));
        assert_eq!(raw.ends().collect::<Vec<_>>(), ends);
        assert_eq!(raw.recv_runs.len(), 3);
        assert_eq!(raw.k, [0.0, 0.5, 1.0, 0.5, 2.0, 0.5, 0.0, 0.5, 1.0, 0.5]);
    }

    #[test]
    fn a_packed_source_unpacks_to_itself() {
        for src in [
            SrcIdx::Cluster(0),
            SrcIdx::Cluster(u32::MAX),
            SrcIdx::Node { root: 0, node: 5 },
            SrcIdx::Node {
                root: u32::MAX - 1,
                node: u32::MAX,
            },
        ] {
            let back = PackedSrc::new(src).get();
            match (src, back) {
                (SrcIdx::Cluster(a), SrcIdx::Cluster(b)) => assert_eq!(a, b),
                (SrcIdx::Node { root: a, node: m }, SrcIdx::Node { root: b, node: n }) => {
                    assert_eq!((a, m), (b, n))
                }
                _ => panic!("the kind changed"),
            }
        }
    }
}
