//! Direct light from punctual lights through shadow rays, and its own refinement: elements split
//! where a child's direct light differs from its parent's (shadow boundaries, spot edges).

use glam::Vec3;

use super::context::{lum, Ctx};
use super::element::{jittered_point, ElemKey, Rng};
use crate::scene::{LightKind, PunctualLight};

/// Below `max_level`, direct light splits an element where a child's direct light differs from
/// the element's by this fraction of the brightest of them (`Ctx::direct_tree`).
pub(super) const DIRECT_EDGE: f32 = 0.25;

impl Ctx<'_> {
    /// Direct irradiance / π per normal at element `k` from every punctual light.
    pub(super) fn direct(&self, k: ElemKey) -> Vec<Vec3> {
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
                let Some((w, dist, scale)) = light_toward(light, p) else {
                    continue;
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

    /// Direct irradiance / π per normal of root `r` at point `p` of its coarse triangle, from
    /// every punctual light through one shadow ray each: the value at a point, where
    /// [`Ctx::direct`] is an element's mean.
    pub(super) fn direct_at(&self, r: u32, p: Vec3) -> Vec<Vec3> {
        let root = &self.roots[r as usize];
        let mut q = vec![Vec3::ZERO; root.normals.len()];
        for light in &self.scene.lights {
            let Some((w, dist, scale)) = light_toward(light, p) else {
                continue;
            };
            if scale <= 0.0 || root.normals.iter().all(|n| n.dot(w) <= 0.0) {
                continue;
            }
            let (a, _) = self.on_surface(r, p);
            if !self.occ.ray_clear(a, w, dist * (1.0 - 1e-5)) {
                continue;
            }
            let colour = Vec3::from(light.color) * light.intensity;
            for (qj, n) in q.iter_mut().zip(&root.normals) {
                *qj += colour * (scale * n.dot(w).max(0.0)) / std::f32::consts::PI;
            }
        }
        q
    }

    /// Direct-light refinement of root `r`: splits where the direct light varies by more than
    /// the oracle allows (shadow boundaries, spot edges). Returns the leaves and their values.
    pub(super) fn direct_tree(
        &self,
        r: u32,
        root_q: Vec<Vec3>,
        eps_power: f32,
    ) -> Vec<(ElemKey, Vec<Vec3>)> {
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
}

/// The direction from `p` to `light`, its distance and the light's falloff there (inverse
/// square, range and spot cone); `None` for a point light at `p` itself.
fn light_toward(light: &PunctualLight, p: Vec3) -> Option<(Vec3, f32, f32)> {
    Some(match light.kind {
        LightKind::Directional => {
            let w = -Vec3::from(light.direction).normalize();
            (w, f32::INFINITY, 1.0)
        }
        LightKind::Point | LightKind::Spot { .. } => {
            let d = Vec3::from(light.position) - p;
            let dist = d.length();
            if dist <= 1e-12 {
                return None;
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
    })
}
