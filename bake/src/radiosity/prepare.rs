//! [`Ctx::new`]: what the solver finds about a scene once, before its first pass: the roots,
//! the cluster hierarchies (the scene's and each object's), the occluders with each root's
//! refined surface, and the per-root, per-cluster and per-object figures the passes read.

use std::sync::{Mutex, OnceLock};

use glam::Vec3;
use rayon::prelude::*;

use super::cluster::{read_parts, ClusterTree};
use super::context::{lum, Ctx, Root, LIGHT_EMISSION};
use super::params::BakeParams;
use super::surface::{lattice_frame, surface_point};
use crate::scene::Scene;
use crate::visibility::Occluders;
use crate::BakeError;

impl<'a> Ctx<'a> {
    /// Everything the solver reads about `scene`: its roots, cluster hierarchies, occluders,
    /// refined surfaces and the figures found once per bake.
    pub(super) fn new(scene: &'a Scene, params: &'a BakeParams) -> Result<Ctx<'a>, BakeError> {
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
        Ok(Ctx {
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
            frames: roots.iter().map(|r| lattice_frame(r.corners)).collect(),
            min_area: {
                let mut area = vec![0.0f64; scene.objects.len()];
                for r in &roots {
                    area[r.object] += f64::from(r.area);
                }
                let scene_area: f64 = area.iter().sum();
                area.iter()
                    .map(|a| {
                        (a.max(scene_area / 16.0) * f64::from(params.min_area_fraction)) as f32
                    })
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
        })
    }
}
