//! Indexed triangle meshes as the generators build them, with smoothing groups for hard edges.
//!
//! A [`Mesh`] holds welded positions (every position distinct) and counter-clockwise triangles.
//! Each triangle carries a smoothing group: when the mesh is written to glTF, a position gets one
//! output vertex per group that uses it, each with the area-weighted normal of that group's
//! triangles. Edges between triangles of different groups therefore have split normals, which
//! is how glTF expresses a hard edge and what `hce bake --creases auto` reads as a crease.

use std::collections::{BTreeMap, HashMap};

use glam::DVec3;

/// An indexed triangle mesh in `f64`, Y up.
#[derive(Clone, Debug, Default, PartialEq)]
pub struct Mesh {
    pub positions: Vec<DVec3>,
    /// Counter-clockwise seen from outside.
    pub triangles: Vec<[u32; 3]>,
    /// Smoothing group of each triangle (same length as `triangles`).
    pub groups: Vec<u32>,
}

/// Edge-use statistics of a mesh, keyed on undirected edges.
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq)]
pub struct EdgeStats {
    /// Edges used by exactly one triangle (open boundary).
    pub boundary: usize,
    /// Edges used by exactly two triangles.
    pub interior: usize,
    /// Edges used by three or more triangles: Loop subdivision cannot take these.
    pub non_manifold: usize,
    /// Directed edges used twice (two neighbours disagree on orientation).
    pub inconsistent: usize,
}

impl Mesh {
    /// Appends a vertex and returns its index.
    pub fn vertex(&mut self, p: DVec3) -> u32 {
        self.positions.push(p);
        (self.positions.len() - 1) as u32
    }

    /// Appends a triangle in smoothing group `group`.
    pub fn triangle(&mut self, t: [u32; 3], group: u32) {
        self.triangles.push(t);
        self.groups.push(group);
    }

    /// Appends the quad `(a, b, c, d)` (counter-clockwise) as two triangles, split along the
    /// shorter diagonal so that the triangles stay as well-shaped as the quad allows. A quad
    /// with a repeated corner (at a pole of a surface of revolution) gives one triangle.
    pub fn quad(&mut self, [a, b, c, d]: [u32; 4], group: u32) {
        let p = |i: u32| self.positions[i as usize];
        let (t1, t2) = if p(a).distance_squared(p(c)) <= p(b).distance_squared(p(d)) {
            ([a, b, c], [a, c, d])
        } else {
            ([a, b, d], [b, c, d])
        };
        for t in [t1, t2] {
            if t[0] != t[1] && t[1] != t[2] && t[2] != t[0] {
                self.triangle(t, group);
            }
        }
    }

    /// Appends `other`, offsetting its smoothing groups by `group_offset`.
    pub fn append(&mut self, other: &Mesh, group_offset: u32) {
        let base = self.positions.len() as u32;
        self.positions.extend_from_slice(&other.positions);
        for (t, g) in other.triangles.iter().zip(&other.groups) {
            self.triangle([t[0] + base, t[1] + base, t[2] + base], g + group_offset);
        }
    }

    /// Applies `f` to every position.
    pub fn map_positions(&mut self, f: impl Fn(DVec3) -> DVec3) {
        for p in &mut self.positions {
            *p = f(*p);
        }
    }

    /// Reverses the orientation of every triangle.
    pub fn flip(&mut self) {
        for t in &mut self.triangles {
            t.swap(1, 2);
        }
    }

    /// Merges positions closer than `tolerance` (the first one seen is kept), drops triangles
    /// that become degenerate (a repeated corner, as at the poles of the teapot's lid and
    /// bottom) and drops positions no triangle uses. Deterministic: the result depends only on
    /// the input order. A tolerance below 1e-12 is taken as 1e-12.
    pub fn weld(&mut self, tolerance: f64) {
        let tolerance = if tolerance >= 1e-12 { tolerance } else { 1e-12 };
        let cell = |p: DVec3| {
            let q = (p / tolerance).floor();
            (q.x as i64, q.y as i64, q.z as i64)
        };
        let mut grid: HashMap<(i64, i64, i64), Vec<u32>> = HashMap::new();
        let mut kept: Vec<DVec3> = Vec::new();
        let mut remap = Vec::with_capacity(self.positions.len());
        for &p in &self.positions {
            let (cx, cy, cz) = cell(p);
            let mut found: Option<u32> = None;
            for dx in -1..=1 {
                for dy in -1..=1 {
                    for dz in -1..=1 {
                        for &k in grid.get(&(cx + dx, cy + dy, cz + dz)).into_iter().flatten() {
                            // The earliest kept position wins, whatever cell it lies in.
                            if kept[k as usize].distance(p) < tolerance
                                && found.is_none_or(|f| k < f)
                            {
                                found = Some(k);
                            }
                        }
                    }
                }
            }
            let k = match found {
                Some(k) => k,
                None => {
                    kept.push(p);
                    let k = (kept.len() - 1) as u32;
                    grid.entry((cx, cy, cz)).or_default().push(k);
                    k
                }
            };
            remap.push(k);
        }
        let mut triangles = Vec::with_capacity(self.triangles.len());
        let mut groups = Vec::with_capacity(self.groups.len());
        for (t, &g) in self.triangles.iter().zip(&self.groups) {
            let t = t.map(|i| remap[i as usize]);
            if t[0] != t[1] && t[1] != t[2] && t[2] != t[0] {
                triangles.push(t);
                groups.push(g);
            }
        }
        self.positions = kept;
        self.triangles = triangles;
        self.groups = groups;
        self.compact();
    }

    /// Drops unused positions, renumbering in order of first use by the triangles.
    pub fn compact(&mut self) {
        let mut remap = vec![u32::MAX; self.positions.len()];
        let mut positions = Vec::new();
        for t in &mut self.triangles {
            for i in t.iter_mut() {
                if remap[*i as usize] == u32::MAX {
                    remap[*i as usize] = positions.len() as u32;
                    positions.push(self.positions[*i as usize]);
                }
                *i = remap[*i as usize];
            }
        }
        self.positions = positions;
    }

    /// Counts boundary, interior, non-manifold and inconsistently oriented edges.
    pub fn edge_stats(&self) -> EdgeStats {
        let mut undirected: BTreeMap<(u32, u32), usize> = BTreeMap::new();
        let mut directed: BTreeMap<(u32, u32), usize> = BTreeMap::new();
        for t in &self.triangles {
            for e in 0..3 {
                let (a, b) = (t[e], t[(e + 1) % 3]);
                *undirected.entry((a.min(b), a.max(b))).or_default() += 1;
                *directed.entry((a, b)).or_default() += 1;
            }
        }
        let mut s = EdgeStats::default();
        for &n in undirected.values() {
            match n {
                1 => s.boundary += 1,
                2 => s.interior += 1,
                _ => s.non_manifold += 1,
            }
        }
        s.inconsistent = directed.values().filter(|&&n| n > 1).count();
        s
    }

    /// Vertices whose incident triangles form more than one fan (two cones touching at a
    /// point): manifold edges alone do not make a surface Loop subdivision can take.
    pub fn non_manifold_vertices(&self) -> usize {
        let mut incident: Vec<Vec<usize>> = vec![Vec::new(); self.positions.len()];
        for (k, t) in self.triangles.iter().enumerate() {
            for &v in t {
                incident[v as usize].push(k);
            }
        }
        let mut count = 0;
        for (v, tris) in incident.iter().enumerate() {
            if tris.is_empty() {
                continue;
            }
            // Flood fill over triangles that share an edge through `v`.
            let others = |k: usize| -> Vec<u32> {
                self.triangles[k]
                    .iter()
                    .copied()
                    .filter(|&w| w as usize != v)
                    .collect()
            };
            let mut reached = vec![false; tris.len()];
            reached[0] = true;
            let mut stack = vec![0usize];
            while let Some(a) = stack.pop() {
                let oa = others(tris[a]);
                for b in 0..tris.len() {
                    if !reached[b] && others(tris[b]).iter().any(|w| oa.contains(w)) {
                        reached[b] = true;
                        stack.push(b);
                    }
                }
            }
            if reached.iter().any(|r| !r) {
                count += 1;
            }
        }
        count
    }

    /// Number of connected components (triangles sharing a vertex are connected).
    pub fn components(&self) -> usize {
        let mut parent: Vec<u32> = (0..self.positions.len() as u32).collect();
        fn find(parent: &mut [u32], mut i: u32) -> u32 {
            while parent[i as usize] != i {
                parent[i as usize] = parent[parent[i as usize] as usize];
                i = parent[i as usize];
            }
            i
        }
        for t in &self.triangles {
            for e in 1..3 {
                let (a, b) = (find(&mut parent, t[0]), find(&mut parent, t[e]));
                if a != b {
                    parent[a.max(b) as usize] = a.min(b);
                }
            }
        }
        let mut roots: Vec<u32> = (0..self.positions.len() as u32)
            .map(|i| find(&mut parent, i))
            .collect();
        roots.sort_unstable();
        roots.dedup();
        roots.len()
    }

    /// Signed volume enclosed by the triangles (positive for a closed, outward-facing mesh).
    pub fn signed_volume(&self) -> f64 {
        self.triangles
            .iter()
            .map(|t| {
                let [a, b, c] = t.map(|i| self.positions[i as usize]);
                a.dot(b.cross(c)) / 6.0
            })
            .sum()
    }

    /// Axis-aligned bounding box `(min, max)`; `None` for an empty mesh.
    pub fn bounds(&self) -> Option<(DVec3, DVec3)> {
        let first = *self.positions.first()?;
        Some(
            self.positions
                .iter()
                .fold((first, first), |(lo, hi), &p| (lo.min(p), hi.max(p))),
        )
    }

    /// Smallest triangle area (zero would be a degenerate triangle).
    pub fn min_triangle_area(&self) -> f64 {
        self.triangles
            .iter()
            .map(|t| self.face_normal(t).length() / 2.0)
            .fold(f64::INFINITY, f64::min)
    }

    /// Cross product of the triangle's edges: its normal scaled by twice its area.
    pub fn face_normal(&self, t: &[u32; 3]) -> DVec3 {
        let [a, b, c] = t.map(|i| self.positions[i as usize]);
        (b - a).cross(c - a)
    }

    /// Whether two distinct positions are closer than `tolerance` (the importer welds equal
    /// positions, so this would silently change the topology).
    pub fn has_coincident_positions(&self, tolerance: f64) -> bool {
        let before = self.positions.len();
        let mut distinct = 0;
        let mut seen: Vec<DVec3> = Vec::new();
        for &p in &self.positions {
            if !seen.iter().any(|q| q.distance(p) < tolerance) {
                distinct += 1;
                seen.push(p);
            }
        }
        distinct != before
    }
}

/// Snaps a coordinate to a multiple of 2⁻²⁰ (about a micrometre for metres). Positions written
/// to the samples go through this so that an ulp of difference in `sin`/`cos` between platforms
/// cannot change the bytes of the generated files, and so that the value is exact in `f32`
/// (below 16 in magnitude).
pub fn snap(x: f64) -> f64 {
    const SCALE: f64 = (1u64 << 20) as f64;
    (x * SCALE).round() / SCALE
}

#[cfg(test)]
mod tests {
    use super::*;

    fn square() -> Mesh {
        let mut m = Mesh::default();
        let v: Vec<u32> = [(0.0, 0.0), (1.0, 0.0), (1.0, 1.0), (0.0, 1.0)]
            .iter()
            .map(|&(x, z)| m.vertex(DVec3::new(x, 0.0, z)))
            .collect();
        m.quad([v[0], v[1], v[2], v[3]], 0);
        m
    }

    #[test]
    fn weld_merges_near_positions_and_drops_degenerate_triangles() {
        let mut m = square();
        // A second copy of the square's corner 2, a hair away, and a triangle that collapses.
        let near = m.vertex(DVec3::new(1.0 + 1e-9, 0.0, 1.0));
        m.triangle([1, 2, near], 0);
        m.weld(1e-6);
        assert_eq!(m.positions.len(), 4);
        assert_eq!(m.triangles.len(), 2);
        let s = m.edge_stats();
        assert_eq!((s.boundary, s.interior, s.non_manifold), (4, 1, 0));
        assert_eq!(s.inconsistent, 0);
    }

    #[test]
    fn edge_stats_detect_flipped_neighbour() {
        let mut m = square();
        m.triangles[1].swap(1, 2);
        assert_eq!(m.edge_stats().inconsistent, 1);
    }

    #[test]
    fn snap_is_exact_in_f32() {
        let x = snap(std::f64::consts::PI);
        assert_eq!(x as f32 as f64, x);
        assert!((x - std::f64::consts::PI).abs() <= 0.5 / (1u64 << 20) as f64);
    }
}
