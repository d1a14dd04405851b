//! The `COLOR_0` fallback of a baked glTF (SPEC.md F.9): the two numbers every writer of it
//! shares, so that `hce bake` and `hce subdivide` give a viewer the same colours.

/// The floor of the per-channel albedo that `COLOR_0` divides by: glTF viewers multiply
/// `COLOR_0` by the base colour, so the fallback stores the light arriving at a vertex, and a
/// near-black material would otherwise blow it up.
pub const ALBEDO_FLOOR: f32 = 0.02;

/// The one exposure of a scene's `COLOR_0`: the reciprocal of the 90th percentile of the
/// per-vertex brightest channels `maxima` (sorted in place), or 1 when that is not a positive
/// finite number.
pub fn colour_exposure(maxima: &mut [f32]) -> f32 {
    maxima.sort_unstable_by(f32::total_cmp);
    let p90 = maxima
        .get((maxima.len() * 9 / 10).min(maxima.len().saturating_sub(1)))
        .copied()
        .unwrap_or(1.0);
    if p90 > 0.0 && p90.is_finite() {
        1.0 / p90
    } else {
        1.0
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn the_exposure_maps_the_90th_percentile_to_one() {
        let mut m: Vec<f32> = (1..=10).rev().map(|x| x as f32).collect();
        assert_eq!(colour_exposure(&mut m), 1.0 / 10.0);
        let mut m: Vec<f32> = (1..=100).map(|x| x as f32 / 100.0).collect();
        assert_eq!(colour_exposure(&mut m), 1.0 / 0.91);
    }

    #[test]
    fn no_positive_finite_percentile_gives_one() {
        assert_eq!(colour_exposure(&mut []), 1.0);
        assert_eq!(colour_exposure(&mut [0.0, 0.0]), 1.0);
        assert_eq!(colour_exposure(&mut [f32::INFINITY]), 1.0);
    }
}
