//! Stage 2: enriched hierarchical radiosity.
//!
//! Hanrahan, Salzman & Aupperle, "A rapid hierarchical radiosity algorithm" (SIGGRAPH 1991):
//! elements are coarse triangles split 1-to-4 (children Top, Left, Center, Right as in
//! `hce_format::model`); a link between a receiver and a source is refined, splitting the
//! larger of the two, while its brightness-weighted estimate (form factor × source radiance ×
//! receiver area, as power) exceeds `bf_epsilon` times the scene's reference power. Two more
//! rules bound a link's error rather than its power: for near pairs, a receiver over which
//! the form factor varies is split, and a source whose radiance varies in the previous
//! solution is split (that error weighed against every receiver that makes it: the whole
//! coarse receiver triangle, so that a finely split receiver cannot hide it, BENCHMARKS.md,
//! Cornell box; and the coarse triangles of the same object around it that see the source
//! from about the same place, so that a finely tessellated object cannot either). Every leaf
//! is drawn, so two rules judge a link against the radiance of its receiver rather than the
//! scene's power: a receiver over which the link's form factor bends more than a linear
//! function follows is split, and so is one that a shadow edge crosses (partial visibility),
//! or that an occluder right next to it shades unevenly (an object resting on it, whose
//! shadow edge every link shares). A link's visibility is the kernel-weighted fraction of its
//! rays that are clear.
//! A link's coefficient is linear over its receiver (its values at the three corners), so that
//! push hands each leaf the form factor over its own part (in a closed furnace, constant links
//! left leaves by a wall 13% too bright). The system is solved
//! by gathering over links and push-pull, and links are refined again against the solution.
//! Instead of linking every pair of input triangles up front, receivers start from
//! the top of a cluster hierarchy ([`crate::cluster`], after Smits et al. 1994) and open
//! clusters by the same oracle, which culls pairs that face away or lie behind each other.
//!
//! Enrichment (Padrón et al. 2010): every element of a multiresolution object stores one
//! radiance per normal of its root triangle's set; gathering evaluates the receiver cosine
//! with each normal, while an element acting as a source radiates with its geometric normal
//! (the value for n0). Punctual lights add direct illumination through shadow rays.
//!
//! Quantities are outgoing radiance `L` (see [`crate::scene`]); a receiver gathers
//! `Q = Σ F·L_src + H_direct / π` and a leaf has `L = L_e + ρ·Q`, the area average over the
//! element. As a source an element sends its reflected light from its open part only (the
//! part not shut in under other geometry, such as the floor under a block standing on it):
//! `L_src = L_e + (L − L_e) / open`.
//!
//! Determinism: work is split per root triangle, every random number is seeded from element
//! ids, and every sum runs in a fixed order, so the result does not depend on the thread count.

use std::collections::{HashMap, HashSet};
use std::sync::{Mutex, OnceLock};
use std::time::Instant;

use glam::Vec3;
use hce_format::MAX_TREE_DEPTH;
use rayon::prelude::*;

use crate::cluster::{ClusterChild, ClusterTree};
use crate::element::{barycentric_of, child_toward, jittered_point, split, ElemKey, Rng};
use crate::formfactor::{disc_estimate, point_to_polygon, stratified_points};
use crate::scene::{LightKind, Scene};
use crate::visibility::Occluders;
use crate::BakeError;

/// Most visibility rays per link accepted (beyond it a bake would take days, not hours).
pub const MAX_VISIBILITY_RAYS: u32 = 4096;

/// Solver parameters (the `hce bake` flags of the same names).
#[derive(Clone, Debug, PartialEq)]
pub struct BakeParams {
    /// Refinement threshold: a link is refined while its estimated transported power exceeds
    /// this fraction of the scene's reference power (emitted plus directly received). Default
    /// 1e-4.
    pub bf_epsilon: f32,
    /// Elements are not split below this fraction of their object's area, or of a sixteenth of
    /// the scene's area if that is larger. Default 1e-5. (It was a fraction of the whole
    /// scene's area, which in a room kept every triangle of a 1000-triangle object whole: the
    /// objects' leaves were their coarse triangles, whatever `max_level` said. The sixteenth
    /// bounds the cost in scenes of many small objects: Chesstime bakes in 1.2x the time,
    /// against 3.5x with each object's own area.)
    pub min_area_fraction: f32,
    /// Deepest element level below a coarse triangle that the power-based refinement reaches,
    /// at most [`hce_format::MAX_TREE_DEPTH`] (the element tree is the HCE tree). Default 4.
    pub max_level: u32,
    /// Deepest level that the rules judged against a receiver's own radiance reach: where a
    /// shadow edge crosses the receiver, or an occluder next to it shades it unevenly. At
    /// least `max_level`, at most [`hce_format::MAX_TREE_DEPTH`]. Default 7: a shadow on the
    /// floor of a room of two coarse triangles is resolved to a hundred-and-twenty-eighth of
    /// the room, without refining the rest of the room as finely. (At 6 the floor's leaves
    /// were as wide as the legs of an object standing on it, and its contact shadows came out
    /// faint and wide: spot's room 2.4% against a path tracer over the whole image, 1.7% at 7.)
    /// Where a light's shadow is narrower than a flat receiver of this level (an object
    /// close above it: Teatime's spoon, the base of its teapot), two levels deeper, down to a
    /// sixteenth of the least element area (`Ctx::narrow_shadow_splittable`).
    pub detail_level: u32,
    /// Jittered rays per link (and per element and light) for visibility; 0 disables
    /// occlusion. A link that brings a large share of its receiver's light takes up to four
    /// times as many (sixteen from a light to a receiver of `detail_level` or deeper), so that
    /// their noise stays under 2% of the receiver's radiance. Default 8.
    pub visibility_rays: u32,
    /// Iterate gather and push-pull until the relative change of the solution drops below
    /// this. Default 1e-4.
    pub tolerance: f32,
    /// Upper bound on gather iterations per solve. Default 200.
    pub max_iterations: u32,
    /// Link refinement passes, each followed by a solve (the first refines against emission
    /// and direct light). Default 2.
    pub refine_passes: u32,
    /// A cluster acts as one source only while its bounding radius is below this fraction of
    /// its distance to the receiver (the Barnes-Hut opening criterion). Default 0.5.
    pub cluster_opening: f32,
}

impl BakeParams {
    /// The parameters as the JSON object text stored in the container's metadata.
    pub fn to_json(&self) -> String {
        serde_json::json!({
            "bf_epsilon": self.bf_epsilon,
            "min_area_fraction": self.min_area_fraction,
            "max_level": self.max_level,
            "detail_level": self.detail_level,
            "visibility_rays": self.visibility_rays,
            "tolerance": self.tolerance,
            "max_iterations": self.max_iterations,
            "refine_passes": self.refine_passes,
            "cluster_opening": self.cluster_opening,
        })
        .to_string()
    }
}

impl Default for BakeParams {
    fn default() -> Self {
        BakeParams {
            bf_epsilon: 1e-4,
            min_area_fraction: 1e-5,
            max_level: 4,
            detail_level: 7,
            visibility_rays: 8,
            tolerance: 1e-4,
            max_iterations: 200,
            refine_passes: 2,
            cluster_opening: 0.5,
        }
    }
}

/// The solution for one coarse triangle: its element tree in breadth-first order.
#[derive(Clone, Debug, PartialEq)]
pub struct TriangleSolution {
    /// Normals colours are stored for, the geometric normal first.
    pub normals: Vec<[f32; 3]>,
    /// `(level, path)` of every node, breadth-first (children Top, Left, Center, Right).
    pub nodes: Vec<(u32, u32)>,
    /// Per node: whether it is split into four children.
    pub subdivided: Vec<bool>,
    /// Outgoing radiance per node and normal, node-major: `colours[k * normals.len() + j]`.
    /// Interior nodes hold the area-weighted average of their children.
    pub colours: Vec<[f32; 3]>,
}

/// The solution for one scene object.
#[derive(Clone, Debug, PartialEq)]
pub struct ObjectSolution {
    pub name: String,
    pub multires: bool,
    pub triangles: Vec<TriangleSolution>,
}

/// Figures for the summary.
#[derive(Clone, Debug, Default, PartialEq)]
pub struct BakeStats {
    pub coarse_triangles: usize,
    pub elements: usize,
    pub links: usize,
    /// Gather iterations summed over all solves.
    pub iterations: u32,
    /// Relative change at the end of the last solve.
    pub final_change: f32,
    /// Wall-clock seconds per phase: (name, seconds).
    pub phase_seconds: Vec<(String, f64)>,
}

/// What [`bake`] returns.
#[derive(Clone, Debug, PartialEq)]
pub struct BakeResult {
    pub objects: Vec<ObjectSolution>,
    pub stats: BakeStats,
}

/// A coarse triangle as the solver sees it.
struct Root {
    corners: [Vec3; 3],
    normal: Vec3,
    area: f32,
    normals: Vec<Vec3>,
    emission: Vec3,
    object: usize,
    triangle: usize,
}

/// A link source.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Hash)]
enum Source {
    Cluster(u32),
    Elem(ElemKey),
}

/// A link as refinement produces it; `k[nn]` form factors (visibility included) per normal.
struct RawLink {
    recv: ElemKey,
    src: Source,
    /// Where the link looks: for a cluster source, the direction light leaves it towards the
    /// receiver; for an element source, the barycentric coordinates over the source of the
    /// centre of the receiver's view of it ([`Ctx::kernel_centre`]).
    aim: Vec3,
    /// For a cluster source, the share of each of its parts in what the receiver sees of it
    /// ([`Ctx::cluster_share`]); unused for an element source.
    share: [f32; READ_PARTS],
    /// For a cluster source: whether its parts are its [`READ_DEPTH`]-level descendants
    /// ([`Ctx::reads_deep`]) rather than its two children.
    deep: bool,
    /// For an element source: which of its normals' radiance it sends towards the receiver
    /// ([`Ctx::facing_normal`]); 0 for a cluster.
    facing: u8,
    /// For an element source: how many levels below it the receiver's view is read
    /// ([`Ctx::footprint`]); 0 for a cluster.
    depth: u8,
    k_start: u32,
    /// Fraction of the visibility rays that were clear.
    visible: f32,
    /// For a cluster source on a receiver that may split: how far its form factor bends over
    /// the receiver, as the refinement judged it ([`Ctx::cluster_factors_over`]); NaN where it
    /// was not judged. The geometry's alone, so the next pass reads it here and does not walk
    /// the cluster again (a tenth of the scaling scene's bake).
    bend: f32,
}

/// A resolved link inside a root's tree.
struct Link {
    recv: u32,
    src: SrcIdx,
    /// As in [`RawLink`].
    aim: Vec3,
    share: [f32; READ_PARTS],
    deep: bool,
    facing: u8,
    depth: u8,
    k_start: u32,
    visible: f32,
    bend: f32,
}

#[derive(Clone, Copy)]
enum SrcIdx {
    Cluster(u32),
    Node { root: u32, node: u32 },
}

/// One root's element tree in breadth-first order, with its links and solution.
struct Tree {
    keys: Vec<ElemKey>,
    /// Index of the first of four children, or `u32::MAX` for a leaf.
    child: Vec<u32>,
    area: Vec<f32>,
    /// Reflectance per node (used at leaves).
    rho: Vec<Vec3>,
    /// Direct-light `H / π` per node and normal (non-zero at direct-pass leaves only).
    direct: Vec<Vec3>,
    links: Vec<Link>,
    k: Vec<f32>,
    /// Per leaf (empty where the root has no refined surface): the form factor its links give
    /// the refined surface's own normal at its points, pushed down to the leaves and averaged
    /// over them (in a closed scene, one). A normal of the receiver's set turned away from the
    /// surface's own sees, through the part of its hemisphere below the surface, the object's
    /// neighbouring patches that the coarse scene does not have there; every form factor it
    /// lacks against this one is filled with the mean radiance the geometric normal gathers,
    /// so that a closed furnace stays exact for every normal.
    closure: Vec<f32>,
    /// Per leaf and normal (`self_view[i * nn + j]`; empty where the root has no refined
    /// surface): the form factor from the leaf's centre on the refined surface to the rest of
    /// its own root's refined triangles, which it gathers its own radiance through
    /// ([`Ctx::closure`]).
    self_view: Vec<f32>,
    /// Radiance per node and normal.
    l: Vec<Vec3>,
    /// Fraction of each node's area that is open, not shut in under other geometry
    /// ([`Ctx::open_fraction`]; interior nodes average their children).
    open: Vec<f32>,
    /// Per leaf: the part of its hemisphere that meets the front of a surface, where it is
    /// known exactly ([`Ctx::enclosure`]); negative where it is not.
    enclosed: Vec<f32>,
}

impl Tree {
    fn index_of(&self, key: ElemKey) -> Option<u32> {
        self.keys
            .binary_search_by(|k| (k.level, k.path).cmp(&(key.level, key.path)))
            .ok()
            .map(|i| i as u32)
    }

    /// The deepest existing node on the way to `key`.
    fn deepest_toward(&self, key: ElemKey) -> u32 {
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

/// What a cluster radiates (normal 0): its faces' radiance times their open area, summed
/// separately for the faces turned towards each of +x, −x, +y, −y, +z, −z (weighed by the
/// cosine), and those weights. Seen from a direction, a cluster shows the faces turned that
/// way: a plain area average also counted the faces turned away or edge-on (the ceiling's own
/// triangles in a cluster that a ceiling element gathers from, the dark undersides of objects),
/// and rooms came out 2-6% darker than a path tracer shows them (`tests/objects_reference.rs`).
#[derive(Clone, Copy, Debug, Default)]
struct ClusterLight {
    radiance: [Vec3; 6],
    weight: [f32; 6],
    /// Plain sums over the open area, for a direction no face is turned to.
    all: Vec3,
    area: f32,
}

impl ClusterLight {
    fn add(&mut self, o: &ClusterLight) {
        for i in 0..6 {
            self.radiance[i] += o.radiance[i];
            self.weight[i] += o.weight[i];
        }
        self.all += o.all;
        self.area += o.area;
    }

    fn add_face(&mut self, l: Vec3, area: f32, n: Vec3) {
        for (a, c) in n.to_array().into_iter().enumerate() {
            let i = if c >= 0.0 { 2 * a } else { 2 * a + 1 };
            self.radiance[i] += l * (area * c.abs());
            self.weight[i] += area * c.abs();
        }
        self.all += l * area;
        self.area += area;
    }

    /// The radiance leaving in unit direction `w`: the faces turned towards `w`, each axis
    /// weighed by how much `w` lies along it (zero `w`: every face alike).
    fn toward(&self, w: Vec3) -> Vec3 {
        let (mut l, mut a) = (Vec3::ZERO, 0.0f32);
        for (axis, c) in w.to_array().into_iter().enumerate() {
            let i = if c >= 0.0 { 2 * axis } else { 2 * axis + 1 };
            l += self.radiance[i] * c.abs();
            a += self.weight[i] * c.abs();
        }
        if a > 0.0 {
            l / a
        } else if self.area > 0.0 {
            self.all / self.area
        } else {
            Vec3::ZERO
        }
    }
}

struct Ctx<'a> {
    scene: &'a Scene,
    params: &'a BakeParams,
    roots: Vec<Root>,
    clusters: ClusterTree,
    /// Per scene object, a cluster hierarchy over its own triangles alone (indices local to
    /// the object) and the index of its first root. The scene's hierarchy mixes a room's
    /// large triangles with an object's small ones, so its clusters around a small receiver
    /// hold only a sliver of the object; these give the receivers around one (`refine_root`).
    object_clusters: Vec<(ClusterTree, u32)>,
    occ: Occluders,
    /// The root each occluder triangle belongs to.
    occ_owner: Vec<u32>,
    /// Per root: its object's occluder triangles over it, by path at their level (empty where
    /// the object casts shadows with its own triangles): rays leave from and arrive at the
    /// points of this surface that correspond to the root's ([`Ctx::on_surface`]).
    surface: Vec<Vec<[Vec3; 3]>>,
    /// Per root: its corners carried onto its refined surface ([`Ctx::on_surface`]); its own
    /// corners where it has none. The triangle that stands for it where its refined triangles
    /// would be too many to sum: in clusters, and as a far source.
    shape: Vec<[Vec3; 3]>,
    /// Per cluster: whether it holds emitting triangles beside others. Such a cluster is
    /// always opened: as one source it spread the emitters' light as if it left the whole
    /// cluster, and a room lit by a panel under its ceiling came out 2-6% darker than a path
    /// tracer shows it, one wall darker than its mirror image (`tests/objects_reference.rs`).
    mixes_emitters: Vec<bool>,
    /// Per cluster: the parts a link to it reads apart when it reads deep ([`read_parts`]),
    /// found once rather than walked for every link in every iteration.
    read_parts: Vec<([ClusterChild; READ_PARTS], u8)>,
    /// Per root: nothing but the scene's outer boundary lies in front of its plane (the convex
    /// side of an object in a room), so that no link it receives needs rays
    /// ([`Occluders::shaft_clear`] over the whole scene, once per root instead of per link).
    unobstructed: Vec<bool>,
    /// Whether the scene's outer boundary closes it ([`Ctx::boundary_closed`]), found once.
    boundary_closed: OnceLock<bool>,
    /// Per cluster: the object all its triangles belong to, if one.
    cluster_object: Vec<Option<u32>>,
    /// Per scene object: its triangles form a convex surface ([`ClusterTree::is_convex`]), so
    /// that a point on one sees none of the others.
    convex: Vec<bool>,
    /// Per scene object: the smallest element area it is split to
    /// ([`BakeParams::min_area_fraction`] of the object's area, or of a sixteenth of the
    /// scene's).
    min_area: Vec<f32>,
    /// Distances to a plane below this count as lying in it (rounding of coplanar
    /// geometry), relative to the scene size.
    plane_eps: f32,
    /// [`LIGHT_EMISSION`] times the scene's emission luminance averaged over all its area
    /// ([`Ctx::lights`]).
    light_floor: f32,
    /// Per root: what the rules judged by the geometry alone found for its elements, kept
    /// from pass to pass ([`Ctx::memo`]).
    memos: Vec<Mutex<GeometryMemo>>,
}

/// What [`Ctx::near_shadow`], [`Ctx::self_shade_varies`] and [`Ctx::open_fraction`] found for
/// the elements of one root. They depend on the geometry alone, so each element's value is
/// found once for the whole bake (every pass judged them again: an eighth of the scaling
/// scene's bake).
#[derive(Default)]
struct GeometryMemo {
    near_shadow: HashMap<ElemKey, bool>,
    shade_varies: HashMap<ElemKey, bool>,
    open: HashMap<ElemKey, f32>,
    enclosed: HashMap<ElemKey, f32>,
    closed: HashMap<ElemKey, bool>,
}

/// The point of the refined triangles `surface` over the coarse triangle `corners` (by path at
/// their level, as `hce_geometry::lattice` numbers them) with the lattice coordinates of `p`, a
/// point of the coarse triangle, and the refined triangle's normal there; `(p, normal)` when
/// `surface` is empty or `p` lies in none of them.
fn surface_point(corners: [Vec3; 3], normal: Vec3, surface: &[[Vec3; 3]], p: Vec3) -> (Vec3, Vec3) {
    if surface.is_empty() {
        return (p, normal);
    }
    let level = (surface.len().trailing_zeros() / 2).min(hce_format::MAX_TREE_DEPTH);
    let n = (1u32 << level) as f32;
    // Lattice coordinates (b, c) of p: p = v0 + (b (v1 - v0) + c (v2 - v0)) / n.
    let [v0, v1, v2] = corners;
    let (e1, e2, d) = (v1 - v0, v2 - v0, p - v0);
    let (d11, d12, d22) = (e1.dot(e1), e1.dot(e2), e2.dot(e2));
    let den = d11 * d22 - d12 * d12;
    if den <= 0.0 {
        return (p, normal);
    }
    let (d1, d2) = (d.dot(e1), d.dot(e2));
    let q = [
        n * (d22 * d1 - d12 * d2) / den,
        n * (d11 * d2 - d12 * d1) / den,
    ];
    // Descend the 1-to-4 split to the refined triangle that holds q (children Top, Left,
    // Center, Right, as `hce_geometry::lattice` numbers them), then weigh its corners.
    let (mut u, mut v) = (q[0].clamp(0.0, n), q[1].clamp(0.0, n));
    let (mut side, mut path) = (n, 0usize);
    for _ in 0..level {
        let h = side * 0.5;
        let child;
        (child, u, v) = hce_geometry::lattice::child_toward(u, v, h);
        path = path * 4 + child as usize;
        side = h;
    }
    if let Some(tri) = surface.get(path) {
        let c = hce_geometry::lattice::fine_corners(level, path as u32)
            .map(|x| [x[0] as f32, x[1] as f32]);
        // Barycentric weights of q in the lattice triangle c.
        let a = [c[1][0] - c[0][0], c[1][1] - c[0][1]];
        let b = [c[2][0] - c[0][0], c[2][1] - c[0][1]];
        let det = a[0] * b[1] - a[1] * b[0];
        let (x, y) = (q[0] - c[0][0], q[1] - c[0][1]);
        let w1 = (x * b[1] - y * b[0]) / det;
        let w2 = (a[0] * y - a[1] * x) / det;
        let w0 = 1.0 - w1 - w2;
        let at = tri[0] * w0 + tri[1] * w1 + tri[2] * w2;
        let refined = (tri[1] - tri[0])
            .cross(tri[2] - tri[0])
            .try_normalize()
            .unwrap_or(normal);
        return (at, refined);
    }
    (p, normal)
}

fn lum(v: Vec3) -> f32 {
    v.max_element()
}

impl Ctx<'_> {
    fn nn(&self, r: u32) -> usize {
        self.roots[r as usize].normals.len()
    }

    /// The object occluder triangle `t` belongs to.
    fn owner_object(&self, t: usize) -> usize {
        self.roots[self.occ_owner[t] as usize].object
    }

    /// The Loop level of root `r`'s refined surface ([`Ctx::on_surface`]), if it has one.
    fn surface_level(&self, r: u32) -> Option<u32> {
        let surf = &self.surface[r as usize];
        (!surf.is_empty()).then(|| surf.len().trailing_zeros() / 2)
    }

    /// The point of root `r`'s occluding surface ([`SolverObject::occluder`]) that corresponds
    /// to point `p` of the root, and that surface's normal there: the same lattice coordinates
    /// on the refined triangle as on the flat subtriangle. `(p, the root's normal)` where the
    /// root casts shadows with its own triangle.
    ///
    /// [`SolverObject::occluder`]: crate::scene::SolverObject::occluder
    fn on_surface(&self, r: u32, p: Vec3) -> (Vec3, Vec3) {
        let root = &self.roots[r as usize];
        surface_point(root.corners, root.normal, &self.surface[r as usize], p)
    }

    /// The triangles that stand for source element `k` (corners `st`) in form factors. For an
    /// object that casts shadows with a refined surface ([`Ctx::on_surface`]) that surface:
    /// where the source is `near` its receiver, the refined triangles under an element one
    /// level above theirs, the four children of one further above with their corners carried
    /// onto the surface, and below their level the element's corners carried onto its refined
    /// triangle; where it is far, the triangle through its corners carried onto the surface.
    /// Else the element itself.
    ///
    /// The surface drawn sends the light, as it casts the shadows. With the control mesh as
    /// the source and the refined surface as the occluder a receiver counted the control
    /// mesh's points both as a source and as a hole through which it saw what lies behind (a
    /// wall in a closed furnace 5% too bright in front of a refined star's point), and at a
    /// concave fold of one object each coarse triangle saw the other over a wider angle than
    /// the refined surface does (the creases of curved objects 5-27% too bright, issue 20).
    fn source_shape<'s>(
        &'s self,
        k: ElemKey,
        st: [Vec3; 3],
        near: bool,
        buf: &'s mut [[Vec3; 3]; 4],
    ) -> &'s [[Vec3; 3]] {
        let surf = &self.surface[k.root as usize];
        let level = surf.len().trailing_zeros() / 2;
        if surf.is_empty() {
            buf[0] = st;
        } else if !near || k.level >= level {
            buf[0] = st.map(|q| self.on_surface(k.root, q).0);
        } else if k.level + 1 == level {
            // Paths number the refined triangles as they number elements (first choice most
            // significant), so the four under `k` are one run.
            let first = (k.path as usize) << 2;
            return &surf[first..first + 4];
        } else {
            // Further above the refined triangles: the element's four children, their corners
            // carried onto the surface (four form factors where the refined triangles under
            // it would take sixteen: the same surface, a level coarser).
            for (b, c) in buf.iter_mut().zip(split(st)) {
                *b = c.map(|q| self.on_surface(k.root, q).0);
            }
            return &buf[..];
        }
        &buf[..1]
    }

    /// The smallest area an element of `k`'s object is split to.
    fn min_area_of(&self, k: ElemKey) -> f32 {
        self.min_area[self.roots[k.root as usize].object]
    }

    fn elem_corners(&self, k: ElemKey) -> [Vec3; 3] {
        k.corners(self.roots[k.root as usize].corners)
    }

    /// Whether the self-shading rule may split `k` ([`Ctx::self_shade_varies`]): an element of
    /// an object with a refined surface, down to a quarter of one of that surface's triangles
    /// (the rays that judge it meet that surface, and resolve nothing finer), whatever its
    /// area: the surface's level bounds the leaves to 4^(level + 1) per coarse triangle, and
    /// `min_area_fraction`, a share of the scene's area in a room, stopped the teapot's spout
    /// junction at leaves of a quarter of its coarse triangles (5.4% against path-traced
    /// images, 3.8% without).
    fn self_shade_splittable(&self, k: ElemKey) -> bool {
        self.surface_level(k.root)
            .is_some_and(|level| k.level <= level && k.level < MAX_TREE_DEPTH)
    }

    fn splittable(&self, k: ElemKey, area: f32) -> bool {
        k.level < self.params.max_level.min(MAX_TREE_DEPTH) && area * 0.25 >= self.min_area_of(k)
    }

    /// Whether a rule judged against the receiver's own radiance may split `k`
    /// ([`BakeParams::detail_level`]).
    fn detail_splittable(&self, k: ElemKey, area: f32) -> bool {
        k.level < self.params.detail_level.min(MAX_TREE_DEPTH) && area * 0.25 >= self.min_area_of(k)
    }

    /// Whether `src` is a light: an element emitting more than [`LIGHT_EMISSION`] times the
    /// scene's mean emission over all its area (`light_floor`), so that its direct light and
    /// its shadows are what the surfaces around it show most (a cluster holding an emitter is
    /// always opened, so only elements are asked). In a closed furnace, where every surface
    /// emits alike, none is.
    fn lights(&self, src: Source) -> bool {
        match src {
            Source::Elem(sk) => self.is_light(sk.root),
            Source::Cluster(_) => false,
        }
    }

    /// Whether root `r` is part of a light ([`Ctx::lights`]).
    fn is_light(&self, r: u32) -> bool {
        lum(self.roots[r as usize].emission) > self.light_floor
    }

    /// Whether the shadow that a light `st` ([`Ctx::lights`]) casts across flat receiver `k`
    /// (corners `rt`), which the link's rays found partly hidden, may be narrower than the
    /// receiver, which then draws it blurred over its whole width: below
    /// [`BakeParams::detail_level`] (down to [`NARROW_SHADOW_LEVELS`] more levels and a
    /// sixteenth of the least area), a surface met between the receiver and the light nearer
    /// than `s·D/W` (receiver size `s`, light distance `D` and width `W`), where its penumbra
    /// is narrower than `s`. Judged by the geometry, from the receiver's centre and inset
    /// corners towards the light's centre and corners, and with no threshold on the light the
    /// link brings, so that the receivers along one shadow edge split alike. Split where that
    /// light passed a threshold, a thin shadow (Teatime's spoon) was
    /// drawn as dashes, sharp where a receiver passed and blurred between; kept to where the
    /// light was a quarter to three quarters hidden, a contact shadow's outline was ragged
    /// (docs/decisions.md; `bake/tests/contact_shadows.rs` holds the outline). `refine_root` takes the receiver's other links down
    /// with the light's.
    fn narrow_shadow_splittable(
        &self,
        k: ElemKey,
        area: f32,
        rt: [Vec3; 3],
        st: [Vec3; 3],
    ) -> bool {
        let object = self.roots[k.root as usize].object;
        if self.scene.objects[object].multires
            || k.level >= (self.params.detail_level + NARROW_SHADOW_LEVELS).min(MAX_TREE_DEPTH)
            || area * 0.25 * NARROW_SHADOW_AREA < self.min_area_of(k)
        {
            return false;
        }
        // Part of it shut in (under a block standing on it): the shadow's edge there is the
        // footprint's, which the open fraction already draws ([`Ctx::shown`]).
        if self.memo(k, |m| &mut m.open, || self.open_fraction(k)) < 1.0 {
            return false;
        }
        let longest = |t: [Vec3; 3]| {
            (0..3)
                .map(|i| (t[(i + 1) % 3] - t[i]).length())
                .fold(0.0, f32::max)
        };
        let rc = (rt[0] + rt[1] + rt[2]) / 3.0;
        let sc = (st[0] + st[1] + st[2]) / 3.0;
        let (size, width, dist) = (longest(rt), longest(st), (sc - rc).length());
        if width <= 0.0 {
            return false;
        }
        let reach = size * dist / width;
        let n = self.roots[k.root as usize].normal;
        let [c0, c1, c2] = inset_corners(rt);
        [rc, c0, c1, c2].iter().any(|&p| {
            [sc, st[0], st[1], st[2]].iter().any(|&q| {
                let d = q - p;
                let len = d.length();
                len > 0.0
                    && n.dot(d) > 0.0
                    && self
                        .occ
                        .first_hit_from(p, n, d / len, reach.min(len * 0.99), |_| false)
                        .is_some()
            })
        })
    }

    /// Whether the bend rule may split receiver `k` for source element `sk`: one level below
    /// `max_level` (a room's corner between a wall and the ceiling, where a leaf of
    /// `max_level` drew a bright line along the corner: the light falls towards it faster than
    /// a linear link follows), but down to `max_level` alone between two coarse triangles of
    /// one object with a refined surface.
    ///
    /// Every link a receiver takes must be able to follow it down: a leaf split below
    /// `max_level` for one source takes the links it could not split for, pushed from its
    /// parent as linear functions, and next to a corner those are far from linear. When one
    /// object stopped at `max_level` at its own edges, a room's walls, one object beside the
    /// floor and the ceiling, were split a level deeper along the floor and the ceiling for
    /// them, and the leaves by the corner where two walls meet read 6% too dark and too bright
    /// in turn in a closed furnace (`tests/furnace_property.rs`, `large_faces`; bright lines
    /// along the room's corners in issue 20).
    fn bend_splittable(&self, k: ElemKey, area: f32, sk: ElemKey) -> bool {
        if self.roots[k.root as usize].object == self.roots[sk.root as usize].object
            && !self.surface[k.root as usize].is_empty()
        {
            return self.splittable(k, area);
        }
        let depth = (self.params.max_level + 1)
            .min(self.params.detail_level)
            .min(MAX_TREE_DEPTH);
        k.level < depth && area * 0.25 >= self.min_area_of(k)
    }

    /// The bend rule's tolerance for receiver `k` and source `src`: half of
    /// [`BEND_TOLERANCE`] where the two lie on one object. Around an edge an object shares
    /// with itself every face on the other side bends alike, and their errors add: at 0.001 the
    /// leaves along the edges of a closed furnace's jittered box came out 1.1-1.3% off, at
    /// 0.0005 within 0.6% (halving it for every pair cost the scaling scene 14% more elements).
    fn bend_tolerance(&self, k: ElemKey, src: Source) -> f32 {
        let object = match src {
            Source::Elem(sk) => Some(self.roots[sk.root as usize].object),
            Source::Cluster(c) => self.cluster_object[c as usize].map(|o| o as usize),
        };
        if object == Some(self.roots[k.root as usize].object) {
            0.5 * BEND_TOLERANCE
        } else {
            BEND_TOLERANCE
        }
    }

    /// Whether root `r`, with its geometric normal alone, sees nothing of object `object`: its
    /// own object, convex (a block, a sphere). Such pairs (half of those the scaling scene's
    /// sphere met) have no positive form factor, and computing it took a walk of the clusters
    /// nearest the receiver.
    fn sees_none_of_own(&self, r: u32, object: usize) -> bool {
        let own = self.roots[r as usize].object;
        own == object && self.convex[own]
    }

    fn reflectance(&self, k: ElemKey) -> Vec3 {
        let root = &self.roots[k.root as usize];
        let obj = &self.scene.objects[root.object];
        let r = match &obj.reflectance_fn {
            Some(f) => f(root.triangle, k.barycentric()),
            None => obj.reflectance[root.triangle],
        };
        Vec3::from(r).clamp(Vec3::ZERO, Vec3::ONE)
    }

    /// Direct irradiance / π per normal at element `k` from every punctual light.
    fn direct(&self, k: ElemKey) -> Vec<Vec3> {
        let root = &self.roots[k.root as usize];
        let nn = root.normals.len();
        let mut q = vec![Vec3::ZERO; nn];
        if self.scene.lights.is_empty() {
            return q;
        }
        let tri = self.elem_corners(k);
        let nv = self.params.visibility_rays;
        let samples = nv.max(1);
        for (li, light) in self.scene.lights.iter().enumerate() {
            let mut rng = Rng::new(k.id(), li as u64, 0x11);
            let colour = Vec3::from(light.color) * light.intensity;
            let mut acc = vec![Vec3::ZERO; nn];
            for i in 0..samples {
                let p = if nv == 0 {
                    (tri[0] + tri[1] + tri[2]) / 3.0
                } else {
                    jittered_point(tri, i, samples, &mut rng)
                };
                let (w, dist, scale) = match light.kind {
                    LightKind::Directional => {
                        let w = -Vec3::from(light.direction).normalize();
                        (w, f32::INFINITY, 1.0)
                    }
                    LightKind::Point | LightKind::Spot { .. } => {
                        let d = Vec3::from(light.position) - p;
                        let dist = d.length();
                        if dist <= 1e-12 {
                            continue;
                        }
                        let w = d / dist;
                        let mut s = 1.0 / (dist * dist);
                        if let Some(range) = light.range {
                            s *= (1.0 - (dist / range).powi(4)).clamp(0.0, 1.0);
                        }
                        if let LightKind::Spot {
                            inner_cone_angle,
                            outer_cone_angle,
                        } = light.kind
                        {
                            let axis = Vec3::from(light.direction).normalize();
                            let cd = (-w).dot(axis);
                            let (ci, co) = (inner_cone_angle.cos(), outer_cone_angle.cos());
                            let t = ((cd - co) / (ci - co).max(1e-4)).clamp(0.0, 1.0);
                            s *= t * t;
                        }
                        (w, dist, s)
                    }
                };
                if scale <= 0.0 || root.normals.iter().all(|n| n.dot(w) <= 0.0) {
                    continue;
                }
                if nv > 0 && {
                    let (a, _) = self.on_surface(k.root, p);
                    !self.occ.ray_clear(a, w, dist * (1.0 - 1e-5))
                } {
                    continue;
                }
                for (a, n) in acc.iter_mut().zip(&root.normals) {
                    *a += colour * (scale * n.dot(w).max(0.0));
                }
            }
            for (qj, a) in q.iter_mut().zip(&acc) {
                *qj += *a / (samples as f32 * std::f32::consts::PI);
            }
        }
        q
    }

    /// Direct-light refinement of root `r`: splits where the direct light varies by more than
    /// the oracle allows (shadow boundaries, spot edges). Returns the leaves and their values.
    fn direct_tree(&self, r: u32, root_q: Vec<Vec3>, eps_power: f32) -> Vec<(ElemKey, Vec<Vec3>)> {
        let mut out = Vec::new();
        let mut stack = vec![(ElemKey::root(r), root_q)];
        while let Some((k, q)) = stack.pop() {
            let area = self.roots[r as usize].area / 4f32.powi(k.level as i32);
            if self.scene.lights.is_empty() || !self.detail_splittable(k, area) {
                out.push((k, q));
                continue;
            }
            let kids: Vec<(ElemKey, Vec<Vec3>)> = (0..4)
                .map(|c| (k.child(c), self.direct(k.child(c))))
                .collect();
            let mut var = 0.0f32;
            for (_, cq) in &kids {
                for (a, b) in cq.iter().zip(&q) {
                    var = var.max(lum((*a - *b).abs()));
                }
            }
            let rho = lum(self.reflectance(k));
            // The power rule to `max_level`; below it, only an edge of the light across the
            // element (a shadow's or a spot's, where a child differs from the whole by a
            // quarter of the brightest) splits it further, down to `detail_level`.
            let bright = kids
                .iter()
                .map(|(_, cq)| lum(cq[0]))
                .fold(lum(q[0]), f32::max);
            let power =
                self.splittable(k, area) && var * rho * area * std::f32::consts::PI > eps_power;
            let edge = var > DIRECT_EDGE * bright
                && bright * rho * area * std::f32::consts::PI > 0.01 * eps_power;
            if power || edge {
                // Children in reverse so that they pop in order.
                stack.extend(kids.into_iter().rev());
            } else {
                let mut mean = vec![Vec3::ZERO; q.len()];
                for (_, cq) in &kids {
                    for (m, v) in mean.iter_mut().zip(cq) {
                        *m += *v * 0.25;
                    }
                }
                out.push((k, mean));
            }
        }
        out.sort_by_key(|(k, _)| (k.level, k.path));
        out
    }

    /// Radiance (normal 0) of a source in the previous solution.
    /// `at` is the receiver's point: a cluster's radiance is that of its faces turned towards it.
    fn src_radiance(&self, trees: &[Tree], cl: &[ClusterLight], s: Source, at: Vec3) -> Vec3 {
        match s {
            Source::Cluster(c) => cl[c as usize].toward(self.leaving(c, at)),
            Source::Elem(k) => {
                let t = &trees[k.root as usize];
                self.source_radiance(k.root, t, t.deepest_toward(k) as usize)
            }
        }
    }

    /// Where in source element `sk` (corners `st`) a receiver at `p` with normal `n` looks:
    /// the barycentric coordinates over the source of its children's centroids, each weighed
    /// by its form factor from `p` as a disc (`A cos cos / (π d² + A)`), for
    /// [`Ctx::seen_radiance`]. The source's centroid where none is in front of `p`.
    fn kernel_centre(&self, p: Vec3, n: Vec3, sk: ElemKey, st: [Vec3; 3]) -> Vec3 {
        let sn = self.roots[sk.root as usize].normal;
        let area = self.roots[sk.root as usize].area / 4f32.powi(sk.level as i32 + 1);
        // The children's centroids in the split order (Top, Left, Center, Right), as
        // barycentric coordinates of the source.
        const CENTROIDS: [[f32; 3]; 4] = [
            [4.0 / 6.0, 1.0 / 6.0, 1.0 / 6.0],
            [1.0 / 6.0, 4.0 / 6.0, 1.0 / 6.0],
            [1.0 / 3.0, 1.0 / 3.0, 1.0 / 3.0],
            [1.0 / 6.0, 1.0 / 6.0, 4.0 / 6.0],
        ];
        let (mut sum, mut total) = (Vec3::ZERO, 0.0f32);
        for b in CENTROIDS {
            let b = Vec3::from(b);
            let q = st[0] * b.x + st[1] * b.y + st[2] * b.z;
            let v = q - p;
            let d2 = v.length_squared();
            let w = n.dot(v).max(0.0) * (-sn.dot(v)).max(0.0)
                / (d2 * (std::f32::consts::PI * d2 + area)).max(f32::MIN_POSITIVE);
            sum += b * w;
            total += w;
        }
        if total > 0.0 && sum.is_finite() {
            sum / total
        } else {
            Vec3::splat(1.0 / 3.0)
        }
    }

    /// How far below source element `sk` (corners `st`) a receiver centred at `p` with normal
    /// `n` reads its radiance, and where: a receiver whose view of the source is centred
    /// nearer than a quarter of the source's size sees mostly the part of it around that
    /// centre (seen from a height `d`, a plane sends 80% of what a point gathers from it from
    /// within `2d` of the foot), so its link reads the node of about four times that distance
    /// there, `depth` levels down, at the centre's barycentric coordinates (the kernel
    /// `cos cos / r²` weighed over sixteen stratified points of the source, clamped into it).
    /// `(0, _)` otherwise.
    ///
    /// A link to a large near source gathered its mean, where its receiver sees the part in
    /// front of it: under a slab floating 10 cm above a lit floor, the floor saw the slab's
    /// whole underside, rim lit by the floor around it, where it looks at the dark middle,
    /// and came out 21% too bright (`tests/contact_shadows.rs`). Refinement does not split
    /// such a source: its variation comes from light that has bounced, which the last pass
    /// judges by the previous solution, where the source was still one leaf.
    fn footprint(&self, p: Vec3, n: Vec3, sk: ElemKey, st: [Vec3; 3]) -> (u8, Vec3) {
        let sn = self.roots[sk.root as usize].normal;
        let size = (st[1] - st[0])
            .length()
            .max((st[2] - st[1]).length())
            .max((st[0] - st[2]).length());
        if sn.dot(p - st[0]).abs() * 4.0 >= size || size <= 0.0 {
            return (0, Vec3::ZERO);
        }
        // The kernel's centre over sixteen stratified points of the source.
        let (mut sum, mut total) = (Vec3::ZERO, 0.0f32);
        for q in stratified_points(st, 2) {
            let v = q - p;
            let d2 = v.length_squared().max(f32::MIN_POSITIVE);
            let w = n.dot(v).max(0.0) * (-sn.dot(v)).max(0.0) / (d2 * d2);
            sum += q * w;
            total += w;
        }
        if total <= 0.0 || !sum.is_finite() {
            return (0, Vec3::ZERO);
        }
        let q = sum / total;
        let dist = (q - p).length();
        if dist * 4.0 >= size {
            return (0, Vec3::ZERO);
        }
        let depth = (size / (4.0 * dist.max(size * 1e-4)))
            .log2()
            .floor()
            .clamp(0.0, 15.0) as u8;
        // Barycentric coordinates of the centre over the source.
        let area2 = (st[1] - st[0]).cross(st[2] - st[0]).dot(sn);
        if depth == 0 || area2.abs() <= f32::MIN_POSITIVE {
            return (0, Vec3::ZERO);
        }
        let b = Vec3::new(
            (st[1] - q).cross(st[2] - q).dot(sn),
            (st[2] - q).cross(st[0] - q).dot(sn),
            (st[0] - q).cross(st[1] - q).dot(sn),
        ) / area2;
        let b = b.max(Vec3::ZERO);
        let sum = b.x + b.y + b.z;
        (
            depth,
            if sum > 0.0 {
                b / sum
            } else {
                Vec3::splat(1.0 / 3.0)
            },
        )
    }

    /// How much of what a receiver at `p` with normal `n` sees of cluster `c` is each of its
    /// parts' ([`Ctx::cluster_parts`]; `deep`, as [`Ctx::reads_deep`] says): each part as a
    /// disc of its front-facing open area at its centre (`cos A / (π d² + A)`), for
    /// [`Ctx::cluster_seen`]. Alike where it sees none.
    fn cluster_share(
        &self,
        trees: &[Tree],
        c: u32,
        p: Vec3,
        n: Vec3,
        deep: bool,
    ) -> [f32; READ_PARTS] {
        let weigh = |ch: ClusterChild| {
            let (centre, area) = match ch {
                ClusterChild::Cluster(x) => {
                    let centre = self.clusters.clusters[x as usize].centre;
                    let w = (p - centre).normalize_or_zero();
                    (centre, self.clusters.projected_area(x, w))
                }
                ClusterChild::Root(x) => {
                    let root = &self.roots[x as usize];
                    let centre = (root.corners[0] + root.corners[1] + root.corners[2]) / 3.0;
                    let w = (p - centre).normalize_or_zero();
                    let open = trees[x as usize].open[0];
                    (centre, root.area * open * root.normal.dot(w).max(0.0))
                }
            };
            let v = centre - p;
            let d2 = v.length_squared().max(1e-20);
            n.dot(v / d2.sqrt()).max(0.0) * area / (std::f32::consts::PI * d2 + area)
        };
        let (parts, count) = self.cluster_parts(c, deep);
        let mut w = [0.0f32; READ_PARTS];
        for (x, part) in w.iter_mut().zip(&parts[..count]) {
            *x = weigh(*part);
        }
        let sum: f32 = w.iter().sum();
        if sum > 0.0 {
            w.map(|x| x / sum)
        } else {
            let mut even = [0.0f32; READ_PARTS];
            even[..count].fill(1.0 / count as f32);
            even
        }
    }

    /// The parts of cluster `c` a link reads apart, and how many there are: its
    /// [`READ_DEPTH`]-level descendants where it reads `deep` ([`read_parts`]), else its two
    /// children.
    fn cluster_parts(&self, c: u32, deep: bool) -> ([ClusterChild; READ_PARTS], usize) {
        if deep {
            let (parts, count) = self.read_parts[c as usize];
            (parts, usize::from(count))
        } else {
            let [a, b] = self.clusters.clusters[c as usize].children;
            let mut parts = [a; READ_PARTS];
            parts[1] = b;
            (parts, 2)
        }
    }

    /// Whether a link from cluster `c` to a receiver centred at `p` reads the cluster in its
    /// [`READ_DEPTH`]-level parts rather than its two children: a cluster near enough for its
    /// radius to be [`DEEP_READ`] of its distance or more. Linked whole up to
    /// `cluster_opening` (a half), it read its two children's mean where the receiver sees one
    /// part of them most: a closed room lit from the middle of its ceiling is brightest in
    /// the middle of its floor, which the ceiling's middle sees square on, and the power the
    /// room's surfaces sent through their links fell 0.6% short of what they reflect (walls
    /// and ceiling 0.7% dark against a path tracer; read by parts, 0.35%:
    /// `a_lit_closed_room_agrees_with_the_path_tracer` in `bake/tests/solver.rs`).
    fn reads_deep(&self, c: u32, p: Vec3) -> bool {
        let cluster = &self.clusters.clusters[c as usize];
        cluster.radius() >= DEEP_READ * (cluster.centre - p).length()
    }

    /// The radiance (normal 0) a link gathers from cluster `c` in direction `w`: its parts'
    /// ([`Ctx::cluster_parts`]; [`ClusterLight::toward`], a root triangle's own), each by its
    /// `share` of the receiver's view ([`Ctx::cluster_share`]). The cluster's own average weighs its
    /// triangles by their areas turned towards `w` alone, which is right from afar; from a
    /// receiver that sees one child closer, or square on, the other edge-on, that child
    /// brings more (a lit room's walls and ceiling gathered 0.3% too little from clusters of
    /// the floor, `tests/gathered_light.rs`).
    fn cluster_seen(
        &self,
        trees: &[Tree],
        cl: &[ClusterLight],
        c: u32,
        w: Vec3,
        share: &[f32; READ_PARTS],
        deep: bool,
    ) -> Vec3 {
        let radiance = |ch: ClusterChild| match ch {
            ClusterChild::Cluster(x) => cl[x as usize].toward(w),
            ClusterChild::Root(x) => self.source_radiance(x, &trees[x as usize], 0),
        };
        let (parts, count) = self.cluster_parts(c, deep);
        parts[..count]
            .iter()
            .zip(share)
            .fold(Vec3::ZERO, |sum, (part, s)| sum + radiance(*part) * *s)
    }

    /// The radiance (normal 0) a link gathers from node `i` of root `r`'s tree, looking at the
    /// point with barycentric coordinates `aim` over it ([`Ctx::kernel_centre`]): the node's
    /// own ([`Ctx::source_radiance`]) where it is a leaf; else the linear function over it
    /// whose corner children have their radiances, read there, held between its children's
    /// least and greatest. A link to a large source whose radiance varies gathered its mean,
    /// where the receiver sees one part of it more than another: a lit room's floor is
    /// brightest under the light, which the ceiling above sees most of, and the room's walls
    /// and ceiling came out 1-2% too dark against a path tracer
    /// (`tests/objects_reference.rs`).
    ///
    /// With `aᵢ` the corner children's (Top, Left, Right) radiances and `m` the node's, a
    /// linear function with those child means is `m + 2 Σ (bᵢ − 1/3) aᵢ` at `b`.
    fn seen_radiance(
        &self,
        r: u32,
        t: &Tree,
        (mut i, depth): (usize, u8),
        mut aim: Vec3,
        j: usize,
    ) -> Vec3 {
        // Down to the node under the receiver's footprint ([`Ctx::footprint`]).
        for _ in 0..depth {
            let c = t.child[i];
            if c == u32::MAX {
                break;
            }
            let (k, local) = child_toward(aim);
            i = c as usize + k;
            aim = local;
        }
        let mean = self.source_radiance_for(r, t, i, j);
        let c = t.child[i];
        if c == u32::MAX {
            return mean;
        }
        let c = c as usize;
        let kids = [c, c + 1, c + 2, c + 3].map(|k| self.source_radiance_for(r, t, k, j));
        let (lo, hi) = kids
            .iter()
            .fold((mean, mean), |(lo, hi), k| (lo.min(*k), hi.max(*k)));
        let tilt = (kids[0] * (aim.x - 1.0 / 3.0)
            + kids[1] * (aim.y - 1.0 / 3.0)
            + kids[3] * (aim.z - 1.0 / 3.0))
            * 2.0;
        (mean + tilt).clamp(lo, hi)
    }

    /// Radiance (normal 0) that node `i` of root `r`'s tree sends out. Its stored value is
    /// the area average that a viewer sees; but light leaves only from the open part of the
    /// element (see [`Ctx::open_fraction`]): the part of a floor element under a block
    /// standing on it receives nothing and sends nothing. Links already give that part no
    /// weight (a receiver finds it behind the block or behind its own plane), so the power
    /// the element reflects must be spread over the open part alone, or the light it sends
    /// is cut once by the dark part in the average and again by the link. Emission is
    /// uniform over the element and is not diluted.
    fn source_radiance(&self, r: u32, t: &Tree, i: usize) -> Vec3 {
        self.source_radiance_for(r, t, i, 0)
    }

    /// [`Ctx::source_radiance`] for normal `j` of the root's set.
    fn source_radiance_for(&self, r: u32, t: &Tree, i: usize, j: usize) -> Vec3 {
        let o = t.open[i];
        if o <= 0.0 {
            return Vec3::ZERO;
        }
        let le = self.roots[r as usize].emission;
        le + (t.l[i * self.nn(r) + j] - le) / o
    }

    /// Which normal of source element `sk`'s set stands for the surface that sends light
    /// towards `p`: the one nearest the mean normal of its refined triangles, each weighed by
    /// its area turned towards `p`. 0 where the root has one normal or no refined surface.
    fn facing_normal(&self, sk: ElemKey, p: Vec3) -> u8 {
        let root = &self.roots[sk.root as usize];
        let surf = &self.surface[sk.root as usize];
        if root.normals.len() < 2 || surf.is_empty() {
            return 0;
        }
        let level = surf.len().trailing_zeros() / 2;
        let tris = if sk.level >= level {
            let i = (sk.path >> (2 * (sk.level - level))) as usize;
            &surf[i..i + 1]
        } else {
            let span = 1usize << (2 * (level - sk.level));
            let first = sk.path as usize * span;
            &surf[first..first + span]
        };
        let mut m = Vec3::ZERO;
        for t in tris {
            let n2 = (t[1] - t[0]).cross(t[2] - t[0]);
            let d = (p - (t[0] + t[1] + t[2]) / 3.0).normalize_or_zero();
            m += n2.normalize_or_zero() * n2.dot(d).max(0.0);
        }
        let mut best = (0u8, root.normals[0].dot(m));
        for (j, n) in root.normals.iter().enumerate().skip(1) {
            let d = n.dot(m);
            if d > best.1 {
                best = (j as u8, d);
            }
        }
        best.0
    }

    /// Per node of `t`: the spread (largest minus smallest) of the source radiance over the
    /// leaves below it, in the current solution. A link's constant source is only as good
    /// as this spread is small: the refinement oracle splits sources by it.
    fn spreads(&self, r: u32, t: &Tree) -> Vec<f32> {
        let n = t.keys.len();
        let mut lo = vec![f32::MAX; n];
        let mut hi = vec![f32::MIN; n];
        // Breadth-first order: children come after their parent, so reverse is bottom-up.
        for i in (0..n).rev() {
            let c = t.child[i];
            if c == u32::MAX {
                let v = lum(self.source_radiance(r, t, i));
                lo[i] = v;
                hi[i] = v;
            } else {
                for ch in c as usize..c as usize + 4 {
                    lo[i] = lo[i].min(lo[ch]);
                    hi[i] = hi[i].max(hi[ch]);
                }
            }
        }
        lo.iter().zip(&hi).map(|(a, b)| b - a).collect()
    }

    /// What the file stores for root `r`'s tree `t` (SPEC.md, A.9): per node and normal the
    /// radiance of the part of the element that can be seen. A leaf partly shut in (under a
    /// block on the floor, inside a spout where it meets a body: [`Ctx::open_fraction`]) holds
    /// the area average of the whole element in the solver, its shut part dark; the viewer
    /// draws the leaf where it is open, so it gets the open part's radiance
    /// ([`Ctx::source_radiance`], as it sends light). Interior nodes average their children.
    /// Drawn with the shut part counted, the teapot's body beside its spout came out 2% dark
    /// over the whole object (8.1% error; now 6.1%).
    fn shown(&self, r: u32, t: &Tree) -> Vec<Vec3> {
        let nn = self.nn(r);
        let le = self.roots[r as usize].emission;
        let mut l = t.l.clone();
        // Breadth-first: children come after their parent, so reverse is bottom-up.
        for i in (0..t.keys.len()).rev() {
            let c = t.child[i];
            if c == u32::MAX {
                let o = t.open[i];
                if o > 0.0 && o < 1.0 {
                    for j in 0..nn {
                        l[i * nn + j] = le + (t.l[i * nn + j] - le) / o;
                    }
                }
            } else {
                for j in 0..nn {
                    let sum: Vec3 = (c as usize..c as usize + 4).map(|ch| l[ch * nn + j]).sum();
                    l[i * nn + j] = sum * 0.25;
                }
            }
        }
        l
    }

    /// Area-weighted mean radiance (normal 0) of the surfaces that emit nothing, in the solution
    /// `trees`: what a receiver counts as dim against (see `DIM_RECEIVER_FLOOR`). In a fixed
    /// order, so the same whatever the thread count.
    fn mean_radiance(&self, trees: &[Tree]) -> f32 {
        let (mut area, mut sum) = (0.0f64, 0.0f64);
        for (root, t) in self.roots.iter().zip(trees) {
            if lum(root.emission) > 0.0 {
                continue;
            }
            area += f64::from(root.area);
            sum += f64::from(root.area) * f64::from(lum(t.l[0]));
        }
        if area > 0.0 {
            (sum / area) as f32
        } else {
            0.0
        }
    }

    /// Spread of a source element's radiance in the previous solution: zero where the
    /// element is not in its tree (it then lies inside a leaf, which is uniform).
    fn src_spread(&self, trees: &[Tree], spreads: &[Vec<f32>], k: ElemKey) -> f32 {
        let t = &trees[k.root as usize];
        let i = t.deepest_toward(k) as usize;
        if t.keys[i] == k {
            spreads[k.root as usize][i]
        } else {
            0.0
        }
    }

    /// Refines the links arriving at root `r` against the previous solution: a depth-first
    /// walk over (receiver, source) pairs from (the root, the scene's top cluster), whose
    /// pairs left after [`REFINE_STEPS`] go on in parallel ([`refine_in_parallel`]).
    fn refine_root(
        &self,
        r: u32,
        trees: &[Tree],
        cl: &[ClusterLight],
        spreads: &[Vec<f32>],
        eps_power: f32,
        judge: Judge,
    ) -> (Vec<RawLink>, Vec<f32>) {
        let Judge {
            mean_radiance,
            dark_floor,
            last_pass,
        } = judge;
        let nn = self.nn(r);
        // Per link: its coefficients, and on a refined surface those of the surface's own
        // normal ([`Ctx::link_coefficients`]).
        let link_len = CORNERS * nn
            + if self.surface[r as usize].is_empty() {
                0
            } else {
                CORNERS
            };
        // Coefficients are a pure function of the pair: reuse those of the previous pass.
        let prev = &trees[r as usize];
        let cache: std::collections::HashMap<(ElemKey, Source), (usize, f32, f32)> = prev
            .links
            .iter()
            .map(|l| {
                let src = match l.src {
                    SrcIdx::Cluster(c) => Source::Cluster(c),
                    SrcIdx::Node { root, node } => {
                        Source::Elem(trees[root as usize].keys[node as usize])
                    }
                };
                (
                    (prev.keys[l.recv as usize], src),
                    (l.k_start as usize, l.visible, l.bend),
                )
            })
            .collect();
        let top = match self.clusters.top {
            ClusterChild::Cluster(c) => Source::Cluster(c),
            ClusterChild::Root(x) => Source::Elem(ElemKey::root(x)),
        };
        let corners_of = |s: Source| match s {
            Source::Elem(k) => self.elem_corners(k),
            Source::Cluster(_) => [Vec3::ZERO; 3],
        };
        // Each pair with the corners of its receiver and (an element) source, carried down as
        // they split.
        let stack: Vec<Pair> = vec![(
            ElemKey::root(r),
            self.roots[r as usize].corners,
            top,
            corners_of(top),
            false,
        )];
        let root = &self.roots[r as usize];
        // Radius and area of the clusters of its own object holding this root, largest
        // first: the receivers around it (see the source variation rule below).
        let (own, first) = &self.object_clusters[root.object];
        let neighbourhood: Vec<(f32, f32)> = own
            .ancestors(r - first)
            .iter()
            .map(|&c| {
                let c = &own.clusters[c as usize];
                (c.radius(), c.area)
            })
            .collect();
        // The receiver's radiance in the previous solution (normal 0), which the rules judged
        // against the receiver weigh their errors by.
        let receiver_radiance = |recv: ElemKey| {
            let t = &trees[r as usize];
            lum(t.l[t.deepest_toward(recv) as usize * nn])
        };
        // What the bend rules judge a receiver's error against: its radiance, but in a first
        // pass of several at least `dark_floor`. Before any light has bounced, a receiver
        // in the dark of the direct light has none, and every bend split it (the scaling
        // scene's ball, pass 1: 97,000 elements, of which the second pass kept 54,000).
        let bend_radiance = |recv: ElemKey| receiver_radiance(recv).max(dark_floor);
        // A link's coefficients and visible fraction, with as many rays as what it brings asks
        // (`est`, the power bound the rules judged; `share`, the radiance it brings its
        // receiver).
        let coefficients = |(recv, rt): (ElemKey, [Vec3; 3]),
                            (src, st): (Source, [Vec3; 3]),
                            est: f32,
                            share: f32,
                            known: KnownFactors| {
            // All the rays where the link brings a visible share of the scene's power or of
            // its receiver's light; a few where it brings little of either (the error it can
            // add is a fraction of that). Judged by the scene's power alone, every link of a
            // small leaf was faint and took two rays, and next to an object resting on a floor
            // the noise of a dozen half-hidden links left leaves 8% off in a closed furnace.
            let nv = self.params.visibility_rays;
            let recv_l = receiver_radiance(recv);
            // In the last pass, whose links make the file, a link that brings much of its
            // receiver's light takes enough rays that their noise cannot move the receiver by
            // more than `VISIBILITY_NOISE` of its radiance: n rays read a visible fraction to
            // within 0.5/√n (one standard deviation), so n ≥ (share / 2τ)², up to
            // `MAX_RAY_FACTOR` times the default. Chosen before any ray is cast, so the
            // estimate stays unbiased (stopping or going on by what the rays found does not).
            // Earlier passes only judge where to refine, and take the default.
            // A light's link to a receiver as small as the shadow rule goes carries most of
            // its light, and the shadow edges there are what the narrow shadow rule finds
            // and draws: it may take more rays.
            let r_area = root.area / 4f32.powi(recv.level as i32);
            let ray_factor = if self.lights(src) && !self.detail_splittable(recv, r_area) {
                LIGHT_RAY_FACTOR
            } else {
                MAX_RAY_FACTOR
            };
            let need = if last_pass {
                (share / recv_l.max(f32::MIN_POSITIVE) / (2.0 * VISIBILITY_NOISE))
                    .powi(2)
                    .ceil()
                    .min((nv * ray_factor) as f32) as u32
            } else {
                0
            };
            let rays = if need > nv {
                need
            } else if est >= 0.05 * eps_power || share >= FAINT_LINK * recv_l {
                nv
            } else {
                nv.min(2)
            };
            // A previous pass's coefficients, where they took as many rays.
            match cache.get(&(recv, src)) {
                Some(&(at, visible, _)) if rays <= nv => {
                    (prev.k[at..at + link_len].to_vec(), visible)
                }
                _ => self.link_coefficients((recv, rt), (src, st), rays, known),
            }
        };
        // The link from `src` (corners `st`) to `recv` (centre `rc`), its coefficients at
        // `k_start`.
        let make_link = |recv: ElemKey,
                         rc: Vec3,
                         src: Source,
                         st: [Vec3; 3],
                         k_start: u32,
                         visible: f32,
                         bend: f32| {
            // The last pass's links read near clusters by their deeper parts
            // ([`Ctx::reads_deep`]): an earlier pass's solve only judges where to refine, and
            // reading them in every solve cost 15-20% of the scaling scene's bake.
            let deep = last_pass && matches!(src, Source::Cluster(c) if self.reads_deep(c, rc));
            let (aim, share, facing, depth) = match src {
                Source::Cluster(c) => (
                    self.leaving(c, rc),
                    self.cluster_share(trees, c, rc, root.normal, deep),
                    0,
                    0,
                ),
                Source::Elem(sk) => {
                    let (depth, foot) = self.footprint(rc, root.normal, sk, st);
                    let aim = if depth > 0 {
                        foot
                    } else {
                        self.kernel_centre(rc, root.normal, sk, st)
                    };
                    (aim, [0.0; READ_PARTS], self.facing_normal(sk, rc), depth)
                }
            };
            RawLink {
                recv,
                src,
                aim,
                share,
                deep,
                facing,
                depth,
                k_start,
                visible,
                bend,
            }
        };
        // The receivers the narrow shadow rule split ([`Ctx::narrow_shadow_splittable`]).
        let narrow: Mutex<HashSet<ElemKey>> = Default::default();
        // Refines the pairs on `stack` depth-first for at most `REFINE_STEPS` pairs; returns the
        // links, their coefficients and the pairs left.
        let run = |mut stack: Vec<Pair>| {
            let mut links = Vec::new();
            let mut ks = Vec::new();
            let mut steps = 0;
            while let Some((recv, rt, src, st, judged)) = stack.pop() {
                if steps == REFINE_STEPS {
                    stack.push((recv, rt, src, st, judged));
                    break;
                }
                steps += 1;
                let r_area = root.area / 4f32.powi(recv.level as i32);
                if !judged
                    && self.detail_splittable(recv, r_area)
                    && self.memo(recv, |m| &mut m.near_shadow, || self.near_shadow(recv))
                {
                    split_receiver(&mut stack, recv, rt, src, st);
                    continue;
                }
                if !judged
                    && self.self_shade_splittable(recv)
                    && self.memo(
                        recv,
                        |m| &mut m.shade_varies,
                        || self.self_shade_varies(recv),
                    )
                {
                    split_receiver(&mut stack, recv, rt, src, st);
                    continue;
                }
                let rc = (rt[0] + rt[1] + rt[2]) / 3.0;
                let open = |c: u32, stack: &mut Vec<Pair>| {
                    for ch in self.clusters.clusters[c as usize].children.iter().rev() {
                        let s = match *ch {
                            ClusterChild::Cluster(c) => Source::Cluster(c),
                            ClusterChild::Root(x) => Source::Elem(ElemKey::root(x)),
                        };
                        stack.push((recv, rt, s, corners_of(s), true));
                    }
                };
                let est;
                let s_area;
                let s_splittable;
                // The geometric normal's form factors the split rules below computed, which the
                // link's coefficients reuse.
                let mut known = KnownFactors::default();
                let mut link_bend = f32::NAN;
                match src {
                    Source::Elem(sk) => {
                        if sk.root == r {
                            continue; // A planar triangle does not see itself.
                        }
                        if nn == 1 && self.sees_none_of_own(r, self.roots[sk.root as usize].object)
                        {
                            continue;
                        }
                        let sn = self.roots[sk.root as usize].normal;
                        // Two parts of one refined surface may see each other where their coarse
                        // triangles are coplanar or turned apart: the link's form factors, on the
                        // refined surface, judge that.
                        let refined_pair = self.roots[sk.root as usize].object == root.object
                            && !self.surface[r as usize].is_empty();
                        // Receiver entirely behind the source, or source behind every normal.
                        if !refined_pair && rt.iter().all(|&v| sn.dot(v - st[0]) <= self.plane_eps)
                        {
                            continue;
                        }
                        let sees = |n: &Vec3| {
                            st.iter()
                                .any(|&s| rt.iter().any(|&v| n.dot(s - v) > self.plane_eps))
                        };
                        if !refined_pair && !root.normals.iter().any(sees) {
                            continue;
                        }
                        s_area = self.roots[sk.root as usize].area / 4f32.powi(sk.level as i32);
                        s_splittable = self.splittable(sk, s_area);
                        let sc = (st[0] + st[1] + st[2]) / 3.0;
                        let d2 = (sc - rc).length_squared();
                        let l = lum(self.src_radiance(trees, cl, src, rc));
                        let far = !near_pair(d2, r_area, s_area);
                        let f_bound;
                        if far {
                            let w = (sc - rc) / d2.sqrt();
                            let cos_r = root.normals.iter().map(|n| n.dot(w)).fold(0.0, f32::max);
                            let f = disc_estimate(cos_r, (-w).dot(sn), s_area, d2);
                            est = f * l * r_area * std::f32::consts::PI;
                            f_bound = f;
                        } else {
                            // Near pairs: the point form factor at the centre and near each
                            // corner of the receiver bounds both its size and its variation.
                            let (mut fmax, mut fmin) = (0.0f32, f32::MAX);
                            let mut bend = 0.0f32;
                            let inset = inset_corners(rt);
                            let mut buf = [st; 4];
                            let polys: &[[Vec3; 3]] = if refined_pair {
                                self.source_shape(sk, st, true, &mut buf)
                            } else {
                                &buf[..1]
                            };
                            // The points, carried onto the refined surface for a refined pair.
                            let lift = |p: Vec3| {
                                if refined_pair {
                                    self.on_surface(r, p).0
                                } else {
                                    p
                                }
                            };
                            let (lc, li) = (lift(rc), inset.map(lift));
                            for (j, n) in root.normals.iter().enumerate() {
                                let f = |p: Vec3| {
                                    polys
                                        .iter()
                                        .map(|t| point_to_polygon(p, *n, t))
                                        .sum::<f32>()
                                };
                                let centre = f(lc);
                                let at = li.map(f);
                                for v in at.into_iter().chain([centre]) {
                                    fmax = fmax.max(v);
                                    fmin = fmin.min(v);
                                }
                                // Against the plane through the three corner samples: at the
                                // centre, and between each two corners (a source corner touching
                                // the receiver's side peaks there). The bend is the geometry's,
                                // alike for every normal: the geometric one judges it.
                                if j == 0 {
                                    known.corners = Some(at);
                                    bend = (centre - (at[0] + at[1] + at[2]) / 3.0).abs();
                                    for (a, b) in [(0, 1), (1, 2), (2, 0)] {
                                        let mid = f(lift((inset[a] + inset[b]) * 0.5));
                                        bend = bend.max((mid - (at[a] + at[b]) * 0.5).abs());
                                    }
                                }
                            }
                            est = fmax * l * r_area * std::f32::consts::PI;
                            f_bound = fmax;
                            // What a link linear over the receiver cannot follow (the form factor
                            // bends, next to the edge a wall shares with the floor), judged as the
                            // radiance it puts wrong into the receiver against the radiance the
                            // receiver has: every leaf is drawn, so a small one next to an edge
                            // matters as much as a large one.
                            let recv_l = bend_radiance(recv);
                            if bend * l * lum(self.reflectance(recv))
                                > self.bend_tolerance(recv, src) * recv_l
                                && self.bend_splittable(recv, r_area, sk)
                            {
                                split_receiver(&mut stack, recv, rt, src, st);
                                continue;
                            }
                            // The form factor varies over the receiver: only a smaller receiver
                            // resolves that (splitting the source would only share the same error
                            // among four links), unless the receiver is as small as it gets.
                            let var = (fmax - fmin) * l * r_area * std::f32::consts::PI;
                            if var > eps_power * 0.2 {
                                if self.splittable(recv, r_area) {
                                    split_receiver(&mut stack, recv, rt, src, st);
                                    continue;
                                }
                                if s_splittable {
                                    split_source(&mut stack, recv, rt, sk, st);
                                    continue;
                                }
                            }
                        }
                        // The source's radiance varies (a lit wall with a shadow on it): a link
                        // gathers its average, and only a smaller source resolves that. The
                        // estimate is the power the error would carry into every receiver that
                        // makes the same error, not into this element alone: receivers are split
                        // finely near sources (the rule above), and with their own small areas
                        // every piece would pass while the error, the same in each, stayed. The
                        // same holds across coarse triangles: the many small ones of a curved
                        // object all gather the mean of a floor they see from about the same
                        // place, although they mostly see its bright middle under the light
                        // (weighed against one coarse triangle, the sides of the objects in
                        // `gen-samples room` came out 5% too dark; `tests/small_receivers.rs`).
                        // So the error is weighed against the largest cluster of the receiver's
                        // own object around it whose radius is below `cluster_opening` times the
                        // larger of the source's distance and radius (the receivers that see the
                        // source from about the same place, as the opening criterion judges a
                        // cluster of sources), or against the coarse triangle if that is larger.
                        // A source is split as deep as its tree goes (below `max_level` where a
                        // shadow's edge crosses it: the floor in front of a block), or the dark
                        // and the lit sides of the edge reach a receiver next to it as one mean.
                        // A receiver darker than the scene's mean is judged against a threshold
                        // lowered with its radiance (see `DIM_RECEIVER_FLOOR`).
                        if self.detail_splittable(sk, s_area) {
                            let spread = self.src_spread(trees, spreads, sk);
                            let s_radius =
                                st.iter().map(|v| (*v - sc).length()).fold(0.0, f32::max);
                            let reach = self.params.cluster_opening * d2.sqrt().max(s_radius);
                            let sharing = neighbourhood
                                .iter()
                                .find(|(radius, _)| *radius < reach)
                                .map_or(root.area, |&(_, area)| area.max(root.area));
                            let svar = f_bound * spread * sharing * std::f32::consts::PI;
                            let dim = (receiver_radiance(recv)
                                / mean_radiance.max(f32::MIN_POSITIVE))
                            .clamp(DIM_RECEIVER_FLOOR, 1.0);
                            if svar > eps_power * dim {
                                split_source(&mut stack, recv, rt, sk, st);
                                continue;
                            }
                        }
                    }
                    Source::Cluster(c) => {
                        if nn == 1
                            && self.cluster_object[c as usize]
                                .is_some_and(|o| self.sees_none_of_own(r, o as usize))
                        {
                            continue;
                        }
                        let cluster = &self.clusters.clusters[c as usize];
                        if self.clusters.holds(c, r)
                            || rt.iter().any(|&v| cluster.contains_point(v))
                        {
                            open(c, &mut stack);
                            continue;
                        }
                        let r_radius = rt.iter().map(|v| (*v - rc).length()).fold(0.0, f32::max);
                        if cluster.faces_away_from(rc, r_radius) {
                            continue;
                        }
                        let corners = cluster.corners();
                        let sees = |n: &Vec3| {
                            corners
                                .iter()
                                .any(|&s| rt.iter().any(|&v| n.dot(s - v) > self.plane_eps))
                        };
                        if !root.normals.iter().any(sees) {
                            continue;
                        }
                        s_area = cluster.area;
                        s_splittable = true;
                        let d = cluster.centre - rc;
                        let d2 = d.length_squared().max(1e-20);
                        let dist = d2.sqrt();
                        let w = d / dist;
                        if cluster.radius() >= dist * self.params.cluster_opening
                            || self.mixes_emitters[c as usize]
                        {
                            open(c, &mut stack);
                            continue;
                        }
                        let proj = self.clusters.projected_area(c, -w);
                        let f = proj / (std::f32::consts::PI * d2 + proj);
                        let l = lum(self.src_radiance(trees, cl, src, rc));
                        est = f * l * r_area * std::f32::consts::PI;
                        // As for near elements below: split a receiver over which the cluster's
                        // form factor bends more than a linear link follows.
                        if self.splittable(recv, r_area) {
                            // With the geometric normal: the bend is the geometry's, judged in
                            // the previous pass where that made this link.
                            let bend = match cache.get(&(recv, src)) {
                                Some(&(_, _, bend)) if !bend.is_nan() => bend,
                                _ => {
                                    let (centre, at) =
                                        self.cluster_factors_over(c, recv, rt, root.normal);
                                    known = KnownFactors {
                                        centre: Some(centre),
                                        corners: Some(at),
                                    };
                                    (centre - (at[0] + at[1] + at[2]) / 3.0).abs()
                                }
                            };
                            link_bend = bend;
                            let recv_l = bend_radiance(recv);
                            if bend * l * lum(self.reflectance(recv))
                                > self.bend_tolerance(recv, src) * recv_l
                            {
                                split_receiver(&mut stack, recv, rt, src, st);
                                continue;
                            }
                        }
                    }
                }
                if est > eps_power {
                    let r_split = self.splittable(recv, r_area);
                    let split_recv = r_split && (r_area >= s_area || !s_splittable);

                    if split_recv {
                        split_receiver(&mut stack, recv, rt, src, st);
                        continue;
                    }
                    if s_splittable {
                        match src {
                            Source::Cluster(c) => open(c, &mut stack),
                            Source::Elem(sk) => {
                                split_source(&mut stack, recv, rt, sk, st);
                            }
                        }
                        continue;
                    }
                }
                let k_start = ks.len() as u32;
                let share = est / (r_area * std::f32::consts::PI) * lum(self.reflectance(recv));
                let (k, visible) = coefficients((recv, rt), (src, st), est, share, known);
                if k.iter().all(|&v| v <= 0.0) {
                    continue;
                }
                // Part of the source hidden from part of the receiver: a shadow's edge crosses the
                // receiver (under a block standing on the floor, or a face in the block's shadow),
                // and the link spreads its light evenly over both sides. Split the receiver while
                // the light put on the wrong side is a visible fraction of what the receiver
                // gets. Judged against the light this link brings as well as the receiver's own
                // radiance, so that the first pass, before any light has arrived, resolves the
                // shadows the emitters cast.
                if visible > 0.0
                    && visible < 1.0
                    && !self.detail_splittable(recv, r_area)
                    && self.lights(src)
                    && self.narrow_shadow_splittable(recv, r_area, rt, st)
                {
                    narrow
                        .lock()
                        .unwrap_or_else(|e| e.into_inner())
                        .insert(recv);
                    split_receiver(&mut stack, recv, rt, src, st);
                    continue;
                }
                if visible > 0.0 && visible < 1.0 && self.detail_splittable(recv, r_area) {
                    let gathered = lum(self.reflectance(recv))
                        * lum(self.src_radiance(trees, cl, src, rc))
                        * (k[0] + k[nn] + k[2 * nn])
                        / 3.0;
                    let wrong = gathered * (1.0 - visible).min(visible) / visible;
                    let recv_l = receiver_radiance(recv);
                    if wrong > SHADOW_TOLERANCE * recv_l.max(gathered) {
                        split_receiver(&mut stack, recv, rt, src, st);
                        continue;
                    }
                }
                ks.extend(k);
                links.push(make_link(recv, rc, src, st, k_start, visible, link_bend));
            }
            (links, ks, stack)
        };
        let (links, ks) = refine_in_parallel(&run, stack);
        let narrow = narrow.into_inner().unwrap_or_else(|e| e.into_inner());
        if narrow.is_empty() {
            return (links, ks);
        }
        // Every other link of a receiver the narrow shadow rule split goes down with the
        // light's, to the same leaves: the links of one leaf sum to what it sees only at one
        // resolution. In a closed furnace the walls' links, split beside an object resting on
        // the floor, saw the object hide them leaf by leaf, while the object's own link, on
        // the larger receiver, spread its share linearly, and the leaves at the point of
        // contact read -13% to +10%.
        // So does a link to a near source (the object casting the shadow) on a larger
        // receiver above one of them: near the point of contact its form factor is far from
        // linear over that receiver.
        let mut above: HashSet<ElemKey> = HashSet::new();
        for k in &narrow {
            let mut k = k.parent();
            while let Some(x) = k {
                if !above.insert(x) {
                    break;
                }
                k = x.parent();
            }
        }
        // Graded along a narrow shadow's edge: the elements beside a receiver the rule split
        // exist at its level, their links taken down with it, so that the dark side of the
        // edge is as fine as the lit side. Otherwise the leaves just inside the umbra, whose
        // light link every ray found hidden and which no rule splits, stayed two or three levels
        // larger than the split ones beside them, and the field drawn along the edge followed
        // their sides: a serrated outline, and the lit leaves' corners pulled dark at the
        // T-vertices on those sides (BENCHMARKS.md, seventeenth and eighteenth rounds).
        let mut graded: HashSet<ElemKey> = HashSet::new();
        for k in &narrow {
            for beside in k.edge_neighbours() {
                let mut x = beside.parent();
                while let Some(a) = x {
                    if !graded.insert(a) {
                        break;
                    }
                    x = a.parent();
                }
            }
        }
        let near = |recv: ElemKey, src: Source| match src {
            Source::Elem(sk) => {
                let (rt, st) = (self.elem_corners(recv), self.elem_corners(sk));
                let d = (st[0] + st[1] + st[2] - rt[0] - rt[1] - rt[2]) / 3.0;
                let r_area = root.area / 4f32.powi(recv.level as i32);
                let s_area = self.roots[sk.root as usize].area / 4f32.powi(sk.level as i32);
                near_pair(d.length_squared(), r_area, s_area)
            }
            Source::Cluster(_) => false,
        };
        let goes_down = |recv: ElemKey, src: Source| {
            narrow.contains(&recv)
                || graded.contains(&recv)
                || above.contains(&recv) && near(recv, src)
        };
        let expand = |l: &RawLink| -> Option<Vec<(RawLink, Vec<f32>)>> {
            if !goes_down(l.recv, l.src) {
                return None;
            }
            let at = l.k_start as usize;
            let k = &ks[at..at + link_len];
            let lt = self.elem_corners(l.recv);
            let share = lum(self.reflectance(l.recv))
                * lum(self.src_radiance(trees, cl, l.src, (lt[0] + lt[1] + lt[2]) / 3.0))
                * (k[0] + k[nn] + k[2 * nn])
                / 3.0;
            let st = corners_of(l.src);
            let mut out = Vec::new();
            let mut stack = vec![(l.recv, lt)];
            while let Some((recv, rt)) = stack.pop() {
                if goes_down(recv, l.src) {
                    let children = split(rt);
                    for c in (0..4).rev() {
                        stack.push((recv.child(c), children[c as usize]));
                    }
                    continue;
                }
                let (k, visible) = coefficients(
                    (recv, rt),
                    (l.src, st),
                    f32::INFINITY,
                    share,
                    KnownFactors::default(),
                );
                if k.iter().all(|&v| v <= 0.0) {
                    continue;
                }
                let rc = (rt[0] + rt[1] + rt[2]) / 3.0;
                out.push((make_link(recv, rc, l.src, st, 0, visible, f32::NAN), k));
            }
            Some(out)
        };
        // Per link: the links it became, where it went down.
        type Expanded = Option<Vec<(RawLink, Vec<f32>)>>;
        let expanded: Vec<Expanded> = links.par_iter().map(expand).collect();
        let mut out_links = Vec::with_capacity(links.len());
        let mut out_ks = Vec::with_capacity(ks.len());
        for (l, e) in links.into_iter().zip(expanded) {
            match e {
                None => {
                    let at = l.k_start as usize;
                    let k_start = out_ks.len() as u32;
                    out_ks.extend_from_slice(&ks[at..at + link_len]);
                    out_links.push(RawLink { k_start, ..l });
                }
                Some(v) => {
                    for (mut nl, k) in v {
                        nl.k_start = out_ks.len() as u32;
                        out_ks.extend(k);
                        out_links.push(nl);
                    }
                }
            }
        }
        (out_links, out_ks)
    }

    /// Form factor times visibility from receiver `recv` to `src`, per receiver normal. A pair
    /// whose form factor is nowhere positive (a cluster whose box reaches above the receiver's
    /// plane while its triangles lie below it) is dropped by the caller, and casts no rays.
    ///
    /// Returns the coefficients (`CORNERS × nn`, corner-major) and the visible fraction. For a
    /// receiver on a refined surface (its points carried onto it, [`Ctx::on_surface`])
    /// `CORNERS` more follow: the same for that surface's own normal at each point, what the
    /// receiver's normals are filled against ([`Tree::closure`]).
    fn link_coefficients(
        &self,
        (recv, rt): (ElemKey, [Vec3; 3]),
        (src, st): (Source, [Vec3; 3]),
        nv: u32,
        known: KnownFactors,
    ) -> (Vec<f32>, f32) {
        let root = &self.roots[recv.root as usize];
        let nn = root.normals.len();
        let rc = (rt[0] + rt[1] + rt[2]) / 3.0;
        let r_size = (rt[1] - rt[0]).length().max((rt[2] - rt[0]).length());
        let src_id = match src {
            Source::Cluster(c) => 0x8000_0000_0000_0000 | u64::from(c),
            Source::Elem(k) => k.id(),
        };
        let mut k = vec![0.0f32; nn];
        let lifted = !self.surface[recv.root as usize].is_empty();
        let mut closure = 0.0f32;
        let mut vis = vec![1.0f32; nn + usize::from(lifted)];
        // Per slot of `vis`, the visible fraction at each corner (`[j * CORNERS + c]`).
        let mut at_corner = vec![1.0f32; vis.len() * CORNERS];
        match src {
            Source::Elem(sk) => {
                let sc = (st[0] + st[1] + st[2]) / 3.0;
                let s_size = (st[1] - st[0]).length().max((st[2] - st[0]).length());
                // Far pairs: the centroid suffices; near pairs: four stratified points.
                let dist = (sc - rc).length();
                let pts: Vec<Vec3> = if dist > 3.0 * (r_size + s_size) {
                    vec![rc]
                } else if dist > r_size + s_size {
                    split(rt)
                        .iter()
                        .map(|t| (t[0] + t[1] + t[2]) / 3.0)
                        .collect()
                } else {
                    stratified_points(rt, 2)
                };
                // Points and source on the refined surfaces where the objects have them.
                let mut buf = [st; 4];
                let polys = self.source_shape(sk, st, pts.len() > 1, &mut buf);
                for p in &pts {
                    let (p, pn) = self.on_surface(recv.root, *p);
                    for (kj, n) in k.iter_mut().zip(&root.normals) {
                        *kj += polys
                            .iter()
                            .map(|t| point_to_polygon(p, *n, t))
                            .sum::<f32>();
                    }
                    if lifted {
                        closure += polys
                            .iter()
                            .map(|t| point_to_polygon(p, pn, t))
                            .sum::<f32>();
                    }
                }
                let inv = 1.0 / pts.len() as f32;
                k.iter_mut().for_each(|v| *v *= inv);
                closure *= inv;
                let at_corners = known.corners.unwrap_or_else(|| {
                    inset_corners(rt).map(|p| point_to_polygon(p, root.normal, &st))
                });
                k = linear_over_receiver(&k, at_corners);
                if lifted {
                    k.extend(linear_over_receiver(&[closure], at_corners));
                }
                if k.iter().all(|&v| v <= 0.0) {
                    return (k, 0.0);
                }
                let sn = self.roots[sk.root as usize].normal;
                let (lo, hi) = (st[0].min(st[1]).min(st[2]), st[0].max(st[1]).max(st[2]));
                if self.certainly_clear(recv, rt, (lo, hi), Some((sn, st[0]))) {
                    return (k, 1.0);
                }
                self.cast_visibility(
                    (recv, rt),
                    src_id,
                    r_size + s_size,
                    nv,
                    (&mut vis, &mut at_corner),
                    |i, rng| (sk.root, jittered_point(st, i, nv, rng)),
                );
            }
            Source::Cluster(c) => {
                let c_size = 2.0 * self.clusters.clusters[c as usize].radius();
                let (centre, at_corners) = match (known.centre, known.corners) {
                    (Some(centre), Some(at)) => (centre, at),
                    _ => self.cluster_factors_over(c, recv, rt, root.normal),
                };
                k[0] = centre;
                let (p, pn) = self.on_surface(recv.root, rc);
                self.cluster_form_factors(c, p, &root.normals[1..], &mut k[1..]);
                k = linear_over_receiver(&k, at_corners);
                if lifted {
                    let mut f = [0.0f32];
                    self.cluster_form_factors(c, p, &[pn], &mut f);
                    k.extend(linear_over_receiver(&f, at_corners));
                }
                if k.iter().all(|&v| v <= 0.0) {
                    return (k, 0.0);
                }
                let cluster = &self.clusters.clusters[c as usize];
                if self.certainly_clear(recv, rt, (cluster.lo, cluster.hi), None) {
                    return (k, 1.0);
                }
                self.cast_visibility(
                    (recv, rt),
                    src_id,
                    r_size + c_size,
                    nv,
                    (&mut vis, &mut at_corner),
                    |i, rng| {
                        // Stratified over the cluster's area as the receiver point is over
                        // the receiver.
                        let u = (i as f32 + rng.next_f32()) / nv as f32;
                        let t = self.clusters.pick(c, u.min(1.0 - f32::EPSILON));
                        (t, jittered_point(self.roots[t as usize].corners, 0, 1, rng))
                    },
                );
            }
        };
        // The visible fraction is linear over the receiver, as the form factor is: a soft
        // shadow's gradient across a link's receiver reaches its leaves, where one fraction
        // for the whole receiver left a step at every receiver's edge (the Cornell box's floor
        // beside the short block, blotchy where the path tracer's penumbra is smooth).
        for (c, row) in k.chunks_mut(nn).take(CORNERS).enumerate() {
            for (j, v) in row.iter_mut().enumerate() {
                *v *= at_corner[j * CORNERS + c];
            }
        }
        if lifted {
            for c in 0..CORNERS {
                k[CORNERS * nn + c] *= at_corner[nn * CORNERS + c];
            }
        }
        (k, vis[0])
    }

    /// Unoccluded form factor from a point `p` with normal `n` to the triangles of cluster
    /// `c`. A cluster small against its distance is one disc of its projected area seen from
    /// its centre; a nearer one is the sum of its children, down to triangles, which are
    /// exact. The link oracle lets a cluster stand for its triangles while its radius is below
    /// `cluster_opening` (one half) times its distance from the receiver's centre; a lone disc
    /// there is 10-20% off, and more at the receiver's corners, which can lie closer (in a
    /// closed furnace, leaves near a cube's corners summed to 8% less or more than the
    /// whole hemisphere, issue 20). The link stays one link; only its coefficient is summed
    /// finer. Adds the form factor for each of `normals` to `out`.
    fn cluster_form_factors(&self, c: u32, p: Vec3, normals: &[Vec3], out: &mut [f32]) {
        if normals.is_empty() {
            return;
        }
        let cluster = &self.clusters.clusters[c as usize];
        let d = cluster.centre - p;
        let d2 = d.length_squared().max(1e-20);
        let dist = d2.sqrt();
        if cluster.radius() < dist * CLUSTER_DISC_OPENING {
            let w = d / dist;
            let proj = self.clusters.projected_area(c, -w);
            for (o, n) in out.iter_mut().zip(normals) {
                *o += disc_factor(*n, w, proj, d2);
            }
            return;
        }
        for ch in cluster.children {
            match ch {
                ClusterChild::Cluster(x) => self.cluster_form_factors(x, p, normals, out),
                ClusterChild::Root(x) => {
                    let tri = &self.shape[x as usize];
                    for (o, n) in out.iter_mut().zip(normals) {
                        *o += point_to_polygon(p, *n, tri);
                    }
                }
            }
        }
    }

    /// Whether nothing can hide any part of a source in the box `src_box` (with its plane, when
    /// one) from receiver `recv` (corners `rt`): its root is unobstructed, or the shaft between
    /// them is empty ([`Occluders::shaft_clear`]).
    fn certainly_clear(
        &self,
        recv: ElemKey,
        rt: [Vec3; 3],
        (lo, hi): (Vec3, Vec3),
        src_plane: Option<(Vec3, Vec3)>,
    ) -> bool {
        let r = recv.root as usize;
        self.unobstructed[r]
            || self
                .occ
                .shaft_clear(rt, self.roots[r].normal, lo, hi, src_plane)
    }

    /// [`Ctx::cluster_form_factors`] with normal `n` at the centre of receiver triangle `rt` and
    /// at its inset corners, in one walk of the cluster tree: the centre's, and the corners'.
    /// Each point opens the clusters it would open alone and sums in the same order, so the
    /// four values are those of four walks (but for the disc's area, which the points share).
    fn cluster_factors_over(
        &self,
        c: u32,
        recv: ElemKey,
        rt: [Vec3; 3],
        n: Vec3,
    ) -> (f32, [f32; CORNERS]) {
        let [a, b, d] = inset_corners(rt);
        let pts = [(rt[0] + rt[1] + rt[2]) / 3.0, a, b, d].map(|p| self.on_surface(recv.root, p).0);
        let mut out = [0.0f32; 4];
        self.cluster_factors_at(c, &pts, n, 0b1111, &mut out);
        (out[0], [out[1], out[2], out[3]])
    }

    /// Adds to `out[i]` the form factor from point `pts[i]` (normal `n`) to cluster `c`, for
    /// every point `i` whose bit is set in `active`.
    fn cluster_factors_at(&self, c: u32, pts: &[Vec3; 4], n: Vec3, active: u8, out: &mut [f32; 4]) {
        let cluster = &self.clusters.clusters[c as usize];
        let mut open = 0u8;
        // The disc's area seen from the first point that takes it, for all: the points are a
        // receiver's, within a fifth of the distance of each other (a sixteenth of the bake's
        // time went to computing it four times).
        let mut proj = None;
        for (i, p) in pts.iter().enumerate() {
            if active & (1 << i) == 0 {
                continue;
            }
            let d = cluster.centre - *p;
            let d2 = d.length_squared().max(1e-20);
            let dist = d2.sqrt();
            if cluster.radius() < dist * CLUSTER_DISC_OPENING {
                let w = d / dist;
                let area = *proj.get_or_insert_with(|| self.clusters.projected_area(c, -w));
                out[i] += disc_factor(n, w, area, d2);
            } else {
                open |= 1 << i;
            }
        }
        if open == 0 {
            return;
        }
        for ch in cluster.children {
            match ch {
                ClusterChild::Cluster(x) => self.cluster_factors_at(x, pts, n, open, out),
                ClusterChild::Root(x) => {
                    let tri = &self.shape[x as usize];
                    for (i, p) in pts.iter().enumerate() {
                        if open & (1 << i) != 0 {
                            out[i] += point_to_polygon(*p, n, tri);
                        }
                    }
                }
            }
        }
    }

    /// Casts the `nv` visibility rays of the link from receiver `recv` (corners `rt`) to a source
    /// and puts into `vis` the fraction each receiver normal sees clear, and after them, on a
    /// refined surface, that of the surface's own normal ([`visible_fractions`]). Ray `i` runs
    /// from a jittered point of the receiver's stratum `i` to `source(i, rng)`, a root and a
    /// point on it, both carried onto their refined surfaces; each normal weighs it by the
    /// form-factor kernel (`size`: the two elements' sizes together) where light passes from
    /// the source point across that normal's plane, and does not count it where it cannot. A
    /// ray that no normal counts is not cast.
    fn cast_visibility(
        &self,
        (recv, rt): (ElemKey, [Vec3; 3]),
        src_id: u64,
        size: f32,
        nv: u32,
        (vis, at_corner): (&mut [f32], &mut [f32]),
        source: impl Fn(u32, &mut Rng) -> (u32, Vec3),
    ) {
        let normals = &self.roots[recv.root as usize].normals;
        visible_fractions(nv, vis, at_corner, |i, w| {
            let mut rng = Rng::new(recv.id(), src_id, u64::from(i));
            let p = jittered_point(rt, i, nv, &mut rng);
            let at = barycentric_of(rt, p);
            let (t, q) = source(i, &mut rng);
            let (a, na) = self.on_surface(recv.root, p);
            let (b, nb) = self.on_surface(t, q);
            let d = b - a;
            if nb.dot(-d) <= self.plane_eps {
                return None;
            }
            // The refined surface's own normal follows the receiver's normals where `w` has
            // a slot for it.
            let own = [na];
            let mut any = false;
            for (x, n) in w.iter_mut().zip(normals.iter().chain(&own)) {
                *x = (n.dot(d) > self.plane_eps).then(|| kernel(a, *n, b, nb, size));
                any |= x.is_some();
            }
            any.then(|| (self.occ.segment_clear_between(a, na, b, nb), at))
        });
    }

    /// Whether the parts of element `k` of an object with a refined surface are shut in by
    /// their surroundings unevenly: at its centre and inset corners, carried onto the refined
    /// surface, the share of [`SELF_SHADE_RINGS`] × [`SELF_SHADE_AZIMUTHS`] cosine-weighted
    /// directions around the surface's normal that meet nothing within
    /// [`NEAR_SHADOW_REACH`] element radii differs between two points by more than
    /// [`SELF_SHADE_TOLERANCE`].
    ///
    /// A fold, a crease, the rim of an eye socket, the junction of a spout with its body: one
    /// side of the element looks out into the room, the other into the object itself. No link
    /// sees that (a link's visibility is at most linear over its receiver, and
    /// [`Ctx::near_shadow`] leaves the object's own surface out), and the element's area
    /// average, drawn at its corners, is too bright at the bottom of the fold and too dark at
    /// its rim. Judged here by the geometry alone, and so the same in every pass.
    fn self_shade_varies(&self, k: ElemKey) -> bool {
        let rt = self.elem_corners(k);
        let rc = (rt[0] + rt[1] + rt[2]) / 3.0;
        let radius = rt.iter().map(|v| (*v - rc).length()).fold(0.0, f32::max);
        let reach = NEAR_SHADOW_REACH * radius;
        let [c0, c1, c2] = inset_corners(rt);
        let (mut lo, mut hi) = (u32::MAX, 0u32);
        for p in [rc, c0, c1, c2] {
            let (q, n) = self.on_surface(k.root, p);
            let open = cosine_strata(n, SELF_SHADE_RINGS, SELF_SHADE_AZIMUTHS, 0.0)
                .filter(|&d| self.occ.first_hit_from(q, n, d, reach, |_| false).is_none())
                .count() as u32;
            lo = lo.min(open);
            hi = hi.max(open);
        }
        (hi - lo) as f32 > SELF_SHADE_TOLERANCE * (SELF_SHADE_RINGS * SELF_SHADE_AZIMUTHS) as f32
    }

    /// Whether an occluder close to receiver `k` casts a shadow edge across it: from the
    /// receiver's centre and inset corners, rays along fixed cosine-stratified directions of
    /// its hemisphere; in a direction where some ray meets a surface within
    /// [`NEAR_SHADOW_REACH`] times the receiver's radius, each point checks that it sees what
    /// every other point sees along it (the end of that point's ray). A wall or a room corner
    /// next to the receiver is seen alike from all its points; an object standing on it, or
    /// the overhang of a fold, hides from one point what another sees. A link's visibility is
    /// at most linear over its receiver (it was one number when this rule was made), so near
    /// such an occluder each link spreads its shadow's edge over the receiver and the errors of
    /// all of them add up with one sign (in a closed furnace, floor leaves next to a resting
    /// object summed form factors to 1.12).
    fn near_shadow(&self, k: ElemKey) -> bool {
        // Nothing but the scene's outer boundary in front: nothing there hides one source
        // from part of the receiver (the convex side of an object in a room).
        if self.unobstructed[k.root as usize] {
            return false;
        }
        let rt = self.elem_corners(k);
        let rc = (rt[0] + rt[1] + rt[2]) / 3.0;
        let radius = rt.iter().map(|v| (*v - rc).length()).fold(0.0, f32::max);
        let reach = NEAR_SHADOW_REACH * radius;
        let n = self.roots[k.root as usize].normal;
        let [c0, c1, c2] = inset_corners(rt);
        let pts = [rc, c0, c1, c2];
        // A multiresolution object's own coarse triangles are not the surface drawn: its folds
        // are shallower once refined, and refining against the coarse ones made the eye
        // sockets of suzanne darker than a path tracer of the refined surface shows them.
        let object = self.roots[k.root as usize].object;
        let own = self.scene.objects[object].multires;
        let ignore = |t: usize| own && self.owner_object(t) == object;
        for d in cosine_strata(n, 3, 4, 0.0) {
            let hits = pts.map(|p| self.occ.first_hit_from(p, n, d, reach, ignore));
            if hits.iter().all(Option::is_none) {
                continue;
            }
            // What each point sees along `d`, stopped short of the surface it meets.
            let ends: Vec<Vec3> = pts
                .iter()
                .zip(&hits)
                .map(|(&p, h)| p + d * (h.unwrap_or(reach) * 0.95))
                .collect();
            for (i, &p) in pts.iter().enumerate() {
                for (j, &e) in ends.iter().enumerate() {
                    if i != j && !self.occ.segment_clear_between_but(p, n, e, d, ignore) {
                        return true;
                    }
                }
            }
        }
        false
    }

    /// `find()`, the value of a rule judged by the geometry alone for element `k`, found once:
    /// `pick` chooses the rule's map in its root's [`GeometryMemo`]. The lock is not held while
    /// `find` runs; parts of the refinement running in parallel may both find a value, and
    /// find the same one.
    fn memo<T: Copy>(
        &self,
        k: ElemKey,
        pick: impl Fn(&mut GeometryMemo) -> &mut HashMap<ElemKey, T>,
        find: impl FnOnce() -> T,
    ) -> T {
        let memo = &self.memos[k.root as usize];
        if let Some(&v) = pick(&mut memo.lock().unwrap_or_else(|e| e.into_inner())).get(&k) {
            return v;
        }
        let v = find();
        pick(&mut memo.lock().unwrap_or_else(|e| e.into_inner())).insert(k, v);
        v
    }

    /// Fraction of element `k` that is open, from four stratified points: a point is shut
    /// in when the first surface met along its normal and along four directions 30 degrees
    /// above its plane is, every time, the back of a triangle (a floor point under a block,
    /// a ceiling point just above a one-sided lamp). The area average the solver stores
    /// counts such a part as dark, and rightly so (it is part of the element), but it
    /// can neither receive nor send light.
    fn open_fraction(&self, k: ElemKey) -> f32 {
        let tri = self.elem_corners(k);
        let open_at = |level: u32| {
            let pts = stratified_points(tri, level);
            let shut = pts.iter().filter(|&&p| self.shut_at(k.root, p)).count();
            1.0 - shut as f32 / pts.len() as f32
        };
        // Four points; sixteen where the four disagree (the edge of a block's footprint): the
        // value drawn for a leaf partly shut in is its open part's ([`Ctx::shown`]), so a
        // coarse fraction shows.
        let o = open_at(1);
        if o > 0.0 && o < 1.0 {
            open_at(2)
        } else {
            o
        }
    }

    /// Whether point `p` of root `r` is shut in ([`Ctx::open_fraction`]): the first surface
    /// met along the root's normal and along four directions 30 degrees above its plane is,
    /// every time, the back of a triangle.
    fn shut_at(&self, r: u32, p: Vec3) -> bool {
        let n = self.roots[r as usize].normal;
        let a = if n.x.abs() < 0.9 { Vec3::X } else { Vec3::Y };
        let t = n.cross(a).normalize();
        let b = n.cross(t);
        let (p, _) = self.on_surface(r, p);
        [
            n,
            (n + t * 1.7).normalize(),
            (n - t * 1.7).normalize(),
            (n + b * 1.7).normalize(),
            (n - b * 1.7).normalize(),
        ]
        .iter()
        .all(|&d| self.occ.first_hit_is_back(p, d))
    }

    /// Whether every ray from root `r`'s open surface meets the front of a surface: the rays
    /// of [`ENCLOSURE_RINGS`] × [`ENCLOSURE_AZIMUTHS`] cosine-weighted directions from each of
    /// its four stratified points that is not shut in ([`Ctx::shut_at`]), turned from point to
    /// point. In a closed room a root that sees no back (of a one-sided lamp, through a gap in
    /// an object) is closed; one that sees out of an open scene is not, and the first ray that
    /// shows it ends the search. A root with nothing but the scene's outer boundary in front
    /// of it (the convex side of an object, `unobstructed`) is closed where the boundary is.
    fn root_closed(&self, r: u32) -> bool {
        let corners = self.roots[r as usize].corners;
        if self.unobstructed[r as usize] {
            return *self.boundary_closed.get_or_init(|| self.boundary_closed());
        }
        stratified_points(corners, 1)
            .iter()
            .enumerate()
            .all(|(s, &p)| self.shut_at(r, p) || self.point_closed(r, p, s))
    }

    /// Whether the scene's outer boundary closes it: the rays of [`Ctx::root_closed`] from the
    /// centroids of up to [`BOUNDARY_PROBES`] roots with nothing but the boundary in front of
    /// them, spread over the scene's roots, all meet the front of a surface (which can only be
    /// the boundary's). A room whose walls close it sees no sky from any point inside.
    fn boundary_closed(&self) -> bool {
        let inside: Vec<u32> = (0..self.roots.len() as u32)
            .filter(|&r| self.unobstructed[r as usize])
            .collect();
        let step = inside.len().div_ceil(BOUNDARY_PROBES).max(1);
        inside.iter().step_by(step).enumerate().all(|(s, &r)| {
            let c = self.roots[r as usize].corners;
            self.point_closed(r, (c[0] + c[1] + c[2]) / 3.0, s)
        })
    }

    /// Whether every ray of [`Ctx::root_closed`]'s directions from point `p` of root `r` (the
    /// `s`-th of its set) meets the front of a surface.
    fn point_closed(&self, r: u32, p: Vec3, s: usize) -> bool {
        let (a, n) = self.on_surface(r, p);
        // Turned by the golden ratio's fraction of a stratum from point to point: never a
        // simple fraction, so that no set of rays lines up with a grid of faces and meets
        // them along their shared edges.
        let turn = (s as f32 + 0.5) * 0.618_034;
        cosine_strata(n, ENCLOSURE_RINGS, ENCLOSURE_AZIMUTHS, turn)
            .all(|d| self.occ.meets_front_from(a, n, d))
    }

    /// The part of leaf `k`'s hemisphere that meets the front of a surface, weighed by the
    /// cosine, where it is known exactly: what the form factors of its links must sum to.
    /// `open` is its open fraction ([`Ctx::open_fraction`]). In a closed root
    /// ([`Ctx::root_closed`]) an open leaf's is one. A leaf partly shut in takes the sixteen
    /// points its open fraction was judged by: where the rays from every open one meet fronts,
    /// its part is its open fraction exactly, the shut ones meeting nothing. Elsewhere (a leaf
    /// that sees out of an open scene, or the back of a one-sided surface) it is not known
    /// well enough from rays (a few per cent off, where the links' form factors are analytic),
    /// and is negative.
    fn enclosure(&self, k: ElemKey, open: f32) -> f32 {
        if open <= 0.0 {
            return 0.0;
        }
        if open >= 1.0 {
            let root = ElemKey::root(k.root);
            let closed = self.memo(root, |m| &mut m.closed, || self.root_closed(k.root));
            return if closed { 1.0 } else { -1.0 };
        }
        let all_open_closed = stratified_points(self.elem_corners(k), 2)
            .iter()
            .enumerate()
            .all(|(s, &p)| self.shut_at(k.root, p) || self.point_closed(k.root, p, s));
        if all_open_closed {
            open
        } else {
            -1.0
        }
    }

    /// Builds root `r`'s tree from the keys that must exist.
    fn build_tree(&self, r: u32, mut keys: Vec<ElemKey>, direct: &[(ElemKey, Vec<Vec3>)]) -> Tree {
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
        let n = all.len();
        let mut tree = Tree {
            child: vec![u32::MAX; n],
            area: all
                .iter()
                .map(|k| self.roots[r as usize].area / 4f32.powi(k.level as i32))
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

    /// [`Tree::closure`] and [`Tree::self_view`] of tree `t` (root `r`), from its links.
    fn closure(&self, r: u32, t: &Tree) -> (Vec<f32>, Vec<f32>) {
        if self.surface[r as usize].is_empty() {
            return (Vec::new(), Vec::new());
        }
        let block = CORNERS * self.nn(r);
        let n = t.keys.len();
        let mut f = vec![0.0f32; n * CORNERS];
        for link in &t.links {
            let at = link.k_start as usize + block;
            for c in 0..CORNERS {
                f[link.recv as usize * CORNERS + c] += t.k[at + c];
            }
        }
        push_linear(t, &mut f, 1);
        let mut closure: Vec<f32> = (0..n)
            .map(|i| (f[i * CORNERS] + f[i * CORNERS + 1] + f[i * CORNERS + 2]) / 3.0)
            .collect();
        // A refined patch sees itself where it curves inwards, which no link carries (the
        // coarse triangle under it is flat): from each leaf's centre, the form factors of its
        // own root's refined triangles, for its normals and the surface's.
        let nn = self.nn(r);
        let surf = &self.surface[r as usize];
        let root = &self.roots[r as usize];
        let mut view = vec![0.0f32; n * nn];
        for i in (0..n).filter(|&i| t.child[i] == u32::MAX) {
            let c = self.elem_corners(t.keys[i]);
            let (p, pn) = self.on_surface(r, (c[0] + c[1] + c[2]) / 3.0);
            let f = |n: Vec3| {
                surf.iter()
                    .map(|tri| point_to_polygon(p, n, tri))
                    .sum::<f32>()
            };
            for (j, n) in root.normals.iter().enumerate() {
                view[i * nn + j] = f(*n);
            }
            closure[i] += f(pn);
        }
        (closure, view)
    }

    /// One gather + push-pull for root `r`; returns the new radiance array.
    /// Per node and normal of root `r`'s tree (`out[i * nn + j]`), the sum of the form factors
    /// its links give it, pushed down from every receiver above it and averaged over its
    /// corners ([`push_linear`]): of all its links, and of those from the lights'
    /// ([`Ctx::is_light`]) elements alone. They depend on the links alone, so every iteration
    /// of a solve reads them ([`Ctx::iterate_root`]).
    fn form_factor_sums(&self, r: u32, t: &Tree) -> Vec<[f32; 2]> {
        let nn = self.nn(r);
        let n = t.keys.len();
        let mut ff = vec![0.0f32; n * CORNERS * nn];
        let mut ff_lit = vec![0.0f32; n * CORNERS * nn];
        for link in &t.links {
            let base = link.recv as usize * CORNERS * nn;
            let ks = &t.k[link.k_start as usize..link.k_start as usize + CORNERS * nn];
            for (x, &k) in ks.iter().enumerate() {
                ff[base + x] += k;
            }
            if self.brings_light(link) {
                for (x, &k) in ks.iter().enumerate() {
                    ff_lit[base + x] += k;
                }
            }
        }
        push_linear(t, &mut ff, nn);
        push_linear(t, &mut ff_lit, nn);
        (0..n * nn)
            .map(|x| {
                let (i, j) = (x / nn, x % nn);
                [corner_mean(&ff, i, j, nn), corner_mean(&ff_lit, i, j, nn)]
            })
            .collect()
    }

    /// Whether `link` brings a light's own light: its source is an element of a light
    /// ([`Ctx::is_light`]).
    fn brings_light(&self, link: &Link) -> bool {
        matches!(link.src, SrcIdx::Node { root, .. } if self.is_light(root))
    }

    /// One Jacobi step for root `r`: its nodes' new radiance from what its links gather from
    /// `trees` and `cl`; `sums` are its [`Ctx::form_factor_sums`].
    fn iterate_root(
        &self,
        r: u32,
        trees: &[Tree],
        cl: &[ClusterLight],
        sums: &[[f32; 2]],
    ) -> Vec<Vec3> {
        let t = &trees[r as usize];
        let nn = self.nn(r);
        let n = t.keys.len();
        // Direct light plus gathered radiance at each node's corners (the links are linear
        // over their receivers), and the gathered part alone for the geometric normal.
        // Corner-major per node: `q[(i * CORNERS + c) * nn + j]`. Apart, what comes from the
        // lights, directly or through links from their elements (`lit`), and what the
        // geometric normal gathers from the rest (`g0_rest`): what a closed leaf's sum leaves
        // alone and what it fills or scales. The form factors they were gathered through are
        // in `sums`.
        let mut q = vec![Vec3::ZERO; n * CORNERS * nn];
        for i in 0..n {
            for c in 0..CORNERS {
                let at = (i * CORNERS + c) * nn;
                q[at..at + nn].copy_from_slice(&t.direct[i * nn..(i + 1) * nn]);
            }
        }
        let mut lit = q.clone();
        let mut g0 = vec![Vec3::ZERO; n * CORNERS];
        let mut g0_rest = vec![Vec3::ZERO; n * CORNERS];
        for link in &t.links {
            let ls = match link.src {
                SrcIdx::Cluster(c) => {
                    self.cluster_seen(trees, cl, c, link.aim, &link.share, link.deep)
                }
                SrcIdx::Node { root, node } => self.seen_radiance(
                    root,
                    &trees[root as usize],
                    (node as usize, link.depth),
                    link.aim,
                    link.facing as usize,
                ),
            };
            let base = link.recv as usize * CORNERS * nn;
            let ks = &t.k[link.k_start as usize..link.k_start as usize + CORNERS * nn];
            for (x, &k) in ks.iter().enumerate() {
                q[base + x] += ls * k;
            }
            let from_light = self.brings_light(link);
            if from_light {
                for (x, &k) in ks.iter().enumerate() {
                    lit[base + x] += ls * k;
                }
            }
            for c in 0..CORNERS {
                let g = ls * ks[c * nn];
                g0[link.recv as usize * CORNERS + c] += g;
                if !from_light {
                    g0_rest[link.recv as usize * CORNERS + c] += g;
                }
            }
        }
        push_linear(t, &mut q, nn);
        push_linear(t, &mut lit, nn);
        push_linear(t, &mut g0, 1);
        push_linear(t, &mut g0_rest, 1);
        // What each leaf gathers: the mean of its linear function, the value at its centroid.
        let mut q_leaf = vec![Vec3::ZERO; n * nn];
        for i in 0..n {
            if t.child[i] != u32::MAX {
                continue;
            }
            for j in 0..nn {
                q_leaf[i * nn + j] = corner_mean(&q, i, j, nn);
            }
            // A refined patch gathers its own radiance where it sees itself.
            let closure = t.closure.get(i).copied();
            if closure.is_some() {
                for j in 0..nn {
                    q_leaf[i * nn + j] += t.l[i * nn] * t.self_view[i * nn + j];
                }
            }
            // The form factors of all the leaf's links, and of the lights' alone.
            let ff = |j: usize| sums[i * nn + j][0];
            let ff_lit = |j: usize| sums[i * nn + j][1];
            let f0 = ff(0);
            if f0 <= 0.0 {
                continue;
            }
            let view = |j: usize| t.self_view.get(i * nn + j).copied().unwrap_or(0.0);
            let mean_of = |g: &[Vec3], f: f32| {
                (g[i * CORNERS] + g[i * CORNERS + 1] + g[i * CORNERS + 2]) / 3.0 / f
            };
            let enclosed = t.enclosed[i];
            if enclosed >= 0.0 {
                // A closed leaf: its form factors sum, for every normal, to the part of its
                // hemisphere that meets the front of a surface ([`Ctx::enclosure`]; its open
                // fraction). The lights' links are the most carefully found (analytic form
                // factors, many rays), so they stay as they are; the rest take up the
                // difference. What they lack is filled with the mean radiance the geometric
                // normal gathers from them: a normal turned away from the geometric one sees,
                // below the element's plane, surface that the coarse scene does not have
                // there (on a refined surface, the object's own neighbouring patches). What
                // they have too much (visibility from a few rays, a cluster's area from a
                // bound, linear functions pushed down from coarser receivers, up to 3% and 6%
                // off in a closed furnace) is taken off in proportion. So a closed furnace is
                // exact at every leaf and for every normal (SPEC.md G.1).
                let rest0 = f0 - ff_lit(0);
                let m_rest = if rest0 > 0.0 {
                    mean_of(&g0_rest, rest0)
                } else {
                    mean_of(&g0, f0)
                };
                for j in 0..nn {
                    let at = i * nn + j;
                    let fixed = corner_mean(&lit, i, j, nn);
                    let from_lights = ff_lit(j);
                    let seen = ff(j) - from_lights + view(j);
                    let due = (enclosed - from_lights).max(0.0);
                    let rest = q_leaf[at] - fixed;
                    q_leaf[at] = fixed
                        + if seen > due {
                            rest * (due / seen)
                        } else {
                            rest + m_rest * (due - seen)
                        };
                }
            } else if nn > 1 || closure.is_some() {
                // Elsewhere every form factor a tilted normal lacks against the geometric one
                // is filled with the mean radiance the geometric normal gathers; on a refined
                // surface every normal, the geometric one too, is filled against the surface's
                // own normal at the receiver's points ([`Tree::closure`]).
                let m = mean_of(&g0, f0);
                let (full, first) = match closure {
                    Some(f) => (f, 0),
                    None => (f0, 1),
                };
                for j in first..nn {
                    let missing = (full - ff(j) - view(j)).max(0.0);
                    q_leaf[i * nn + j] += m * missing;
                }
            }
        }
        let q = q_leaf;
        let le = self.roots[r as usize].emission;
        let mut l = vec![Vec3::ZERO; n * nn];
        // Pull: leaves reflect, interior nodes average their children by area.
        for i in (0..n).rev() {
            let c = t.child[i];
            if c == u32::MAX {
                for j in 0..nn {
                    l[i * nn + j] = le + t.rho[i] * q[i * nn + j];
                }
            } else {
                let c = c as usize;
                let a: f32 = (c..c + 4).map(|ch| t.area[ch]).sum();
                for j in 0..nn {
                    let mut s = Vec3::ZERO;
                    for ch in c..c + 4 {
                        s += l[ch * nn + j] * t.area[ch];
                    }
                    l[i * nn + j] = s / a;
                }
            }
        }
        l
    }

    /// Cluster radiances (normal 0), bottom-up: per cluster the sums of radiance times open
    /// area turned towards each of ±x, ±y, ±z ([`ClusterLight`]).
    fn cluster_radiance(&self, trees: &[Tree]) -> Vec<ClusterLight> {
        let cs = &self.clusters.clusters;
        let mut out = vec![ClusterLight::default(); cs.len()];
        // Children are created after their parent, so reverse order is bottom-up.
        for c in (0..cs.len()).rev() {
            let mut sum = ClusterLight::default();
            for ch in cs[c].children {
                match ch {
                    ClusterChild::Cluster(x) => sum.add(&out[x as usize]),
                    ClusterChild::Root(x) => {
                        let t = &trees[x as usize];
                        // Its radiance is that of its open surface, as for an element (see
                        // `source_radiance`).
                        let root = &self.roots[x as usize];
                        sum.add_face(
                            self.source_radiance(x, t, 0),
                            t.open[0] * root.area,
                            root.normal,
                        );
                    }
                }
            }
            out[c] = sum;
        }
        out
    }

    /// The unit direction in which light leaves cluster `c` towards the point `at`.
    fn leaving(&self, c: u32, at: Vec3) -> Vec3 {
        (at - self.clusters.clusters[c as usize].centre).normalize_or_zero()
    }

    fn solve(
        &self,
        trees: &mut [Tree],
        cl: &mut Vec<ClusterLight>,
        max_iterations: u32,
        report: &dyn Fn(usize),
    ) -> (u32, f32) {
        let mut change = f32::INFINITY;
        let mut it = 0;
        let sums: Vec<Vec<[f32; 2]>> = (0..trees.len() as u32)
            .into_par_iter()
            .map(|r| self.form_factor_sums(r, &trees[r as usize]))
            .collect();
        while it < max_iterations {
            it += 1;
            report(it as usize);
            let new: Vec<Vec<Vec3>> = (0..trees.len() as u32)
                .into_par_iter()
                .map(|r| self.iterate_root(r, trees, cl, &sums[r as usize]))
                .collect();
            let (mut num, mut den) = (0.0f64, 0.0f64);
            for (t, l) in trees.iter_mut().zip(new) {
                for (a, b) in t.l.iter().zip(&l) {
                    num += f64::from((*a - *b).abs().element_sum());
                    den += f64::from(b.abs().element_sum());
                }
                t.l = l;
            }
            *cl = self.cluster_radiance(trees);
            change = if den > 0.0 { (num / den) as f32 } else { 0.0 };
            if change < self.params.tolerance {
                break;
            }
        }
        (it, change)
    }
}

/// A link's coefficients are a linear function over its receiver, stored as its values at the
/// receiver's three corners (per normal: `k[c * nn + j]`). A constant per link, pushed down to
/// every leaf below its receiver, gives a leaf near the edge of a large receiver that
/// receiver's average form factor rather than its own: next to a wall, where the form factor to
/// the wall rises towards one half and those to everything else fall, the leaves summed up to
/// 10% more than the whole hemisphere in a closed furnace and came out 13% too bright (issue
/// 20). With the first-order variation of every link kept, the push hands each child the
/// coefficient over its own part of the receiver, and what remains is curvature.
const CORNERS: usize = 3;

/// Largest error, relative to the receiver's radiance, that a link's bend over its receiver
/// may put into it before the receiver is split (see `refine_root`).
const BEND_TOLERANCE: f32 = 0.001;

/// The source variation rule weighs its error against the scene's power (`bf_epsilon`), which
/// lets a dim receiver (a face in shadow, lit by a floor whose shadow it faces) carry a larger
/// relative error than a bright one: the Cornell box's short block's front face, a tenth of
/// the mean, came out 6% too bright. A receiver below the mean radiance of the scene's
/// non-emitting surfaces lowers the rule's threshold in proportion to its radiance, down to
/// this fraction of it (+2.4% on that face against 2^20 paths, for 16-29% more bake time on the
/// samples; at 2^18 paths 0.3 gave +2.8%, 0.5 +3.4%, 0.2 +2.6%).
const DIM_RECEIVER_FLOOR: f32 = 0.3;

/// Largest error, relative to the receiver's radiance, that a shadow edge crossing the
/// receiver may put into it before the receiver is split (see `refine_root`).
const SHADOW_TOLERANCE: f32 = 0.05;

/// How far from a receiver, in receiver radii, an occluder is looked for by
/// [`Ctx::near_shadow`].
const NEAR_SHADOW_REACH: f32 = 10.0;

/// Directions [`Ctx::self_shade_varies`] casts from each point: rings of equal cosine-weighted
/// measure, and directions per ring (24 in all: with 12, the same gain on the teapot took
/// twice the bake time).
const SELF_SHADE_RINGS: u32 = 4;
const SELF_SHADE_AZIMUTHS: u32 = 6;

/// Largest difference, as a share of the directions, between what two points of an element
/// see open before [`Ctx::self_shade_varies`] splits it: more than 2 of 24. (4 of 24 took the
/// teapot to 4.1% instead of 3.8% against path-traced images, in 80% of the time.)
const SELF_SHADE_TOLERANCE: f32 = 0.1;

/// What the noise of one link's visibility rays may move its receiver's radiance by, as a
/// fraction of that radiance (one standard deviation, at worst): links that bring a large share
/// of their receiver's light take more rays than `visibility_rays`. Eight rays for every link
/// left the dark undersides of curved objects blotchy (the visibility of the few links that
/// light them read to ±18%): spot 2.49% against path-traced images, 2.38% at 2%, 2.36% at 1%,
/// for 1.0x, 1.0x and 1.35x on the scaling scene.
const VISIBILITY_NOISE: f32 = 0.02;

/// At most this many times `visibility_rays` for one link ([`VISIBILITY_NOISE`]).
const MAX_RAY_FACTOR: u32 = 4;

/// How many times the scene's mean emission an emitter sends to count as a light
/// ([`Ctx::lights`]).
const LIGHT_EMISSION: f32 = 2.0;

/// [`MAX_RAY_FACTOR`] for a link from a light ([`Ctx::lights`]) to a receiver of
/// `detail_level` or deeper: in a penumbra its visibility is most of what its receiver gets.
const LIGHT_RAY_FACTOR: u32 = 16;

/// How many levels below [`BakeParams::detail_level`] an emitter's narrow shadow splits a
/// flat receiver ([`Ctx::narrow_shadow_splittable`]).
const NARROW_SHADOW_LEVELS: u32 = 2;

/// The least area [`Ctx::narrow_shadow_splittable`] splits to, as a fraction of the object's
/// least element area.
const NARROW_SHADOW_AREA: f32 = 16.0;

/// A link bringing less than this share of its receiver's radiance is faint: a few rays bound
/// what its visibility can put wrong.
const FAINT_LINK: f32 = 0.01;

/// Below `max_level`, direct light splits an element where a child's direct light differs from
/// the element's by this fraction of the brightest of them (`Ctx::direct_tree`).
const DIRECT_EDGE: f32 = 0.25;

/// A cluster is one disc in a link's coefficient while its radius is below this fraction of
/// its distance ([`Ctx::cluster_form_factor`]).
const CLUSTER_DISC_OPENING: f32 = 0.2;

/// How many levels below a linked cluster its radiance is read apart ([`Ctx::cluster_seen`]),
/// and so into how many parts at most.
const READ_DEPTH: u32 = 2;
const READ_PARTS: usize = 1 << READ_DEPTH;

/// A cluster whose radius is at least this fraction of its distance from the receiver is read
/// in parts ([`Ctx::reads_deep`]).
const DEEP_READ: f32 = 0.25;

/// Where a receiver's form factor is sampled for its slope: its corners moved a tenth of the
/// way towards the centroid (a corner on an edge shared with the source sits where the kernel
/// is steepest).
const CORNER_INSET: f32 = 0.1;

/// Cosine-weighted rings and azimuths of the directions [`Ctx::root_closed`] casts from each
/// of a root's four points (and [`Ctx::enclosure`] from each of a partly shut leaf's sixteen).
const ENCLOSURE_RINGS: u32 = 4;
const ENCLOSURE_AZIMUTHS: u32 = 4;

/// How many roots [`Ctx::boundary_closed`] casts its rays from.
const BOUNDARY_PROBES: usize = 64;

/// The parts of cluster `c` that a link to it reads apart ([`Ctx::cluster_seen`]): its
/// descendants [`READ_DEPTH`] levels down, a root triangle met on the way standing for
/// itself; and how many there are.
fn read_parts(clusters: &ClusterTree, c: u32) -> ([ClusterChild; READ_PARTS], u8) {
    let mut parts = [ClusterChild::Cluster(c); READ_PARTS];
    let mut count = 1;
    for _ in 0..READ_DEPTH {
        let mut next = parts;
        let mut n = 0;
        for part in &parts[..count] {
            match *part {
                ClusterChild::Cluster(x) => {
                    for ch in clusters.clusters[x as usize].children {
                        next[n] = ch;
                        n += 1;
                    }
                }
                root => {
                    next[n] = root;
                    n += 1;
                }
            }
        }
        parts = next;
        count = n;
    }
    (parts, count as u8)
}

/// Fixed directions over the hemisphere around unit normal `n`, `rings` × `azimuths` strata of
/// equal cosine-weighted measure, ring by ring from the normal outwards: the sin² of each
/// direction's angle from `n` is the middle of one of `rings` equal parts of [0, 1], and each
/// ring's azimuths are turned half a step from the previous ring's, and all by `turn` steps.
fn cosine_strata(n: Vec3, rings: u32, azimuths: u32, turn: f32) -> impl Iterator<Item = Vec3> {
    let a = if n.x.abs() < 0.9 { Vec3::X } else { Vec3::Y };
    let tu = n.cross(a).normalize();
    let tv = n.cross(tu);
    (0..rings).flat_map(move |ring| {
        let s2 = (2 * ring + 1) as f32 / (2 * rings) as f32;
        let (sin, cos) = (s2.sqrt(), (1.0 - s2).sqrt());
        (0..azimuths).map(move |az| {
            let phi =
                std::f32::consts::TAU / azimuths as f32 * (az as f32 + 0.5 * ring as f32 + turn);
            tu * (sin * phi.cos()) + tv * (sin * phi.sin()) + n * cos
        })
    })
}

fn inset_corners(t: [Vec3; 3]) -> [Vec3; CORNERS] {
    let c = (t[0] + t[1] + t[2]) / 3.0;
    t.map(|v| v + (c - v) * CORNER_INSET)
}

/// The linear function over the receiver with mean `mean[j]` for each normal (the link's
/// estimate over the whole receiver) and the relative slope of the geometric normal's values
/// `at` sampled at the inset corners (the slope is the geometry's: distance and angle to the
/// source change alike for every normal), as corner values, never below zero. Corner-major:
/// `out[c * nn + j]`.
fn linear_over_receiver(mean: &[f32], at: [f32; CORNERS]) -> Vec<f32> {
    let nn = mean.len();
    let mut out = vec![0.0f32; CORNERS * nn];
    let fm = (at[0] + at[1] + at[2]) / 3.0;
    // Relative change at each corner; none when the geometric normal sees nothing (a source
    // below the coarse plane that only tilted normals see).
    let slope = if fm > 0.0 {
        at.map(|v| (v - fm) / (fm * (1.0 - CORNER_INSET)))
    } else {
        [0.0; CORNERS]
    };
    // A slope steep enough to take a corner below zero is flattened until that corner is zero,
    // keeping the mean (clamping the corner alone would add light).
    let low = slope.iter().copied().fold(0.0f32, f32::min);
    let scale = if low < -1.0 { 1.0 / -low } else { 1.0 };
    for (j, &m) in mean.iter().enumerate() {
        for c in 0..CORNERS {
            out[c * nn + j] = (m * (1.0 + slope[c] * scale)).max(0.0);
        }
    }
    out
}

/// The mean over node `i`'s corners of value `j` of `v`, which holds `width` values per corner
/// of every node, corner-major (`v[(i * CORNERS + corner) * width + j]`): what a leaf gathers
/// from a linear function, its value at the centroid.
fn corner_mean<T>(v: &[T], i: usize, j: usize, width: usize) -> T
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
fn push_linear<T>(t: &Tree, v: &mut [T], width: usize)
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

/// The corners of child `c` of the 1-to-4 split as weights of the parent's corners:
/// `(a, b)` is the midpoint of parent corners `a` and `b` (a corner itself when `a == b`).
const CHILD_CORNERS: [[(usize, usize); 3]; 4] = [
    [(0, 0), (0, 1), (2, 0)],
    [(0, 1), (1, 1), (1, 2)],
    [(1, 2), (2, 0), (0, 1)],
    [(2, 0), (1, 2), (2, 2)],
];

/// The visible fraction of a link, for every normal of the receiver, estimated from the rays
/// that the geometric normal (`normals[0]`) exchanges; clear when it exchanges none (a source
/// wholly below the coarse element's plane, which only tilted normals see).
///
/// Rays that only a tilted normal exchanges leave the coarse element below its own plane, into
/// the coarse object itself, while the refined surface whose normals the tilted ones stand for
/// curves away and sees past it. Counting those rays made every normal of curved objects too
/// dark (the geometric one included: 4-8% against path-traced images, BENCHMARKS.md); counting
/// them only where the geometric normal has none made it 4.7% on spot and 6.2% on suzanne at
/// level 3, against 3.8% and 4.5% this way.
/// Form factor from a point with normal `n` to a disc of projected area `proj` at squared
/// distance `d2` along unit `w` (how a cluster small against its distance counts).
fn disc_factor(n: Vec3, w: Vec3, proj: f32, d2: f32) -> f32 {
    (n.dot(w).max(0.0) * proj / (std::f32::consts::PI * d2 + proj)).min(1.0)
}

/// What a refinement pass judges the rules weighed against a receiver's own radiance by: the
/// mean radiance of the surfaces that emit nothing (`DIM_RECEIVER_FLOOR`), and the least
/// radiance the bend rules count a receiver as having (in a first pass of several, before any
/// light has bounced, a fraction of that mean; else zero).
#[derive(Clone, Copy)]
struct Judge {
    mean_radiance: f32,
    dark_floor: f32,
    /// Whether this pass's links make the file.
    last_pass: bool,
}

/// A receiver and a source that may exchange light, with the corners of the receiver and of the
/// source (when an element).
/// A receiver (its key and corners), a source (with its corners, for an element), and whether
/// the receiver's own rules (`near_shadow`, `self_shade_varies`) are known to leave it whole:
/// so a pair that splits or opens its source, keeping the receiver, does not ask again.
type Pair = (ElemKey, [Vec3; 3], Source, [Vec3; 3], bool);

/// Pairs one part of a root's refinement takes before it hands the pairs left on its stack
/// to parts that run in parallel ([`refine_in_parallel`]).
const REFINE_STEPS: usize = 16384;

/// Refines `stack` with `run` ([`Ctx::refine_root`]'s depth-first walk of at most
/// [`REFINE_STEPS`] pairs), then each pair it left in parallel, the same way; the links in
/// the order the walk would have popped them, their coefficients' offsets moved to match.
/// Where the parts fall depends on the step count alone, so the links come out the same for
/// any number of threads. A room of a few large coarse triangles was refined one triangle per
/// thread, and the floor's alone took most of the time (the Cornell box: 1.2 cores busy of 2).
#[allow(clippy::type_complexity)]
fn refine_in_parallel(
    run: &(dyn Fn(Vec<Pair>) -> (Vec<RawLink>, Vec<f32>, Vec<Pair>) + Sync),
    stack: Vec<Pair>,
) -> (Vec<RawLink>, Vec<f32>) {
    // The parts' results in order, joined once at the end.
    #[allow(clippy::type_complexity)]
    fn parts(
        run: &(dyn Fn(Vec<Pair>) -> (Vec<RawLink>, Vec<f32>, Vec<Pair>) + Sync),
        stack: Vec<Pair>,
    ) -> Vec<(Vec<RawLink>, Vec<f32>)> {
        let (links, ks, left) = run(stack);
        let mut out = vec![(links, ks)];
        if !left.is_empty() {
            let rest: Vec<Vec<(Vec<RawLink>, Vec<f32>)>> = left
                .into_par_iter()
                .rev()
                .map(|p| parts(run, vec![p]))
                .collect();
            out.extend(rest.into_iter().flatten());
        }
        out
    }
    let mut all = parts(run, stack);
    if all.len() == 1 {
        return all.pop().unwrap_or_default();
    }
    let (mut links, mut ks) = (
        Vec::with_capacity(all.iter().map(|p| p.0.len()).sum()),
        Vec::with_capacity(all.iter().map(|p| p.1.len()).sum()),
    );
    for (part_links, part_ks) in all {
        let offset = ks.len() as u32;
        links.extend(part_links.into_iter().map(|mut l| {
            l.k_start += offset;
            l
        }));
        ks.extend(part_ks);
    }
    (links, ks)
}

/// Whether a receiver and a source element of areas `r_area` and `s_area`, their centres `d2`
/// apart (squared), are near: within six times the root of their summed areas, where the
/// form factor is bounded at points of the receiver, not by a disc from afar.
fn near_pair(d2: f32, r_area: f32, s_area: f32) -> bool {
    d2 <= 36.0 * (r_area + s_area)
}

/// Pushes the pairs of the four children of receiver `recv` (corners `rt`) with `src`.
fn split_receiver(stack: &mut Vec<Pair>, recv: ElemKey, rt: [Vec3; 3], src: Source, st: [Vec3; 3]) {
    let children = split(rt);
    for c in (0..4).rev() {
        stack.push((recv.child(c), children[c as usize], src, st, false));
    }
}

/// Pushes the pairs of `recv` with the four children of source element `sk` (corners `st`).
fn split_source(stack: &mut Vec<Pair>, recv: ElemKey, rt: [Vec3; 3], sk: ElemKey, st: [Vec3; 3]) {
    let children = split(st);
    for c in (0..4).rev() {
        stack.push((
            recv,
            rt,
            Source::Elem(sk.child(c)),
            children[c as usize],
            true,
        ));
    }
}

/// Form factors to a link's source with the receiver's geometric normal, already computed by
/// the rules that decided to make the link: at the receiver's centre, and at its inset corners
/// ([`inset_corners`]).
#[derive(Clone, Copy, Default)]
struct KnownFactors {
    centre: Option<f32>,
    corners: Option<[f32; 3]>,
}

/// The kernel-weighted fraction of `n` rays that are clear, for each receiver normal (and the
/// refined surface's own normal after them) into `vis`, and the same fraction as a linear
/// function over the receiver, its value at each corner, into `at_corner` (`[j * CORNERS + c]`
/// for slot `j` of `vis`). `ray(i, w)` fills `w` with ray `i`'s weight per normal (`None`
/// where that normal's plane hides its source point: it does not count) and casts it,
/// returning whether it is clear and the barycentric coordinates of its receiver point, or
/// returns `None` when no normal counts it.
///
/// Each normal weighs the rays by its own kernel and counts only those its plane lets through.
/// One fraction for all, the geometric normal's, left a tilted normal with the visibility of
/// rays it does not see along (and with none at all, read as wholly clear, where the source
/// lies behind the geometric plane): under spot's muzzle, normals facing the chest and the
/// floor came out too bright (issue 20). A normal no ray counts takes the fraction of all the
/// rays cast.
///
/// Every ray is cast and weighed by the kernel. Stopping after four that agreed made the
/// estimate lean to whole visibility for links mostly visible (a link 90% visible read 93%),
/// and counting the rays alike, points spread evenly over a large source, read the part of it
/// straight above the receiver no heavier than the part at its horizon: next to an object
/// resting on a floor, which hides the first, floor leaves in a closed furnace summed form
/// factors to 1.07 (issue 20).
///
/// The linear function: the rays weighed also by their point's barycentric coordinate of
/// corner `c` read, for rays spread evenly over the receiver, a linear visibility at the point
/// a quarter of the way from the centroid to corner `c` (`∫ b_c V / ∫ b_c`), so the value at
/// the corner is the mean plus four times that reading's difference from the mean of the
/// three readings: the least-squares linear fit. Its mean is the fraction in `vis`, and a
/// slope that would take a corner outside [0, 1] is flattened until it does not, keeping the
/// mean (BENCHMARKS.md, "Eighteenth round").
fn visible_fractions(
    n: u32,
    vis: &mut [f32],
    at_corner: &mut [f32],
    mut ray: impl FnMut(u32, &mut [Option<f32>]) -> Option<(bool, [f32; CORNERS])>,
) {
    let m = vis.len();
    debug_assert_eq!(at_corner.len(), m * CORNERS);
    // Per normal: clear weight, total weight, clear rays, rays; and per normal and corner the
    // clear and total weights times the barycentric coordinate.
    let mut acc = vec![(0.0f64, 0.0f64, 0u32, 0u32); m];
    let mut by_corner = vec![(0.0f64, 0.0f64); m * CORNERS];
    let (mut cast, mut clear_rays) = (0u32, 0u32);
    let mut w = vec![None; m];
    for i in 0..n {
        let Some((clear, at)) = ray(i, &mut w) else {
            continue;
        };
        cast += 1;
        clear_rays += u32::from(clear);
        for (j, (a, x)) in acc.iter_mut().zip(&w).enumerate() {
            if let Some(x) = *x {
                let x = f64::from(x);
                a.0 += if clear { x } else { 0.0 };
                a.1 += x;
                a.2 += u32::from(clear);
                a.3 += 1;
                for (c, b) in at.iter().enumerate() {
                    let e = &mut by_corner[j * CORNERS + c];
                    let xb = x * f64::from(b.clamp(0.0, 1.0));
                    e.0 += if clear { xb } else { 0.0 };
                    e.1 += xb;
                }
            }
        }
    }
    for (j, (v, a)) in vis.iter_mut().zip(&acc).enumerate() {
        *v = if a.1 > 0.0 {
            (a.0 / a.1) as f32
        } else if a.3 > 0 {
            a.2 as f32 / a.3 as f32
        } else if cast > 0 {
            clear_rays as f32 / cast as f32
        } else {
            1.0
        };
        let reading: [f32; CORNERS] = std::array::from_fn(|c| {
            let e = by_corner[j * CORNERS + c];
            if a.1 > 0.0 && e.1 > 0.0 {
                (e.0 / e.1) as f32
            } else {
                *v
            }
        });
        let mean = (reading[0] + reading[1] + reading[2]) / 3.0;
        let slope = reading.map(|r| 4.0 * (r - mean));
        let mut scale = 1.0f32;
        for d in slope {
            if *v + d > 1.0 {
                scale = scale.min((1.0 - *v) / d);
            } else if *v + d < 0.0 {
                scale = scale.min(*v / -d);
            }
        }
        for (c, d) in slope.iter().enumerate() {
            at_corner[j * CORNERS + c] = (*v + d * scale.max(0.0)).clamp(0.0, 1.0);
        }
    }
}

/// The form-factor kernel `cos θp cos θq / r²` between a receiver point `p` (normal `np`) and
/// a source point `q` (normal `nq`), the distance kept above a twentieth of `size` (the two
/// elements' sizes together) so that one pair next to a contact cannot outweigh all others.
fn kernel(p: Vec3, np: Vec3, q: Vec3, nq: Vec3, size: f32) -> f32 {
    let d = q - p;
    let r2 = d.length_squared();
    let floor = (0.05 * size).powi(2);
    let inv = 1.0 / r2.max(1e-30).sqrt();
    (np.dot(d) * inv).max(0.0) * (-nq.dot(d) * inv).max(0.0) / r2.max(floor)
}

/// Bakes the scene: direct light, link refinement, solve, repeated `refine_passes` times.
pub fn bake(scene: &Scene, params: &BakeParams) -> Result<BakeResult, BakeError> {
    bake_with_progress(scene, params, &|_: &str, _: usize, _: usize| {})
}

/// Progress callback: `(phase, done, total)`, e.g. `("refine 1", 1200, 20000)` coarse
/// triangles, or `("solve 2", 3, 200)` iterations (the total is the iteration cap). Called
/// from worker threads; it only reports and never changes the result.
pub type Progress<'a> = &'a (dyn Fn(&str, usize, usize) + Sync);

/// [`bake`] with a progress report per phase (for progress bars).
pub fn bake_with_progress(
    scene: &Scene,
    params: &BakeParams,
    progress: Progress<'_>,
) -> Result<BakeResult, BakeError> {
    scene.validate()?;
    if params.max_level > MAX_TREE_DEPTH {
        return Err(BakeError::InvalidParameter(format!(
            "max_level {} exceeds {MAX_TREE_DEPTH}, the deepest HCE tree a file may hold (SPEC.md B.2)",
            params.max_level
        )));
    }
    if params.detail_level > MAX_TREE_DEPTH || params.detail_level < params.max_level {
        return Err(BakeError::InvalidParameter(format!(
            "detail_level {} must lie between max_level {} and {MAX_TREE_DEPTH}, the deepest HCE tree a file may hold (SPEC.md B.2)",
            params.detail_level, params.max_level
        )));
    }
    if params.visibility_rays > MAX_VISIBILITY_RAYS {
        return Err(BakeError::InvalidParameter(format!(
            "visibility_rays {} exceeds {MAX_VISIBILITY_RAYS}",
            params.visibility_rays
        )));
    }
    let positive = |x: f32| x.is_finite() && x > 0.0;
    if !positive(params.bf_epsilon)
        || !positive(params.tolerance)
        || !positive(params.cluster_opening)
    {
        return Err(BakeError::InvalidParameter(
            "bf_epsilon, tolerance and cluster_opening must be positive and finite".into(),
        ));
    }
    let mut stats = BakeStats::default();
    let t0 = Instant::now();
    let mut roots = Vec::new();
    for (oi, o) in scene.objects.iter().enumerate() {
        for t in 0..o.triangles.len() {
            let corners = o.corners(t);
            let c = (corners[1] - corners[0]).cross(corners[2] - corners[0]);
            roots.push(Root {
                corners,
                normal: c.normalize(),
                area: c.length() * 0.5,
                normals: o.normals_of(t),
                emission: Vec3::from(o.emission_of(t)),
                object: oi,
                triangle: t,
            });
        }
    }
    if roots.len() >= u32::MAX as usize {
        return Err(BakeError::InvalidParameter("too many triangles".into()));
    }
    let all_tris: Vec<[Vec3; 3]> = roots.iter().map(|r| r.corners).collect();
    let clusters = ClusterTree::build(&all_tris);
    let emits = |t: u32| roots[t as usize].emission.max_element() > 0.0;
    let mixes_emitters = clusters
        .clusters
        .iter()
        .map(|c| {
            let ts = clusters.roots_of(c);
            let e = ts.iter().filter(|&&t| emits(t)).count();
            e > 0 && e < ts.len()
        })
        .collect();
    let read_parts = (0..clusters.clusters.len() as u32)
        .map(|c| read_parts(&clusters, c))
        .collect();
    // What casts shadows: every root, but a multiresolution object with an occluder of its
    // own ([`SolverObject::occluder`]) by that; each occluder triangle with its root.
    let (occ_tris, occ_owner, surface) = {
        let (mut tris, mut owner) = (Vec::new(), Vec::new());
        let mut surface: Vec<Vec<[Vec3; 3]>> = vec![Vec::new(); roots.len()];
        let mut first = 0u32;
        for o in &scene.objects {
            if o.occluder.is_empty() {
                for t in 0..o.triangles.len() as u32 {
                    tris.push(roots[(first + t) as usize].corners);
                    owner.push(first + t);
                }
            } else {
                for (tri, t) in &o.occluder {
                    let tri = tri.map(Vec3::from);
                    surface[(first + *t) as usize].push(tri);
                    tris.push(tri);
                    owner.push(first + *t);
                }
            }
            first += o.triangles.len() as u32;
        }
        (tris, owner, surface)
    };
    let occ = Occluders::new(occ_tris.iter().copied());
    let plane_eps = {
        let (mut lo, mut hi) = (Vec3::splat(f32::MAX), Vec3::splat(f32::MIN));
        for t in &all_tris {
            for v in t {
                lo = lo.min(*v);
                hi = hi.max(*v);
            }
        }
        (hi - lo).length() * 1e-6
    };
    let object_clusters: Vec<(ClusterTree, u32)> = {
        let mut first = 0usize;
        scene
            .objects
            .iter()
            .map(|o| {
                let n = o.triangles.len();
                let tree = ClusterTree::build(&all_tris[first..first + n]);
                first += n;
                (tree, (first - n) as u32)
            })
            .collect()
    };
    let convex = object_clusters
        .iter()
        .map(|(tree, first)| {
            let tris = &all_tris[*first as usize..*first as usize + tree.order.len()];
            !tris.is_empty() && tree.is_convex(tris, 10.0 * plane_eps)
        })
        .collect();
    let cluster_object = clusters
        .clusters
        .iter()
        .map(|c| {
            let ts = clusters.roots_of(c);
            let object = roots[ts[0] as usize].object;
            ts.iter()
                .all(|&t| roots[t as usize].object == object)
                .then_some(object as u32)
        })
        .collect();
    let ctx = Ctx {
        scene,
        params,
        clusters,
        object_clusters,
        convex,
        mixes_emitters,
        read_parts,
        cluster_object,
        boundary_closed: OnceLock::new(),
        unobstructed: roots
            .par_iter()
            .map(|r| occ.shaft_clear(r.corners, r.normal, Vec3::MIN, Vec3::MAX, None))
            .collect(),
        occ,
        occ_owner,
        shape: roots
            .iter()
            .zip(&surface)
            .map(|(r, surf)| {
                r.corners
                    .map(|q| surface_point(r.corners, r.normal, surf, q).0)
            })
            .collect(),
        surface,
        min_area: {
            let mut area = vec![0.0f64; scene.objects.len()];
            for r in &roots {
                area[r.object] += f64::from(r.area);
            }
            let scene_area: f64 = area.iter().sum();
            area.iter()
                .map(|a| (a.max(scene_area / 16.0) * f64::from(params.min_area_fraction)) as f32)
                .collect()
        },
        plane_eps,
        memos: roots.iter().map(|_| Mutex::default()).collect(),
        light_floor: {
            let (mut area, mut sent) = (0.0f64, 0.0f64);
            for r in &roots {
                area += f64::from(r.area);
                sent += f64::from(r.area) * f64::from(lum(r.emission));
            }
            (f64::from(LIGHT_EMISSION) * sent / area.max(f64::MIN_POSITIVE)) as f32
        },
        roots,
    };
    stats.coarse_triangles = ctx.roots.len();
    stats
        .phase_seconds
        .push(("setup".into(), t0.elapsed().as_secs_f64()));

    // Direct light, first at the roots to fix the reference power, then refined.
    let t1 = Instant::now();
    let n_roots = ctx.roots.len() as u32;
    let root_q: Vec<Vec<Vec3>> = (0..n_roots)
        .into_par_iter()
        .map(|r| ctx.direct(ElemKey::root(r)))
        .collect();
    let mut ref_power = 0.0f64;
    for (r, (root, q)) in ctx.roots.iter().zip(&root_q).enumerate() {
        let rho = lum(ctx.reflectance(ElemKey::root(r as u32)));
        let r = root;
        ref_power +=
            f64::from(r.area) * std::f64::consts::PI * f64::from(lum(r.emission) + rho * lum(q[0]));
    }
    let eps_power = (ref_power * f64::from(params.bf_epsilon)) as f32;
    let counter = std::sync::atomic::AtomicUsize::new(0);
    let direct: Vec<Vec<(ElemKey, Vec<Vec3>)>> = root_q
        .into_par_iter()
        .enumerate()
        .map(|(r, q)| {
            let out = ctx.direct_tree(r as u32, q, eps_power);
            let done = counter.fetch_add(1, std::sync::atomic::Ordering::Relaxed) + 1;
            progress("direct", done, n_roots as usize);
            out
        })
        .collect();
    let mut trees: Vec<Tree> = (0..n_roots)
        .into_par_iter()
        .map(|r| ctx.build_tree(r, Vec::new(), &direct[r as usize]))
        .collect();
    let mut cl = vec![ClusterLight::default(); ctx.clusters.clusters.len()];
    // Without links one pass gives L = Le + ρ H/π.
    ctx.solve(&mut trees, &mut cl, 1, &|_| {});
    stats
        .phase_seconds
        .push(("direct".into(), t1.elapsed().as_secs_f64()));

    for pass in 0..params.refine_passes.max(1) {
        let t2 = Instant::now();
        let phase = format!("refine {}", pass + 1);
        counter.store(0, std::sync::atomic::Ordering::Relaxed);
        let spreads: Vec<Vec<f32>> = (0..n_roots)
            .into_par_iter()
            .map(|r| ctx.spreads(r, &trees[r as usize]))
            .collect();
        let mean_radiance = ctx.mean_radiance(&trees);
        let judge = Judge {
            mean_radiance,
            dark_floor: if pass == 0 && params.refine_passes > 1 {
                DIM_RECEIVER_FLOOR * mean_radiance
            } else {
                0.0
            },
            last_pass: pass + 1 >= params.refine_passes.max(1),
        };
        let refined: Vec<(Vec<RawLink>, Vec<f32>)> = (0..n_roots)
            .into_par_iter()
            .map(|r| {
                let out = ctx.refine_root(r, &trees, &cl, &spreads, eps_power, judge);
                let done = counter.fetch_add(1, std::sync::atomic::Ordering::Relaxed) + 1;
                progress(&phase, done, n_roots as usize);
                out
            })
            .collect();
        // Every source element must exist in its tree: collect keys per root in fixed order.
        let mut needed: Vec<Vec<ElemKey>> = vec![Vec::new(); n_roots as usize];
        for (links, _) in &refined {
            for l in links {
                needed[l.recv.root as usize].push(l.recv);
                if let Source::Elem(k) = l.src {
                    needed[k.root as usize].push(k);
                }
            }
        }
        let mut new_trees: Vec<Tree> = needed
            .into_par_iter()
            .enumerate()
            .map(|(r, keys)| ctx.build_tree(r as u32, keys, &direct[r]))
            .collect();
        stats.links = 0;
        for (r, (links, ks)) in refined.into_iter().enumerate() {
            stats.links += links.len();
            let resolved: Vec<Link> = links
                .iter()
                .map(|l| Link {
                    recv: new_trees[r].index_of(l.recv).expect("receiver present"),
                    src: match l.src {
                        Source::Cluster(c) => SrcIdx::Cluster(c),
                        Source::Elem(k) => SrcIdx::Node {
                            root: k.root,
                            node: new_trees[k.root as usize]
                                .index_of(k)
                                .expect("source present"),
                        },
                    },
                    aim: l.aim,
                    share: l.share,
                    deep: l.deep,
                    facing: l.facing,
                    depth: l.depth,
                    k_start: l.k_start,
                    visible: l.visible,
                    bend: l.bend,
                })
                .collect();
            new_trees[r].links = resolved;
            new_trees[r].k = ks;
            (new_trees[r].closure, new_trees[r].self_view) = ctx.closure(r as u32, &new_trees[r]);
        }
        // Start from the previous solution where it exists so that the solve converges fast.
        for (nt, ot) in new_trees.iter_mut().zip(&trees) {
            let nn = nt.l.len() / nt.keys.len();
            for i in 0..nt.keys.len() {
                let j = ot.deepest_toward(nt.keys[i]) as usize;
                nt.l[i * nn..(i + 1) * nn].copy_from_slice(&ot.l[j * nn..(j + 1) * nn]);
            }
        }
        trees = new_trees;
        stats
            .phase_seconds
            .push((format!("refine {}", pass + 1), t2.elapsed().as_secs_f64()));
        let t3 = Instant::now();
        let phase = format!("solve {}", pass + 1);
        let cap = params.max_iterations as usize;
        let (it, change) = ctx.solve(&mut trees, &mut cl, params.max_iterations, &|i| {
            progress(&phase, i, cap)
        });
        stats.iterations += it;
        stats.final_change = change;
        stats
            .phase_seconds
            .push((format!("solve {}", pass + 1), t3.elapsed().as_secs_f64()));
    }

    stats.elements = trees.iter().map(|t| t.keys.len()).sum();
    let mut objects: Vec<ObjectSolution> = scene
        .objects
        .iter()
        .map(|o| ObjectSolution {
            name: o.name.clone(),
            multires: o.multires,
            triangles: Vec::with_capacity(o.triangles.len()),
        })
        .collect();
    for (r, t) in trees.iter().enumerate() {
        let root = &ctx.roots[r];
        objects[root.object].triangles.push(TriangleSolution {
            normals: root.normals.iter().map(|n| n.to_array()).collect(),
            nodes: t.keys.iter().map(|k| (k.level, k.path)).collect(),
            subdivided: t.child.iter().map(|&c| c != u32::MAX).collect(),
            colours: ctx
                .shown(r as u32, t)
                .iter()
                .map(|v| v.to_array())
                .collect(),
        });
    }
    Ok(BakeResult { objects, stats })
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn each_normal_weighs_the_rays_its_plane_lets_through() {
        // Rays 0-3 reach a source point above the geometric normal's plane and are clear;
        // rays 4-7 reach one only a tilted normal sees, and are hidden; the third slot (a
        // normal no ray reaches) takes the fraction of all rays cast.
        let mid = [1.0 / 3.0; CORNERS];
        let mut vis = [0.5f32; 3];
        let mut at = [0.5f32; 9];
        visible_fractions(8, &mut vis, &mut at, |i, w| {
            w[0] = (i < 4).then_some(1.0);
            w[1] = Some(if i < 4 { 1.0 } else { 3.0 });
            w[2] = None;
            Some((i < 4, mid))
        });
        assert_eq!(vis[0], 1.0);
        assert!((vis[1] - 4.0 / 16.0).abs() < 1e-6, "{}", vis[1]);
        assert_eq!(vis[2], 0.5);
        // Every ray at the centroid: no slope, each corner the mean.
        for j in 0..3 {
            for c in 0..CORNERS {
                assert!(
                    (at[j * CORNERS + c] - vis[j]).abs() < 1e-6,
                    "{j} {c} {at:?}"
                );
            }
        }
        // No ray any normal counts: nothing hides the source.
        let mut vis = [0.0f32; 2];
        let mut at = [0.0f32; 6];
        visible_fractions(8, &mut vis, &mut at, |_, w| {
            w.iter_mut().for_each(|x| *x = None);
            None
        });
        assert_eq!(vis, [1.0, 1.0]);
        assert_eq!(at, [1.0; 6]);
        // No rays at all (occlusion off).
        let mut vis = [0.0f32; 2];
        let mut at = [0.0f32; 6];
        visible_fractions(0, &mut vis, &mut at, |_, _| unreachable!());
        assert_eq!(vis, [1.0, 1.0]);
        assert_eq!(at, [1.0; 6]);
    }

    #[test]
    fn a_soft_shadow_across_a_receiver_is_linear_over_it() {
        // A visibility linear over the receiver, 1 at corner 0 and 0.2 at corners 1 and 2,
        // sampled by many rays spread evenly over it (each ray clear with that probability,
        // a fixed pattern): the corners come back to within the sampling's noise, and their
        // mean is the fraction of clear rays.
        let n = 4096u32;
        let truth = |b: [f32; 3]| b[0] * 1.0 + (b[1] + b[2]) * 0.2;
        let mut rng = Rng::new(1, 2, 3);
        let rays: Vec<([f32; 3], bool)> = (0..n)
            .map(|i| {
                let p = jittered_point([Vec3::ZERO, Vec3::X, Vec3::Y], i, n, &mut rng);
                let b = barycentric_of([Vec3::ZERO, Vec3::X, Vec3::Y], p);
                (b, rng.next_f32() < truth(b))
            })
            .collect();
        let mut vis = [0.0f32];
        let mut at = [0.0f32; 3];
        visible_fractions(n, &mut vis, &mut at, |i, w| {
            w[0] = Some(1.0);
            let (b, clear) = rays[i as usize];
            Some((clear, b))
        });
        let clear = rays.iter().filter(|r| r.1).count() as f32 / n as f32;
        assert!((vis[0] - clear).abs() < 1e-6);
        assert!(
            ((at[0] + at[1] + at[2]) / 3.0 - vis[0]).abs() < 1e-5,
            "{at:?}"
        );
        assert!((at[0] - 1.0).abs() < 0.06, "{at:?}");
        assert!(
            (at[1] - 0.2).abs() < 0.06 && (at[2] - 0.2).abs() < 0.06,
            "{at:?}"
        );
        // A step: clear only where corner 0's coordinate is over a half. The slope that
        // would take corner 0 above 1 is flattened, the mean kept, every corner in [0, 1].
        let mut vis = [0.0f32];
        let mut at = [0.0f32; 3];
        visible_fractions(n, &mut vis, &mut at, |i, w| {
            w[0] = Some(1.0);
            let b = rays[i as usize].0;
            Some((b[0] > 0.5, b))
        });
        assert!(at.iter().all(|v| (0.0..=1.0).contains(v)), "{at:?}");
        assert!(
            ((at[0] + at[1] + at[2]) / 3.0 - vis[0]).abs() < 1e-5,
            "{at:?}"
        );
        assert!(
            at[0] > 0.5 && at[1] < vis[0] && at[2] < vis[0],
            "{at:?} {vis:?}"
        );
    }

    /// The level-`level` surface over `corners` whose lattice point `(b, c)` is at
    /// `at(b, c)`, by path as `hce_geometry::lattice` numbers the fine triangles.
    fn surface(level: u32, at: impl Fn(f32, f32) -> Vec3) -> Vec<[Vec3; 3]> {
        (0..1u32 << (2 * level))
            .map(|path| {
                hce_geometry::lattice::fine_corners(level, path)
                    .map(|[b, c]| at(b as f32, c as f32))
            })
            .collect()
    }

    #[test]
    fn points_map_to_the_occluding_surface_at_their_lattice_coordinates() {
        let corners = [
            Vec3::new(0.0, 0.0, 0.0),
            Vec3::new(2.0, 0.0, 0.1),
            Vec3::new(0.3, 1.5, -0.2),
        ];
        let normal = (corners[1] - corners[0])
            .cross(corners[2] - corners[0])
            .normalize();
        let n = 4.0;
        let flat = |b: f32, c: f32| {
            corners[0] + (corners[1] - corners[0]) * (b / n) + (corners[2] - corners[0]) * (c / n)
        };
        // A bump that differs on every lattice point, so that a point mapped through the wrong
        // fine triangle or the wrong corner lands elsewhere.
        let bump = |b: f32, c: f32| flat(b, c) + normal * (0.05 * b + 0.11 * c + 0.02 * b * c);
        let mut rng = crate::element::Rng::new(1, 2, 3);
        for _ in 0..200 {
            let (mut u, mut v) = (rng.next_f32(), rng.next_f32());
            if u + v > 1.0 {
                (u, v) = (1.0 - u, 1.0 - v);
            }
            let p = flat(n * u, n * v);
            // In its own plane, a point is where it is, with the triangle's normal.
            let (q, m) = surface_point(corners, normal, &surface(2, flat), p);
            assert!((q - p).length() < 1e-5, "{p} went to {q}");
            assert!(m.dot(normal) > 0.9999);
            // Lifted, it follows the surface: linear within each fine triangle.
            let (q, _) = surface_point(corners, normal, &surface(2, bump), p);
            let (b, c) = (n * u, n * v);
            let lift = (q - p).dot(normal);
            let (lo, hi) = {
                // The bump at the corners of the lattice cell around (b, c) bounds it.
                let (b0, c0) = (b.floor(), c.floor());
                let h = |b: f32, c: f32| 0.05 * b + 0.11 * c + 0.02 * b * c;
                let hs = [
                    h(b0, c0),
                    h(b0 + 1.0, c0),
                    h(b0, c0 + 1.0),
                    h(b0 + 1.0, c0 + 1.0),
                ];
                (
                    hs.iter().copied().fold(f32::MAX, f32::min),
                    hs.iter().copied().fold(f32::MIN, f32::max),
                )
            };
            assert!(
                lift >= lo - 1e-4 && lift <= hi + 1e-4,
                "({b}, {c}) lifted by {lift}, outside [{lo}, {hi}]"
            );
            assert!(
                (q - p - normal * lift).length() < 1e-4,
                "moved off the normal"
            );
        }
        // The lattice points themselves land exactly on the surface's.
        for (b, c) in [
            (0.0, 0.0),
            (4.0, 0.0),
            (0.0, 4.0),
            (1.0, 2.0),
            (3.0, 1.0),
            (2.0, 2.0),
        ] {
            let (q, _) = surface_point(corners, normal, &surface(2, bump), flat(b, c));
            assert!(
                (q - bump(b, c)).length() < 1e-4,
                "({b}, {c}): {q} against {}",
                bump(b, c)
            );
        }
        // Without a surface of its own a root is its own.
        let p = flat(1.0, 1.0);
        assert_eq!(surface_point(corners, normal, &[], p), (p, normal));
    }

    /// The occluder the pipeline hands the solver lists each coarse triangle's Loop triangles
    /// by path with their corners in `fine_corners` order, as `surface_point` reads them: on a
    /// planar grid, which Loop subdivision leaves where it is away from its boundary (whose
    /// rules move the boundary's points along it), every refined corner of a triangle two rings
    /// in is the flat lattice point.
    #[test]
    fn loop_triangles_follow_the_lattice_order() {
        let (w, h) = (8u32, 7u32);
        let positions: Vec<[f32; 3]> = (0..=h)
            .flat_map(|y| (0..=w).map(move |x| [x as f32, y as f32 * 0.7, 0.0]))
            .collect();
        let at = |x: u32, y: u32| y * (w + 1) + x;
        let mut triangles = Vec::new();
        for y in 0..h {
            for x in 0..w {
                triangles.push([at(x, y), at(x + 1, y), at(x + 1, y + 1)]);
                triangles.push([at(x, y), at(x + 1, y + 1), at(x, y + 1)]);
            }
        }
        let top = hce_geometry::build_control_mesh(
            &positions,
            &triangles,
            None,
            &hce_geometry::TopologyConfig::default(),
        )
        .unwrap();
        let level = 2;
        let refined = hce_geometry::subdivide(&top.mesh, level).unwrap();
        let per = 1usize << (2 * level);
        let n = (1u32 << level) as f32;
        let mut checked = 0;
        for t in 0..top.mesh.triangle_count() {
            let [v0, v1, v2] = top
                .mesh
                .triangle(t)
                .map(|v| Vec3::from(top.mesh.position(v)));
            let inside = |v: Vec3| {
                let (x, y) = (v.x, v.y / 0.7);
                x >= 2.0 && x <= (w - 2) as f32 && y >= 2.0 && y <= (h - 2) as f32
            };
            if ![v0, v1, v2].into_iter().all(inside) {
                continue;
            }
            checked += 1;
            for path in 0..per {
                let want = hce_geometry::lattice::fine_corners(level, path as u32)
                    .map(|[b, c]| v0 + (v1 - v0) * (b as f32 / n) + (v2 - v0) * (c as f32 / n));
                let got = refined.indices[t * per + path]
                    .map(|v| Vec3::from(refined.positions[v as usize]));
                for k in 0..3 {
                    assert!(
                        (got[k] - want[k]).length() < 1e-4,
                        "triangle {t} path {path} corner {k}: {} against {}",
                        got[k],
                        want[k]
                    );
                }
            }
        }
        assert!(
            checked >= 10,
            "only {checked} triangles away from the boundary"
        );
    }
}
