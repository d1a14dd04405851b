//! The 1-to-4 lattice of a refined coarse triangle and its numbering: the one home, in Rust, of
//! fine-triangle paths, lattice coordinates, the subtriangles of a level and the numbering of
//! refined vertices. Flat refinement ([`crate::flat`]), Loop subdivision
//! ([`crate::subdivide`](mod@crate::subdivide)) and the colour reconstruction
//! ([`crate::colour`], [`crate::lighting`]) all read it from here.
//!
//! Its WGSL twin is `runtime/src/gpu/hce_lattice.wgsl`, prepended to the flat and Loop kernels:
//! [`corner_point`], [`edge_point`], [`interior_index`], [`interior_coords`], [`fine_corners`]
//! and [`locate`] are its `corner_lattice`, `edge_lattice`, `interior_offset`,
//! `interior_coords`, `fine_corners` and `locate`, and its `vertex_index` is [`site`] followed
//! by [`Numbering`] (combined as in [`crate::flat::vertex_index`]). The arithmetic is the same
//! on both sides; a change here is a change there, and the GPU tests compare the two.
//!
//! The split orders children Top `(v0, m01, m20)`, Left `(m01, v1, m12)`, Center
//! `(m12, m20, m01)`, Right `(m20, m12, v2)` (SPEC.md, Appendix F), so the level-`L` subtriangle
//! `t · 4^L + path` is the HCE tree node reached by following `path` (two bits per level, the
//! first split most significant): the regular 1-to-4 split that Loop subdivision refines (Loop
//! 1987) and that the HCE trees of Concheiro et al. (GRAPP 2012) encode.
//!
//! # Lattice triangles
//! Every triangle of the split is a [`LatticeTriangle`] `(C0, σ, s)` with corners `C0`,
//! `C0 + σ s e_b`, `C0 + σ s e_c`: the children Top, Left and Right keep `σ`, Center flips it.
//! The same descent gives the subtriangles of a refinement level ([`fine_corners`],
//! [`subtriangle_cells`]) and the leaf elements of a baked tree ([`crate::lighting`]).
//!
//! # Refined-mesh numbering
//! At level `L` with `n = 2^L`, a point of coarse triangle `(v0, v1, v2)` has lattice coordinates
//! `(a, b, c)`, `a + b + c = n`, position `(a p0 + b p1 + c p2) / n`; it is a corner, a point of
//! an edge or an interior point ([`site`]). Output vertices are ([`Numbering`]):
//! `[coarse vertices (V)] [edge points: E × (n − 1)] [interior points: F × (n − 1)(n − 2) / 2]`.
//! Edge `id`'s point `k` (`1 ≤ k < n`) is `V + id (n − 1) + k − 1`, counted from the owning
//! triangle's `v_e` towards its `v_{e+1}` ([`hce_format::ControlMesh::edges`]). Triangle `t`'s
//! interior point `(b, c)` is `V + E (n − 1) + t I + I − j (j + 1) / 2 + b − 1` with
//! `I = (n − 1)(n − 2) / 2` and `j = n − 1 − c` (rows of constant `c` in increasing `c`, each in
//! increasing `b`), so flat and Loop refinements number vertices alike. Fine triangle
//! `t · 4^L + path`.

/// Interior lattice points of one triangle at `n = 2^L` segments per edge: `(n − 1)(n − 2) / 2`.
pub fn interior_per_triangle(n: u64) -> u64 {
    if n < 2 {
        0
    } else {
        (n - 1) * (n - 2) / 2
    }
}

/// A triangle of the 1-to-4 split in the lattice of its coarse triangle: corners `origin`,
/// `origin + sigma side e_b` and `origin + sigma side e_c`, in the order of SPEC.md 2.2.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub struct LatticeTriangle {
    pub origin: [i32; 2],
    /// `1` for a triangle oriented as the coarse one, `-1` for one turned by a Center child.
    pub sigma: i32,
    /// Segments per edge (a power of two).
    pub side: i32,
}

impl LatticeTriangle {
    /// The coarse triangle itself, in a lattice of `side` segments per edge.
    pub fn root(side: i32) -> Self {
        LatticeTriangle {
            origin: [0, 0],
            sigma: 1,
            side,
        }
    }

    /// Child `c` (0 Top, 1 Left, 2 Center, 3 Right).
    pub fn child(self, c: u32) -> Self {
        let h = self.side / 2;
        let s = self.sigma;
        let [x, y] = self.origin;
        match c {
            0 => LatticeTriangle { side: h, ..self },
            1 => LatticeTriangle {
                origin: [x + s * h, y],
                side: h,
                ..self
            },
            2 => LatticeTriangle {
                origin: [x + s * h, y + s * h],
                sigma: -s,
                side: h,
            },
            _ => LatticeTriangle {
                origin: [x, y + s * h],
                side: h,
                ..self
            },
        }
    }

    /// The descendant reached by following `path`, `depth` children (two bits each, the first
    /// most significant).
    pub fn descend(self, depth: u32, path: u32) -> Self {
        (0..depth).fold(self, |t, k| t.child((path >> (2 * (depth - 1 - k))) & 3))
    }

    /// Corners 0, 1, 2.
    pub fn corners(self) -> [[i32; 2]; 3] {
        let [x, y] = self.origin;
        let d = self.sigma * self.side;
        [[x, y], [x + d, y], [x, y + d]]
    }
}

/// The lattice corners `(b, c)` of fine triangle `path` at level `level` (`n = 2^level`), found
/// by descending the 1-to-4 split.
pub fn fine_corners(level: u32, path: u32) -> [[i32; 2]; 3] {
    LatticeTriangle::root(1 << level)
        .descend(level, path)
        .corners()
}

/// Lattice corners `(b, c)` of every level-`level` subtriangle of a coarse triangle, indexed by
/// path: [`fine_corners`] for all paths at once, in `O(4^level)`.
pub fn subtriangle_cells(level: u32) -> Vec<[[u32; 2]; 3]> {
    fn rec(t: LatticeTriangle, d: u32, out: &mut Vec<[[u32; 2]; 3]>) {
        if d == 0 {
            out.push(t.corners().map(|p| p.map(|x| x as u32)));
            return;
        }
        for c in 0..4 {
            rec(t.child(c), d - 1, out);
        }
    }
    let mut out = Vec::with_capacity(1 << (2 * level));
    rec(LatticeTriangle::root(1 << level), level, &mut out);
    out
}

/// One step down the 1-to-4 split towards a point: for a point `(u, v)` in the frame of a node
/// of side `2h` (origin at its corner 0, axes along its sides), the child that holds it (0 Top,
/// 1 Left, 2 Center, 3 Right) and the point in that child's frame. The border between children
/// goes to the first of Left (`u` at least `h`), Right (`v` at least `h`), Top (`u + v` at most
/// `h`), Center (SPEC.md G.4, step 2). For lattice integers and for `f32` alike.
pub fn child_toward<T>(u: T, v: T, h: T) -> (u32, T, T)
where
    T: Copy + PartialOrd + std::ops::Add<Output = T> + std::ops::Sub<Output = T>,
{
    if u >= h {
        (1, u - h, v)
    } else if v >= h {
        (3, u, v - h)
    } else if u + v <= h {
        (0, u, v)
    } else {
        (2, h - u, h - v)
    }
}

/// The path of the fine triangle whose centroid, times 3, is `q` (lattice `(b, c)` units).
pub fn locate(level: u32, q: [i32; 2]) -> u32 {
    let mut c0 = [0i32, 0i32];
    let mut sigma = 1i32;
    let mut s = 1i32 << level;
    let mut path = 0u32;
    for _ in 0..level {
        let h = s / 2;
        let l1 = sigma * (q[0] - 3 * c0[0]);
        let l2 = sigma * (q[1] - 3 * c0[1]);
        let l0 = 3 * s - l1 - l2;
        let child = if l0 > 3 * h {
            0
        } else if l1 > 3 * h {
            c0[0] += sigma * h;
            1
        } else if l2 > 3 * h {
            c0[1] += sigma * h;
            3
        } else {
            c0 = [c0[0] + sigma * h, c0[1] + sigma * h];
            sigma = -sigma;
            2
        };
        path = path * 4 + child;
        s = h;
    }
    path
}

/// Paths of the fine triangles around lattice point `(b, c)` inside one coarse triangle, in the
/// fixed order the kernels sum them: up triangles anchored at `(b, c)`, `(b − 1, c)`,
/// `(b, c − 1)`, then down triangles anchored at `(b, c)`, `(b + 1, c)`, `(b, c + 1)`.
pub fn incident_paths(level: u32, b: i32, c: i32) -> impl Iterator<Item = u32> {
    let n = 1i32 << level;
    let ups = [(b, c), (b - 1, c), (b, c - 1)];
    let downs = [(b, c), (b + 1, c), (b, c + 1)];
    let up = ups
        .into_iter()
        .filter(move |&(x, y)| x >= 0 && y >= 0 && x + y < n)
        .map(move |(x, y)| locate(level, [3 * x + 1, 3 * y + 1]));
    let down = downs
        .into_iter()
        .filter(move |&(x, y)| x >= 1 && y >= 1 && x + y <= n)
        .map(move |(x, y)| locate(level, [3 * x - 1, 3 * y - 1]));
    up.chain(down)
}

/// The lattice point of corner `c` of a triangle with `n` segments per edge.
pub fn corner_point(n: i32, c: u32) -> [i32; 2] {
    match c {
        0 => [0, 0],
        1 => [n, 0],
        _ => [0, n],
    }
}

/// The lattice point of edge `e` of a triangle at `k` steps from its `v_e`.
pub fn edge_point(n: i32, e: u32, k: i32) -> [i32; 2] {
    match e {
        0 => [k, 0],
        1 => [n - k, k],
        _ => [0, n - k],
    }
}

/// `(b, c)` of interior point `local` (inverse of the numbering in the module docs).
pub fn interior_coords(n: i32, local: u32) -> (i32, i32) {
    let ip = interior_per_triangle(n as u64) as u32;
    // Counted from the last point, rows have 1, 2, 3, ... points: the row of length j holds
    // r = ip − 1 − local when j (j − 1) / 2 <= r < j (j + 1) / 2. Start from the float root,
    // correct exactly.
    let r = ip - 1 - local;
    let mut j = ((1.0 + (1.0 + 8.0 * r as f64).sqrt()) / 2.0).floor() as u32;
    while j * (j - 1) / 2 > r {
        j -= 1;
    }
    while (j + 1) * j / 2 <= r {
        j += 1;
    }
    let b = (local - (ip - j * (j + 1) / 2)) as i32 + 1;
    (b, n - 1 - j as i32)
}

/// The local number of interior point `(b, c)` (`1 ≤ b, c`, `b + c < n`) within its triangle:
/// the inverse of [`interior_coords`].
pub fn interior_index(n: i32, b: i32, c: i32) -> u32 {
    let j = (n - 1 - c) as u32;
    let ip = interior_per_triangle(n as u64) as u32;
    (ip - j * (j + 1) / 2) + (b as u32 - 1)
}

/// Index of lattice point `(b, c)` among all `(n + 1)(n + 2) / 2` points of a triangle with `n`
/// segments per edge, in rows of constant `c` (the order of the interior numbering, with the
/// edges included).
#[inline(always)]
pub fn grid_index(n: usize, b: usize, c: usize) -> usize {
    c * (n + 1) - c * c.saturating_sub(1) / 2 + b
}

/// Where a lattice point of a coarse triangle lies.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum Site {
    /// Corner `c` (`v_c`).
    Corner(usize),
    /// Point `k` (`1 ≤ k < n`) of edge `edge`, counted from `v_edge` ([`edge_point`]).
    Edge { edge: usize, k: i32 },
    /// Strictly inside.
    Interior,
}

/// Whether lattice point `(b, c)` of a triangle with `n` segments per edge is a corner, an edge
/// point or an interior point (`a = n − b − c`; a corner before an edge).
pub fn site(n: i32, b: i32, c: i32) -> Site {
    match (n - b - c, b, c) {
        (_, 0, 0) => Site::Corner(0),
        (0, _, 0) => Site::Corner(1),
        (0, 0, _) => Site::Corner(2),
        (_, _, 0) => Site::Edge { edge: 0, k: b },
        (0, _, _) => Site::Edge { edge: 1, k: c },
        (a, 0, _) => Site::Edge { edge: 2, k: a },
        _ => Site::Interior,
    }
}

/// The output numbering of a mesh of `vertices`, `edges` and `triangles` refined to `level`
/// (see the module documentation). Counts are 32-bit, as in the format; numbers are `u64`, so
/// no level up to 15 overflows.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub struct Numbering {
    pub level: u32,
    pub vertices: u32,
    pub edges: u32,
    pub triangles: u32,
}

impl Numbering {
    /// Segments per coarse edge, `2^level`.
    pub fn n(&self) -> u64 {
        1 << self.level
    }

    /// Points strictly inside one coarse edge, `n − 1`.
    pub fn per_edge(&self) -> u64 {
        self.n() - 1
    }

    /// Points strictly inside one coarse triangle, `(n − 1)(n − 2) / 2`.
    pub fn per_triangle(&self) -> u64 {
        interior_per_triangle(self.n())
    }

    pub fn vertex_count(&self) -> u64 {
        u64::from(self.vertices)
            + u64::from(self.edges) * self.per_edge()
            + u64::from(self.triangles) * self.per_triangle()
    }

    pub fn triangle_count(&self) -> u64 {
        u64::from(self.triangles) << (2 * self.level)
    }

    /// Point `k` (`1 ≤ k < n`) of edge `id`, counted from its owner's `v_e`.
    pub fn edge_point(&self, id: u32, k: u64) -> u64 {
        u64::from(self.vertices) + u64::from(id) * self.per_edge() + k - 1
    }

    /// Interior point `local` ([`interior_index`]) of triangle `t`.
    pub fn interior_point(&self, t: u32, local: u64) -> u64 {
        u64::from(self.vertices)
            + u64::from(self.edges) * self.per_edge()
            + u64::from(t) * self.per_triangle()
            + local
    }

    /// What output vertex `i` (below [`Numbering::vertex_count`]) is: the inverse of
    /// [`Numbering::edge_point`] and [`Numbering::interior_point`].
    pub fn point(&self, i: u64) -> RefinedPoint {
        let v = u64::from(self.vertices);
        let interior = self.interior_point(0, 0);
        if i < v {
            RefinedPoint::Coarse(i as u32)
        } else if i < interior {
            let (id, k) = ((i - v) / self.per_edge(), (i - v) % self.per_edge() + 1);
            RefinedPoint::Edge { id: id as u32, k }
        } else {
            let (t, local) = (
                (i - interior) / self.per_triangle(),
                (i - interior) % self.per_triangle(),
            );
            RefinedPoint::Interior { t: t as u32, local }
        }
    }
}

/// An output vertex of a refinement, by where it lies on the control mesh.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum RefinedPoint {
    /// Control vertex `v`.
    Coarse(u32),
    /// Point `k` (`1 ≤ k < n`) of edge `id`, counted from its owner's `v_e`.
    Edge { id: u32, k: u64 },
    /// Interior point `local` of triangle `t`.
    Interior { t: u32, local: u64 },
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn locate_inverts_fine_corners() {
        for level in 0..5 {
            for path in 0..(1u32 << (2 * level)) {
                let [p0, p1, p2] = fine_corners(level, path);
                let q = [p0[0] + p1[0] + p2[0], p0[1] + p1[1] + p2[1]];
                assert_eq!(locate(level, q), path, "level {level}");
            }
        }
    }

    #[test]
    fn first_level_children_have_the_model_corners() {
        // n = 2: v0 = (0,0), v1 = (2,0), v2 = (0,2), m01 = (1,0), m12 = (1,1), m20 = (0,1).
        assert_eq!(fine_corners(1, 0), [[0, 0], [1, 0], [0, 1]]); // Top (v0, m01, m20)
        assert_eq!(fine_corners(1, 1), [[1, 0], [2, 0], [1, 1]]); // Left (m01, v1, m12)
        assert_eq!(fine_corners(1, 2), [[1, 1], [0, 1], [1, 0]]); // Center (m12, m20, m01)
        assert_eq!(fine_corners(1, 3), [[0, 1], [1, 1], [0, 2]]); // Right (m20, m12, v2)
    }

    #[test]
    fn interior_numbering_is_a_bijection() {
        for level in 2..6 {
            let n = 1i32 << level;
            let ip = interior_per_triangle(n as u64) as u32;
            let mut seen = std::collections::HashSet::new();
            for local in 0..ip {
                let (b, c) = interior_coords(n, local);
                assert!(b >= 1 && c >= 1 && b + c < n, "({b}, {c}) at level {level}");
                let j = (n - 1 - c) as u32;
                assert_eq!(ip - j * (j + 1) / 2 + b as u32 - 1, local);
                assert!(seen.insert((b, c)));
            }
            // The order of crate::subdivide: rows of increasing c, each of increasing b.
            let order: Vec<(i32, i32)> = (1..n)
                .flat_map(|c| (1..n - c).map(move |b| (b, c)))
                .collect();
            let ours: Vec<(i32, i32)> = (0..ip).map(|l| interior_coords(n, l)).collect();
            assert_eq!(ours, order, "level {level}");
        }
    }

    #[test]
    fn every_lattice_point_has_its_incident_fine_triangles() {
        let level = 3;
        let n = 8;
        // Interior points touch 6 fine triangles, edge points 3, corners 1.
        assert_eq!(incident_paths(level, 3, 2).count(), 6);
        assert_eq!(incident_paths(level, 3, 0).count(), 3);
        assert_eq!(incident_paths(level, 0, 0).count(), 1);
        assert_eq!(incident_paths(level, n, 0).count(), 1);
        for path in incident_paths(level, 3, 2) {
            assert!(fine_corners(level, path).contains(&[3, 2]));
        }
    }

    #[test]
    fn subtriangle_cells_are_the_fine_corners_of_every_path() {
        for level in 0..=6 {
            let cells = subtriangle_cells(level);
            assert_eq!(cells.len(), 1 << (2 * level));
            for (path, cell) in cells.iter().enumerate() {
                let want = fine_corners(level, path as u32).map(|p| p.map(|x| x as u32));
                assert_eq!(*cell, want, "level {level} path {path}");
            }
        }
    }

    #[test]
    fn sites_classify_corners_edge_points_and_interior_points() {
        let n = 8;
        for c in 0..3 {
            assert_eq!(
                site(n, corner_point(n, c)[0], corner_point(n, c)[1]),
                Site::Corner(c as usize)
            );
        }
        for e in 0..3 {
            for k in 1..n {
                let [b, c] = edge_point(n, e, k);
                assert_eq!(
                    site(n, b, c),
                    Site::Edge {
                        edge: e as usize,
                        k
                    }
                );
            }
            // Edge e runs from corner e (k = 0) to corner e + 1 (k = n).
            assert_eq!(edge_point(n, e, n), corner_point(n, (e + 1) % 3));
            assert_eq!(edge_point(n, e, 0), corner_point(n, e));
        }
        for local in 0..interior_per_triangle(n as u64) as u32 {
            let (b, c) = interior_coords(n, local);
            assert_eq!(site(n, b, c), Site::Interior);
            assert_eq!(interior_index(n, b, c), local);
        }
    }

    #[test]
    fn grid_index_orders_interior_points_as_the_interior_numbering() {
        for level in 0..6 {
            let n = 1usize << level;
            let mut seen = vec![false; (n + 1) * (n + 2) / 2];
            for c in 0..=n {
                for b in 0..=n - c {
                    let g = grid_index(n, b, c);
                    assert!(!seen[g], "({b}, {c}) at level {level}");
                    seen[g] = true;
                }
            }
            assert!(seen.iter().all(|&s| s));
            let ip = interior_per_triangle(n as u64) as u32;
            let grid: Vec<usize> = (0..ip)
                .map(|l| interior_coords(n as i32, l))
                .map(|(b, c)| grid_index(n, b as usize, c as usize))
                .collect();
            assert!(grid.windows(2).all(|w| w[0] < w[1]), "level {level}");
        }
    }

    #[test]
    fn numbering_is_dense_and_inverted_by_point() {
        // 5 vertices, 7 edges, 3 triangles at level 3: 5 + 7 · 7 + 3 · 21 vertices.
        let num = Numbering {
            level: 3,
            vertices: 5,
            edges: 7,
            triangles: 3,
        };
        assert_eq!(num.vertex_count(), 5 + 49 + 63);
        assert_eq!(num.triangle_count(), 3 * 64);
        let mut seen = vec![false; num.vertex_count() as usize];
        let mut mark = |i: u64, p: RefinedPoint| {
            assert_eq!(num.point(i), p);
            assert!(!std::mem::replace(&mut seen[i as usize], true), "{i} twice");
        };
        for v in 0..5 {
            mark(u64::from(v), RefinedPoint::Coarse(v));
        }
        for id in 0..7 {
            for k in 1..8 {
                mark(num.edge_point(id, k), RefinedPoint::Edge { id, k });
            }
        }
        for t in 0..3 {
            for local in 0..21 {
                mark(
                    num.interior_point(t, local),
                    RefinedPoint::Interior { t, local },
                );
            }
        }
        assert!(seen.iter().all(|&s| s));
    }

    #[test]
    fn center_children_turn_the_lattice_triangle() {
        // A Center child turns the triangle: its corners are the parent's edge midpoints.
        let root = LatticeTriangle::root(4096);
        assert_eq!(
            root.child(2).corners(),
            [[2048, 2048], [0, 2048], [2048, 0]]
        );
        // Center of Center is upright again, inside the first Center.
        let cc = root.child(2).child(2);
        assert_eq!(cc.sigma, 1);
        assert_eq!(cc.corners(), [[1024, 1024], [2048, 1024], [1024, 2048]]);
        assert_eq!(root.descend(2, 0b1010), cc);
    }
}
