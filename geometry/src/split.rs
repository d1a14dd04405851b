//! Split vertices where the surface folds (SPEC.md F.5 "Split vertices", F.6): a refined vertex
//! on an edge that has a neighbour but does not join it (G.2: the edge is sharp, or, on a flat
//! object, the two triangles fold by more than [`FLAT_JOIN_DEGREES`]) is drawn once per side,
//! so that the baked light (G.4) and the normals change across a crease or a fold instead of
//! blending over one ring of fine triangles, as glTF exporters split vertices at hard edges.
//!
//! The regions are the smooth regions of SPEC.md G.2: groups of the corners at a control point
//! joined across edges ([`joined_sides`], [`corner_groups`], the one definition
//! [`crate::lighting`] also reads). The owner's region of a vertex keeps its F.5 number; every
//! other region gets a copy appended after the F.5 vertices: first one per extra region of each
//! control point, then `M − 1` per split edge.
//!
//! [`SplitTables`] are level-independent and built once per object (the GPU kernels upload its
//! slot lists); [`SplitTables::apply`] turns a Loop subdivision
//! ([`crate::subdivide`](mod@crate::subdivide)) into the split mesh: copies of the positions,
//! the fine triangles' corners moved to their region's vertex, and each split vertex's normal
//! summed over its own region's fine triangles in the order of the kernels' gather
//! ([`crate::lattice::incident_paths`]). The flat refinement ([`crate::flat`]) applies the same
//! tables with [`SplitTables::copy_sources`] and [`SplitTables::split_index`].

use hce_format::{ControlMesh, ObjectKind, NO_NEIGHBOUR, SPOKE_SHARP};

use crate::incidence::FlatTopology;
use crate::lattice::{corner_point, edge_point, incident_paths};
use crate::subdivide::Refined;
use crate::tables::InvalidObject;

/// Marks a corner or an edge that keeps its F.5 vertex.
pub const NO_COPY: u32 = u32::MAX;

/// Flat objects join neighbouring coarse triangles whose geometric normals are within this many
/// degrees (SPEC.md G.2); across a steeper fold (the corner of a room, the edge of a block)
/// values and refined vertices are not shared.
pub const FLAT_JOIN_DEGREES: f64 = 10.0;

/// Why a refined mesh cannot be split: it is not the subdivision of the tables' control mesh at
/// its level, or the split would number more vertices than 32-bit indices reach.
#[derive(Debug, Clone, PartialEq, Eq, thiserror::Error)]
pub enum SplitError {
    #[error(
        "the refined mesh has {found} vertices where its level-{level} numbering has \
         {expected}: split a fresh subdivision of the same control mesh"
    )]
    Numbering {
        level: u32,
        found: usize,
        expected: usize,
    },
    #[error("splitting at level {level} gives {total} refined vertices, more than 2^32")]
    TooLarge { level: u32, total: usize },
}

/// `joined[3t + e]`: side `e` of triangle `t` is joined to its neighbour (SPEC.md G.2): the
/// side has a neighbour, its spoke is not sharp, and, for a flat object, the two triangles'
/// geometric normals (from `POSN`, in `f64`) are within [`FLAT_JOIN_DEGREES`]. Values mix and
/// refined vertices are shared across joined sides only. This is the one definition the
/// lighting table, the split and the kernels' tables read.
pub fn joined_sides(mesh: &ControlMesh, kind: ObjectKind) -> Vec<bool> {
    let f = mesh.triangles.len() / 3;
    let normals: Vec<[f64; 3]> = match kind {
        ObjectKind::Flat => (0..f).map(|t| coarse_normal(mesh, t)).collect(),
        ObjectKind::Multiresolution => Vec::new(),
    };
    let cos_join = FLAT_JOIN_DEGREES.to_radians().cos();
    (0..3 * f)
        .map(|s| {
            let u = mesh.neighbours.get(s).copied().unwrap_or(NO_NEIGHBOUR);
            if u == NO_NEIGHBOUR || u as usize >= f {
                return false;
            }
            let v = mesh.triangles[s] as usize;
            let spoke = mesh
                .ring_offsets
                .get(v)
                .zip(mesh.corner_spokes.get(s))
                .and_then(|(&o, &k)| mesh.spoke_flags.get((o + k) as usize))
                .copied()
                .unwrap_or(SPOKE_SHARP);
            spoke & SPOKE_SHARP == 0
                && match kind {
                    ObjectKind::Multiresolution => true,
                    ObjectKind::Flat => dot(normals[s / 3], normals[u as usize]) >= cos_join,
                }
        })
        .collect()
}

/// The unit geometric normal of coarse triangle `t` in `f64` from its `POSN` corners (SPEC.md
/// G.2), the zero vector for a degenerate triangle (which then joins nothing).
fn coarse_normal(mesh: &ControlMesh, t: usize) -> [f64; 3] {
    let p = |c: usize| {
        let v = mesh.triangles[3 * t + c] as usize;
        [0, 1, 2].map(|k| f64::from(mesh.positions.get(3 * v + k).copied().unwrap_or(0.0)))
    };
    let (p0, p1, p2) = (p(0), p(1), p(2));
    let (u, w) = (
        [0, 1, 2].map(|k| p1[k] - p0[k]),
        [0, 1, 2].map(|k| p2[k] - p0[k]),
    );
    let n = [
        u[1] * w[2] - u[2] * w[1],
        u[2] * w[0] - u[0] * w[2],
        u[0] * w[1] - u[1] * w[0],
    ];
    let l = dot(n, n).sqrt();
    if l > 0.0 {
        n.map(|x| x / l)
    } else {
        [0.0; 3]
    }
}

fn dot(a: [f64; 3], b: [f64; 3]) -> f64 {
    a[0] * b[0] + a[1] * b[1] + a[2] * b[2]
}

/// The group of every triangle corner `3t + c`: the smallest corner linked to it by a chain of
/// `joined` sides at the same vertex (union-find; the smaller root wins, so the result does not
/// depend on the order of the unions).
pub fn corner_groups(mesh: &ControlMesh, joined: &[bool]) -> Vec<u32> {
    let f = mesh.triangles.len() / 3;
    let mut up: Vec<u32> = (0..3 * f as u32).collect();
    fn find(up: &mut [u32], mut a: u32) -> u32 {
        while up[a as usize] != a {
            let next = up[up[a as usize] as usize];
            up[a as usize] = next;
            a = next;
        }
        a
    }
    for t in 0..f {
        for e in 0..3 {
            if !joined[3 * t + e] {
                continue;
            }
            let u = mesh.neighbours[3 * t + e] as usize;
            let (a, b) = (
                mesh.triangles[3 * t + e],
                mesh.triangles[3 * t + (e + 1) % 3],
            );
            for (c, v) in [(e, a), ((e + 1) % 3, b)] {
                if let Some(cu) = (0..3).find(|&cu| mesh.triangles[3 * u + cu] == v) {
                    let (ra, rb) = (
                        find(&mut up, (3 * t + c) as u32),
                        find(&mut up, (3 * u + cu) as u32),
                    );
                    let (lo, hi) = (ra.min(rb), ra.max(rb));
                    up[hi as usize] = lo;
                }
            }
        }
    }
    (0..3 * f as u32).map(|i| find(&mut up, i)).collect()
}

/// Where an object's refined vertices split (SPEC.md F.5), independent of the level.
#[derive(Clone, Debug, Default, PartialEq, Eq)]
pub struct SplitTables {
    pub vertex_count: u32,
    pub edge_count: u32,
    /// Per corner `3t + c`: [`NO_COPY`] when the corner is in its vertex's owner region, else
    /// the rank of its region's copy among the `copies` corner copies.
    pub corner_copy: Vec<u32>,
    /// Per edge id: [`NO_COPY`], or the edge's rank among the `split_edges` split edges.
    pub edge_copy: Vec<u32>,
    /// `X`: corner copies.
    pub copies: u32,
    /// `S`: split edges, the edges with a neighbour that are not joined (SPEC.md G.2).
    pub split_edges: u32,
    /// CSR over corner slots (`V + X`: control point `v`'s owner region, then the copies):
    /// the region's corners `3t + c`, increasing.
    pub corner_slot_offsets: Vec<u32>,
    pub corner_slot_corners: Vec<u32>,
    /// CSR over edge slots (`E + S`: edge `id`, then the split edges' copies): the sides
    /// `3t + e` whose fine triangles meet the slot's points, owner first; a split edge's slot
    /// holds its owner side, its copy the other side.
    pub edge_slot_offsets: Vec<u32>,
    pub edge_slot_sides: Vec<u32>,
    /// Per corner slot, then per edge slot: 1 when the slot is a region of a split vertex (its
    /// normal is its region's, F.6), else 0.
    pub slot_split: Vec<u32>,
}

impl SplitTables {
    /// The split of an object's control mesh of kind `kind`, whose triangles and edge ids must
    /// pass the checks of [`FlatTopology::new`].
    pub fn new(name: &str, mesh: &ControlMesh, kind: ObjectKind) -> Result<Self, InvalidObject> {
        let topo = FlatTopology::new(name, mesh)?;
        Ok(Self::from_topology(mesh, &topo, kind))
    }

    /// [`SplitTables::new`] from the incidence tables already built.
    ///
    /// A mesh without a neighbour table (a plain mesh previewed as a flat object in memory,
    /// never a container's object, whose `NBRS` is required) has no edge with a neighbour;
    /// nothing is split there and its vertices keep their F.5 sharing.
    pub fn from_topology(mesh: &ControlMesh, topo: &FlatTopology, kind: ObjectKind) -> Self {
        let joined = joined_sides(mesh, kind);
        let adjacency = mesh.neighbours.len() == mesh.triangles.len();
        let group: Vec<u32> = if adjacency {
            corner_groups(mesh, &joined)
        } else {
            // One region per control point: every corner in the group of the vertex's first.
            let mut g = vec![0u32; mesh.triangles.len()];
            for v in 0..topo.vertex_count as usize {
                let corners = &topo.vertex_corners[topo.vertex_corner_offsets[v] as usize
                    ..topo.vertex_corner_offsets[v + 1] as usize];
                for &c in corners {
                    g[c as usize] = corners[0];
                }
            }
            g
        };
        let nv = topo.vertex_count as usize;
        let ne = topo.edge_count as usize;
        let mut corner_copy = vec![NO_COPY; mesh.triangles.len()];
        // Owner regions first (slot v), copies after: two passes over the vertices.
        let mut owner_lists: Vec<Vec<u32>> = vec![Vec::new(); nv];
        let mut copy_lists: Vec<Vec<u32>> = Vec::new();
        let mut split_vertex = vec![false; nv];
        let mut copy_split = Vec::new();
        for v in 0..nv {
            let corners = &topo.vertex_corners[topo.vertex_corner_offsets[v] as usize
                ..topo.vertex_corner_offsets[v + 1] as usize];
            // Regions in order of their first corner; the owner corner is the first of all.
            let mut roots: Vec<u32> = Vec::new();
            let mut ranks: Vec<usize> = Vec::new();
            for &c in corners {
                let g = group[c as usize];
                let r = roots.iter().position(|&x| x == g).unwrap_or_else(|| {
                    roots.push(g);
                    if roots.len() > 1 {
                        ranks.push(copy_lists.len());
                        copy_lists.push(Vec::new());
                        copy_split.push(true);
                    }
                    roots.len() - 1
                });
                if r == 0 {
                    owner_lists[v].push(c);
                } else {
                    copy_lists[ranks[r - 1]].push(c);
                    corner_copy[c as usize] = ranks[r - 1] as u32;
                }
            }
            split_vertex[v] = roots.len() > 1;
        }
        let copies = copy_lists.len() as u32;
        let mut corner_slot_offsets = vec![0u32];
        let mut corner_slot_corners = Vec::with_capacity(mesh.triangles.len());
        for list in owner_lists.iter().chain(&copy_lists) {
            corner_slot_corners.extend_from_slice(list);
            corner_slot_offsets.push(corner_slot_corners.len() as u32);
        }
        let mut edge_copy = vec![NO_COPY; ne];
        let mut edge_slot_offsets = vec![0u32];
        let mut edge_slot_sides = Vec::with_capacity(mesh.triangles.len());
        let mut copy_sides = Vec::new();
        let mut edge_split = vec![false; ne];
        for id in 0..ne {
            let sides = &topo.edge_sides
                [topo.edge_side_offsets[id] as usize..topo.edge_side_offsets[id + 1] as usize];
            let neighboured =
                sides.len() == 2 && mesh.neighbours.get(sides[0] as usize) == Some(&(sides[1] / 3));
            if neighboured && !joined[sides[0] as usize] {
                edge_copy[id] = copy_sides.len() as u32;
                edge_split[id] = true;
                edge_slot_sides.push(sides[0]);
                copy_sides.push(sides[1]);
            } else {
                edge_slot_sides.extend_from_slice(sides);
            }
            edge_slot_offsets.push(edge_slot_sides.len() as u32);
        }
        let split_edges = copy_sides.len() as u32;
        for s in copy_sides {
            edge_slot_sides.push(s);
            edge_slot_offsets.push(edge_slot_sides.len() as u32);
        }
        let slot_split = split_vertex
            .iter()
            .copied()
            .chain(copy_split)
            .chain(edge_split)
            .chain(std::iter::repeat_n(true, split_edges as usize))
            .map(u32::from)
            .collect();
        Self {
            vertex_count: topo.vertex_count,
            edge_count: topo.edge_count,
            corner_copy,
            edge_copy,
            copies,
            split_edges,
            corner_slot_offsets,
            corner_slot_corners,
            edge_slot_offsets,
            edge_slot_sides,
            slot_split,
        }
    }

    /// Whether nothing splits (every edge with a neighbour is joined).
    pub fn is_empty(&self) -> bool {
        self.copies == 0 && self.split_edges == 0
    }

    /// The seven tables the kernels upload, in the order their uploads and the browser's frames
    /// lay them out: edge slots (offsets, sides), corner slots (offsets, corners), the corner and
    /// edge copies, and `slot_split`. The flat kernel takes the first six.
    pub fn tables(&self) -> [&[u32]; 7] {
        [
            &self.edge_slot_offsets,
            &self.edge_slot_sides,
            &self.corner_slot_offsets,
            &self.corner_slot_corners,
            &self.corner_copy,
            &self.edge_copy,
            &self.slot_split,
        ]
    }

    /// Vertices appended at `level`: `X + S (2^level − 1)`.
    pub fn appended(&self, level: u32) -> u64 {
        u64::from(self.copies) + u64::from(self.split_edges) * ((1u64 << level) - 1)
    }

    /// The corners of corner slot `slot`.
    pub fn corner_slot(&self, slot: usize) -> &[u32] {
        &self.corner_slot_corners
            [self.corner_slot_offsets[slot] as usize..self.corner_slot_offsets[slot + 1] as usize]
    }

    /// The sides of edge slot `slot`.
    pub fn edge_slot(&self, slot: usize) -> &[u32] {
        &self.edge_slot_sides
            [self.edge_slot_offsets[slot] as usize..self.edge_slot_offsets[slot + 1] as usize]
    }

    /// The F.5 vertex each appended vertex repeats at `level`, in order: a corner copy the
    /// control point of its corners, an edge copy the owner's point `k` of its edge.
    pub fn copy_sources(&self, mesh: &ControlMesh, level: u32) -> Vec<u32> {
        let per_edge = (1u32 << level) - 1;
        let nv = self.vertex_count as usize;
        let mut out = Vec::with_capacity(self.appended(level) as usize);
        for slot in nv..nv + self.copies as usize {
            out.push(mesh.triangles[self.corner_slot(slot)[0] as usize]);
        }
        for id in 0..self.edge_count {
            if self.edge_copy[id as usize] != NO_COPY {
                out.extend((0..per_edge).map(|k| self.vertex_count + id * per_edge + k));
            }
        }
        out
    }

    /// The vertex the fine triangles of coarse triangle `t` use where the F.5 numbering at
    /// `level` (with `base` F.5 vertices) gives `i`: the copy of `t`'s region where `i` is split
    /// (SPEC.md F.5), else `i`. `corners` are `t`'s three control points.
    pub fn split_index(&self, level: u32, base: usize, t: usize, corners: [u32; 3], i: u32) -> u32 {
        let per_edge = (1usize << level) - 1;
        let nv = self.vertex_count as usize;
        let iu = i as usize;
        if iu < nv {
            if let Some(c) = (0..3).find(|&c| corners[c] == i) {
                let copy = self.corner_copy[3 * t + c];
                if copy != NO_COPY {
                    return (base + copy as usize) as u32;
                }
            }
        } else if iu < nv + self.edge_count as usize * per_edge {
            let id = (iu - nv) / per_edge;
            let copy = self.edge_copy[id];
            if copy != NO_COPY && self.edge_slot(id)[0] as usize / 3 != t {
                return (base
                    + self.copies as usize
                    + copy as usize * per_edge
                    + (iu - nv) % per_edge) as u32;
            }
        }
        i
    }

    /// Splits `r`, a Loop subdivision of the same control mesh numbered as F.5 says (before any
    /// split), in place: appends the copies (positions bit for bit, SPEC.md F.5), moves the
    /// fine triangles' corners to their region's vertex and gives every split vertex the
    /// normal of its own region (F.6).
    pub fn apply(&self, mesh: &ControlMesh, r: &mut Refined) -> Result<(), SplitError> {
        let level = r.level;
        let m = 1i32 << level;
        let per_edge = (m - 1) as usize;
        let nv = self.vertex_count as usize;
        let edge_base = nv;
        let base = r.positions.len();
        let expected = nv
            + self.edge_count as usize * per_edge
            + r.coarse_triangles * per_edge * per_edge.saturating_sub(1) / 2;
        if base != expected || r.normals.len() != base || r.coarse_vertices != nv {
            return Err(SplitError::Numbering {
                level,
                found: base,
                expected,
            });
        }
        if self.is_empty() {
            return Ok(());
        }
        let x = self.copies as usize;
        let total = base + self.appended(level) as usize;
        if u32::try_from(total).is_err() {
            return Err(SplitError::TooLarge { level, total });
        }
        // Positions (and placeholder normals) of the copies.
        for i in self.copy_sources(mesh, level) {
            r.positions.push(r.positions[i as usize]);
            r.normals.push(r.normals[i as usize]);
        }
        let split_ids: Vec<usize> = (0..self.edge_count as usize)
            .filter(|&id| self.edge_copy[id] != NO_COPY)
            .collect();
        // Fine triangles: each corner to its region's vertex.
        let per = 1usize << (2 * level);
        for t in 0..r.coarse_triangles {
            let tv = [0, 1, 2].map(|c| mesh.triangles[3 * t + c]);
            for f in &mut r.indices[t * per..(t + 1) * per] {
                for o in f.iter_mut() {
                    *o = self.split_index(level, base, t, tv, *o);
                }
            }
        }
        // Normals of split vertices: their own region's fine triangles (F.6).
        for slot in 0..nv + x {
            if self.slot_split[slot] == 0 {
                continue;
            }
            let at = if slot < nv { slot } else { base + slot - nv };
            let points: Vec<(usize, [i32; 2])> = self
                .corner_slot(slot)
                .iter()
                .map(|&c| (c as usize / 3, corner_point(m, c % 3)))
                .collect();
            r.normals[at] = region_normal(r, &points);
        }
        let edge_slots = self.edge_count as usize + split_ids.len();
        for slot in 0..edge_slots {
            if self.slot_split[nv + x + slot] == 0 {
                continue;
            }
            let side = self.edge_slot(slot)[0] as usize;
            let (t, e) = (side / 3, (side % 3) as u32);
            let (id, first) = if slot < self.edge_count as usize {
                (slot, edge_base + slot * per_edge)
            } else {
                let s = slot - self.edge_count as usize;
                (split_ids[s], base + x + s * per_edge)
            };
            // The owner side counts k from its own v_e; the other side from its v_{e+1}.
            let from_owner = self.edge_slot(id)[0] as usize == side;
            for k in 1..m {
                let kk = if from_owner { k } else { m - k };
                r.normals[first + (k - 1) as usize] =
                    region_normal(r, &[(t, edge_point(m, e, kk))]);
            }
        }
        Ok(())
    }
}

/// The unit normal of a split vertex (SPEC.md F.6): the sum of the normals of the fine
/// triangles of coarse triangle `t` at lattice point `p`, for each `(t, p)` in order, each in
/// the order of [`incident_paths`].
fn region_normal(r: &Refined, points: &[(usize, [i32; 2])]) -> [f32; 3] {
    let per = 1usize << (2 * r.level);
    let mut s: Option<[f32; 3]> = None;
    for &(t, [b, c]) in points {
        for path in incident_paths(r.level, b, c) {
            let tri = r.indices[t * per + path as usize].map(|i| r.positions[i as usize]);
            let n = crate::normal::face_normal(tri);
            s = Some(match s {
                None => n,
                Some(s) => [s[0] + n[0], s[1] + n[1], s[2] + n[2]],
            });
        }
    }
    crate::subdivide::unit_normal(s.unwrap_or([0.0; 3]))
}
