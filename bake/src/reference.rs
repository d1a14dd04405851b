//! An independent Monte-Carlo path tracer for diffuse scenes, to check the radiosity solver
//! against (Kajiya, "The rendering equation", SIGGRAPH 1986; next-event estimation and Russian
//! roulette as in Arvo & Kirk, "Particle transport and image synthesis", SIGGRAPH 1990).
//!
//! It reads the same [`Scene`] model as the solver but shares none of its code: no elements,
//! form factors, clusters, links or BVH. Rays are intersected with every triangle in turn
//! (Möller & Trumbore 1997), so it suits small scenes (the Cornell box has 32 triangles); its
//! cost is linear in the triangle count.
//!
//! The physics are the solver's, restated independently: every triangle is one-sided (it emits
//! and reflects from its front, the side its counter-clockwise winding faces; seen from behind
//! it is black, though it still blocks light); reflection is Lambertian with the triangle's
//! reflectance (per-triangle `reflectance`; texture hooks are not evaluated); emission is
//! radiance; punctual lights follow KHR_lights_punctual (candela, lux, the range window and the
//! smooth spot falloff).
//!
//! [`surface_radiance`] estimates the area-averaged outgoing radiance of a set of triangles:
//! `L = Le + ρ E / π` averaged over points drawn uniformly by area, with the irradiance `E`
//! from one emitter sample (by area), every punctual light through a shadow ray, and one
//! cosine-distributed bounce that continues the path (emission found by a bounce is not
//! counted: the emitter samples already carry it). Paths end by Russian roulette on the
//! reflectance, with a hard cap of [`MAX_DEPTH`] bounces so that nothing can loop forever.
//!
//! Deterministic: path `i` of a query draws its random numbers from its own generator, seeded
//! by `(seed, i)`, and paths are summed in a fixed order, so the result does not depend on the
//! number of threads.

use glam::DVec3;
use rayon::prelude::*;

use crate::scene::{LightKind, Scene};

/// Bounces after which a path stops whatever its weight (0.95^64 < 4 %; with Cornell box
/// reflectances the truncated energy is far below the noise).
pub const MAX_DEPTH: u32 = 64;

/// Paths per parallel chunk (the unit of work and of the fixed-order sum).
const CHUNK: u64 = 1024;

/// One triangle with everything a path needs.
struct Tri {
    p0: DVec3,
    e1: DVec3,
    e2: DVec3,
    /// Unit geometric normal (front side).
    n: DVec3,
    area: f64,
    rho: DVec3,
    le: DVec3,
}

/// A scene prepared for path tracing.
pub struct PathTracer<'a> {
    scene: &'a Scene,
    tris: Vec<Tri>,
    /// First triangle of each object in `tris`.
    object_start: Vec<usize>,
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

/// A uniform point on a triangle.
fn point_on(t: &Tri, rng: &mut Pcg) -> DVec3 {
    let (mut u, mut v) = (rng.next(), rng.next());
    if u + v > 1.0 {
        u = 1.0 - u;
        v = 1.0 - v;
    }
    t.p0 + t.e1 * u + t.e2 * v
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

impl<'a> PathTracer<'a> {
    /// Prepares `scene`; objects, triangles and lights are used as they are (call
    /// [`Scene::validate`] first for a clear error on bad input).
    pub fn new(scene: &'a Scene) -> Self {
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
        PathTracer {
            scene,
            tris,
            object_start,
            emitters,
            emitter_cdf,
            eps: diag.max(1e-9) * 1e-7,
        }
    }

    /// The nearest triangle hit by the ray `o + t d` with `eps < t < max_t`, and its distance.
    fn nearest(&self, o: DVec3, d: DVec3, max_t: f64) -> Option<(usize, f64)> {
        let mut best: Option<(usize, f64)> = None;
        let mut limit = max_t;
        for (i, t) in self.tris.iter().enumerate() {
            let p = d.cross(t.e2);
            let det = t.e1.dot(p);
            if det.abs() < 1e-300 {
                continue;
            }
            let inv = 1.0 / det;
            let s = o - t.p0;
            let u = s.dot(p) * inv;
            if !(0.0..=1.0).contains(&u) {
                continue;
            }
            let q = s.cross(t.e1);
            let v = d.dot(q) * inv;
            if v < 0.0 || u + v > 1.0 {
                continue;
            }
            let dist = t.e2.dot(q) * inv;
            if dist > self.eps && dist < limit {
                limit = dist;
                best = Some((i, dist));
            }
        }
        best
    }

    fn clear(&self, from: DVec3, to: DVec3) -> bool {
        let d = to - from;
        let len = d.length();
        len <= 2.0 * self.eps || self.nearest(from, d / len, len - 2.0 * self.eps).is_none()
    }

    /// Irradiance / π at `x` (normal `n`, on the front of triangle `at`) straight from the
    /// emitters (one sample) and the punctual lights.
    fn direct(&self, x: DVec3, n: DVec3, rng: &mut Pcg) -> DVec3 {
        let origin = x + n * self.eps;
        let mut e = DVec3::ZERO;
        if let Some(&total) = self.emitter_cdf.last() {
            let u = rng.next() * total;
            let k = self.emitter_cdf.partition_point(|&c| c <= u);
            let k = k.min(self.emitters.len() - 1);
            let t = &self.tris[self.emitters[k]];
            let pdf_pick = (t.area * t.le.max_element()) / total;
            let y = point_on(t, rng);
            let to = y - origin;
            let d2 = to.length_squared();
            if d2 > 0.0 {
                let w = to / d2.sqrt();
                let (cos_x, cos_y) = (n.dot(w), t.n.dot(-w));
                if cos_x > 0.0 && cos_y > 0.0 && self.clear(origin, y) {
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
            if cos_x <= 0.0 || scale <= 0.0 {
                continue;
            }
            let blocked = if dist.is_finite() {
                !self.clear(origin, origin + w * dist)
            } else {
                self.nearest(origin, w, f64::INFINITY).is_some()
            };
            if !blocked {
                e += colour * (scale * cos_x / std::f64::consts::PI);
            }
        }
        e
    }

    /// Reflected radiance (without emission) leaving point `x` of triangle `at`, by one path.
    fn reflected(&self, at: usize, x: DVec3, rng: &mut Pcg) -> DVec3 {
        let mut total = DVec3::ZERO;
        let mut weight = DVec3::ONE;
        let (mut at, mut x) = (at, x);
        for _ in 0..MAX_DEPTH {
            let t = &self.tris[at];
            weight *= t.rho;
            if weight.max_element() <= 0.0 {
                break;
            }
            total += weight * self.direct(x, t.n, rng);
            // Russian roulette on this surface's reflectance: unbiased, and it ends dark paths.
            let survive = t.rho.max_element().clamp(0.05, 0.95);
            if rng.next() >= survive {
                break;
            }
            weight /= survive;
            let d = cosine_direction(t.n, rng);
            let origin = x + t.n * self.eps;
            let Some((hit, dist)) = self.nearest(origin, d, f64::INFINITY) else {
                break;
            };
            // A triangle seen from behind is black.
            if self.tris[hit].n.dot(d) >= 0.0 {
                break;
            }
            at = hit;
            x = origin + d * dist;
        }
        total
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
                    let x = point_on(&self.tris[at], &mut rng);
                    let v = self.reflected(at, x, &mut rng);
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
    use crate::scene::{PunctualLight, SceneObject};

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
            objects: vec![SceneObject::new("box", pos, tris, [0.5; 3]).with_emission([1.0; 3])],
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

    #[test]
    fn point_light_over_a_patch_follows_the_inverse_square_law() {
        // 8 cd, 2 m above a small patch of reflectance 0.5: L = 0.5 · 2 / π.
        let (p, t) = quad([-0.01, -0.01, 0.0], [0.02, 0.0, 0.0], [0.0, 0.02, 0.0]);
        let scene = Scene {
            objects: vec![SceneObject::new("patch", p.to_vec(), t.to_vec(), [0.5; 3])],
            lights: vec![PunctualLight {
                name: "l".into(),
                kind: LightKind::Point,
                position: [0.0, 0.0, 2.0],
                direction: [0.0, 0.0, -1.0],
                color: [1.0; 3],
                intensity: 8.0,
                range: None,
            }],
        };
        let e = PathTracer::new(&scene).surface_radiance(0, &[0, 1], 64, 3);
        let want = 0.5 * 2.0 / std::f64::consts::PI;
        assert!((e.mean[0] - want).abs() < 1e-3 * want, "{e:?} vs {want}");
    }
}
