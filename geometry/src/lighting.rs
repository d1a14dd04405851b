//! Smooth reconstruction of baked lighting (SPEC.md, Appendix G): a field that is continuous in
//! position over the surface and linear in the normal, so that a mesh refined to any level gets
//! the shading its own normals call for and converges as the level grows.
//!
//! Based on:
//! * Ravi Ramamoorthi and Pat Hanrahan. An efficient representation for irradiance environment
//!   maps. SIGGRAPH 2001 (the fit over normals).
//! * Michael F. Cohen and John R. Wallace. Radiosity and Realistic Image Synthesis. Academic
//!   Press, 1993, section 9.2 (nodal averaging and T-vertices, the interpolation over positions).
//! * Padrón et al. Hierarchical radiosity for multiresolution systems based on normal tests,
//!   2010 (the representative normals whose colours are fitted).
//!
//! Three steps, the first two linear in the stored colours:
//!
//! * **A fit over normals at every leaf corner**, per object: the `n` colours `B_j` of a tree
//!   node, stored for its coarse triangle's representative normals `n_j` (Padrón et al.,
//!   "Hierarchical radiosity for multiresolution systems based on normal tests", 2010), are
//!   samples of the node's radiance as a function of the normal. Each corner point of the leaf
//!   elements pools the samples of every leaf meeting there (across coarse-triangle borders,
//!   except across sharp edges and, for flat objects, folds), each leaf weighted by its area,
//!   and fits them by one linear function of the normal, `B(n) = c + G n`, by ridge-regularised
//!   least squares. Irradiance is a very smooth function of the normal (Ramamoorthi &
//!   Hanrahan, "An efficient representation for irradiance environment maps", SIGGRAPH 2001:
//!   its first spherical-harmonic bands hold it to a few percent), and over the normals around
//!   one point the constant and linear band carry it. Pooling gives the fit the normals on
//!   every side of the point: a vertex's normal lies among them instead of beyond one
//!   triangle's set (averaging per-triangle fits extrapolated each to its neighbours' normals,
//!   which at folds of a coarse mesh made a quarter of the RMS error against a path tracer), and a
//!   triangle with a single normal still gets the slope its neighbours show. The ridge term
//!   keeps directions the normals do not span at zero slope.
//! * **Over positions**: a point inside a leaf interpolates its leaf's corner models linearly.
//!   A corner that lies inside the edge of a larger leaf (a T-vertex) takes the value
//!   interpolated along that edge, so the field is continuous everywhere (Cohen & Wallace,
//!   "Radiosity and Realistic Image Synthesis", 1993, section 9.2: nodal averaging and
//!   T-vertices).
//! * **One correction towards the leaves' colours**: a leaf's colour is the mean of the light
//!   over its area, and the fit at a point a mean of such means, so the interpolated field is
//!   blurred over about two leaves (a penumbra as wide as the leaves drawn twice as wide, a
//!   room's corner taking the mean of leaves whose centres lie on one side). Every point's
//!   constant term moves by the weighted mean of its leaves' residuals (a leaf's colour less
//!   the mean of its corners' models), kept between the colours around it; the T-vertices are
//!   then resolved again. It is the first step of van Cittert's iterative deconvolution
//!   (P. H. van Cittert, Zeitschrift für Physik, 1931), limited as slope limiters are: where
//!   the fit already reproduces the field, constant (a closed furnace) or linear inside a
//!   regular grid of leaves, the residuals are zero.
//!
//! An object whose bake stored each colour at its leaves' corners too (SPEC.md A.10: the light
//! at those points, not a mean) gives each point those samples in place of its leaves' colours,
//! and makes no correction: the means it would correct towards are what the corner colours
//! replace.
//!
//! A refined vertex with unit normal `n` at lattice point `p` of coarse triangle `t` then gets
//! `max(0, c(p) + G(p) n)`, evaluated per channel. The corner models are computed once per
//! object on the CPU ([`LightingTable::build`]); the GPU kernels read the same table.

use std::collections::HashMap;

use hce_format::{rgb9e5, Object, ObjectKind, Tree, TreeError};

use crate::lattice::{site, LatticeTriangle, Site};
use crate::split::{corner_groups, joined_sides};

/// Denominator of the lattice in which leaf corners are identified: the finest split a tree can
/// have (`hce_format::MAX_TREE_DEPTH` = 12).
pub const TREE_LATTICE_BITS: u32 = 12;
pub(crate) const TREE_LATTICE: i32 = 1 << TREE_LATTICE_BITS;

/// Denominator of the lattice in which points are evaluated: deep enough for every render level
/// the kernels accept (15) and every tree depth (12).
pub const EVAL_LATTICE_BITS: u32 = 16;

/// Ridge weight of the normal fit, relative to the samples' total weight (SPEC.md G.3).
pub const RIDGE: f64 = 1e-4;

/// Floats per model: `c` (RGB), then `G` row by row (the red, green and blue gradients).
pub const MODEL_FLOATS: usize = 12;

/// Marks a leaf in [`LightingTable::nodes`]; the other bits are the leaf's index.
pub const LEAF: u32 = 1 << 31;

/// How baked colours become vertex colours.
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq)]
pub enum Reconstruction {
    /// Continuous in position and linear in the normal (SPEC.md G.1 to G.4). The default.
    #[default]
    Smooth,
    /// The paper's rule (Concheiro et al. 2012, section 4; SPEC.md G.5): each subtriangle takes
    /// the colour of its tree node whose representative normal is closest to its own, and each
    /// vertex averages its subtriangles' colours.
    NearestNormal,
    /// Classic radiosity rendering (Cohen & Wallace 1993, section 9.2), for comparison: each
    /// leaf's colour for its triangle's geometric normal, averaged at leaf corners as
    /// [`Reconstruction::Smooth`] averages its fits and interpolated the same way, with no
    /// dependence on the normal. What one colour per element looks like when drawn smoothly;
    /// not part of SPEC.md.
    Gouraud,
}

impl std::str::FromStr for Reconstruction {
    type Err = String;
    fn from_str(s: &str) -> Result<Self, String> {
        match s {
            "smooth" => Ok(Self::Smooth),
            "nearest" | "nearest-normal" => Ok(Self::NearestNormal),
            "gouraud" => Ok(Self::Gouraud),
            _ => Err(format!(
                "unknown reconstruction '{s}': expected 'smooth', 'nearest' or 'gouraud'"
            )),
        }
    }
}

/// Why a lighting table cannot be built: the object's records, trees or colours are
/// inconsistent (a validated object never is).
#[derive(Debug, thiserror::Error, PartialEq)]
pub enum LightingError {
    #[error("object '{object}', triangle {triangle}: {what}; re-bake the file")]
    Record {
        object: String,
        triangle: usize,
        what: String,
    },
    #[error("object '{object}', triangle {triangle}: bad HCE tree: {source}")]
    Tree {
        object: String,
        triangle: usize,
        #[source]
        source: TreeError,
    },
}

/// Per object: the models at the corners of every leaf element, in the layout the GPU kernels
/// read. Leaves that meet at a point share its model.
#[derive(Clone, Debug, PartialEq)]
pub struct LightingTable {
    /// Per coarse triangle: the index in `nodes` of its tree's node 0.
    pub node_start: Vec<u32>,
    /// Per tree node (breadth-first, SPEC.md B.2), one word: for a subdivided node the number of
    /// its first child (`1 + 4 rank`), for a leaf [`LEAF`] plus the leaf's index (the tree walk
    /// of G.4 without counting bits).
    pub nodes: Vec<u32>,
    /// Three point indices per leaf, for its corners 0, 1, 2 in the order of SPEC.md 2.2.
    pub leaf_points: Vec<u32>,
    /// [`MODEL_FLOATS`] floats per point: `models[12 * point ..][..12]`.
    pub models: Vec<f32>,
}

/// One coarse triangle's share of an object's baked lighting, bounds-checked.
#[derive(Clone, Copy, Debug)]
pub struct TriangleLighting<'a> {
    /// The normal set, geometric normal first.
    pub normals: &'a [[f32; 3]],
    pub tree: Tree<'a>,
    /// Node-major: node `k`, normal `j` is `colours[k * normals.len() + j]`.
    pub colours: &'a [u32],
    /// The colours at the nodes' corners (SPEC.md A.10), three per colour:
    /// `corner_colours[3 * (k * normals.len() + j) + c]`; empty when the object has none.
    pub corner_colours: &'a [u32],
}

/// The normals, tree and colours of triangle `t` of `object`, checked against what the object
/// holds (SPEC.md A.9).
pub fn triangle_lighting(object: &Object, t: usize) -> Result<TriangleLighting<'_>, LightingError> {
    let record_err = |what: String| LightingError::Record {
        object: object.name.clone(),
        triangle: t,
        what,
    };
    let rec = object
        .triangles
        .get(t)
        .ok_or_else(|| record_err(format!("no record among {}", object.triangles.len())))?;
    let (ns, nc) = (rec.normal_start as usize, rec.normal_count as usize);
    let normals = ns
        .checked_add(nc)
        .filter(|_| nc >= 1)
        .and_then(|end| object.normals.get(ns..end))
        .ok_or_else(|| {
            record_err(format!(
                "normals {ns}+{nc} lie outside the {} stored normals",
                object.normals.len()
            ))
        })?;
    let tree =
        Tree::new(&object.bits, object.bit_len, u64::from(rec.bits_start)).map_err(|source| {
            LightingError::Tree {
                object: object.name.clone(),
                triangle: t,
                source,
            }
        })?;
    let nodes = tree.node_count() as usize;
    let cs = rec.colour_start as usize;
    let colours = nodes
        .checked_mul(nc)
        .and_then(|len| cs.checked_add(len))
        .and_then(|end| object.colours.get(cs..end))
        .ok_or_else(|| {
            record_err(format!(
                "{nodes} nodes x {nc} colours from {cs} lie outside the {} stored colours",
                object.colours.len()
            ))
        })?;
    let corner_colours = if object.corner_colours.is_empty() {
        &[][..]
    } else {
        object
            .corner_colours
            .get(3 * cs..3 * (cs + colours.len()))
            .ok_or_else(|| {
                record_err(format!(
                    "the corner colours of colours {cs}+{} lie outside the {} stored",
                    colours.len(),
                    object.corner_colours.len()
                ))
            })?
    };
    Ok(TriangleLighting {
        normals,
        tree,
        colours,
        corner_colours,
    })
}

/// Identity of a leaf corner on the object's surface, shared by every leaf that meets there
/// within one smooth region.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Hash)]
pub(crate) enum PointKey {
    /// A control vertex, within one group of its triangle fan joined across smooth edges.
    Vertex { vertex: u32, group: u32 },
    /// A point inside a joined coarse edge, at `param / 4096` from its lower-numbered vertex.
    Edge { edge: u32, param: u32 },
    /// A point that belongs to one coarse triangle only.
    Face { triangle: u32, x: u32, y: u32 },
}

/// The coarse-mesh facts the point identities need.
pub(crate) struct Surface<'a> {
    object: &'a Object,
    /// `joined[3t + e]`: values mix across edge `e` of triangle `t`.
    joined: Vec<bool>,
    /// Group of each triangle corner's vertex (a root of the union-find over corners).
    group: Vec<u32>,
}

impl<'a> Surface<'a> {
    pub(crate) fn new(object: &'a Object) -> Self {
        let joined = joined_sides(&object.mesh, object.kind);
        let group = corner_groups(&object.mesh, &joined);
        Surface {
            object,
            joined,
            group,
        }
    }

    /// The key of lattice point `(x, y)` (denominator 4096) of coarse triangle `t`.
    pub(crate) fn key(&self, t: usize, x: i32, y: i32) -> PointKey {
        let m = &self.object.mesh;
        let n = TREE_LATTICE;
        match site(n, x, y) {
            Site::Corner(c) => PointKey::Vertex {
                vertex: m.triangles[3 * t + c],
                group: self.group[3 * t + c],
            },
            // Edge e runs from v_e to v_{e+1}; `k` is the distance from v_e.
            Site::Edge { edge: e, k } if self.joined[3 * t + e] => {
                let (a, b) = (m.triangles[3 * t + e], m.triangles[3 * t + (e + 1) % 3]);
                let param = if a < b { k } else { n - k };
                PointKey::Edge {
                    edge: m.edges[3 * t + e],
                    param: param as u32,
                }
            }
            _ => PointKey::Face {
                triangle: t as u32,
                x: x as u32,
                y: y as u32,
            },
        }
    }
}

fn coarse_area(object: &Object, t: usize) -> f64 {
    let m = &object.mesh;
    let p = |c: usize| {
        let v = m.triangles[3 * t + c] as usize;
        [0, 1, 2].map(|k| f64::from(m.positions.get(3 * v + k).copied().unwrap_or(0.0)))
    };
    let n = cross(sub(p(1), p(0)), sub(p(2), p(0)));
    0.5 * dot(n, n).sqrt()
}

fn invert3(m: [[f64; 3]; 3]) -> [[f64; 3]; 3] {
    let c =
        |r0: usize, c0: usize, r1: usize, c1: usize| m[r0][c0] * m[r1][c1] - m[r0][c1] * m[r1][c0];
    let adj = [
        [c(1, 1, 2, 2), -c(0, 1, 2, 2), c(0, 1, 1, 2)],
        [-c(1, 0, 2, 2), c(0, 0, 2, 2), -c(0, 0, 1, 2)],
        [c(1, 0, 2, 1), -c(0, 0, 2, 1), c(0, 0, 1, 1)],
    ];
    let det = m[0][0] * adj[0][0] + m[0][1] * adj[1][0] + m[0][2] * adj[2][0];
    // The ridge term makes the matrix positive definite: det >= lambda^3 > 0.
    adj.map(|row| row.map(|x| x / det))
}

fn mat_vec(m: [[f64; 3]; 3], v: [f64; 3]) -> [f64; 3] {
    m.map(|row| dot(row, v))
}

/// A leaf element met while building the table.
struct Leaf {
    triangle: u32,
    depth: u32,
    cell: LatticeTriangle,
    /// Index of the leaf's first corner point in the point list (three consecutive slots of
    /// `corner_points`).
    corners: [usize; 3],
    /// Its samples' weight (its area weight over their count) and where they start in the
    /// table's sample list, and how many it has (G.3).
    sample_weight: f64,
    samples: (usize, usize),
}

/// One sample of a leaf (G.3): a normal and the colour stored for it, in `f64`.
type Sample = ([f64; 3], [f64; 3]);

impl LightingTable {
    /// Builds the table of `object` (SPEC.md G.2 to G.4).
    pub fn build(object: &Object) -> Result<LightingTable, LightingError> {
        Self::build_with(object, Reconstruction::Smooth)
    }

    /// The table of [`Reconstruction::Smooth`], or with [`Reconstruction::Gouraud`] the table of
    /// the geometric normals' colours without slopes; the nearest-normal rule uses no table and
    /// gets the smooth one.
    pub fn build_with(
        object: &Object,
        reconstruction: Reconstruction,
    ) -> Result<LightingTable, LightingError> {
        let gouraud = reconstruction == Reconstruction::Gouraud;
        let surface = Surface::new(object);
        let mut point_index: HashMap<PointKey, usize> = HashMap::new();

        let mut moments: Vec<Moments> = Vec::new();
        let mut leaves: Vec<Leaf> = Vec::new();
        let mut samples_of: Vec<Sample> = Vec::new();
        let mut node_start = Vec::with_capacity(object.triangles.len());
        let mut nodes: Vec<u32> = Vec::new();
        let too_large = |t: usize, what: &str| LightingError::Record {
            object: object.name.clone(),
            triangle: t,
            what: format!("more than 2^31 {what} in one object's lighting table"),
        };
        for t in 0..object.triangles.len() {
            node_start.push(
                u32::try_from(nodes.len())
                    .ok()
                    .filter(|&n| n < LEAF)
                    .ok_or_else(|| too_large(t, "tree nodes"))?,
            );
            let TriangleLighting {
                normals,
                tree,
                colours,
                corner_colours,
            } = triangle_lighting(object, t)?;
            let nc = normals.len();
            let area = coarse_area(object, t);
            // Breadth-first walk: the children of the r-th subdivided node are 1 + 4r + c.
            let mut cells = vec![LatticeTriangle::root(TREE_LATTICE); 1];
            let mut subdivided_seen = 0usize;
            for info in tree.nodes() {
                let k = info.index as usize;
                let cell = cells[k];
                if info.subdivided {
                    let first = 1 + 4 * subdivided_seen;
                    subdivided_seen += 1;
                    nodes.push(first as u32);
                    // Blocks of children are consecutive, so the vector only ever grows at its end.
                    cells.resize(first + 4, cell);
                    for c in 0..4 {
                        cells[first + c] = cell.child(c as u32);
                    }
                    continue;
                }
                let w = area / (1u64 << (2 * info.depth)) as f64;
                let samples = if gouraud { 1 } else { nc };
                let first_sample = samples_of.len();
                samples_of.extend((0..samples).map(|j| {
                    (
                        normals[j].map(f64::from),
                        rgb9e5::decode(colours[k * nc + j]).map(f64::from),
                    )
                }));
                let mut at_corner: Vec<Sample> = Vec::new();
                let mut corners = [0usize; 3];
                for (c, (slot, p)) in corners.iter_mut().zip(cell.corners()).enumerate() {
                    let key = surface.key(t, p[0], p[1]);
                    let i = *point_index.entry(key).or_insert_with(|| {
                        moments.push(Moments::default());
                        moments.len() - 1
                    });
                    // With corner colours, a leaf's samples at a point are its colours there.
                    if corner_colours.is_empty() {
                        moments[i].add(w, &samples_of[first_sample..]);
                    } else {
                        at_corner.clear();
                        at_corner.extend((0..samples).map(|j| {
                            (
                                normals[j].map(f64::from),
                                rgb9e5::decode(corner_colours[3 * (k * nc + j) + c]).map(f64::from),
                            )
                        }));
                        moments[i].add(w, &at_corner);
                    }
                    *slot = i;
                }
                nodes.push(
                    LEAF | u32::try_from(leaves.len())
                        .ok()
                        .filter(|&n| n < LEAF)
                        .ok_or_else(|| too_large(t, "leaf elements"))?,
                );
                leaves.push(Leaf {
                    triangle: t as u32,
                    depth: info.depth,
                    cell,
                    corners,
                    sample_weight: w / samples as f64,
                    samples: (first_sample, samples),
                });
            }
        }
        let flat = gouraud || object.kind == ObjectKind::Flat;
        let mut values: Vec<[f64; MODEL_FLOATS]> = moments.iter().map(|m| m.fit(flat)).collect();
        let mut order: Vec<usize> = (0..leaves.len()).collect();
        order.sort_by_key(|&i| leaves[i].depth);
        resolve_t_vertices(&surface, &point_index, &leaves, &order, &mut values);
        // Gouraud, classic radiosity shading for comparison, keeps the corner means; corner
        // colours are the light at the points already, not means to correct towards.
        if !gouraud && object.corner_colours.is_empty() {
            correct(&leaves, &samples_of, &moments, &mut values);
            resolve_t_vertices(&surface, &point_index, &leaves, &order, &mut values);
        }
        let too_many = |what: &str| LightingError::Record {
            object: object.name.clone(),
            triangle: object.triangles.len().saturating_sub(1),
            what: format!("more than 2^32 {what} in one object's lighting table"),
        };
        let mut leaf_points = Vec::with_capacity(3 * leaves.len());
        for leaf in &leaves {
            for &p in &leaf.corners {
                leaf_points.push(u32::try_from(p).map_err(|_| too_many("points"))?);
            }
        }
        let models = values.iter().flatten().map(|&x| x as f32).collect();
        Ok(LightingTable {
            node_start,
            nodes,
            leaf_points,
            models,
        })
    }

    /// The model at corner `corner` of leaf `leaf`.
    fn model(&self, leaf: usize, corner: usize) -> &[f32] {
        let at = self.leaf_points[3 * leaf + corner] as usize * MODEL_FLOATS;
        &self.models[at..at + MODEL_FLOATS]
    }

    /// The table as the `hce_light` words of `hce_light.wgsl`: two header words (where the
    /// point indices and the models start), then per triangle the word of its node 0, the node
    /// words, three point indices per leaf, and the models as f32 bit patterns. `None` when the
    /// table is too large to be addressed by 32-bit word indices.
    pub fn to_words(&self) -> Option<Vec<u32>> {
        let nodes_at = 2 + self.node_start.len();
        let points_at = nodes_at + self.nodes.len();
        let models_at = points_at + self.leaf_points.len();
        let total = models_at + self.models.len();
        u32::try_from(total).ok()?;
        let mut words = Vec::with_capacity(total);
        words.push(points_at as u32);
        words.push(models_at as u32);
        words.extend(self.node_start.iter().map(|&n| nodes_at as u32 + n));
        words.extend(&self.nodes);
        words.extend(&self.leaf_points);
        words.extend(self.models.iter().map(|x| x.to_bits()));
        Some(words)
    }

    /// The leaf holding lattice point `(x, y)` (denominator `2^16`) of coarse triangle `t` and
    /// the point's barycentric weights of the leaf's corners 0, 1, 2 (SPEC.md G.4). A point on
    /// the border between children goes to the first of Left (its `u` is at least half the
    /// side), Right (`v` at least half), Top (`u + v` at most half), Center.
    pub fn locate(&self, t: usize, x: u32, y: u32) -> (usize, [f32; 3]) {
        let base = self.node_start[t] as usize;
        let (mut u, mut v) = (x, y);
        let mut side = 1u32 << EVAL_LATTICE_BITS;
        let mut word = self.nodes[base];
        while word & LEAF == 0 && side > 1 {
            let h = side / 2;
            let c;
            (c, u, v) = crate::lattice::child_toward(u, v, h);
            word = self.nodes[base + (word + c) as usize];
            side = h;
        }
        let s = side as f32;
        let (w1, w2) = (u as f32 / s, v as f32 / s);
        ((word & !LEAF) as usize, [1.0 - w1 - w2, w1, w2])
    }

    /// The reconstructed colour at lattice point `(x, y)` (denominator `2^16`) of coarse triangle
    /// `t`, for a surface with unit normal `normal` (SPEC.md G.4).
    pub fn evaluate(&self, t: usize, x: u32, y: u32, normal: [f32; 3]) -> [f32; 3] {
        let (leaf, w) = self.locate(t, x, y);
        let b: [[f32; 3]; 3] = [0, 1, 2].map(|c| eval_model(self.model(leaf, c), normal));
        [0, 1, 2].map(|ch| (b[0][ch] * w[0] + b[1][ch] * w[1] + b[2][ch] * w[2]).max(0.0))
    }
}

/// `c + G n` per channel, in the order the kernels use: `c + ((g.x n.x + g.y n.y) + g.z n.z)`.
fn eval_model(m: &[f32], n: [f32; 3]) -> [f32; 3] {
    [0, 1, 2].map(|ch| {
        let g = &m[3 + 3 * ch..6 + 3 * ch];
        m[ch] + (g[0] * n[0] + g[1] * n[1] + g[2] * n[2])
    })
}

/// The T-vertex step of G.3: from the largest leaves down (`order`), a corner of smaller leaves
/// inside a leaf's edge takes the model interpolated along that edge.
fn resolve_t_vertices(
    surface: &Surface,
    index: &HashMap<PointKey, usize>,
    leaves: &[Leaf],
    order: &[usize],
    values: &mut [[f64; MODEL_FLOATS]],
) {
    for &i in order {
        let leaf = &leaves[i];
        let pts = leaf.cell.corners();
        for e in 0..3 {
            let (a, b) = (e, (e + 1) % 3);
            resolve_edge(
                surface,
                index,
                values,
                leaf.triangle as usize,
                (pts[a], leaf.corners[a]),
                (pts[b], leaf.corners[b]),
            );
        }
    }
}

/// Model `v`'s channel `ch` for normal `n`, `c + ((g.x n.x + g.y n.y) + g.z n.z)` in `f64`.
fn model_at(v: &[f64; MODEL_FLOATS], n: [f64; 3], ch: usize) -> f64 {
    let g = &v[3 + 3 * ch..6 + 3 * ch];
    v[ch] + ((g[0] * n[0] + g[1] * n[1]) + g[2] * n[2])
}

/// The correction step of G.3: every point's constant term moves by the weighted mean of its
/// leaves' residuals (a sample's colour less the mean of its leaf's corner models for its
/// normal), limited so that the point's model at its mean normal stays between the least and
/// greatest colour of its samples. The fit is a mean of area means, so a field drawn from it is
/// blurred over about two leaves: a penumbra as wide as the leaves came out twice as wide (the
/// floor under a teapot 2.3 times as bright as a path tracer's in its umbra, in direct light
/// alone), and a point on a room's corner took the mean of leaves whose centres lie on one side
/// (measured in commit 1e873ba; `bake/tests/contact_shadows.rs` holds the umbra to the path
/// tracer). All residuals are found before any model moves.
fn correct(
    leaves: &[Leaf],
    samples: &[Sample],
    moments: &[Moments],
    values: &mut [[f64; MODEL_FLOATS]],
) {
    let n = values.len();
    let mut sum = vec![[0.0f64; 3]; n];
    let mut lo = vec![[f64::INFINITY; 3]; n];
    let mut hi = vec![[f64::NEG_INFINITY; 3]; n];
    for leaf in leaves {
        let (first, count) = leaf.samples;
        for &(normal, colour) in &samples[first..first + count] {
            for ch in 0..3 {
                let [m0, m1, m2] = leaf.corners.map(|c| model_at(&values[c], normal, ch));
                let residual = colour[ch] - (m0 + m1 + m2) / 3.0;
                for &c in &leaf.corners {
                    sum[c][ch] += leaf.sample_weight * residual;
                    lo[c][ch] = lo[c][ch].min(colour[ch]);
                    hi[c][ch] = hi[c][ch].max(colour[ch]);
                }
            }
        }
    }
    for (p, value) in values.iter_mut().enumerate() {
        let w = moments[p].w;
        if w <= 0.0 {
            continue;
        }
        let nbar = moments[p].n.map(|x| x / w);
        for ch in 0..3 {
            let v = model_at(value, nbar, ch);
            let delta = (sum[p][ch] / w).clamp(lo[p][ch] - v, hi[p][ch] - v);
            value[ch] += delta;
        }
    }
}

/// Gives the corners of smaller leaves that lie inside the segment from `a` to `b` (a leaf edge
/// of triangle `t`) the values interpolated along it.
fn resolve_edge(
    surface: &Surface,
    index: &HashMap<PointKey, usize>,
    values: &mut [[f64; MODEL_FLOATS]],
    t: usize,
    a: ([i32; 2], usize),
    b: ([i32; 2], usize),
) {
    let (pa, pb) = (a.0, b.0);
    if (pa[0] - pb[0]).abs() < 2 && (pa[1] - pb[1]).abs() < 2 {
        return;
    }
    let pm = [(pa[0] + pb[0]) / 2, (pa[1] + pb[1]) / 2];
    let Some(&m) = index.get(&surface.key(t, pm[0], pm[1])) else {
        return;
    };
    let (va, vb) = (values[a.1], values[b.1]);
    values[m] = std::array::from_fn(|i| 0.5 * (va[i] + vb[i]));
    resolve_edge(surface, index, values, t, a, (pm, m));
    resolve_edge(surface, index, values, t, (pm, m), b);
}

/// Weighted moments of the samples `(normal, colour)` of the leaves meeting at one point
/// (SPEC.md G.3), accumulated raw and centred in [`Moments::fit`].
#[derive(Clone, Default)]
struct Moments {
    w: f64,
    n: [f64; 3],
    nn: [[f64; 3]; 3],
    b: [f64; 3],
    bn: [[f64; 3]; 3],
}

impl Moments {
    /// Adds a leaf of area weight `w` with its samples, one colour per normal of its
    /// triangle's set: each sample weighs `w / samples.len()`, so a leaf counts by its area
    /// alone.
    fn add(&mut self, w: f64, samples: &[Sample]) {
        let ws = w / samples.len() as f64;
        for &(n, rgb) in samples {
            self.w += ws;
            for a in 0..3 {
                self.n[a] += ws * n[a];
                self.b[a] += ws * rgb[a];
                for b in 0..3 {
                    self.nn[a][b] += ws * n[a] * n[b];
                    self.bn[a][b] += ws * rgb[a] * n[b];
                }
            }
        }
    }

    /// The model `c, G` fitted to the samples (SPEC.md G.3): weighted least squares, linear in
    /// the normal, ridge-regularised so that directions the normals do not span get slope zero;
    /// for a flat object the weighted mean and no slope. No samples (or zero weight): zero.
    fn fit(&self, flat: bool) -> [f64; MODEL_FLOATS] {
        let w = self.w;
        if w <= 0.0 {
            // Zero-area leaves only: the point carries no light that a refined triangle shows.
            return [0.0; MODEL_FLOATS];
        }
        let nbar = self.n.map(|x| x / w);
        let bbar = self.b.map(|x| x / w);
        let mut out = [0.0; MODEL_FLOATS];
        if flat {
            out[..3].copy_from_slice(&bbar);
            return out;
        }
        let mut m = [[0.0; 3]; 3];
        for a in 0..3 {
            for b in 0..3 {
                m[a][b] = self.nn[a][b] / w - nbar[a] * nbar[b] + if a == b { RIDGE } else { 0.0 };
            }
        }
        let inv = invert3(m);
        for ch in 0..3 {
            let cov: [f64; 3] = std::array::from_fn(|a| self.bn[ch][a] / w - bbar[ch] * nbar[a]);
            let g = mat_vec(inv, cov);
            out[ch] = bbar[ch] - dot(g, nbar);
            out[3 + 3 * ch..6 + 3 * ch].copy_from_slice(&g);
        }
        out
    }
}

fn sub(a: [f64; 3], b: [f64; 3]) -> [f64; 3] {
    [a[0] - b[0], a[1] - b[1], a[2] - b[2]]
}

fn cross(a: [f64; 3], b: [f64; 3]) -> [f64; 3] {
    [
        a[1] * b[2] - a[2] * b[1],
        a[2] * b[0] - a[0] * b[2],
        a[0] * b[1] - a[1] * b[0],
    ]
}

fn dot(a: [f64; 3], b: [f64; 3]) -> f64 {
    a[0] * b[0] + a[1] * b[1] + a[2] * b[2]
}
