//! Elements of the radiosity hierarchy: a coarse triangle and its 1-to-4 subdivisions, named
//! by a key (root triangle, level, path) so that any element's geometry can be computed without
//! storing it, and deterministic hash-based sampling.
//!
//! The split and child order are those of `hce_format::model`: Top `(v0, m01, m20)`, Left
//! `(m01, v1, m12)`, Center `(m12, m20, m01)`, Right `(m20, m12, v2)`.

use glam::Vec3;

// Elements are nodes of the HCE tree, so no element is deeper than the format's
// `hce_format::MAX_TREE_DEPTH`; [`ElemKey::id`] packs paths of two bits per level into 28 bits.
const _: () = assert!(2 * hce_format::MAX_TREE_DEPTH <= 28);

/// Splits a triangle 1-to-4 in the model's child order.
pub fn split(t: [Vec3; 3]) -> [[Vec3; 3]; 4] {
    let [v0, v1, v2] = t;
    let m01 = (v0 + v1) * 0.5;
    let m12 = (v1 + v2) * 0.5;
    let m20 = (v2 + v0) * 0.5;
    [
        [v0, m01, m20],
        [m01, v1, m12],
        [m12, m20, m01],
        [m20, m12, v2],
    ]
}

/// Child `c` of [`split`], the same values to the bit, without building the other three. The
/// ray loop takes one child per level: picking it out of `split`'s array went through memory,
/// whose partial reloads of the triangle just stored stalled it (a fifth of a bake's time).
#[inline]
fn split_child(t: [Vec3; 3], c: u32) -> [Vec3; 3] {
    let [v0, v1, v2] = t;
    let m01 = (v0 + v1) * 0.5;
    let m12 = (v1 + v2) * 0.5;
    let m20 = (v2 + v0) * 0.5;
    match c {
        0 => [v0, m01, m20],
        1 => [m01, v1, m12],
        2 => [m12, m20, m01],
        _ => [m20, m12, v2],
    }
}

/// An element: root triangle (scene-global index), level and path (first choice most
/// significant, as in the model's path numbering).
#[derive(Clone, Copy, Debug, PartialEq, Eq, PartialOrd, Ord, Hash)]
pub struct ElemKey {
    pub root: u32,
    pub level: u32,
    pub path: u32,
}

impl ElemKey {
    pub fn root(root: u32) -> Self {
        ElemKey {
            root,
            level: 0,
            path: 0,
        }
    }

    pub fn child(self, c: u32) -> Self {
        ElemKey {
            root: self.root,
            level: self.level + 1,
            path: self.path * 4 + c,
        }
    }

    pub fn parent(self) -> Option<Self> {
        (self.level > 0).then(|| ElemKey {
            root: self.root,
            level: self.level - 1,
            path: self.path / 4,
        })
    }

    /// Child index taken at depth `d` (0-based) on the way down.
    pub fn choice(self, d: u32) -> u32 {
        (self.path >> (2 * (self.level - 1 - d))) & 3
    }

    /// Whether `self` is `other` or one of its descendants.
    pub fn within(self, other: Self) -> bool {
        self.root == other.root
            && self.level >= other.level
            && (self.path >> (2 * (self.level - other.level))) == other.path
    }

    /// A stable 64-bit id for hashing.
    pub fn id(self) -> u64 {
        (u64::from(self.root) << 32) | (u64::from(self.level) << 28) | u64::from(self.path)
    }

    /// Corners of the element inside its root triangle `root_corners`.
    pub fn corners(self, root_corners: [Vec3; 3]) -> [Vec3; 3] {
        let mut t = root_corners;
        for d in 0..self.level {
            t = split(t)[self.choice(d) as usize];
        }
        t
    }

    /// Barycentric coordinates of the element's corners in its root triangle.
    pub fn barycentric(self) -> [[f32; 3]; 3] {
        let c = self.corners([Vec3::X, Vec3::Y, Vec3::Z]);
        c.map(|v| v.to_array())
    }

    /// The element of level `level` of root `root` that holds the point of barycentric
    /// coordinates `b` in the root, or `None` for a point outside it. A point on a border
    /// between two elements goes to the first of Top, Left, Right that holds it, else Center.
    pub fn containing(root: u32, level: u32, b: Vec3) -> Option<Self> {
        if b.min_element() < 0.0 {
            return None;
        }
        let mut b = b;
        let mut k = ElemKey::root(root);
        for _ in 0..level {
            let (c, nb) = child_toward(b);
            k = k.child(c as u32);
            b = nb;
        }
        Some(k)
    }

    /// The elements of the same level that share an edge with this one inside its root (none
    /// across the root's own edges): up to three.
    pub fn edge_neighbours(self) -> impl Iterator<Item = Self> {
        let t = self.barycentric().map(Vec3::from_array);
        let c = (t[0] + t[1] + t[2]) / 3.0;
        [(0, 1), (1, 2), (2, 0)]
            .into_iter()
            .filter_map(move |(i, j)| {
                // Just across the edge's midpoint, a twelfth of the element's height beyond it.
                let m = (t[i] + t[j]) * 0.5;
                Self::containing(self.root, self.level, m + (m - c) * 0.25)
            })
    }
}

/// SplitMix64 finaliser: a good 64-bit mixing function.
pub fn mix64(mut z: u64) -> u64 {
    z = z.wrapping_add(0x9e37_79b9_7f4a_7c15);
    z = (z ^ (z >> 30)).wrapping_mul(0xbf58_476d_1ce4_e5b9);
    z = (z ^ (z >> 27)).wrapping_mul(0x94d0_49bb_1331_11eb);
    z ^ (z >> 31)
}

/// Deterministic random stream seeded by the ids of what is sampled, never by thread.
pub struct Rng(u64);

impl Rng {
    pub fn new(a: u64, b: u64, c: u64) -> Self {
        Rng(mix64(mix64(mix64(a) ^ b) ^ c))
    }

    pub fn next_u64(&mut self) -> u64 {
        self.0 = self.0.wrapping_add(0x9e37_79b9_7f4a_7c15);
        mix64(self.0)
    }

    /// Uniform in `[0, 1)`.
    pub fn next_f32(&mut self) -> f32 {
        (self.next_u64() >> 40) as f32 * (1.0 / (1u64 << 24) as f32)
    }
}

/// The child of a split triangle (Top, Left, Center, Right: [`split`]) holding the point of
/// barycentric coordinates `b`, and the point's coordinates over that child.
pub fn child_toward(b: Vec3) -> (usize, Vec3) {
    if b.x >= 0.5 {
        (0, Vec3::new(2.0 * b.x - 1.0, 2.0 * b.y, 2.0 * b.z))
    } else if b.y >= 0.5 {
        (1, Vec3::new(2.0 * b.x, 2.0 * b.y - 1.0, 2.0 * b.z))
    } else if b.z >= 0.5 {
        (3, Vec3::new(2.0 * b.x, 2.0 * b.y, 2.0 * b.z - 1.0))
    } else {
        (
            2,
            Vec3::new(1.0 - 2.0 * b.x, 1.0 - 2.0 * b.y, 1.0 - 2.0 * b.z),
        )
    }
}

/// The barycentric coordinates of point `p` (in the plane of triangle `t`) with respect to
/// `t`'s corners; a third each for a degenerate triangle.
pub fn barycentric_of(t: [Vec3; 3], p: Vec3) -> [f32; 3] {
    let (e1, e2, d) = (t[1] - t[0], t[2] - t[0], p - t[0]);
    let (d00, d01, d11) = (e1.dot(e1), e1.dot(e2), e2.dot(e2));
    let (d20, d21) = (d.dot(e1), d.dot(e2));
    let den = d00 * d11 - d01 * d01;
    if den.is_nan() || den <= 0.0 {
        return [1.0 / 3.0; 3];
    }
    let b1 = (d11 * d20 - d01 * d21) / den;
    let b2 = (d00 * d21 - d01 * d20) / den;
    [1.0 - b1 - b2, b1, b2]
}

/// Point `i` of `n` stratified jittered points on triangle `t`: the triangle is split into
/// `4^k >= n` congruent subtriangles and point `i` is a uniform random point in subtriangle
/// `i * 4^k / n`.
pub fn jittered_point(t: [Vec3; 3], i: u32, n: u32, rng: &mut Rng) -> Vec3 {
    let mut k = 0;
    while (1u32 << (2 * k)) < n && k < 8 {
        k += 1;
    }
    let cells = 1u64 << (2 * k);
    let cell = (u64::from(i) * cells / u64::from(n.max(1))) as u32;
    let mut tri = t;
    for d in 0..k {
        tri = split_child(tri, (cell >> (2 * (k - 1 - d))) & 3);
    }
    let (mut u, mut v) = (rng.next_f32(), rng.next_f32());
    if u + v > 1.0 {
        u = 1.0 - u;
        v = 1.0 - v;
    }
    tri[0] + (tri[1] - tri[0]) * u + (tri[2] - tri[0]) * v
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn edge_neighbours_are_the_elements_across_each_edge_within_the_root() {
        let top = ElemKey::root(3).child(0);
        let centre = ElemKey::root(3).child(2);
        assert_eq!(top.edge_neighbours().collect::<Vec<_>>(), vec![centre]);
        let mut around: Vec<_> = centre.edge_neighbours().collect();
        around.sort();
        assert_eq!(
            around,
            vec![top, ElemKey::root(3).child(1), ElemKey::root(3).child(3)]
        );
        // At level 4: every neighbour shares an edge (two corners) and has this one among
        // its own neighbours; an element away from the root's border has three.
        for path in 0..256u32 {
            let k = ElemKey {
                root: 3,
                level: 4,
                path,
            };
            let c = k.barycentric();
            let near: Vec<_> = k.edge_neighbours().collect();
            // On the root's edge opposite corner e: two corners with no weight of e.
            let on_border = (0..3).any(|e| (0..3).filter(|&v| c[v][e] == 0.0).count() >= 2);
            assert!(on_border || near.len() == 3, "{k:?} {near:?}");
            for n in near {
                assert_eq!(n.level, 4);
                let d = n.barycentric();
                let shared = c.iter().filter(|p| d.contains(p)).count();
                assert_eq!(shared, 2, "{k:?} {n:?}");
                assert!(n.edge_neighbours().any(|x| x == k), "{k:?} {n:?}");
            }
        }
        assert_eq!(ElemKey::containing(3, 2, Vec3::new(-0.1, 0.6, 0.5)), None);
    }

    #[test]
    fn keys_navigate_like_the_model_paths() {
        let k = ElemKey::root(7).child(2).child(3).child(1);
        assert_eq!(k.path, 2 * 16 + 3 * 4 + 1);
        assert_eq!([k.choice(0), k.choice(1), k.choice(2)], [2, 3, 1]);
        assert_eq!(k.parent().unwrap(), ElemKey::root(7).child(2).child(3));
        assert!(k.within(ElemKey::root(7).child(2)));
        assert!(!k.within(ElemKey::root(7).child(1)));
        let b = ElemKey::root(0).child(3).barycentric();
        // Right child (m20, m12, v2).
        assert_eq!(b[2], [0.0, 0.0, 1.0]);
        assert_eq!(b[0], [0.5, 0.0, 0.5]);
    }

    #[test]
    fn split_child_is_splits_child_to_the_bit() {
        let mut rng = Rng::new(1, 2, 3);
        for _ in 0..1000 {
            let t: [Vec3; 3] = std::array::from_fn(|_| {
                Vec3::new(rng.next_f32(), rng.next_f32(), rng.next_f32()) * 7.0 - 3.0
            });
            let all = split(t);
            for c in 0..4 {
                let one = split_child(t, c);
                let bits = |t: [Vec3; 3]| t.map(|v| v.to_array().map(f32::to_bits));
                assert_eq!(bits(one), bits(all[c as usize]));
            }
        }
    }

    #[test]
    fn jittered_points_stay_inside_their_cells() {
        let t = [Vec3::ZERO, Vec3::X, Vec3::Y];
        let mut rng = Rng::new(1, 2, 3);
        let mut quad = [0; 4];
        for i in 0..16 {
            let p = jittered_point(t, i, 16, &mut rng);
            assert!(p.x >= 0.0 && p.y >= 0.0 && p.x + p.y <= 1.0 + 1e-6);
            // The first four points lie in the Top child (x + y small... near v0).
            if i < 4 {
                assert!(p.x <= 0.5 + 1e-6 && p.y <= 0.5 + 1e-6 && p.x + p.y <= 0.5 + 1e-6);
            }
            quad[(i / 4) as usize] += 1;
        }
        assert_eq!(quad, [4; 4]);
    }
}
