//! What every part of the solver reads: the coarse triangles (roots), the cluster hierarchies,
//! the occluders and refined surfaces, the figures found once per bake, and the memo of what the
//! geometry alone decides per element. The state and what it answers directly; it is built in
//! [`prepare`](super::prepare), and the solver's readings and rules add their own methods
//! in their files.

use std::collections::HashMap;
use std::sync::{Mutex, OnceLock};

use glam::Vec3;
use hce_format::MAX_TREE_DEPTH;

use super::cluster::{ClusterChild, ClusterTree, READ_PARTS};
use super::element::ElemKey;
use super::links::Source;
use super::params::BakeParams;
use crate::scene::Scene;
use crate::visibility::Occluders;

/// A coarse triangle as the solver sees it.
pub(super) struct Root {
    pub(super) corners: [Vec3; 3],
    pub(super) normal: Vec3,
    pub(super) area: f32,
    pub(super) normals: Vec<Vec3>,
    pub(super) emission: Vec3,
    pub(super) object: usize,
    pub(super) triangle: usize,
}

pub(super) struct Ctx<'a> {
    pub(super) scene: &'a Scene,
    pub(super) params: &'a BakeParams,
    pub(super) roots: Vec<Root>,
    pub(super) clusters: ClusterTree,
    /// Per scene object, a cluster hierarchy over its own triangles alone (indices local to
    /// the object) and the index of its first root. The scene's hierarchy mixes a room's
    /// large triangles with an object's small ones, so its clusters around a small receiver
    /// hold only a sliver of the object; these give the receivers around one (`refine_root`).
    pub(super) object_clusters: Vec<(ClusterTree, u32)>,
    pub(super) occ: Occluders,
    /// The root each occluder triangle belongs to.
    pub(super) occ_owner: Vec<u32>,
    /// Per root: its object's occluder triangles over it, by path at their level (empty where
    /// the object casts shadows with its own triangles): rays leave from and arrive at the
    /// points of this surface that correspond to the root's ([`Ctx::on_surface`]).
    pub(super) surface: Vec<Vec<[Vec3; 3]>>,
    /// Per root: its [`lattice_frame`](super::surface::lattice_frame), which every point
    /// carried onto its surface reads.
    pub(super) frames: Vec<[f32; 4]>,
    /// Per root: its corners carried onto its refined surface ([`Ctx::on_surface`]); its own
    /// corners where it has none. The triangle that stands for it where its refined triangles
    /// would be too many to sum: in clusters, and as a far source.
    pub(super) shape: Vec<[Vec3; 3]>,
    /// Per cluster: whether it holds emitting triangles beside others. Such a cluster is
    /// always opened: as one source it spread the emitters' light as if it left the whole
    /// cluster, and a room lit by a panel under its ceiling came out 2-6% darker than a path
    /// tracer shows it, one wall darker than its mirror image (`tests/objects_reference.rs`).
    pub(super) mixes_emitters: Vec<bool>,
    /// Per cluster: the parts a link to it reads apart when it reads deep
    /// ([`read_parts`](super::cluster::read_parts)),
    /// found once rather than walked for every link in every iteration.
    pub(super) read_parts: Vec<([ClusterChild; READ_PARTS], u8)>,
    /// Per root: nothing but the scene's outer boundary lies in front of its plane (the convex
    /// side of an object in a room), so that no link it receives needs rays
    /// ([`Occluders::shaft_clear`] over the whole scene, once per root instead of per link).
    pub(super) unobstructed: Vec<bool>,
    /// Whether the scene's outer boundary closes it ([`Ctx::boundary_closed`]), found once.
    pub(super) boundary_closed: OnceLock<bool>,
    /// Per cluster: the object all its triangles belong to, if one.
    pub(super) cluster_object: Vec<Option<u32>>,
    /// Per scene object: its triangles form a convex surface ([`ClusterTree::is_convex`]), so
    /// that a point on one sees none of the others.
    pub(super) convex: Vec<bool>,
    /// Per scene object: the smallest element area it is split to
    /// ([`BakeParams::min_area_fraction`] of the object's area, or of a sixteenth of the
    /// scene's).
    pub(super) min_area: Vec<f32>,
    /// Distances to a plane below this count as lying in it (rounding of coplanar
    /// geometry), relative to the scene size.
    pub(super) plane_eps: f32,
    /// [`LIGHT_EMISSION`] times the scene's emission luminance averaged over all its area
    /// ([`Ctx::lights`]).
    pub(super) light_floor: f32,
    /// Per root: what the rules judged by the geometry alone found for its elements, kept
    /// from pass to pass ([`Ctx::memo`]).
    pub(super) memos: Vec<Mutex<HashMap<ElemKey, GeometryMemo>>>,
}

/// What [`Ctx::near_shadow`], [`Ctx::self_shade_varies`], [`Ctx::open_fraction`] and the
/// enclosure rules found for one element, `None` where not asked yet. They depend on the
/// geometry alone, so each element's value is found once for the whole bake (every pass
/// judged them again: an eighth of the scaling scene's bake). One map a root, of these: a map
/// a rule was five tables for every root of a million-triangle scene, 0.7 GB.
#[derive(Default)]
pub(super) struct GeometryMemo {
    pub(super) near_shadow: Option<bool>,
    pub(super) shade_varies: Option<bool>,
    pub(super) closed: Option<bool>,
    pub(super) open: Option<f32>,
    pub(super) enclosed: Option<f32>,
}

pub(super) fn lum(v: Vec3) -> f32 {
    v.max_element()
}

/// How many times the scene's mean emission an emitter sends to count as a light
/// ([`Ctx::lights`]).
pub(super) const LIGHT_EMISSION: f32 = 2.0;

impl Ctx<'_> {
    pub(super) fn nn(&self, r: u32) -> usize {
        self.roots[r as usize].normals.len()
    }

    /// The object occluder triangle `t` belongs to.
    pub(super) fn owner_object(&self, t: usize) -> usize {
        self.roots[self.occ_owner[t] as usize].object
    }

    /// The smallest area an element of `k`'s object is split to.
    pub(super) fn min_area_of(&self, k: ElemKey) -> f32 {
        self.min_area[self.roots[k.root as usize].object]
    }

    pub(super) fn elem_corners(&self, k: ElemKey) -> [Vec3; 3] {
        k.corners(self.roots[k.root as usize].corners)
    }

    pub(super) fn splittable(&self, k: ElemKey, area: f32) -> bool {
        k.level < self.params.max_level.min(MAX_TREE_DEPTH) && area * 0.25 >= self.min_area_of(k)
    }

    /// Whether a rule judged against the receiver's own radiance may split `k`
    /// ([`BakeParams::detail_level`]).
    pub(super) fn detail_splittable(&self, k: ElemKey, area: f32) -> bool {
        k.level < self.params.detail_level.min(MAX_TREE_DEPTH) && area * 0.25 >= self.min_area_of(k)
    }

    /// Whether `src` is a light: an element emitting more than [`LIGHT_EMISSION`] times the
    /// scene's mean emission over all its area (`light_floor`), so that its direct light and
    /// its shadows are what the surfaces around it show most (a cluster holding an emitter is
    /// always opened, so only elements are asked). In a closed furnace, where every surface
    /// emits alike, none is.
    pub(super) fn lights(&self, src: Source) -> bool {
        match src {
            Source::Elem(sk) => self.is_light(sk.root),
            Source::Cluster(_) => false,
        }
    }

    /// Whether root `r` is part of a light ([`Ctx::lights`]).
    pub(super) fn is_light(&self, r: u32) -> bool {
        lum(self.roots[r as usize].emission) > self.light_floor
    }

    /// Whether root `r`, with its geometric normal alone, sees nothing of object `object`: its
    /// own object, convex (a block, a sphere). Such pairs (half of those the scaling scene's
    /// sphere met) have no positive form factor, and computing it took a walk of the clusters
    /// nearest the receiver.
    pub(super) fn sees_none_of_own(&self, r: u32, object: usize) -> bool {
        let own = self.roots[r as usize].object;
        own == object && self.convex[own]
    }

    pub(super) fn reflectance(&self, k: ElemKey) -> Vec3 {
        let root = &self.roots[k.root as usize];
        let obj = &self.scene.objects[root.object];
        let r = match &obj.reflectance_fn {
            Some(f) => f(root.triangle, k.barycentric()),
            None => obj.reflectance[root.triangle],
        };
        Vec3::from(r).clamp(Vec3::ZERO, Vec3::ONE)
    }

    /// `find()`, the value of a rule judged by the geometry alone for element `k`, found once:
    /// `pick` chooses the rule's value in its [`GeometryMemo`]. The lock is not held while
    /// `find` runs; parts of the refinement running in parallel may both find a value, and
    /// find the same one.
    pub(super) fn memo<T: Copy>(
        &self,
        k: ElemKey,
        pick: impl Fn(&mut GeometryMemo) -> &mut Option<T>,
        find: impl FnOnce() -> T,
    ) -> T {
        let memo = &self.memos[k.root as usize];
        let known = memo
            .lock()
            .unwrap_or_else(|e| e.into_inner())
            .get_mut(&k)
            .and_then(|m| *pick(m));
        if let Some(v) = known {
            return v;
        }
        let v = find();
        *pick(
            memo.lock()
                .unwrap_or_else(|e| e.into_inner())
                .entry(k)
                .or_default(),
        ) = Some(v);
        v
    }
}
