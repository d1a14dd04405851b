//! One root's element tree, breadth-first, with its links and solution; push, which hands every
//! node the linear functions its ancestors gathered.

use glam::Vec3;

use super::context::Ctx;
use super::element::ElemKey;
use super::links::{Link, CORNERS};

/// One root's element tree in breadth-first order, with its links and solution.
pub(super) struct Tree {
    pub(super) keys: Vec<ElemKey>,
    /// Index of the first of four children, or `u32::MAX` for a leaf.
    pub(super) child: Vec<u32>,
    pub(super) area: Vec<f32>,
    /// Centroid per node, as the refinement's walk finds it (the same values to the bit): where
    /// a cluster link's light goes ([`Link::share`]).
    pub(super) centre: Vec<Vec3>,
    /// Reflectance per node (used at leaves).
    pub(super) rho: Vec<Vec3>,
    /// Direct-light `H / π` per node and normal (non-zero at direct-pass leaves only).
    pub(super) direct: Vec<Vec3>,
    pub(super) links: Vec<Link>,
    pub(super) k: Vec<f32>,
    /// Per leaf (empty where the root has no refined surface): the form factor its links give
    /// the refined surface's own normal at its points, pushed down to the leaves and averaged
    /// over them (in a closed scene, one). A normal of the receiver's set turned away from the
    /// surface's own sees, through the part of its hemisphere below the surface, the object's
    /// neighbouring patches that the coarse scene does not have there; every form factor it
    /// lacks against this one is filled with the mean radiance the geometric normal gathers,
    /// so that a closed furnace stays exact for every normal.
    pub(super) closure: Vec<f32>,
    /// Per leaf and normal (`self_view[i * nn + j]`; empty where the root has no refined
    /// surface): the form factor from the leaf's centre on the refined surface to the rest of
    /// its own root's refined triangles, which it gathers its own radiance through
    /// ([`Ctx::closure`]).
    pub(super) self_view: Vec<f32>,
    /// Radiance per node and normal.
    pub(super) l: Vec<Vec3>,
    /// Fraction of each node's area that is open, not shut in under other geometry
    /// ([`Ctx::open_fraction`]; interior nodes average their children).
    pub(super) open: Vec<f32>,
    /// Per leaf: the part of its hemisphere that meets the front of a surface, where it is
    /// known exactly ([`Ctx::enclosure`]); negative where it is not.
    pub(super) enclosed: Vec<f32>,
}

impl Tree {
    /// Each link with its coefficients: every link of a root has as many, one after another
    /// in `k` in the links' order.
    pub(super) fn links_with_k(&self) -> impl Iterator<Item = (&Link, &[f32])> {
        let len = self.k.len().checked_div(self.links.len()).unwrap_or(0);
        self.links.iter().zip(self.k.chunks(len.max(1)))
    }

    pub(super) fn index_of(&self, key: ElemKey) -> Option<u32> {
        self.keys
            .binary_search_by(|k| (k.level, k.path).cmp(&(key.level, key.path)))
            .ok()
            .map(|i| i as u32)
    }

    /// The deepest existing node on the way to `key`.
    pub(super) fn deepest_toward(&self, key: ElemKey) -> u32 {
        let mut i = 0u32;
        for d in 0..key.level {
            let c = self.child[i as usize];
            if c == u32::MAX {
                break;
            }
            i = c + key.choice(d);
        }
        i
    }
}

/// The corners of child `c` of the 1-to-4 split as weights of the parent's corners:
/// `(a, b)` is the midpoint of parent corners `a` and `b` (a corner itself when `a == b`).
pub(super) const CHILD_CORNERS: [[(usize, usize); 3]; 4] = [
    [(0, 0), (0, 1), (2, 0)],
    [(0, 1), (1, 1), (1, 2)],
    [(1, 2), (2, 0), (0, 1)],
    [(2, 0), (1, 2), (2, 2)],
];

/// The mean over node `i`'s corners of value `j` of `v`, which holds `width` values per corner
/// of every node, corner-major (`v[(i * CORNERS + corner) * width + j]`): what a leaf gathers
/// from a linear function, its value at the centroid.
pub(super) fn corner_mean<T>(v: &[T], i: usize, j: usize, width: usize) -> T
where
    T: Copy + std::ops::Add<Output = T> + std::ops::Div<f32, Output = T>,
{
    (v[(i * CORNERS) * width + j]
        + v[(i * CORNERS + 1) * width + j]
        + v[(i * CORNERS + 2) * width + j])
        / 3.0
}

/// Push: every node of `t` receives what its ancestors gathered (breadth-first order puts
/// parents first), each child the linear function over its own part. `v` holds `width` values
/// per corner of every node, corner-major (`v[(node * CORNERS + corner) * width + j]`).
pub(super) fn push_linear<T>(t: &Tree, v: &mut [T], width: usize)
where
    T: Copy + std::ops::Add<Output = T> + std::ops::Mul<f32, Output = T> + std::ops::AddAssign,
{
    for i in 0..t.keys.len() {
        let first = t.child[i];
        if first == u32::MAX {
            continue;
        }
        for (ch, corners) in (first as usize..first as usize + 4).zip(CHILD_CORNERS) {
            for (cc, (a, b)) in corners.into_iter().enumerate() {
                let (pa, pb) = ((i * CORNERS + a) * width, (i * CORNERS + b) * width);
                let to = (ch * CORNERS + cc) * width;
                for j in 0..width {
                    let x = (v[pa + j] + v[pb + j]) * 0.5;
                    v[to + j] += x;
                }
            }
        }
    }
}

impl Ctx<'_> {
    /// Builds root `r`'s tree from the keys that must exist.
    pub(super) fn build_tree(
        &self,
        r: u32,
        mut keys: Vec<ElemKey>,
        direct: &[(ElemKey, Vec<Vec3>)],
    ) -> Tree {
        let nn = self.nn(r);
        keys.push(ElemKey::root(r));
        keys.extend(direct.iter().map(|(k, _)| *k));
        // Close under ancestors, then give every split node all four children.
        let mut all: Vec<ElemKey> = Vec::with_capacity(keys.len() * 2);
        for k in keys {
            let mut k = Some(k);
            while let Some(x) = k {
                all.push(x);
                k = x.parent();
            }
        }
        all.sort_by_key(|k| (k.level, k.path));
        all.dedup();
        let parents: Vec<ElemKey> = all.iter().filter_map(|k| k.parent()).collect();
        for p in parents {
            for c in 0..4 {
                all.push(p.child(c));
            }
        }
        all.sort_by_key(|k| (k.level, k.path));
        all.dedup();
        // Made for every key a link named, duplicates and ancestors included, and kept as the
        // tree's keys.
        all.shrink_to_fit();
        let n = all.len();
        let mut tree = Tree {
            child: vec![u32::MAX; n],
            area: all
                .iter()
                .map(|k| self.roots[r as usize].area / 4f32.powi(k.level as i32))
                .collect(),
            centre: all
                .iter()
                .map(|&k| {
                    let t = self.elem_corners(k);
                    (t[0] + t[1] + t[2]) / 3.0
                })
                .collect(),
            rho: vec![Vec3::ZERO; n],
            open: vec![1.0; n],
            enclosed: vec![-1.0; n],
            direct: vec![Vec3::ZERO; n * nn],
            links: Vec::new(),
            k: Vec::new(),
            closure: Vec::new(),
            self_view: Vec::new(),
            l: vec![Vec3::ZERO; n * nn],
            keys: all,
        };
        for i in 1..n {
            let p = tree.keys[i].parent().expect("non-root has a parent");
            let pi = tree.index_of(p).expect("ancestors are present") as usize;
            if tree.keys[i].path % 4 == 0 {
                tree.child[pi] = i as u32;
            }
        }
        for i in 0..n {
            if tree.child[i] == u32::MAX {
                tree.rho[i] = self.reflectance(tree.keys[i]);
                let k = tree.keys[i];
                tree.open[i] = self.memo(k, |m| &mut m.open, || self.open_fraction(k));
                let o = tree.open[i];
                tree.enclosed[i] = self.memo(k, |m| &mut m.enclosed, || self.enclosure(k, o));
            }
        }
        for i in (0..n).rev() {
            let c = tree.child[i];
            if c != u32::MAX {
                tree.open[i] = (c as usize..c as usize + 4)
                    .map(|ch| tree.open[ch])
                    .sum::<f32>()
                    * 0.25;
            }
        }
        for (k, q) in direct {
            let i = tree.index_of(*k).expect("direct keys are present") as usize;
            tree.direct[i * nn..(i + 1) * nn].copy_from_slice(q);
        }
        tree
    }
}
