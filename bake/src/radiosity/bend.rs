//! The bend rule: a receiver is split where a link's form factor bends over it more than a
//! linear function follows (next to the edge a wall shares with the floor, a room's corners),
//! judged against the receiver's own radiance since every leaf is drawn. Shown by
//! `tests/corner_leaves.rs` and the corner leaves of `tests/furnace_property.rs`.

use hce_format::MAX_TREE_DEPTH;

use super::context::Ctx;
use super::element::ElemKey;
use super::links::Source;

/// Largest error, relative to the receiver's radiance, that a link's bend over its receiver
/// may put into it before the receiver is split (see `refine_root`).
pub(super) const BEND_TOLERANCE: f32 = 0.001;

impl Ctx<'_> {
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
    /// along the room's corners, `tests/corner_leaves.rs`).
    pub(super) fn bend_splittable(&self, k: ElemKey, area: f32, sk: ElemKey) -> bool {
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
    pub(super) fn bend_tolerance(&self, k: ElemKey, src: Source) -> f32 {
        let object = match src {
            Source::Elem(sk) => Some(self.roots[sk.root as usize].object),
            Source::Cluster(c) => self.cluster_object[c as usize].map(|o| o as usize),
        };
        bend_tolerance(object == Some(self.roots[k.root as usize].object))
    }
}

/// [`BEND_TOLERANCE`], halved between two parts of one object ([`Ctx::bend_tolerance`]).
pub(super) fn bend_tolerance(same_object: bool) -> f32 {
    if same_object {
        0.5 * BEND_TOLERANCE
    } else {
        BEND_TOLERANCE
    }
}

/// Whether a link whose form factor bends by `bend` over its receiver, from a source of radiance
/// `l` onto a receiver of reflectance `rho` and radiance `recv_l`, puts more than `tolerance`
/// of the receiver's radiance wrong.
pub(super) fn bend_splits(bend: f32, l: f32, rho: f32, tolerance: f32, recv_l: f32) -> bool {
    bend * l * rho > tolerance * recv_l
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn a_bend_over_a_thousandth_of_the_receivers_radiance_splits() {
        // A bend of a thousandth of the receiver's radiance, as it gathers it.
        let splits = |wrong: f32, same_object| {
            bend_splits(wrong, 1.0, 1.0, bend_tolerance(same_object), 1.0)
        };
        assert!(splits(0.0011, false));
        assert!(!splits(0.0009, false));
        // Half of it within one object.
        assert!(splits(0.00055, true));
        assert!(!splits(0.00045, true));
        assert!(!splits(0.00055, false));
        // Source radiance and reflectance weigh it; the receiver's radiance scales the bound.
        assert!(bend_splits(0.0006, 2.0, 1.0, BEND_TOLERANCE, 1.0));
        assert!(!bend_splits(0.0011, 1.0, 0.5, BEND_TOLERANCE, 1.0));
        assert!(!bend_splits(0.0011, 1.0, 1.0, BEND_TOLERANCE, 2.0));
    }
}
