//! The form factor variation rule: for a near pair, a receiver over which the form factor to the
//! source varies by more than a fifth of the power threshold is split (splitting the source would
//! only share the same error among four links), or the source where the receiver is as small as
//! it gets. It resolves the fall of light over a receiver next to its source: a floor beside a
//! wall, the leaves of `tests/furnace_property.rs` next to a shared edge.

/// The share of the power threshold that a link's variation over its receiver may carry.
pub(super) const FACTOR_VARIATION: f32 = 0.2;

/// Whether the point form factors `fmax` and `fmin` over a receiver of area `r_area`, from a
/// source of radiance `l`, vary by more power than `FACTOR_VARIATION` times `eps_power`.
pub(super) fn factor_variation_splits(
    fmax: f32,
    fmin: f32,
    l: f32,
    r_area: f32,
    eps_power: f32,
) -> bool {
    let var = (fmax - fmin) * l * r_area * std::f32::consts::PI;
    var > eps_power * FACTOR_VARIATION
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn a_variation_over_a_fifth_of_the_threshold_splits() {
        // (fmax − fmin) π: the variation's power for unit radiance and area.
        let eps = 1.0;
        let at =
            |share: f32| factor_variation_splits(share / std::f32::consts::PI, 0.0, 1.0, 1.0, eps);
        assert!(at(0.21));
        assert!(!at(0.19));
        // Radiance and area weigh it alike.
        assert!(factor_variation_splits(
            0.11 / std::f32::consts::PI,
            0.0,
            2.0,
            1.0,
            eps
        ));
        assert!(!factor_variation_splits(
            0.09 / std::f32::consts::PI,
            0.0,
            1.0,
            2.0,
            eps
        ));
    }
}
