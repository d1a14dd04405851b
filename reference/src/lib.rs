//! # hce-reference
//!
//! An independent Monte-Carlo path tracer for diffuse scenes, to check the radiosity solver
//! and the rendered results against (Kajiya, "The rendering equation", SIGGRAPH 1986;
//! next-event estimation and Russian roulette as in Arvo & Kirk, "Particle transport and image
//! synthesis", SIGGRAPH 1990).
//!
//! It reads the same [`Scene`] model as the solver but shares none of its code: no elements,
//! form factors, clusters, links or visibility module. Rays are intersected with the triangles
//! through its own `obvhs` BVH (a compressed wide BVH, Ylitie et al. 2017) that only culls: every
//! candidate triangle is tested in double precision (Möller & Trumbore 1997), exactly as
//! [`Accel::BruteForce`] tests every triangle in turn, so both give the same paths.
//!
//! The physics are the solver's, restated independently: every triangle is one-sided (it emits
//! and reflects from its front, the side its counter-clockwise winding faces; seen from behind
//! it is black, though it still blocks light); reflection is Lambertian with the triangle's
//! reflectance (per-triangle `reflectance`; texture hooks are not evaluated); emission is
//! radiance; punctual lights follow KHR_lights_punctual (candela, lux, the range window and the
//! smooth spot falloff).
//!
//! Smooth shading ([`PathTracer::set_vertex_normals`]): an object may carry unit vertex
//! normals; wherever a path meets one of its triangles, the cosines of the irradiance and the
//! bounce direction use the normal interpolated at the hit instead of the flat one, so the
//! object reflects as the smooth surface its normals describe (a Loop-refined mesh, say), while
//! rays still meet, leave and are blocked by the true triangles. Light arriving from below the
//! triangle's own plane and bounces that would enter it count as nothing.
//!
//! [`surface_radiance`](PathTracer::surface_radiance) estimates the area-averaged outgoing
//! radiance of a set of triangles and [`radiance_along`](PathTracer::radiance_along) the
//! radiance seen along a camera ray: `L = Le + ρ E / π` at the surface point, with the
//! irradiance `E` from one emitter sample (by area), every punctual light through a shadow ray,
//! and one cosine-distributed bounce that continues the path (emission found by a bounce is not
//! counted: the emitter samples already carry it). Paths end by Russian roulette on the
//! reflectance, with a hard cap of [`MAX_BOUNCES`] bounces so that nothing can loop forever.
//!
//! Deterministic: path `i` of a surface query draws its random numbers from its own generator,
//! seeded by `(seed, i)`, every pixel of an image from one seeded by `(seed, pixel)`, and sums
//! are taken in a fixed order, so results do not depend on the number of threads.
#![forbid(unsafe_code)]

use std::time::Duration;

use glam::{DVec3, Vec3A};
use obvhs::{
    cwbvh::{builder::build_cwbvh_from_tris, CwBvh},
    ray::{Ray, RayHit},
    triangle::Triangle,
    BvhBuildParams,
};
use rayon::prelude::*;

use hce_meshio::solver_scene::{LightKind, Scene};

/// Bounces after which a path stops whatever its weight (0.95^64 < 4 %; with Cornell box
/// reflectances the truncated energy is far below the noise).
pub const MAX_BOUNCES: u32 = 64;

/// Paths per parallel chunk (the unit of work and of the fixed-order sum).
const CHUNK: u64 = 1024;

/// Stream of the pixel generators, apart from the surface queries' `(seed, path)` streams.
const PIXEL_STREAM: u64 = 0x7069_7865_6c73;

/// One triangle with everything a path needs.
struct Tri {
    p0: DVec3,
    e1: DVec3,
    e2: DVec3,
    /// Unit geometric normal (front side).
    n: DVec3,
    /// Unit vertex normals for smooth shading, when the object has them.
    shading: Option<[DVec3; 3]>,
    area: f64,
    rho: DVec3,
    le: DVec3,
}

impl Tri {
    /// The shading normal at barycentric `(u, v)` (weights of corners 1 and 2): the
    /// interpolated vertex normal where there is one on the front side, else the flat normal.
    fn normal_at(&self, u: f64, v: f64) -> DVec3 {
        match self.shading {
            Some([a, b, c]) => {
                let s = (a * (1.0 - u - v) + b * u + c * v).normalize_or_zero();
                if s.dot(self.n) > 0.0 {
                    s
                } else {
                    self.n
                }
            }
            None => self.n,
        }
    }
}

/// How rays find triangles.
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq)]
pub enum Accel {
    /// A BVH over every triangle (the default).
    #[default]
    Bvh,
    /// Every triangle in turn: linear in the triangle count, kept as the plainest statement of
    /// the intersection to check the BVH against.
    BruteForce,
}

/// Where a ray meets the scene.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Hit {
    /// Object index in the scene.
    pub object: usize,
    /// Triangle index in the object.
    pub triangle: usize,
    pub distance: f64,
    /// Whether the ray met the triangle's back (which is black).
    pub back: bool,
}

/// A scene prepared for path tracing.
pub struct PathTracer<'a> {
    scene: &'a Scene,
    tris: Vec<Tri>,
    /// First triangle of each object in `tris`.
    object_start: Vec<usize>,
    bvh: Option<CwBvh>,
    /// Emissive triangles and the cumulative distribution of their area × luminance.
    emitters: Vec<usize>,
    emitter_cdf: Vec<f64>,
    /// Ray origins are moved this far off their surface (relative to the scene size).
    eps: f64,
}

/// An estimate and its standard error, per channel.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Estimate {
    pub mean: [f64; 3],
    pub std_error: [f64; 3],
    pub paths: u64,
}

/// A small PCG-style generator (O'Neill 2014, XSH-RR output), seeded per path.
struct Pcg(u64);

impl Pcg {
    fn new(seed: u64, stream: u64) -> Self {
        let mut g = Pcg(0);
        g.0 = splitmix(seed ^ splitmix(stream.wrapping_add(0x9e37_79b9_7f4a_7c15)));
        g.next_u32();
        g
    }

    fn next_u32(&mut self) -> u32 {
        let old = self.0;
        self.0 = old
            .wrapping_mul(6_364_136_223_846_793_005)
            .wrapping_add(1_442_695_040_888_963_407);
        let x = (((old >> 18) ^ old) >> 27) as u32;
        x.rotate_right((old >> 59) as u32)
    }

    /// Uniform in [0, 1).
    fn next(&mut self) -> f64 {
        let hi = u64::from(self.next_u32()) << 21;
        let lo = u64::from(self.next_u32() >> 11);
        ((hi | lo) as f64) / (1u64 << 53) as f64
    }
}

fn splitmix(mut z: u64) -> u64 {
    z = z.wrapping_add(0x9e37_79b9_7f4a_7c15);
    z = (z ^ (z >> 30)).wrapping_mul(0xbf58_476d_1ce4_e5b9);
    z = (z ^ (z >> 27)).wrapping_mul(0x94d0_49bb_1331_11eb);
    z ^ (z >> 31)
}

/// A uniform point on a triangle and its barycentric `(u, v)`.
fn point_on(t: &Tri, rng: &mut Pcg) -> (DVec3, f64, f64) {
    let (mut u, mut v) = (rng.next(), rng.next());
    if u + v > 1.0 {
        u = 1.0 - u;
        v = 1.0 - v;
    }
    (t.p0 + t.e1 * u + t.e2 * v, u, v)
}

/// A cosine-distributed direction around the unit normal `n` (Malley's method).
fn cosine_direction(n: DVec3, rng: &mut Pcg) -> DVec3 {
    let (u1, u2) = (rng.next(), rng.next());
    let r = u1.sqrt();
    let phi = 2.0 * std::f64::consts::PI * u2;
    let a = if n.x.abs() < 0.9 { DVec3::X } else { DVec3::Y };
    let t = n.cross(a).normalize();
    let b = n.cross(t);
    (t * (r * phi.cos()) + b * (r * phi.sin()) + n * (1.0 - u1).max(0.0).sqrt()).normalize()
}

/// Möller-Trumbore: distance and barycentric `(u, v)` where the ray meets `t`, if it does.
fn intersect(t: &Tri, o: DVec3, d: DVec3) -> Option<(f64, f64, f64)> {
    let p = d.cross(t.e2);
    let det = t.e1.dot(p);
    if det.abs() < 1e-300 {
        return None;
    }
    let inv = 1.0 / det;
    let s = o - t.p0;
    let u = s.dot(p) * inv;
    if !(0.0..=1.0).contains(&u) {
        return None;
    }
    let q = s.cross(t.e1);
    let v = d.dot(q) * inv;
    if v < 0.0 || u + v > 1.0 {
        return None;
    }
    Some((t.e2.dot(q) * inv, u, v))
}

/// The f32 ray `obvhs` traverses with; `None` when the ray cannot be represented. A negative
/// zero in the direction is made positive (`-0.0 + 0.0` is `+0.0`): its reciprocal is `-inf`,
/// for which the BVH's slab test misses every box.
fn bvh_ray(o: DVec3, d: DVec3) -> Option<Ray> {
    let (o, d) = (o.as_vec3a(), d.as_vec3a());
    (o.is_finite() && d.is_finite()).then(|| Ray::new(o, d + Vec3A::ZERO, 0.0, f32::INFINITY))
}

/// A distance the BVH may prune beyond without losing a hit at `dist` (rounded up).
fn prune_at(dist: f64) -> f32 {
    (dist as f32) * (1.0 + 4.0 * f32::EPSILON) + f32::MIN_POSITIVE
}

impl<'a> PathTracer<'a> {
    /// Prepares `scene` with a BVH; objects, triangles and lights are used as they are (call
    /// [`Scene::validate`] first for a clear error on bad input).
    pub fn new(scene: &'a Scene) -> Self {
        Self::with_accel(scene, Accel::Bvh)
    }

    /// Prepares `scene`, finding triangles as `accel` says.
    pub fn with_accel(scene: &'a Scene, accel: Accel) -> Self {
        let mut tris = Vec::with_capacity(scene.triangle_count());
        let mut object_start = Vec::with_capacity(scene.objects.len());
        let (mut lo, mut hi) = (DVec3::splat(f64::MAX), DVec3::splat(f64::MIN));
        for o in &scene.objects {
            object_start.push(tris.len());
            for t in 0..o.triangles.len() {
                let [a, b, c] = o.corners(t).map(|v| v.as_dvec3());
                for v in [a, b, c] {
                    lo = lo.min(v);
                    hi = hi.max(v);
                }
                let cr = (b - a).cross(c - a);
                tris.push(Tri {
                    p0: a,
                    e1: b - a,
                    e2: c - a,
                    n: cr.normalize_or_zero(),
                    shading: None,
                    area: 0.5 * cr.length(),
                    rho: DVec3::from(o.reflectance[t].map(f64::from)),
                    le: DVec3::from(o.emission_of(t).map(f64::from)),
                });
            }
        }
        let mut emitters = Vec::new();
        let mut emitter_cdf = Vec::new();
        let mut acc = 0.0;
        for (i, t) in tris.iter().enumerate() {
            let w = t.area * t.le.max_element();
            if w > 0.0 {
                acc += w;
                emitters.push(i);
                emitter_cdf.push(acc);
            }
        }
        let diag = if tris.is_empty() {
            1.0
        } else {
            (hi - lo).length()
        };
        let bvh = (accel == Accel::Bvh && !tris.is_empty()).then(|| {
            let boxes: Vec<Triangle> = tris
                .iter()
                .map(|t| Triangle {
                    v0: t.p0.as_vec3a(),
                    v1: (t.p0 + t.e1).as_vec3a(),
                    v2: (t.p0 + t.e2).as_vec3a(),
                })
                .collect();
            build_cwbvh_from_tris(
                &boxes,
                BvhBuildParams::medium_build(),
                &mut Duration::default(),
            )
        });
        PathTracer {
            scene,
            tris,
            object_start,
            bvh,
            emitters,
            emitter_cdf,
            eps: diag.max(1e-9) * 1e-7,
        }
    }

    /// Gives object `object` smooth shading: `normals` are its world-space vertex normals,
    /// one per position (see the module documentation). Errors name a wrong count.
    pub fn set_vertex_normals(
        &mut self,
        object: usize,
        normals: &[[f32; 3]],
    ) -> Result<(), String> {
        let o = self
            .scene
            .objects
            .get(object)
            .ok_or_else(|| format!("object {object} does not exist"))?;
        if normals.len() != o.positions.len() {
            return Err(format!(
                "object '{}': {} normals for {} vertices",
                o.name,
                normals.len(),
                o.positions.len()
            ));
        }
        let start = self.object_start[object];
        for (t, tri) in o.triangles.iter().enumerate() {
            let n =
                tri.map(|v| DVec3::from(normals[v as usize].map(f64::from)).normalize_or_zero());
            self.tris[start + t].shading = Some(n);
        }
        Ok(())
    }

    /// The triangle (index in `tris`), distance and barycentric `(u, v)` of the nearest hit of
    /// the ray `o + t d` with `eps < t < max_t`.
    fn nearest(&self, o: DVec3, d: DVec3, max_t: f64) -> Option<(usize, f64, f64, f64)> {
        let mut best: Option<(usize, f64, f64, f64)> = None;
        let mut limit = max_t;
        let mut test = |i: usize| -> f32 {
            match intersect(&self.tris[i], o, d) {
                Some((dist, u, v)) if dist > self.eps && dist < limit => {
                    limit = dist;
                    best = Some((i, dist, u, v));
                    prune_at(dist)
                }
                _ => f32::INFINITY,
            }
        };
        match (&self.bvh, bvh_ray(o, d)) {
            (Some(bvh), Some(ray)) => {
                let mut hit = RayHit::none();
                bvh.ray_traverse(ray, &mut hit, |_, id| {
                    test(bvh.primitive_indices[id] as usize)
                });
            }
            (Some(_), None) => {}
            (None, _) => {
                for i in 0..self.tris.len() {
                    test(i);
                }
            }
        }
        best
    }

    /// Whether any triangle lies on the ray `o + t d` with `eps < t < max_t`.
    fn blocked(&self, o: DVec3, d: DVec3, max_t: f64) -> bool {
        let test = |i: usize| {
            intersect(&self.tris[i], o, d).is_some_and(|(t, _, _)| t > self.eps && t < max_t)
        };
        match (&self.bvh, bvh_ray(o, d)) {
            (Some(bvh), Some(ray)) => !bvh.ray_traverse_miss(ray, |_, id| {
                if test(bvh.primitive_indices[id] as usize) {
                    0.0
                } else {
                    f32::INFINITY
                }
            }),
            (Some(_), None) => false,
            (None, _) => (0..self.tris.len()).any(test),
        }
    }

    fn clear(&self, from: DVec3, to: DVec3) -> bool {
        let d = to - from;
        let len = d.length();
        len <= 2.0 * self.eps || !self.blocked(from, d / len, len - 2.0 * self.eps)
    }

    /// Irradiance / π at `x` on a triangle of flat normal `ng`, for the shading normal `n`,
    /// straight from the emitters (one sample) and the punctual lights.
    fn direct(&self, x: DVec3, ng: DVec3, n: DVec3, rng: &mut Pcg) -> DVec3 {
        let origin = x + ng * self.eps;
        let mut e = DVec3::ZERO;
        if let Some(&total) = self.emitter_cdf.last() {
            let u = rng.next() * total;
            let k = self.emitter_cdf.partition_point(|&c| c <= u);
            let k = k.min(self.emitters.len() - 1);
            let t = &self.tris[self.emitters[k]];
            let pdf_pick = (t.area * t.le.max_element()) / total;
            let (y, _, _) = point_on(t, rng);
            let to = y - origin;
            let d2 = to.length_squared();
            if d2 > 0.0 {
                let w = to / d2.sqrt();
                let (cos_x, cos_y) = (n.dot(w), t.n.dot(-w));
                if cos_x > 0.0 && ng.dot(w) > 0.0 && cos_y > 0.0 && self.clear(origin, y) {
                    // pdf by area = pdf_pick / area.
                    e += t.le * (cos_x * cos_y / d2) * (t.area / pdf_pick) / std::f64::consts::PI;
                }
            }
        }
        for l in &self.scene.lights {
            let colour = DVec3::from(l.color.map(f64::from)) * f64::from(l.intensity);
            let (w, dist, scale) = match l.kind {
                LightKind::Directional => {
                    let w = -DVec3::from(l.direction.map(f64::from)).normalize();
                    (w, f64::INFINITY, 1.0)
                }
                LightKind::Point | LightKind::Spot { .. } => {
                    let to = DVec3::from(l.position.map(f64::from)) - origin;
                    let dist = to.length();
                    if dist <= 0.0 {
                        continue;
                    }
                    let w = to / dist;
                    let mut s = 1.0 / (dist * dist);
                    if let Some(r) = l.range {
                        s *= (1.0 - (dist / f64::from(r)).powi(4)).clamp(0.0, 1.0);
                    }
                    if let LightKind::Spot {
                        inner_cone_angle,
                        outer_cone_angle,
                    } = l.kind
                    {
                        let axis = DVec3::from(l.direction.map(f64::from)).normalize();
                        let (ci, co) = (
                            f64::from(inner_cone_angle).cos(),
                            f64::from(outer_cone_angle).cos(),
                        );
                        let scale_a = 1.0 / (ci - co).max(1e-3);
                        let a = ((-w).dot(axis) * scale_a - co * scale_a).clamp(0.0, 1.0);
                        s *= a * a;
                    }
                    (w, dist, s)
                }
            };
            let cos_x = n.dot(w);
            if cos_x <= 0.0 || ng.dot(w) <= 0.0 || scale <= 0.0 {
                continue;
            }
            let blocked = if dist.is_finite() {
                !self.clear(origin, origin + w * dist)
            } else {
                self.blocked(origin, w, f64::INFINITY)
            };
            if !blocked {
                e += colour * (scale * cos_x / std::f64::consts::PI);
            }
        }
        e
    }

    /// Reflected radiance (without emission) leaving point `x` (barycentric `(u, v)`) of
    /// triangle `at`, by one path.
    fn reflected(&self, at: usize, x: DVec3, uv: (f64, f64), rng: &mut Pcg) -> DVec3 {
        let mut total = DVec3::ZERO;
        let mut weight = DVec3::ONE;
        let (mut at, mut x, mut uv) = (at, x, uv);
        for _ in 0..MAX_BOUNCES {
            let t = &self.tris[at];
            weight *= t.rho;
            if weight.max_element() <= 0.0 {
                break;
            }
            let n = t.normal_at(uv.0, uv.1);
            total += weight * self.direct(x, t.n, n, rng);
            // Russian roulette on this surface's reflectance: unbiased, and it ends dark paths.
            let survive = t.rho.max_element().clamp(0.05, 0.95);
            if rng.next() >= survive {
                break;
            }
            weight /= survive;
            let d = cosine_direction(n, rng);
            // A bounce around a shading normal may point into the triangle: it carries nothing.
            if d.dot(t.n) <= 0.0 {
                break;
            }
            let origin = x + t.n * self.eps;
            let Some((hit, dist, u, v)) = self.nearest(origin, d, f64::INFINITY) else {
                break;
            };
            // A triangle seen from behind is black.
            if self.tris[hit].n.dot(d) >= 0.0 {
                break;
            }
            at = hit;
            x = origin + d * dist;
            uv = (u, v);
        }
        total
    }

    /// The object and triangle of `tris[i]`.
    fn locate(&self, i: usize) -> (usize, usize) {
        let object = self.object_start.partition_point(|&s| s <= i) - 1;
        (object, i - self.object_start[object])
    }

    /// What the ray from `origin` along unit `dir` meets first, if anything.
    pub fn first_hit(&self, origin: [f64; 3], dir: [f64; 3]) -> Option<Hit> {
        let (o, d) = (DVec3::from(origin), DVec3::from(dir));
        self.nearest(o, d, f64::INFINITY)
            .map(|(i, distance, _, _)| {
                let (object, triangle) = self.locate(i);
                Hit {
                    object,
                    triangle,
                    distance,
                    back: self.tris[i].n.dot(d) >= 0.0,
                }
            })
    }

    fn radiance_with(&self, o: DVec3, d: DVec3, paths: u32, rng: &mut Pcg) -> (DVec3, Option<Hit>) {
        let Some((i, distance, u, v)) = self.nearest(o, d, f64::INFINITY) else {
            return (DVec3::ZERO, None);
        };
        let (object, triangle) = self.locate(i);
        let t = &self.tris[i];
        let back = t.n.dot(d) >= 0.0;
        let hit = Hit {
            object,
            triangle,
            distance,
            back,
        };
        if back || paths == 0 {
            return (if back { DVec3::ZERO } else { t.le }, Some(hit));
        }
        let x = o + d * distance;
        let mut sum = DVec3::ZERO;
        for _ in 0..paths {
            sum += self.reflected(i, x, (u, v), rng);
        }
        (t.le + sum / f64::from(paths), Some(hit))
    }

    /// Outgoing radiance `Le + ρ E / π` at the first surface the ray from `origin` along unit
    /// `dir` meets (the ray's own point, averaged over `paths` paths from it; zero on a
    /// triangle's back or when nothing is met), and that hit. Seeded by `(seed, stream)`.
    pub fn radiance_along(
        &self,
        origin: [f64; 3],
        dir: [f64; 3],
        paths: u32,
        seed: u64,
        stream: u64,
    ) -> ([f64; 3], Option<Hit>) {
        let mut rng = Pcg::new(seed, stream);
        let (l, hit) = self.radiance_with(DVec3::from(origin), DVec3::from(dir), paths, &mut rng);
        (l.to_array(), hit)
    }

    /// An image: pixel `(x, y)` (rows top to bottom) is the mean over its `positions` sample
    /// positions `s` of [`Self::radiance_along`] the ray `ray(x, y, s)` gives, the `paths`
    /// shared out among them (the first `paths % positions` get one more), all seeded by
    /// `(seed, pixel index)`; with one position, the ray's radiance over all `paths`. The hit is
    /// the one every position sees (same object and side), else `None`. Rows run in parallel;
    /// `row_done` is called once per finished row (from any thread). Deterministic for any
    /// thread count.
    #[allow(clippy::too_many_arguments)]
    pub fn render(
        &self,
        width: u32,
        height: u32,
        paths: u32,
        positions: usize,
        seed: u64,
        ray: impl Fn(u32, u32, usize) -> ([f64; 3], [f64; 3]) + Sync,
        row_done: impl Fn() + Sync,
    ) -> Vec<([f32; 3], Option<Hit>)> {
        let positions = positions.max(1);
        (0..height)
            .into_par_iter()
            .flat_map_iter(|y| {
                let row: Vec<([f32; 3], Option<Hit>)> = (0..width)
                    .map(|x| {
                        let pixel = u64::from(y) * u64::from(width) + u64::from(x);
                        let mut rng = Pcg::new(seed ^ PIXEL_STREAM, pixel);
                        let mut sum = DVec3::ZERO;
                        let mut shared: Option<Option<Hit>> = None;
                        for s in 0..positions {
                            let (o, d) = ray(x, y, s);
                            // Paths shared out: the first `paths % positions` get one more.
                            let n = paths / positions as u32
                                + u32::from((s as u32) < paths % positions as u32);
                            let (l, hit) =
                                self.radiance_with(DVec3::from(o), DVec3::from(d), n, &mut rng);
                            sum += l;
                            let same = |a: &Option<Hit>| match (a, &hit) {
                                (Some(a), Some(h)) => a.object == h.object && a.back == h.back,
                                (None, None) => true,
                                _ => false,
                            };
                            shared = match shared {
                                None => Some(hit),
                                Some(first) if same(&first) => Some(first),
                                Some(_) => Some(None),
                            };
                        }
                        let l = sum / positions as f64;
                        (l.as_vec3().to_array(), shared.flatten())
                    })
                    .collect();
                row_done();
                row
            })
            .collect()
    }

    /// Area-averaged outgoing radiance over triangles `triangles` of object `object`, from
    /// `paths` paths seeded by `seed`. Empty or zero-area sets give zero.
    pub fn surface_radiance(
        &self,
        object: usize,
        triangles: &[usize],
        paths: u64,
        seed: u64,
    ) -> Estimate {
        let start = self.object_start.get(object).copied().unwrap_or(0);
        let ids: Vec<usize> = triangles
            .iter()
            .map(|&t| start + t)
            .filter(|&i| i < self.tris.len())
            .collect();
        let mut cdf = Vec::with_capacity(ids.len());
        let mut area = 0.0;
        for &i in &ids {
            area += self.tris[i].area;
            cdf.push(area);
        }
        if area <= 0.0 || paths == 0 {
            return Estimate {
                mean: [0.0; 3],
                std_error: [0.0; 3],
                paths: 0,
            };
        }
        // Emission is the same at every point of a triangle: add its area average exactly.
        let le: DVec3 = ids
            .iter()
            .map(|&i| self.tris[i].le * self.tris[i].area)
            .sum::<DVec3>()
            / area;
        let chunks = paths.div_ceil(CHUNK);
        let sums: Vec<(DVec3, DVec3)> = (0..chunks)
            .into_par_iter()
            .map(|c| {
                let (mut s, mut s2) = (DVec3::ZERO, DVec3::ZERO);
                for i in c * CHUNK..((c + 1) * CHUNK).min(paths) {
                    let mut rng = Pcg::new(seed ^ splitmix(object as u64), i);
                    let u = rng.next() * area;
                    let k = cdf.partition_point(|&a| a <= u).min(ids.len() - 1);
                    let at = ids[k];
                    let (x, bu, bv) = point_on(&self.tris[at], &mut rng);
                    let v = self.reflected(at, x, (bu, bv), &mut rng);
                    s += v;
                    s2 += v * v;
                }
                (s, s2)
            })
            .collect();
        let (mut s, mut s2) = (DVec3::ZERO, DVec3::ZERO);
        for (a, b) in sums {
            s += a;
            s2 += b;
        }
        let n = paths as f64;
        let mean = s / n;
        let var = (s2 / n - mean * mean).max(DVec3::ZERO);
        Estimate {
            mean: (le + mean).to_array(),
            std_error: (var / n).sqrt().to_array(),
            paths,
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use hce_meshio::solver_scene::{PunctualLight, SolverObject};

    fn quad(o: [f32; 3], u: [f32; 3], v: [f32; 3]) -> ([[f32; 3]; 4], [[u32; 3]; 2]) {
        let p = |a: f32, b: f32| [0, 1, 2].map(|k| o[k] + a * u[k] + b * v[k]);
        (
            [p(0., 0.), p(1., 0.), p(1., 1.), p(0., 1.)],
            [[0, 1, 2], [0, 2, 3]],
        )
    }

    #[test]
    fn furnace_box_gives_emission_over_one_minus_reflectance() {
        // The inside of the unit cube, every face facing inwards.
        let faces = [
            ([0., 0., 0.], [1., 0., 0.], [0., 1., 0.]),
            ([0., 0., 1.], [0., 1., 0.], [1., 0., 0.]),
            ([0., 0., 0.], [0., 1., 0.], [0., 0., 1.]),
            ([1., 0., 0.], [0., 0., 1.], [0., 1., 0.]),
            ([0., 0., 0.], [0., 0., 1.], [1., 0., 0.]),
            ([0., 1., 0.], [1., 0., 0.], [0., 0., 1.]),
        ];
        let (mut pos, mut tris) = (Vec::new(), Vec::new());
        for (o, u, v) in faces {
            let (p, t) = quad(o, u, v);
            let b = pos.len() as u32;
            pos.extend(p);
            tris.extend(t.map(|t| t.map(|i| i + b)));
        }
        let scene = Scene {
            objects: vec![SolverObject::new("box", pos, tris, [0.5; 3]).with_emission([1.0; 3])],
            lights: Vec::new(),
        };
        let pt = PathTracer::new(&scene);
        let e = pt.surface_radiance(0, &[0, 1], 20000, 1);
        for k in 0..3 {
            assert!((e.mean[k] - 2.0).abs() < 0.03, "{e:?}");
        }
        // The same seed gives the same estimate, whatever the thread count.
        let one = rayon::ThreadPoolBuilder::new()
            .num_threads(1)
            .build()
            .unwrap()
            .install(|| pt.surface_radiance(0, &[0, 1], 20000, 1));
        assert_eq!(one, e);
    }

    /// Rays with a zero direction component meet what brute force meets, whatever the zero's
    /// sign: a direction negated from one with a `+0.0` component has `-0.0` there, and the
    /// BVH's slab test missed every box for it (a ray along a block's face from the floor
    /// found nothing).
    #[test]
    fn rays_with_signed_zero_components_hit_as_brute_force_does() {
        // Two boxes, one standing on a floor quad.
        let (mut pos, mut tris) = (Vec::new(), Vec::new());
        let mut add = |o: [f32; 3], u: [f32; 3], v: [f32; 3]| {
            let (p, t) = quad(o, u, v);
            let b = pos.len() as u32;
            pos.extend(p);
            tris.extend(t.map(|t| t.map(|i| i + b)));
        };
        add([-1.0, 0.0, -1.0], [0.0, 0.0, 2.0], [2.0, 0.0, 0.0]);
        for (x, z) in [(0.1f32, 0.05f32), (-0.6, -0.4)] {
            let (w, h) = (0.3f32, 0.2f32);
            add([x, 0.0, z], [w, 0.0, 0.0], [0.0, h, 0.0]);
            add([x + w, 0.0, z], [0.0, 0.0, w], [0.0, h, 0.0]);
            add([x + w, 0.0, z + w], [-w, 0.0, 0.0], [0.0, h, 0.0]);
            add([x, 0.0, z + w], [0.0, 0.0, -w], [0.0, h, 0.0]);
            add([x, h, z], [0.0, 0.0, w], [w, 0.0, 0.0]);
        }
        let scene = Scene {
            objects: vec![SolverObject::new("boxes", pos, tris, [0.5; 3])],
            lights: Vec::new(),
        };
        let bvh = PathTracer::new(&scene);
        let brute = PathTracer::with_accel(&scene, Accel::BruteForce);
        let mut hits = 0;
        for ox in [-0.9, -0.3, 0.25, 0.8] {
            for oy in [0.0025, 0.1, 0.5] {
                for oz in [-0.9, -0.2, 0.02, 0.7] {
                    for d in [
                        [1.0, 0.0, 0.0],
                        [1.0, -0.0, 0.0],
                        [-1.0, -0.0, -0.0],
                        [0.0, -1.0, 0.0],
                        [-0.0, -1.0, -0.0],
                        [0.0, 0.0, 1.0],
                        [-0.0, -0.0, 1.0],
                        [0.6, -0.0, 0.8],
                        [-0.6, -0.0, -0.8],
                        [-0.6, 0.0, 0.8],
                    ] {
                        let o = [ox, oy, oz];
                        let want = brute.first_hit(o, d);
                        assert_eq!(bvh.first_hit(o, d), want, "ray {o:?} along {d:?}");
                        hits += usize::from(want.is_some());
                    }
                }
            }
        }
        assert!(hits > 100, "only {hits} rays met something");
    }

    /// A 2 cm patch of reflectance 0.5 at the origin, facing +z, with an 8 cd point light 2 m
    /// straight above it.
    fn patch_under_point_light() -> Scene {
        let (p, t) = quad([-0.01, -0.01, 0.0], [0.02, 0.0, 0.0], [0.0, 0.02, 0.0]);
        Scene {
            objects: vec![SolverObject::new("patch", p.to_vec(), t.to_vec(), [0.5; 3])],
            lights: vec![PunctualLight {
                name: "l".into(),
                kind: LightKind::Point,
                position: [0.0, 0.0, 2.0],
                direction: [0.0, 0.0, -1.0],
                color: [1.0; 3],
                intensity: 8.0,
                range: None,
            }],
        }
    }

    #[test]
    fn point_light_over_a_patch_follows_the_inverse_square_law() {
        // 8 cd, 2 m above a small patch of reflectance 0.5: L = 0.5 · 2 / π.
        let scene = patch_under_point_light();
        let e = PathTracer::new(&scene).surface_radiance(0, &[0, 1], 64, 3);
        let want = 0.5 * 2.0 / std::f64::consts::PI;
        assert!((e.mean[0] - want).abs() < 1e-3 * want, "{e:?} vs {want}");
    }

    fn cornell() -> Scene {
        let path =
            std::path::Path::new(env!("CARGO_MANIFEST_DIR")).join("../samples/cornell-box.glb");
        use hce_meshio::scene::{import_scene, ImportOptions, ToSolver};
        import_scene(&path, &ImportOptions::default())
            .unwrap()
            .solver_scene()
    }

    #[test]
    fn bvh_agrees_with_brute_force_on_the_cornell_box() {
        let scene = cornell();
        let bvh = PathTracer::new(&scene);
        let brute = PathTracer::with_accel(&scene, Accel::BruteForce);
        assert!(bvh.bvh.is_some() && brute.bvh.is_none());
        // The same first hits for a fan of rays from inside the box.
        let eye = DVec3::new(0.278, 0.273, -0.2);
        for k in 0..400 {
            let (a, b) = (
                f64::from(k % 20) / 19.0 - 0.5,
                f64::from(k / 20) / 19.0 - 0.5,
            );
            let d = DVec3::new(a * 0.9, b * 0.9, 1.0).normalize().to_array();
            let (h1, h2) = (
                bvh.first_hit(eye.to_array(), d),
                brute.first_hit(eye.to_array(), d),
            );
            let key = |h: Option<Hit>| h.map(|h| (h.object, h.triangle, h.back));
            assert_eq!(key(h1), key(h2), "ray {k}");
            let (d1, d2) = (h1.unwrap().distance, h2.unwrap().distance);
            assert!((d1 - d2).abs() < 1e-9, "ray {k}: {d1} vs {d2}");
        }
        // Every surface's radiance within noise of the brute-force estimate.
        for (oi, o) in scene.objects.iter().enumerate() {
            let tris: Vec<usize> = (0..o.triangles.len()).collect();
            let e1 = bvh.surface_radiance(oi, &tris, 2048, 7);
            let e2 = brute.surface_radiance(oi, &tris, 2048, 7);
            for c in 0..3 {
                let noise = (e1.std_error[c].powi(2) + e2.std_error[c].powi(2)).sqrt();
                assert!(
                    (e1.mean[c] - e2.mean[c]).abs() <= 3.0 * noise + 1e-12,
                    "{}: {e1:?} vs {e2:?}",
                    o.name
                );
            }
        }
    }

    #[test]
    fn camera_rays_see_emission_plus_reflection_and_are_deterministic() {
        let scene = cornell();
        let pt = PathTracer::new(&scene);
        let light = scene
            .objects
            .iter()
            .position(|o| !o.emission.is_empty())
            .unwrap();
        // Straight up at the light from the floor's middle: at least its emission.
        let (l, hit) = pt.radiance_along([0.278, 0.01, 0.2795], [0.0, 1.0, 0.0], 16, 1, 0);
        assert_eq!(hit.unwrap().object, light);
        assert!(l[0] >= 17.0 && l[0] < 17.5, "{l:?}");
        // Seen from above (outside the box), the ceiling is its black back.
        let (l, hit) = pt.radiance_along([0.1, 2.0, 0.1], [0.0, -1.0, 0.0], 16, 1, 0);
        assert!(hit.unwrap().back && l == [0.0; 3]);
        // A small image, the same bits on one thread as on all.
        let ray = |x: u32, y: u32, _: usize| {
            let d = DVec3::new(
                0.3 * f64::from(x) / 7.0 - 0.15,
                0.15 - 0.3 * f64::from(y) / 5.0,
                1.0,
            );
            ([0.278, 0.273, -0.8], d.normalize().to_array())
        };
        let all = pt.render(8, 6, 8, 1, 5, ray, || {});
        let one = rayon::ThreadPoolBuilder::new()
            .num_threads(1)
            .build()
            .unwrap()
            .install(|| pt.render(8, 6, 8, 1, 5, ray, || {}));
        assert_eq!(all, one);
        assert!(all.iter().all(|(l, _)| l.iter().all(|c| c.is_finite())));
        assert!(all.iter().filter(|(_, h)| h.is_some()).count() == 48);
        assert!(all.iter().any(|(l, _)| l[0] > 0.05));
        // Four sample positions along the same ray share the eight paths out, two each, from
        // the pixel's one random stream: the same paths as one position, in the same order,
        // so the mean over positions of two-path means is the eight-path mean.
        let four = pt.render(8, 6, 8, 4, 5, ray, || {});
        for ((a, ha), (b, hb)) in all.iter().zip(&four) {
            assert_eq!(ha, hb);
            for c in 0..3 {
                assert!(
                    (a[c] - b[c]).abs() <= 1e-6 * a[c].abs().max(1.0),
                    "{a:?} {b:?}"
                );
            }
        }
        // A pixel whose positions see different objects has no shared hit.
        let split = |x: u32, y: u32, s: usize| {
            if s == 0 {
                ([0.278, 0.01, 0.2795], [0.0, 1.0, 0.0])
            } else {
                ray(x, y, s)
            }
        };
        let mixed = pt.render(2, 1, 4, 2, 5, split, || {});
        assert!(mixed.iter().all(|(_, h)| h.is_none()), "{mixed:?}");
    }

    #[test]
    fn vertex_normals_shade_a_flat_patch_like_a_tilted_one() {
        // A point light straight above a patch: flat, the patch reflects ρ I / (π d²); with
        // every vertex normal tilted by 60° about x, the cosine halves.
        let scene = patch_under_point_light();
        let flat = 0.5 * 2.0 / std::f64::consts::PI;
        let mut pt = PathTracer::new(&scene);
        let (l, _) = pt.radiance_along([0.0, 0.001, 1.0], [0.0, 0.0, -1.0], 4, 1, 0);
        assert!((l[0] - flat).abs() < 1e-3 * flat, "{l:?}");
        let tilted = [0.0, -(60f32.to_radians().sin()), 60f32.to_radians().cos()];
        pt.set_vertex_normals(0, &[tilted; 4]).unwrap();
        let (l, _) = pt.radiance_along([0.0, 0.001, 1.0], [0.0, 0.0, -1.0], 4, 1, 0);
        assert!((l[0] - 0.5 * flat).abs() < 1e-3 * flat, "{l:?}");
        assert!(pt.set_vertex_normals(0, &[tilted; 3]).is_err());
    }
}
