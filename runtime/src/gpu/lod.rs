//! Level of detail: how finely to refine an object for a given view.
//!
//! Concheiro et al. (GRAPP 2012) choose each object's subdivision level from its distance to
//! the viewer. We make the rule explicit in screen terms: each Loop or linear subdivision step
//! halves the edge length, so refining a coarse edge of world length `ℓ` to level `L` gives
//! edges of `ℓ / 2^L`. Projected at distance `d` with a vertical field of view `fov` onto a
//! viewport `H` pixels high, one world unit covers `H / (2 d tan(fov / 2))` pixels. The level is
//! the smallest `L` for which a fine edge covers at most `target_pixels_per_edge` pixels:
//!
//! `L = ceil(log2(ℓ · H / (2 d tan(fov / 2) · target)))`, clamped to `[min_level, max_level]`.
//!
//! `d` is the distance from the eye to the nearest point of the object's bounding sphere (at
//! least `1e-6` of the radius, so an eye inside the bounds gets the finest level).

/// A perspective camera.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Camera {
    pub eye: [f32; 3],
    pub target: [f32; 3],
    /// Vertical field of view in degrees.
    pub fov_y_degrees: f32,
}

/// Parameters of [`choose_level`].
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct LodParams {
    /// Screen length, in pixels, that a refined edge should not exceed. Default 8.
    pub target_pixels_per_edge: f32,
    /// Lowest level chosen. Default 0.
    pub min_level: u32,
    /// Highest level chosen. Default 5 (memory grows as 4^L; the Loop kernel accepts up to
    /// [`hce_geometry::subdivide::MAX_LOOP_LEVEL`], the flat kernel up to
    /// [`hce_geometry::decode::MAX_PATH_LEVEL`]).
    pub max_level: u32,
    /// Use this level whatever the view (`--level N`). Default `None`.
    pub force_level: Option<u32>,
}

impl Default for LodParams {
    fn default() -> Self {
        Self {
            target_pixels_per_edge: 8.0,
            min_level: 0,
            max_level: 5,
            force_level: None,
        }
    }
}

/// The level for an object with bounds `[min, max]` and mean coarse edge length
/// `mean_edge_length`, seen by `camera` on a viewport `viewport_height` pixels high.
/// See the module documentation for the formula.
pub fn choose_level(
    bounds_min: [f32; 3],
    bounds_max: [f32; 3],
    mean_edge_length: f32,
    camera: &Camera,
    viewport_height: u32,
    params: &LodParams,
) -> u32 {
    if let Some(level) = params.force_level {
        return level;
    }
    let centre: [f32; 3] = std::array::from_fn(|k| 0.5 * (bounds_min[k] + bounds_max[k]));
    let radius = 0.5 * dist(bounds_min, bounds_max);
    let d = (dist(camera.eye, centre) - radius).max(1e-6 * radius.max(1e-12));
    let half_fov = (camera.fov_y_degrees.clamp(1.0, 179.0) * 0.5).to_radians();
    let pixels_per_unit = viewport_height as f32 / (2.0 * d * half_fov.tan());
    let coarse_pixels = mean_edge_length * pixels_per_unit;
    let ratio = coarse_pixels / params.target_pixels_per_edge.max(1e-3);
    let level = if ratio.is_finite() && ratio > 1.0 {
        ratio.log2().ceil() as u32
    } else if ratio.is_finite() {
        0
    } else {
        params.max_level
    };
    level.clamp(params.min_level, params.max_level.max(params.min_level))
}

fn dist(a: [f32; 3], b: [f32; 3]) -> f32 {
    ((a[0] - b[0]).powi(2) + (a[1] - b[1]).powi(2) + (a[2] - b[2]).powi(2)).sqrt()
}

#[cfg(test)]
mod tests {
    use super::*;

    fn camera_at(z: f32) -> Camera {
        Camera {
            eye: [0.0, 0.0, z],
            target: [0.0; 3],
            fov_y_degrees: 90.0,
        }
    }

    #[test]
    fn level_follows_the_formula_and_drops_with_distance() {
        let p = LodParams::default();
        let (lo, hi) = ([-1.0; 3], [1.0; 3]);
        let r = 3f32.sqrt();
        // d = 10 - r; 1 unit = 1000 / (2 d) px; a 0.5 edge covers 250 / d px.
        let d = 10.0 - r;
        let expected = ((250.0 / d) / 8.0f32).log2().ceil() as u32;
        assert_eq!(
            choose_level(lo, hi, 0.5, &camera_at(10.0), 1000, &p),
            expected
        );
        assert_eq!(expected, 2);
        let near = choose_level(lo, hi, 0.5, &camera_at(3.0), 1000, &p);
        let far = choose_level(lo, hi, 0.5, &camera_at(1000.0), 1000, &p);
        assert!(near > expected && far == 0, "near {near} far {far}");
        // Inside the bounds: the finest allowed level.
        assert_eq!(
            choose_level(lo, hi, 0.5, &camera_at(0.5), 1000, &p),
            p.max_level
        );
    }

    #[test]
    fn forced_level_wins() {
        let p = LodParams {
            force_level: Some(3),
            ..Default::default()
        };
        assert_eq!(
            choose_level([0.0; 3], [1.0; 3], 0.1, &camera_at(1e6), 10, &p),
            3
        );
    }
}
