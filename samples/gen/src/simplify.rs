//! Mesh simplification by edge collapse, to make a coarse control mesh from a fine one.
//!
//! This work is based on: Michael Garland and Paul S. Heckbert, "Surface simplification using
//! quadric error metrics", SIGGRAPH 1997. Every vertex carries the sum of the squared-distance
//! quadrics of the planes of its triangles (weighted by area); the edge whose collapse costs the
//! least error goes first, its two ends merging at the best of the quadric's optimum, either end
//! and the midpoint.
//!
//! A multiresolution object is a coarse control mesh that Loop subdivision refines, so the result
//! must stay a surface subdivision can take: a collapse is refused when it would join two sheets
//! (the link condition of Dey et al. 1999: the ends share exactly the two vertices opposite the
//! edge), turn a triangle over or make it a sliver, or leave a vertex with fewer than three
//! neighbours. Vertices on open boundaries or non-manifold edges of the input stay where they are.
//! Deterministic: ties in cost are broken by vertex indices.

use std::cmp::Reverse;
use std::collections::{BTreeSet, BinaryHeap};

use glam::{DMat3, DVec3};

use crate::mesh::Mesh;

/// A symmetric 4×4 quadric `[A b; bᵀ c]`: the error of a point `p` is `pᵀAp + 2bᵀp + c`.
#[derive(Clone, Copy, Default)]
struct Quadric {
    a: [f64; 6],
    b: DVec3,
    c: f64,
}

impl Quadric {
    /// Squared distance to the plane through `p` with unit normal `n`, times `weight`.
    fn plane(n: DVec3, p: DVec3, weight: f64) -> Self {
        let d = -n.dot(p);
        Quadric {
            a: [
                n.x * n.x,
                n.x * n.y,
                n.x * n.z,
                n.y * n.y,
                n.y * n.z,
                n.z * n.z,
            ]
            .map(|v| v * weight),
            b: n * d * weight,
            c: d * d * weight,
        }
    }

    fn add(&self, o: &Quadric) -> Quadric {
        Quadric {
            a: std::array::from_fn(|i| self.a[i] + o.a[i]),
            b: self.b + o.b,
            c: self.c + o.c,
        }
    }

    fn matrix(&self) -> DMat3 {
        let a = &self.a;
        DMat3::from_cols(
            DVec3::new(a[0], a[1], a[2]),
            DVec3::new(a[1], a[3], a[4]),
            DVec3::new(a[2], a[4], a[5]),
        )
    }

    fn error(&self, p: DVec3) -> f64 {
        (p.dot(self.matrix() * p) + 2.0 * self.b.dot(p) + self.c).max(0.0)
    }

    /// The point of least error, when the quadric pins one down well.
    fn optimum(&self) -> Option<DVec3> {
        let m = self.matrix();
        let scale = self.a[0] + self.a[3] + self.a[5];
        (m.determinant().abs() > 1e-9 * scale * scale * scale).then(|| -(m.inverse() * self.b))
    }
}

/// Twice the area times the unit normal of the triangle `a, b, c`.
fn cross(a: DVec3, b: DVec3, c: DVec3) -> DVec3 {
    (b - a).cross(c - a)
}

/// Shape quality in (0, 1]: 1 for an equilateral triangle, 0 for a degenerate one.
fn quality(a: DVec3, b: DVec3, c: DVec3) -> f64 {
    let den = a.distance_squared(b) + b.distance_squared(c) + c.distance_squared(a);
    if den <= 0.0 {
        return 0.0;
    }
    2.0 * 3f64.sqrt() * cross(a, b, c).length() / den
}

struct Simplifier {
    pos: Vec<DVec3>,
    tris: Vec<[u32; 3]>,
    alive: Vec<bool>,
    /// Live triangles around each vertex.
    around: Vec<Vec<u32>>,
    quadric: Vec<Quadric>,
    locked: Vec<bool>,
    /// Bumped whenever a vertex's quadric changes, so that stale heap entries are skipped.
    version: Vec<u32>,
    live: usize,
}

impl Simplifier {
    fn neighbours(&self, v: u32) -> BTreeSet<u32> {
        self.around[v as usize]
            .iter()
            .flat_map(|&t| self.tris[t as usize])
            .filter(|&w| w != v)
            .collect()
    }

    /// Cost and target position of collapsing edge `(a, b)`.
    fn plan(&self, a: u32, b: u32) -> (f64, DVec3) {
        let (pa, pb) = (self.pos[a as usize], self.pos[b as usize]);
        let q = self.quadric[a as usize].add(&self.quadric[b as usize]);
        let mut options = match (self.locked[a as usize], self.locked[b as usize]) {
            (true, _) => vec![pa],
            (false, true) => vec![pb],
            (false, false) => vec![pa, pb, (pa + pb) * 0.5],
        };
        if !self.locked[a as usize] && !self.locked[b as usize] {
            // The optimum only when it stays near the edge (a flat region's quadric pins
            // nothing down, and a nearly flat one can throw the point far away).
            if let Some(p) = q.optimum() {
                let reach = pa.distance(pb);
                if p.distance((pa + pb) * 0.5) <= reach {
                    options.push(p);
                }
            }
        }
        options
            .into_iter()
            .map(|p| (q.error(p), p))
            .fold(
                (f64::INFINITY, pa),
                |best, c| if c.0 < best.0 { c } else { best },
            )
    }

    /// Whether collapsing `(a, b)` into `p` keeps a manifold surface of sound triangles.
    fn allowed(&self, a: u32, b: u32, p: DVec3) -> bool {
        if self.locked[a as usize] && self.locked[b as usize] {
            return false;
        }
        let shared: Vec<u32> = self.around[a as usize]
            .iter()
            .copied()
            .filter(|t| self.tris[*t as usize].contains(&b))
            .collect();
        if shared.len() != 2 {
            return false;
        }
        let opposite: BTreeSet<u32> = shared
            .iter()
            .flat_map(|&t| self.tris[t as usize])
            .filter(|&w| w != a && w != b)
            .collect();
        let (na, nb) = (self.neighbours(a), self.neighbours(b));
        if opposite.len() != 2 || na.intersection(&nb).copied().collect::<BTreeSet<_>>() != opposite
        {
            return false;
        }
        // The two vertices opposite the edge each lose a neighbour.
        if opposite.iter().any(|&o| self.neighbours(o).len() <= 3) {
            return false;
        }
        for v in [a, b] {
            for &t in &self.around[v as usize] {
                if shared.contains(&t) {
                    continue;
                }
                let old = self.tris[t as usize].map(|i| self.pos[i as usize]);
                let new = self.tris[t as usize].map(|i| {
                    if i == a || i == b {
                        p
                    } else {
                        self.pos[i as usize]
                    }
                });
                let (n0, n1) = (cross(old[0], old[1], old[2]), cross(new[0], new[1], new[2]));
                // Not turned over (or much tilted), and not made a sliver.
                if n1.dot(n0) <= 0.5 * n0.length() * n1.length() {
                    return false;
                }
                let (q0, q1) = (
                    quality(old[0], old[1], old[2]),
                    quality(new[0], new[1], new[2]),
                );
                if q1 < 0.15 && q1 < q0 {
                    return false;
                }
            }
        }
        true
    }

    /// Merges `b` into `a` at `p`.
    fn collapse(&mut self, a: u32, b: u32, p: DVec3) {
        let tb = std::mem::take(&mut self.around[b as usize]);
        for &t in &tb {
            let tri = &mut self.tris[t as usize];
            if tri.contains(&a) {
                self.alive[t as usize] = false;
                self.live -= 1;
                for &w in tri.iter() {
                    if w != b {
                        self.around[w as usize].retain(|&x| x != t);
                    }
                }
            } else {
                for w in tri.iter_mut() {
                    if *w == b {
                        *w = a;
                    }
                }
                self.around[a as usize].push(t);
            }
        }
        self.around[a as usize].sort_unstable();
        self.pos[a as usize] = p;
        self.quadric[a as usize] = self.quadric[a as usize].add(&self.quadric[b as usize]);
        self.locked[a as usize] |= self.locked[b as usize];
        self.version[a as usize] += 1;
        self.version[b as usize] += 1;
    }
}

/// `mesh` simplified to at most `target` triangles where the rules above allow (fewer
/// collapses are possible on tiny or locked meshes), in one smoothing group.
pub fn simplify(mesh: &Mesh, target: usize) -> Mesh {
    let n = mesh.positions.len();
    let mut s = Simplifier {
        pos: mesh.positions.clone(),
        tris: mesh.triangles.clone(),
        alive: vec![true; mesh.triangles.len()],
        around: vec![Vec::new(); n],
        quadric: vec![Quadric::default(); n],
        locked: vec![false; n],
        version: vec![0; n],
        live: mesh.triangles.len(),
    };
    let mut uses: std::collections::BTreeMap<(u32, u32), u32> = Default::default();
    for (k, t) in mesh.triangles.iter().enumerate() {
        let [a, b, c] = t.map(|i| mesh.positions[i as usize]);
        let cr = cross(a, b, c);
        let area = cr.length() * 0.5;
        let plane = Quadric::plane(cr.normalize_or_zero(), a, area);
        for e in 0..3 {
            let v = t[e] as usize;
            s.around[v].push(k as u32);
            s.quadric[v] = s.quadric[v].add(&plane);
            let (x, y) = (t[e], t[(e + 1) % 3]);
            *uses.entry((x.min(y), x.max(y))).or_default() += 1;
        }
    }
    for (&(x, y), &count) in &uses {
        if count != 2 {
            s.locked[x as usize] = true;
            s.locked[y as usize] = true;
        }
    }
    let mut heap = BinaryHeap::new();
    let push = |s: &Simplifier, heap: &mut BinaryHeap<_>, a: u32, b: u32| {
        let (a, b) = (a.min(b), a.max(b));
        let (cost, _) = s.plan(a, b);
        let stamp = (s.version[a as usize], s.version[b as usize]);
        heap.push(Reverse((cost.to_bits(), a, b, stamp)));
    };
    for &(x, y) in uses.keys() {
        push(&s, &mut heap, x, y);
    }
    while s.live > target {
        let Some(Reverse((_, a, b, stamp))) = heap.pop() else {
            break;
        };
        if stamp != (s.version[a as usize], s.version[b as usize]) {
            continue;
        }
        let (_, p) = s.plan(a, b);
        if !s.allowed(a, b, p) {
            continue;
        }
        // Keep the locked end, if any, so that it does not move.
        let (keep, gone) = if s.locked[b as usize] { (b, a) } else { (a, b) };
        s.collapse(keep, gone, p);
        for w in s.neighbours(keep) {
            push(&s, &mut heap, keep, w);
        }
    }
    let mut out = Mesh {
        positions: s.pos,
        ..Default::default()
    };
    for (t, alive) in s.tris.iter().zip(&s.alive) {
        if *alive {
            out.triangle(*t, 0);
        }
    }
    out.compact();
    out
}

#[cfg(test)]
mod tests {
    use super::*;

    /// A UV sphere of `rings × 2 rings` quads (poles fanned), radius 1.
    fn sphere(rings: u32) -> Mesh {
        let mut m = Mesh::default();
        let segs = 2 * rings;
        let top = m.vertex(DVec3::Y);
        let mut ring = Vec::new();
        for j in 1..rings {
            let th = std::f64::consts::PI * f64::from(j) / f64::from(rings);
            ring.push(
                (0..segs)
                    .map(|i| {
                        let ph = std::f64::consts::TAU * f64::from(i) / f64::from(segs);
                        m.vertex(DVec3::new(
                            th.sin() * ph.cos(),
                            th.cos(),
                            th.sin() * ph.sin(),
                        ))
                    })
                    .collect::<Vec<u32>>(),
            );
        }
        let bottom = m.vertex(-DVec3::Y);
        let k = segs as usize;
        for i in 0..k {
            m.triangle([top, ring[0][(i + 1) % k], ring[0][i]], 0);
            let last = &ring[ring.len() - 1];
            m.triangle([bottom, last[i], last[(i + 1) % k]], 0);
        }
        for j in 0..ring.len() - 1 {
            for i in 0..k {
                let (a, b) = (ring[j][i], ring[j][(i + 1) % k]);
                let (c, d) = (ring[j + 1][(i + 1) % k], ring[j + 1][i]);
                m.quad([a, b, c, d], 0);
            }
        }
        m
    }

    #[test]
    fn a_sphere_simplifies_to_a_closed_coarse_sphere() {
        let fine = sphere(40);
        assert_eq!(
            (fine.edge_stats().boundary, fine.edge_stats().inconsistent),
            (0, 0)
        );
        assert!(fine.signed_volume() > 0.0);
        let coarse = simplify(&fine, 200);
        assert!(coarse.triangles.len() <= 200 && coarse.triangles.len() >= 190);
        // Still a closed, consistently oriented, manifold surface of one piece.
        let e = coarse.edge_stats();
        assert_eq!((e.boundary, e.non_manifold, e.inconsistent), (0, 0, 0));
        assert_eq!(coarse.non_manifold_vertices(), 0);
        assert_eq!(coarse.components(), 1);
        // Every vertex stays near the unit sphere and the volume near the fine one's.
        for p in &coarse.positions {
            assert!((p.length() - 1.0).abs() < 0.05, "{p}");
        }
        let (v0, v1) = (fine.signed_volume(), coarse.signed_volume());
        assert!((v1 - v0).abs() / v0 < 0.06, "{v0} {v1}");
        // No slivers: the worst triangle keeps a reasonable shape.
        let worst = coarse
            .triangles
            .iter()
            .map(|t| {
                let [a, b, c] = t.map(|i| coarse.positions[i as usize]);
                quality(a, b, c)
            })
            .fold(1.0, f64::min);
        assert!(worst >= 0.15, "{worst}");
        // Deterministic.
        assert_eq!(simplify(&fine, 200), coarse);
    }

    #[test]
    fn open_boundaries_stay_where_they_are() {
        // A hemisphere: the sphere's upper half, whose rim must not move.
        let fine = sphere(24);
        let mut half = Mesh {
            positions: fine.positions.clone(),
            ..Default::default()
        };
        for t in &fine.triangles {
            if t.iter().all(|&i| fine.positions[i as usize].y >= -1e-9) {
                half.triangle(*t, 0);
            }
        }
        half.compact();
        let rim: Vec<DVec3> = half
            .positions
            .iter()
            .copied()
            .filter(|p| p.y.abs() < 1e-9)
            .collect();
        assert_eq!(rim.len(), 48);
        let coarse = simplify(&half, 100);
        assert!(coarse.triangles.len() <= 100);
        let e = coarse.edge_stats();
        assert_eq!((e.boundary, e.non_manifold, e.inconsistent), (48, 0, 0));
        for p in &rim {
            assert!(coarse.positions.contains(p));
        }
    }
}
