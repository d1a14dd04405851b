//! Loop subdivision (CPU reference) computed from the control-mesh adjacency tables, one
//! independent local patch per coarse triangle, as the GPU kernel computes it.
//!
//! Based on:
//! * Charles Loop. Smooth Subdivision Surfaces Based on Triangles. MSc thesis, University of
//!   Utah, 1987.
//! * Joe Warren and Scott Schaefer. A factored approach to subdivision surfaces. IEEE Computer
//!   Graphics and Applications 24(3), 2004 (linear split, averaging, valence correction
//!   `cf(n) = 5/3 - 8/3 (3/8 + 1/4 cos(2π/n))²`).
//! * Infinitely sharp creases and boundaries as in OpenSubdiv 3.5 (`Sdc::SCHEME_LOOP`,
//!   `VTX_BOUNDARY_EDGE_AND_CORNER`): midpoint on sharp edges, `3/4, 1/8, 1/8` for vertices with
//!   two sharp edges, fixed corners (three or more sharp edges, or a boundary vertex with a
//!   single triangle).
//!
//! # The local patch
//!
//! Triangle `t = (v0, v1, v2)` at level `l` (`N = 2^l` segments per edge) holds:
//!
//! * `grid`: the `(N+1)(N+2)/2` points of the triangle, lattice point `(i, j)` (barycentric
//!   `v0 + i/N (v1 - v0) + j/N (v2 - v0)`, `i, j >= 0`, `i + j <= N`; the `(b, c)` of
//!   [`crate::lattice`]) at index `j (N+1) - j (j-1)/2 + i` (rows of constant `j`,
//!   [`crate::lattice::grid_index`]).
//! * `band[e]` for each interior edge `e` (from `v_e` to `v_{e+1}`, points `p_0 = v_e .. p_N`):
//!   the `N` vertices of the neighbouring triangle one row away from the edge; `band[e][m]` is
//!   adjacent to `p_m` and `p_{m+1}`. As lattice points outside the grid: edge 0 `(m+1, -1)`,
//!   edge 1 `(N-m, m+1)`, edge 2 `(-1, N-m)`.
//! * `ring[c]`: corner `c`'s whole one-ring at level `l`, in the order of the control-mesh ring
//!   (its length, the valence, never changes), with the spoke flags of the table.
//!
//! On the CPU the grid and the bands live in one `(N+3)²` array over lattice points
//! `-1 ..= N+1` (index `(i+1) + (j+1)(N+3)`), so that a neighbour read never branches on
//! which of them holds it; a GPU port may keep the same array.
//!
//! Level `l + 1` is computed from level `l` alone: the rings from the rings (the child of spoke
//! `m` is the edge point of spoke `m`, whose opposite vertices are spokes `m - 1` and `m + 1`),
//! the grid from the grid and bands, and the new bands from the grid, the old bands and the new
//! rings (every new band vertex is an edge point; the first and last are ring spokes). The same
//! fine vertex may be computed twice inside one patch (a ring spoke next to a corner is also a
//! grid or band point); the edge-point formula is symmetric in its endpoints and in its
//! opposite vertices, bit for bit, so both copies are equal.
//!
//! # Order of arithmetic (for a bit-faithful port)
//!
//! All in `f32`, per component, without fused multiply-add:
//! * `mid(a, b) = (a + b) * 0.5`.
//! * Smooth edge point of edge `(a, b)` with opposite vertices `c`, `d`:
//!   `(a + b) * 0.375 + (c + d) * 0.125`. Sharp edge point: `mid(a, b)`.
//! * Smooth vertex point of `v` with neighbours `n_0 .. n_{k-1}`:
//!   `s = mid(v, n_0); s = s + mid(v, n_1); ...` (a corner in the order of its table ring
//!   from index 0; a grid point in the lattice directions `(1,0), (0,1), (-1,1), (-1,0),
//!   (0,-1), (1,-1)`, a direction outside the grid read from the band), then
//!   `avg = v * 0.25 + s * (0.75 / k as f32)` and `v + (avg - v) * cf(k)` with
//!   `cf(k)` rounded from `f64` to `f32` ([`correction_factor`]).
//! * Crease vertex with sharp neighbours `a`, `b` (a corner: its two sharp spokes in ring
//!   order; a point on a sharp coarse edge: its previous and next points along the edge):
//!   `v * 0.75 + (a + b) * 0.125`. Corner vertex: `v`.
//! * Per level, in this order: rings and corner points, then the grid in rows of increasing
//!   `J`, then the bands (first and last band points copied from the new rings, at ring
//!   positions `k_e - 1` of corner `e` and `k_{e+1} + 2` of corner `e + 1`, mod the valence).
//!
//! # Output numbering
//!
//! The numbering of [`crate::lattice`] ([`crate::lattice::Numbering`]), shared with flat
//! refinement. With `M = 2^L`, `V` control vertices, `E` edges and `F` triangles:
//! `[V coarse vertices][E edges × (M − 1) points, from the owning triangle's v_e to v_{e+1}]
//! [F triangles × (M−1)(M−2)/2 interior points]`, interior points in rows of increasing `j`,
//! each row in increasing `i` (`1 <= i, j`, `i + j <= M - 1`). Fine triangle `t · 4^L + path`
//! has the corners the recursive 1-to-4 split gives (child order Top, Left, Center, Right of
//! `hce_format::model`; [`crate::lattice::subtriangle_cells`]). Every output vertex is written
//! by exactly one owner (a coarse vertex by the first triangle corner that uses it in scan
//! order, an edge point by the owner of its edge, an interior point by its triangle), so shared
//! vertices cannot disagree.
//!
//! # Normals
//!
//! Per-vertex normals are the normalised sum of the (area-weighted) normals of the fine
//! triangles around the vertex at the output level, not limit normals; every vertex owner has
//! the full one-ring in its patch, so this is local too. Each fine triangle's normal
//! `cross(q - p, r - p)` is computed once per patch, with `p, q, r` = `(a,b), (a+1,b), (a,b+1)`
//! for an up triangle and `(a+1,b), (a+1,b+1), (a,b+1)` for a down one; a lattice vertex sums
//! its six triangles counter-clockwise from the one between directions `(1,0)` and `(0,1)`
//! (a triangle across a boundary edge counts as zero), a corner sums
//! `cross(r_f - v, r_{f+1} - v)` over consecutive spokes of its ring.
//!
//! # The output level
//!
//! At the last level a patch computes only what it writes: the bands of the edges it owns
//! (their points' normals need the triangles across) and the rings of its owned corners and of
//! those bands' end points. Vertices it does not own come from their owners, whose arithmetic
//! is the same.

// Index loops over corners, edges and lattice rows mirror the WGSL kernel this is ported to.
#![allow(clippy::needless_range_loop)]

use hce_format::{
    ControlMesh, NO_NEIGHBOUR, RULE_CORNER, RULE_CREASE, SPOKE_SHARP, VERTEX_BOUNDARY,
};
use rayon::prelude::*;

use crate::lattice::{subtriangle_cells, Numbering};
use crate::tables::check_loop_tables;

/// Deepest Loop subdivision level: of this CPU reference and of the GPU Loop kernel alike, which
/// check the same bound (`4^6` fine triangles per coarse one; a level-6 patch already takes
/// 105 KiB of GPU scratch). Flat refinement goes deeper, to [`crate::decode::MAX_PATH_LEVEL`].
pub const MAX_LOOP_LEVEL: u32 = 6;

/// A point of the patch. `Vec3A` keeps x, y, z in one SIMD register; its `+`, `-` and `*`
/// are the per-component `f32` operations of the documented order (no fused multiply-add), so
/// the bits are those of scalar code.
type P = glam::Vec3A;
/// An output point.
type Out = [f32; 3];

#[inline(always)]
fn add(a: P, b: P) -> P {
    a + b
}
#[inline(always)]
fn sub(a: P, b: P) -> P {
    a - b
}
#[inline(always)]
fn mul(a: P, s: f32) -> P {
    a * s
}
#[inline(always)]
fn cross(a: P, b: P) -> P {
    a.cross(b)
}
#[inline(always)]
fn mid(a: P, b: P) -> P {
    mul(add(a, b), 0.5)
}

/// Edge point of edge `(a, b)` with opposite vertices `c` and `d`. In the factored form it is
/// the averaging of the linearly split mesh at the midpoint (valence 6, `cf(6) = 1`, so no
/// correction): `m/4 + 1/8 Σ` of its six fine neighbours, which collapses exactly to Loop's
/// `3/8 (a + b) + 1/8 (c + d)`; the collapsed form is 4 times cheaper and, being symmetric
/// in `a, b` and in `c, d`, gives the same bits whichever way round the edge is read.
#[inline(always)]
fn odd_smooth(a: P, b: P, c: P, d: P) -> P {
    add(mul(add(a, b), 0.375), mul(add(c, d), 0.125))
}

/// Vertex point of a smooth vertex: averaging `v' = v/4 + 3/(4n) Σ mid(v, n_i)` then the
/// valence correction `v'' = v + cf(n) (v' - v)`.
#[inline(always)]
fn even_smooth(v: P, sum_mid: P, n: usize, cf: f32) -> P {
    let avg = add(mul(v, 0.25), mul(sum_mid, 0.75 / n as f32));
    add(v, mul(sub(avg, v), cf))
}

/// Crease rule for a vertex with two sharp edges to `a` and `b`.
#[inline(always)]
fn even_crease(v: P, a: P, b: P) -> P {
    add(mul(v, 0.75), mul(add(a, b), 0.125))
}

/// The valence correction factor of Warren & Schaefer, `cf(n)`.
pub fn correction_factor(n: usize) -> f32 {
    let a = 0.375 + 0.25 * (2.0 * std::f64::consts::PI / n as f64).cos();
    (5.0 / 3.0 - 8.0 / 3.0 * a * a) as f32
}

/// Errors of subdivision.
#[derive(Debug, thiserror::Error, PartialEq)]
pub enum SubdivError {
    #[error("subdivision level {0} is out of range; use 0..={MAX_LOOP_LEVEL}")]
    Level(u32),
    #[error("control mesh tables are inconsistent: {0}")]
    Tables(String),
    #[error("level {level} output of {triangles} coarse triangles is too large ({what})")]
    TooLarge {
        level: u32,
        triangles: usize,
        what: &'static str,
    },
}

/// A mesh refined to one level.
#[derive(Clone, Debug, Default, PartialEq)]
pub struct Refined {
    pub level: u32,
    pub positions: Vec<[f32; 3]>,
    /// Unit per-vertex normals (see the module documentation).
    pub normals: Vec<[f32; 3]>,
    /// Fine triangle `t · 4^level + path`, counter-clockwise.
    pub indices: Vec<[u32; 3]>,
    pub coarse_vertices: usize,
    pub coarse_edges: usize,
    pub coarse_triangles: usize,
}

impl Refined {
    /// The coarse triangle fine triangle `f` lies in.
    pub fn coarse_triangle(&self, f: usize) -> usize {
        f >> (2 * self.level)
    }
    /// The path of fine triangle `f` in its coarse triangle (see `hce_format::model`).
    pub fn path(&self, f: usize) -> u32 {
        (f & ((1usize << (2 * self.level)) - 1)) as u32
    }
}

/// Index of lattice point `(i, j)`, `-1 <= i, j <= n + 1`, in the square array of a level with
/// `n` segments per edge: width `n + 3`, index `(i + 1) + (j + 1)(n + 3)`.
#[inline(always)]
fn sq(n: usize, i: isize, j: isize) -> usize {
    (i + 1) as usize + (j + 1) as usize * (n + 3)
}

/// Square index of corner `c`.
#[inline(always)]
fn sq_corner(n: usize, c: usize) -> usize {
    match c {
        0 => sq(n, 0, 0),
        1 => sq(n, n as isize, 0),
        _ => sq(n, 0, n as isize),
    }
}

/// Square index of point `m` of edge `e` (from `v_e`).
#[inline(always)]
fn sq_edge(n: usize, e: usize, m: usize) -> usize {
    let (n, m) = (n as isize, m as isize);
    match e {
        0 => sq(n as usize, m, 0),
        1 => sq(n as usize, n - m, m),
        _ => sq(n as usize, 0, n - m),
    }
}

/// Square index of point `m` of band `e` (see the module documentation).
#[inline(always)]
fn sq_band(n: usize, e: usize, m: usize) -> usize {
    let (n, m) = (n as isize, m as isize);
    match e {
        0 => sq(n as usize, m + 1, -1),
        1 => sq(n as usize, n - m, m + 1),
        _ => sq(n as usize, -1, n - m),
    }
}

/// Per-triangle constants read from the tables once.
struct Corner {
    /// Offset of the ring in `mesh.ring`.
    off: usize,
    n: usize,
    k: usize,
    closed: bool,
    rule: u32,
    /// The two sharp spokes of a crease vertex.
    creases: [usize; 2],
}

/// Local patch storage, reused across the triangles of one task.
#[derive(Default)]
struct Patch {
    /// Grid and bands of the current level, over lattice points `-1 ..= n+1` (see [`sq`]).
    /// Entries across a boundary edge, and entries no level wrote for this triangle, hold
    /// stale values that are never read.
    sq: Vec<P>,
    next: Vec<P>,
    ring: [Vec<P>; 3],
    next_ring: [Vec<P>; 3],
    /// Normals (cross products, not normalised) of the fine triangles at the output level on
    /// the same square: `up[(a, b)]` is `(a,b), (a+1,b), (a,b+1)`, `down[(a, b)]` is
    /// `(a+1,b), (a+1,b+1), (a,b+1)`.
    up: Vec<P>,
    down: Vec<P>,
}

struct Tri<'a> {
    mesh: &'a ControlMesh,
    corners: [Corner; 3],
    /// Edge `e` is interior (has a band).
    interior: [bool; 3],
    sharp: [bool; 3],
    cf: &'a [f32],
}

/// Smooth vertex point of a valence-6 lattice vertex, neighbours in the lattice direction
/// order of the module documentation.
#[inline(always)]
fn even_lattice(v: P, nb: [P; 6], cf6: f32) -> P {
    let mut s = mid(v, nb[0]);
    s = add(s, mid(v, nb[1]));
    s = add(s, mid(v, nb[2]));
    s = add(s, mid(v, nb[3]));
    s = add(s, mid(v, nb[4]));
    s = add(s, mid(v, nb[5]));
    even_smooth(v, s, 6, cf6)
}

/// `cross(q - p, r - p)` for the triangle `p, q, r`.
#[inline(always)]
fn face(p: P, q: P, r: P) -> P {
    cross(sub(q, p), sub(r, p))
}

fn ensure_len(v: &mut Vec<P>, len: usize) {
    if v.len() < len {
        v.resize(len, P::ZERO);
    }
}

impl Patch {
    /// Level 0: the triangle's corners, its rings and the one-point bands.
    fn load(&mut self, tri: &Tri, tv: [u32; 3]) {
        let mesh = tri.mesh;
        ensure_len(&mut self.sq, 16);
        for c in 0..3 {
            let corner = &tri.corners[c];
            let ring = &mut self.ring[c];
            ring.clear();
            ring.extend(
                mesh.ring[corner.off..corner.off + corner.n]
                    .iter()
                    .map(|&s| P::from(mesh.position(s))),
            );
            self.sq[sq_corner(1, c)] = P::from(mesh.position(tv[c]));
        }
        for e in 0..3 {
            if tri.interior[e] {
                let c = &tri.corners[e];
                self.sq[sq_band(1, e, 0)] = self.ring[e][(c.k + c.n - 1) % c.n];
            }
        }
    }

    /// One level: `n` segments to `2n`. Only the bands in `need_band` and the rings in
    /// `need_ring` are computed (all of them except at the output level, where the patch owner
    /// needs only what its own vertices' normals read).
    fn step(&mut self, tri: &Tri, n: usize, need_band: [bool; 3], need_ring: [bool; 3]) {
        let m2 = 2 * n;
        let w = n + 3;
        // Rings and corners.
        let mut new_corner = [P::ZERO; 3];
        for c in 0..3 {
            let corner = &tri.corners[c];
            let v = self.sq[sq_corner(n, c)];
            let ring = &self.ring[c];
            let cn = corner.n;
            if need_ring[c] {
                let flags = &tri.mesh.spoke_flags[corner.off..corner.off + cn];
                let nr = &mut self.next_ring[c];
                nr.clear();
                for s in 0..cn {
                    let r = ring[s];
                    nr.push(if flags[s] & SPOKE_SHARP != 0 {
                        mid(v, r)
                    } else {
                        odd_smooth(v, r, ring[(s + cn - 1) % cn], ring[(s + 1) % cn])
                    });
                }
            }
            new_corner[c] = match corner.rule {
                RULE_CORNER => v,
                RULE_CREASE => even_crease(v, ring[corner.creases[0]], ring[corner.creases[1]]),
                _ => {
                    let mut s = P::ZERO;
                    for &r in ring.iter() {
                        s = add(s, mid(v, r));
                    }
                    even_smooth(v, s, cn, tri.cf[cn])
                }
            };
        }
        // Grid, two new rows per old row `j`: vertex and edge points on row `2j`, the edge
        // points between rows `j` and `j + 1` on row `2j + 1`.
        ensure_len(&mut self.next, (m2 + 3) * (m2 + 3));
        let (s, d) = (&self.sq, &mut self.next);
        let sharp = tri.sharp;
        let cf6 = tri.cf[6];
        for j in 0..=n {
            let len = n - j;
            let x0 = sq(n, 0, j as isize);
            let y0 = sq(m2, 0, 2 * j as isize);
            for i in 0..=len {
                let x = x0 + i;
                let v = s[x];
                d[y0 + 2 * i] = if j == 0 && i == 0 {
                    new_corner[0]
                } else if j == 0 && i == n {
                    new_corner[1]
                } else if j == n {
                    new_corner[2]
                } else if j == 0 && sharp[0] {
                    // On a sharp coarse edge: crease rule along the edge.
                    even_crease(v, s[x - 1], s[x + 1])
                } else if i == len && sharp[1] {
                    even_crease(v, s[x + 1 - w], s[x - 1 + w])
                } else if i == 0 && sharp[2] {
                    even_crease(v, s[x - w], s[x + w])
                } else {
                    let nb = [
                        s[x + 1],
                        s[x + w],
                        s[x + w - 1],
                        s[x - 1],
                        s[x - w],
                        s[x - w + 1],
                    ];
                    even_lattice(v, nb, cf6)
                };
                if i < len {
                    let b = s[x + 1];
                    d[y0 + 2 * i + 1] = if j == 0 && sharp[0] {
                        mid(v, b)
                    } else {
                        odd_smooth(v, b, s[x + w], s[x + 1 - w])
                    };
                }
            }
            if j < n {
                let y1 = sq(m2, 0, 2 * j as isize + 1);
                for i in 0..len {
                    let x = x0 + i;
                    let (a, b) = (s[x], s[x + w]);
                    d[y1 + 2 * i] = if i == 0 && sharp[2] {
                        mid(a, b)
                    } else {
                        odd_smooth(a, b, s[x + 1], s[x + w - 1])
                    };
                    let a = s[x + 1];
                    d[y1 + 2 * i + 1] = if i + 1 == len && sharp[1] {
                        mid(a, b)
                    } else {
                        odd_smooth(a, b, s[x], s[x + w + 1])
                    };
                }
            }
        }
        // Bands.
        for e in 0..3 {
            if !tri.interior[e] || !need_band[e] {
                continue;
            }
            let (c0, c1) = (&tri.corners[e], &tri.corners[(e + 1) % 3]);
            d[sq_band(m2, e, 0)] = self.next_ring[e][(c0.k + c0.n - 1) % c0.n];
            for m in 0..n {
                if m >= 1 {
                    d[sq_band(m2, e, 2 * m)] = odd_smooth(
                        s[sq_edge(n, e, m)],
                        s[sq_band(n, e, m)],
                        s[sq_edge(n, e, m + 1)],
                        s[sq_band(n, e, m - 1)],
                    );
                }
                if m + 2 <= n {
                    d[sq_band(m2, e, 2 * m + 1)] = odd_smooth(
                        s[sq_edge(n, e, m + 1)],
                        s[sq_band(n, e, m)],
                        s[sq_edge(n, e, m)],
                        s[sq_band(n, e, m + 1)],
                    );
                }
            }
            d[sq_band(m2, e, m2 - 1)] = self.next_ring[(e + 1) % 3][(c1.k + 2) % c1.n];
        }
        std::mem::swap(&mut self.sq, &mut self.next);
        std::mem::swap(&mut self.ring, &mut self.next_ring);
    }

    /// Normals of the fine triangles at the output level (`n` segments): every triangle inside
    /// the patch, and the triangles across each edge in `edges` (from the band, or zero across
    /// a boundary edge, where there is no triangle).
    fn face_normals(&mut self, tri: &Tri, n: usize, edges: [bool; 3]) {
        let w = n + 3;
        ensure_len(&mut self.up, w * w);
        ensure_len(&mut self.down, w * w);
        let (s, up, down) = (&self.sq, &mut self.up, &mut self.down);
        let fu = |x: usize| face(s[x], s[x + 1], s[x + w]);
        let fd = |x: usize| face(s[x + 1], s[x + 1 + w], s[x + w]);
        for b in 0..n {
            let x0 = sq(n, 0, b as isize);
            let len = n - b;
            for a in 0..len {
                up[x0 + a] = fu(x0 + a);
            }
            for a in 0..len - 1 {
                down[x0 + a] = fd(x0 + a);
            }
        }
        for e in 0..3 {
            if !edges[e] {
                continue;
            }
            let live = tri.interior[e];
            let ni = n as isize;
            for a in 0..ni {
                // Down triangles across the edge (n of them), then up triangles (n - 1).
                let xd = match e {
                    0 => sq(n, a, -1),
                    1 => sq(n, a, ni - 1 - a),
                    _ => sq(n, -1, a),
                };
                down[xd] = if live { fd(xd) } else { P::ZERO };
                if a >= 1 {
                    let xu = match e {
                        0 => sq(n, a, -1),
                        1 => sq(n, a, ni - a),
                        _ => sq(n, -1, a),
                    };
                    up[xu] = if live { fu(xu) } else { P::ZERO };
                }
            }
        }
    }

    /// Sum of the normals of the six fine triangles around the lattice point at square index
    /// `x` (not a corner), counter-clockwise from the one between directions `(1,0)` and
    /// `(0,1)`. [`Patch::face_normals`] must have covered them.
    #[inline(always)]
    fn vertex_normal(&self, n: usize, x: usize) -> P {
        let w = n + 3;
        let (u, d) = (&self.up, &self.down);
        let mut s = u[x];
        s = add(s, d[x - 1]);
        s = add(s, u[x - 1]);
        s = add(s, d[x - 1 - w]);
        s = add(s, u[x - w]);
        add(s, d[x - w])
    }

    /// Sum of the normals of the fine triangles around corner `c` from its ring.
    fn corner_normal(&self, tri: &Tri, n: usize, c: usize) -> P {
        let corner = &tri.corners[c];
        let v = self.sq[sq_corner(n, c)];
        let ring = &self.ring[c];
        let faces = if corner.closed {
            corner.n
        } else {
            corner.n - 1
        };
        let mut s = P::ZERO;
        for f in 0..faces {
            s = add(s, cross(sub(ring[f], v), sub(ring[(f + 1) % corner.n], v)));
        }
        s
    }
}

/// A vertex normal's sum normalised as SPEC.md F.6 says (`(0, 0, 1)` without a direction): the
/// one normalisation of refined multiresolution normals, split ones included
/// ([`crate::split`]).
pub(crate) fn unit_normal(s: [f32; 3]) -> [f32; 3] {
    normalize(P::from_array(s))
}

fn normalize(s: P) -> Out {
    let l = (s.x * s.x + s.y * s.y + s.z * s.z).sqrt();
    if l > 0.0 && l.is_finite() {
        mul(s, 1.0 / l).to_array()
    } else {
        [0.0, 0.0, 1.0]
    }
}

/// Everything the per-triangle tasks share, derived from the tables once (O(V + F)). The GPU
/// kernel (`hce_runtime::gpu::loop_kernel`) uploads the same derived tables, so both sides agree
/// on owners, crease spokes and correction factors.
pub struct Prepared {
    /// `vertex_owner[v]`: the corner `3 t + c` that writes coarse vertex `v`.
    pub vertex_owner: Vec<u32>,
    /// `edge_start[t]`: the first edge id owned by triangle `t` (ids are in first-appearance
    /// order, so triangle `t` owns `edge_start[t] .. edge_start[t + 1]`).
    pub edge_start: Vec<u32>,
    /// Whether `(t, e)` owns its edge.
    pub owns_edge: Vec<bool>,
    pub crease_spokes: Vec<[u32; 2]>,
    pub cf: Vec<f32>,
    pub edge_count: usize,
}

/// Validates every table the subdivision reads ([`check_loop_tables`]) and derives
/// [`Prepared`].
pub fn prepare(mesh: &ControlMesh) -> Result<Prepared, SubdivError> {
    let tables = check_loop_tables(mesh).map_err(SubdivError::Tables)?;
    let nv = mesh.vertex_count();
    let nf = mesh.triangle_count();
    // Owners: a sequential scan in scan order, which is the order of first appearance that the
    // edge ids were checked to follow.
    let mut vertex_owner = vec![u32::MAX; nv];
    let mut edge_start = Vec::with_capacity(nf + 1);
    let mut owns_edge = vec![false; 3 * nf];
    let mut next = 0u32;
    for t in 0..nf {
        edge_start.push(next);
        let tri = mesh.triangle(t);
        for c in 0..3 {
            let v = tri[c] as usize;
            if vertex_owner[v] == u32::MAX {
                vertex_owner[v] = (3 * t + c) as u32;
            }
            if mesh.edges[3 * t + c] == next {
                owns_edge[3 * t + c] = true;
                next += 1;
            }
        }
    }
    edge_start.push(next);
    let cf = (0..=tables.max_valence)
        .map(|n| if n < 2 { 0.0 } else { correction_factor(n) })
        .collect();
    Ok(Prepared {
        vertex_owner,
        edge_start,
        owns_edge,
        crease_spokes: tables.crease_spokes,
        cf,
        edge_count: next as usize,
    })
}

fn make_tri<'a>(mesh: &'a ControlMesh, prep: &'a Prepared, t: usize) -> Tri<'a> {
    let tri = mesh.triangle(t);
    let corners = std::array::from_fn(|c| {
        let v = tri[c] as usize;
        let off = mesh.ring_offsets[v] as usize;
        let n = mesh.ring_offsets[v + 1] as usize - off;
        let cs = prep.crease_spokes[v];
        Corner {
            off,
            n,
            k: mesh.corner_spokes[3 * t + c] as usize,
            closed: mesh.vertex_flags[v] & VERTEX_BOUNDARY == 0,
            rule: mesh.rule(v as u32),
            creases: [cs[0] as usize, cs[1] as usize],
        }
    });
    let interior = std::array::from_fn(|e| mesh.neighbours[3 * t + e] != NO_NEIGHBOUR);
    let sharp = std::array::from_fn(|e| {
        let c: &Corner = &corners[e];
        mesh.spoke_flags[c.off + c.k] & SPOKE_SHARP != 0
    });
    Tri {
        mesh,
        corners,
        interior,
        sharp,
        cf: &prep.cf,
    }
}

/// The size of [`subdivide`]'s output and, found without subdividing the whole mesh, the
/// per-axis minimum and maximum of its positions: what a glTF writer puts in its header before
/// the buffers, so that it can write them as they are computed.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct OutputShape {
    pub vertices: usize,
    pub triangles: usize,
    /// `None` where a control position is not finite.
    pub bounds: Option<([f32; 3], [f32; 3])>,
}

/// [`OutputShape`] of `subdivide(mesh, level)`.
///
/// Every refined point of a coarse triangle's patch is a convex combination of the control
/// points its patch loads (its corners and their rings): the Loop edge and vertex weights (with
/// the valence correction, `1 - 3 cf(n) / 8` and `3 cf(n) / 8n`), the crease, sharp-edge and
/// corner rules are all non-negative and sum to one. So only triangles whose control box
/// reaches, with a margin far above `f32` rounding, past a refined point already found can hold
/// an extreme; those few are subdivided here, each writing only the points it owns, with the
/// arithmetic of [`subdivide`], so the bounds are those of its output bit for bit. (A writer
/// should still compare them with the output's, as a check that costs one pass.)
pub fn output_shape(mesh: &ControlMesh, level: u32) -> Result<OutputShape, SubdivError> {
    Ok(plan(mesh, level)?.shape())
}

impl Plan<'_> {
    /// [`output_shape`] of the planned mesh and level.
    pub fn shape(&self) -> OutputShape {
        let Plan {
            mesh,
            level,
            ref prep,
            numbering,
        } = *self;
        let nf = mesh.triangle_count();
        let mut shape = OutputShape {
            vertices: numbering.vertex_count() as usize,
            triangles: numbering.triangle_count() as usize,
            bounds: None,
        };
        if nf == 0 || !mesh.positions.iter().all(|p| p.is_finite()) {
            return shape;
        }
        // Control box of each vertex and its ring, then of each triangle's patch (its corners'
        // boxes), with its margin.
        let vertex_boxes: Vec<(P, P)> = (0..mesh.vertex_count())
            .into_par_iter()
            .map(|v| {
                let off = mesh.ring_offsets[v] as usize;
                let end = mesh.ring_offsets[v + 1] as usize;
                let p = P::from(mesh.position(v as u32));
                mesh.ring[off..end].iter().fold((p, p), |(lo, hi), &q| {
                    let q = P::from(mesh.position(q));
                    (lo.min(q), hi.max(q))
                })
            })
            .collect();
        let boxes: Vec<(P, P, f32)> = mesh
            .triangles
            .par_chunks_exact(3)
            .map(|tv| {
                let b = tv.iter().map(|&v| vertex_boxes[v as usize]);
                let (lo, hi) = b.reduce(|a, b| (a.0.min(b.0), a.1.max(b.1))).unwrap();
                let scale = lo.abs().max(hi.abs()).max_element();
                (lo, hi, scale * 1e-4 + f32::MIN_POSITIVE)
            })
            .collect();
        let m = 1usize << level;
        let mut patch = Patch::default();
        // The points triangle `t` writes (`all`: every point of its grid, owned or not).
        let mut points = |t: usize, all: bool, f: &mut dyn FnMut(P)| {
            let tri = make_tri(mesh, prep, t);
            let tv = mesh.triangle(t);
            patch.load(&tri, tv);
            let mut n = 1;
            while n < m {
                patch.step(&tri, n, [true; 3], [true; 3]);
                n *= 2;
            }
            for j in 0..=m {
                for i in 0..=m - j {
                    let owned = if (i, j) == (0, 0) || (i, j) == (m, 0) || (i, j) == (0, m) {
                        let c = if j == m { 2 } else { usize::from(i == m) };
                        prep.vertex_owner[tv[c] as usize] == (3 * t + c) as u32
                    } else if j == 0 {
                        prep.owns_edge[3 * t]
                    } else if i + j == m {
                        prep.owns_edge[3 * t + 1]
                    } else if i == 0 {
                        prep.owns_edge[3 * t + 2]
                    } else {
                        true
                    };
                    if all || owned {
                        f(patch.sq[sq(m, i as isize, j as isize)]);
                    }
                }
            }
        };
        let mut candidates = Vec::new();
        for axis in 0..3 {
            for top in [false, true] {
                // A refined point near the extreme: from the triangle reaching furthest.
                let key = |b: &(P, P, f32)| if top { -b.1[axis] } else { b.0[axis] };
                let first = (0..nf)
                    .min_by(|&a, &b| key(&boxes[a]).total_cmp(&key(&boxes[b])))
                    .unwrap_or(0);
                let mut found = if top {
                    f32::NEG_INFINITY
                } else {
                    f32::INFINITY
                };
                points(first, true, &mut |p| {
                    found = if top {
                        found.max(p[axis])
                    } else {
                        found.min(p[axis])
                    };
                });
                candidates.extend((0..nf).filter(|&t| {
                    let (lo, hi, margin) = boxes[t];
                    if top {
                        hi[axis] + margin >= found
                    } else {
                        lo[axis] - margin <= found
                    }
                }));
            }
        }
        candidates.sort_unstable();
        candidates.dedup();
        let (mut lo, mut hi) = ([f32::INFINITY; 3], [f32::NEG_INFINITY; 3]);
        for t in candidates {
            points(t, false, &mut |p| {
                for k in 0..3 {
                    lo[k] = lo[k].min(p[k]);
                    hi[k] = hi[k].max(p[k]);
                }
            });
        }
        shape.bounds = Some((lo, hi));
        shape
    }
}

/// Triangles per parallel task.
const CHUNK: usize = 64;
/// Triangles per parallel task of [`subdivide_streamed`] with a sink: each task's output is
/// written with a handful of system calls, and fewer, larger writes cost less (about 270 tasks
/// for the Stanford bunny, still plenty to balance two to a few tens of threads).
const STREAM_CHUNK: usize = 256;

/// A range of coarse triangles `t0..t1` with its disjoint slices of the output.
struct Job<'a> {
    t0: usize,
    t1: usize,
    edge_pos: &'a mut [Out],
    edge_nrm: &'a mut [Out],
    int_pos: &'a mut [Out],
    int_nrm: &'a mut [Out],
    idx: &'a mut [[u32; 3]],
}

/// How much output each coarse triangle has, for [`split`].
struct Sizes<'a> {
    edge_start: &'a [u32],
    per_edge: usize,
    per_tri: usize,
    fine_per_tri: usize,
}

/// `job` as consecutive jobs of `chunk` triangles.
fn split<'a>(job: Job<'a>, chunk: usize, z: &Sizes) -> Vec<Job<'a>> {
    let Job {
        t0: first,
        t1: last,
        edge_pos: mut ep,
        edge_nrm: mut en,
        int_pos: mut ip,
        int_nrm: mut inn,
        idx: mut idx_rest,
    } = job;
    let mut jobs = Vec::with_capacity((last - first).div_ceil(chunk));
    for t0 in (first..last).step_by(chunk) {
        let t1 = (t0 + chunk).min(last);
        let ecount = (z.edge_start[t1] - z.edge_start[t0]) as usize * z.per_edge;
        let icount = (t1 - t0) * z.per_tri;
        let (a, b) = std::mem::take(&mut ep).split_at_mut(ecount);
        ep = b;
        let (c, d) = std::mem::take(&mut en).split_at_mut(ecount);
        en = d;
        let (e, f) = std::mem::take(&mut ip).split_at_mut(icount);
        ip = f;
        let (g, h) = std::mem::take(&mut inn).split_at_mut(icount);
        inn = h;
        let (i, j) = std::mem::take(&mut idx_rest).split_at_mut((t1 - t0) * z.fine_per_tri);
        idx_rest = j;
        jobs.push(Job {
            t0,
            t1,
            edge_pos: a,
            edge_nrm: c,
            int_pos: e,
            int_nrm: g,
            idx: i,
        });
    }
    jobs
}

/// Subdivides `mesh` to `level` (0..=6) with positions, normals and indices. Level 0 gives
/// the control mesh itself (with normals), numbered as the tables number it.
pub fn subdivide(mesh: &ControlMesh, level: u32) -> Result<Refined, SubdivError> {
    let mut out = Refined::default();
    subdivide_into(mesh, level, &mut out)?;
    Ok(out)
}

/// Sizes `v` to `len` elements whose values do not matter (every one is overwritten). Fresh
/// memory comes zeroed from the allocator (`calloc`), so its pages are first touched by the
/// parallel writers instead of by a single-threaded fill; reused memory is not cleared.
fn fit<T: Clone>(v: &mut Vec<T>, len: usize, zero: T) {
    if v.capacity() < len {
        // Free the old buffer first: peak memory stays one output.
        *v = Vec::new();
        *v = vec![zero; len];
        crate::os::advise_huge_pages(v);
    } else {
        v.resize(len, zero);
    }
}

/// [`subdivide`] into the buffers of `out`, reusing their allocations: a viewer refining every
/// frame (or a benchmark) then pays no page faults for fresh output memory. `out` is
/// overwritten entirely; on error it is left empty.
pub fn subdivide_into(
    mesh: &ControlMesh,
    level: u32,
    out: &mut Refined,
) -> Result<(), SubdivError> {
    subdivide_streamed(mesh, level, out, None)
}

/// Output finished by [`subdivide_streamed`]: the edge points, interior points and fine
/// triangles of a range of coarse triangles, final (the coarse vertices come last, in the
/// returned [`Refined`] only). Each range is contiguous in the output arrays.
pub struct Written<'a> {
    /// Output vertex number of `edge_positions[0]` (and `edge_normals[0]`).
    pub first_edge_point: usize,
    pub edge_positions: &'a [Out],
    pub edge_normals: &'a [Out],
    /// Output vertex number of `interior_positions[0]`.
    pub first_interior_point: usize,
    pub interior_positions: &'a [Out],
    pub interior_normals: &'a [Out],
    /// Output triangle number of `indices[0]`.
    pub first_triangle: usize,
    pub indices: &'a [[u32; 3]],
}

/// [`subdivide_into`], handing each finished range of coarse triangles' output to `sink` on
/// another thread while the rest is computed, so that a caller can write the output
/// as it comes (`hce subdivide` overlaps the GLB's disk writes with the subdivision). The
/// result is the same, bit for bit, with or without a sink.
pub fn subdivide_streamed(
    mesh: &ControlMesh,
    level: u32,
    out: &mut Refined,
    sink: Option<&(dyn Fn(Written<'_>) + Sync)>,
) -> Result<(), SubdivError> {
    let result = subdivide_checked(mesh, level, out, sink);
    if result.is_err() {
        out.positions.clear();
        out.normals.clear();
        out.indices.clear();
    }
    result
}

/// A subdivision of one mesh to one level, checked and prepared once ([`plan`]): its
/// [`OutputShape`] and the subdivision itself then share the table checks.
pub struct Plan<'a> {
    mesh: &'a ControlMesh,
    level: u32,
    prep: Prepared,
    numbering: Numbering,
}

/// Checks `level` and every table [`subdivide`] reads, and the output's size, with
/// [`subdivide`]'s errors.
pub fn plan(mesh: &ControlMesh, level: u32) -> Result<Plan<'_>, SubdivError> {
    if level > MAX_LOOP_LEVEL {
        return Err(SubdivError::Level(level));
    }
    let prep = prepare(mesh)?;
    let nf = mesh.triangle_count();
    let too_large = || SubdivError::TooLarge {
        level,
        triangles: nf,
        what: "more than 2^32 vertices or indices",
    };
    let count = |x: usize| u32::try_from(x).map_err(|_| too_large());
    let numbering = Numbering {
        level,
        vertices: count(mesh.vertex_count())?,
        edges: count(prep.edge_count)?,
        triangles: count(nf)?,
    };
    if numbering.vertex_count() > u64::from(u32::MAX)
        || numbering.triangle_count() > u64::from(u32::MAX / 3)
    {
        return Err(too_large());
    }
    Ok(Plan {
        mesh,
        level,
        prep,
        numbering,
    })
}

impl Plan<'_> {
    /// [`subdivide_streamed`] of the planned mesh and level.
    pub fn subdivide_streamed(
        &self,
        out: &mut Refined,
        sink: Option<&(dyn Fn(Written<'_>) + Sync)>,
    ) {
        subdivide_planned(self, out, sink);
    }
}

fn subdivide_checked(
    mesh: &ControlMesh,
    level: u32,
    out: &mut Refined,
    sink: Option<&(dyn Fn(Written<'_>) + Sync)>,
) -> Result<(), SubdivError> {
    subdivide_planned(&plan(mesh, level)?, out, sink);
    Ok(())
}

fn subdivide_planned(
    plan: &Plan<'_>,
    out: &mut Refined,
    sink: Option<&(dyn Fn(Written<'_>) + Sync)>,
) {
    let Plan {
        mesh,
        level,
        ref prep,
        numbering,
    } = *plan;
    let nv = mesh.vertex_count();
    let nf = mesh.triangle_count();
    let ne = prep.edge_count;
    let m = 1usize << level;
    let per_edge = numbering.per_edge() as usize;
    let per_tri = numbering.per_triangle() as usize;
    let fine_per_tri = 1usize << (2 * level);
    let total_v = numbering.vertex_count() as usize;
    // Fine triangles as square indices of their corners, by path.
    let local_cells: Vec<[u32; 3]> = subtriangle_cells(level)
        .iter()
        .map(|t| t.map(|[i, j]| sq(m, i as isize, j as isize) as u32))
        .collect();

    let mut positions = std::mem::take(&mut out.positions);
    let mut normals = std::mem::take(&mut out.normals);
    let mut indices = std::mem::take(&mut out.indices);
    fit(&mut positions, total_v, [0.0; 3]);
    fit(&mut normals, total_v, [0.0; 3]);
    fit(&mut indices, nf * fine_per_tri, [0; 3]);

    // Split the outputs into per-chunk disjoint slices: a chunk of triangles owns a contiguous
    // range of edge ids (first-appearance order) and of interior points and fine triangles.
    let sizes = Sizes {
        edge_start: &prep.edge_start,
        per_edge,
        per_tri,
        fine_per_tri,
    };
    let (_, rest_p) = positions.split_at_mut(nv);
    let (_, rest_n) = normals.split_at_mut(nv);
    let (ep, ip) = rest_p.split_at_mut(ne * per_edge);
    let (en, inn) = rest_n.split_at_mut(ne * per_edge);
    let whole = Job {
        t0: 0,
        t1: nf,
        edge_pos: ep,
        edge_nrm: en,
        int_pos: ip,
        int_nrm: inn,
        idx: &mut indices,
    };
    let work = |patch: &mut Patch, job: &mut Job<'_>| {
        // Global vertex number of each square entry of the output level.
        let mut gmap = vec![0u32; (m + 3) * (m + 3)];
        let mut owned = Vec::new();
        for t in job.t0..job.t1 {
            let tri = make_tri(mesh, prep, t);
            let tv = mesh.triangle(t);
            let own_corner: [bool; 3] =
                std::array::from_fn(|c| prep.vertex_owner[tv[c] as usize] == (3 * t + c) as u32);
            let own_edge: [bool; 3] = std::array::from_fn(|e| prep.owns_edge[3 * t + e]);
            patch.load(&tri, tv);
            let mut n = 1;
            while n < m {
                if 2 * n < m {
                    patch.step(&tri, n, [true; 3], [true; 3]);
                } else {
                    // The output level: bands only where this patch writes the edge's
                    // normals, rings only for those bands and for owned corners.
                    let rings = std::array::from_fn(|c| {
                        own_corner[c] || own_edge[c] || own_edge[(c + 2) % 3]
                    });
                    patch.step(&tri, n, own_edge, rings);
                }
                n *= 2;
            }
            if m >= 2 {
                patch.face_normals(&tri, m, own_edge);
            }
            for c in 0..3 {
                let x = sq_corner(m, c);
                gmap[x] = tv[c];
                if own_corner[c] {
                    let nrm = normalize(patch.corner_normal(&tri, m, c));
                    owned.push((tv[c], patch.sq[x].to_array(), nrm));
                }
            }
            for e in 0..3 {
                let id = mesh.edges[3 * t + e];
                if own_edge[e] {
                    // Only an owned edge lies in this job's contiguous slice of edge
                    // points; an edge owned by an earlier triangle may have a smaller id.
                    let local = (id - prep.edge_start[job.t0]) as usize * per_edge;
                    for k in 1..m {
                        let x = sq_edge(m, e, k);
                        gmap[x] = numbering.edge_point(id, k as u64) as u32;
                        job.edge_pos[local + k - 1] = patch.sq[x].to_array();
                        job.edge_nrm[local + k - 1] = normalize(patch.vertex_normal(m, x));
                    }
                } else {
                    // Counted from the owner's end, the other way round.
                    for k in 1..m {
                        gmap[sq_edge(m, e, k)] = numbering.edge_point(id, (m - k) as u64) as u32;
                    }
                }
            }
            let ibase = numbering.interior_point(t as u32, 0) as usize;
            let local = (t - job.t0) * per_tri;
            let mut q = 0;
            for j in 1..m {
                let x0 = sq(m, 1, j as isize);
                for x in x0..x0 + (m - j).saturating_sub(1) {
                    gmap[x] = (ibase + q) as u32;
                    job.int_pos[local + q] = patch.sq[x].to_array();
                    job.int_nrm[local + q] = normalize(patch.vertex_normal(m, x));
                    q += 1;
                }
            }
            let out = &mut job.idx[(t - job.t0) * fine_per_tri..(t - job.t0 + 1) * fine_per_tri];
            for (o, c) in out.iter_mut().zip(&local_cells) {
                *o = c.map(|l| gmap[l as usize]);
            }
        }
        owned
    };
    let chunk = if sink.is_some() { STREAM_CHUNK } else { CHUNK };
    let jobs = split(whole, chunk, &sizes);
    let corner_out: Vec<Vec<(u32, Out, Out)>> = match sink {
        None => jobs
            .into_par_iter()
            .map_init(Patch::default, |patch, mut job| work(patch, &mut job))
            .collect(),
        Some(sink) => std::thread::scope(|scope| {
            // Finished jobs go to the sink's thread, which only reads them.
            let (tx, rx) = std::sync::mpsc::channel::<Job<'_>>();
            let edge_start = &prep.edge_start;
            scope.spawn(move || {
                for b in rx {
                    sink(Written {
                        first_edge_point: nv + edge_start[b.t0] as usize * per_edge,
                        edge_positions: b.edge_pos,
                        edge_normals: b.edge_nrm,
                        first_interior_point: nv + ne * per_edge + b.t0 * per_tri,
                        interior_positions: b.int_pos,
                        interior_normals: b.int_nrm,
                        first_triangle: b.t0 * fine_per_tri,
                        indices: b.idx,
                    });
                }
            });
            let out = jobs
                .into_par_iter()
                .map_init(Patch::default, |patch, mut job| {
                    let owned = work(patch, &mut job);
                    // A send fails only if the sink's thread has gone, which only a panic in
                    // `sink` does (and the scope then passes it on).
                    let _ = tx.send(job);
                    owned
                })
                .collect();
            drop(tx);
            out
        }),
    };
    for list in corner_out {
        for (v, p, n) in list {
            positions[v as usize] = p;
            normals[v as usize] = n;
        }
    }
    *out = Refined {
        level,
        positions,
        normals,
        indices,
        coarse_vertices: nv,
        coarse_edges: ne,
        coarse_triangles: nf,
    };
}
