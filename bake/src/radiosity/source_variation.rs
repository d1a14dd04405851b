//! The source variation rule: a source whose radiance varies in the previous solution (a lit
//! wall with a shadow on it) is split, its error weighed against every receiver that makes the
//! same error, and the threshold lowered for a receiver darker than the scene's mean. Shown by
//! `tests/small_receivers.rs` and the Cornell box's short block (`tests/cornell_reference.rs`).

use super::context::{lum, Ctx};
use super::element::ElemKey;
use super::tree::Tree;

/// The source variation rule weighs its error against the scene's power (`bf_epsilon`), which
/// lets a dim receiver (a face in shadow, lit by a floor whose shadow it faces) carry a larger
/// relative error than a bright one: the Cornell box's short block's front face, a tenth of
/// the mean, came out 6% too bright. A receiver below the mean radiance of the scene's
/// non-emitting surfaces lowers the rule's threshold in proportion to its radiance, down to
/// this fraction of it (+2.4% on that face against 2^20 paths, for 16-29% more bake time on the
/// samples; at 2^18 paths 0.3 gave +2.8%, 0.5 +3.4%, 0.2 +2.6%).
pub(super) const DIM_RECEIVER_FLOOR: f32 = 0.3;

impl Ctx<'_> {
    /// Per node of `t`: the spread (largest minus smallest) of the source radiance over the
    /// leaves below it, in the current solution. A link's constant source is only as good
    /// as this spread is small: the refinement oracle splits sources by it.
    pub(super) fn spreads(&self, r: u32, t: &Tree) -> Vec<f32> {
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

    /// Area-weighted mean radiance (normal 0) of the surfaces that emit nothing, in the solution
    /// `trees`: what a receiver counts as dim against (see `DIM_RECEIVER_FLOOR`). In a fixed
    /// order, so the same whatever the thread count.
    pub(super) fn mean_radiance(&self, trees: &[Tree]) -> f32 {
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
    pub(super) fn src_spread(&self, trees: &[Tree], spreads: &[Vec<f32>], k: ElemKey) -> f32 {
        let t = &trees[k.root as usize];
        let i = t.deepest_toward(k) as usize;
        if t.keys[i] == k {
            spreads[k.root as usize][i]
        } else {
            0.0
        }
    }
}

/// The area of the receivers that make the same error as one receiver of a source whose
/// radiance varies: the largest of the clusters of its own object around it (`neighbourhood`,
/// their radii and areas, largest first) whose radius is below `reach`, or its coarse triangle
/// (`root_area`) if that is larger.
pub(super) fn receivers_sharing(neighbourhood: &[(f32, f32)], reach: f32, root_area: f32) -> f32 {
    neighbourhood
        .iter()
        .find(|(radius, _)| *radius < reach)
        .map_or(root_area, |&(_, area)| area.max(root_area))
}

/// Whether `svar`, the power a source's variation puts wrong into the receivers that share the
/// error, exceeds `eps_power`, lowered for a receiver whose radiance `receiver_l` is below the
/// scene's mean `mean_l` in proportion, down to [`DIM_RECEIVER_FLOOR`].
pub(super) fn source_variation_splits(
    svar: f32,
    eps_power: f32,
    receiver_l: f32,
    mean_l: f32,
) -> bool {
    let dim = (receiver_l / mean_l.max(f32::MIN_POSITIVE)).clamp(DIM_RECEIVER_FLOOR, 1.0);
    svar > eps_power * dim
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn a_dim_receiver_lowers_the_threshold_down_to_the_floor() {
        // As bright as the scene's mean: the threshold itself.
        assert!(source_variation_splits(1.01, 1.0, 1.0, 1.0));
        assert!(!source_variation_splits(0.99, 1.0, 1.0, 1.0));
        // Half as bright: half the threshold.
        assert!(source_variation_splits(0.51, 1.0, 0.5, 1.0));
        assert!(!source_variation_splits(0.49, 1.0, 0.5, 1.0));
        // A tenth as bright: the floor, three tenths.
        assert!(source_variation_splits(0.31, 1.0, 0.1, 1.0));
        assert!(!source_variation_splits(0.29, 1.0, 0.1, 1.0));
    }

    #[test]
    fn the_error_is_shared_by_the_largest_cluster_within_reach() {
        let around = [(4.0, 100.0), (2.0, 30.0), (0.5, 3.0)];
        assert_eq!(receivers_sharing(&around, 3.0, 1.0), 30.0);
        assert_eq!(receivers_sharing(&around, 5.0, 1.0), 100.0);
        // None within reach, or the coarse triangle larger: the coarse triangle.
        assert_eq!(receivers_sharing(&around, 0.4, 1.0), 1.0);
        assert_eq!(receivers_sharing(&around, 1.0, 5.0), 5.0);
    }
}
