//! The shadow edge rule: a receiver that a shadow's edge crosses (part of the source hidden from
//! part of the receiver) is split while the light the link puts on the wrong side of the edge is
//! a visible fraction of what the receiver gets. Shown by the floor beside the block of
//! `tests/contact_shadows.rs` and the Cornell box's floor.

/// Largest error, relative to the receiver's radiance, that a shadow edge crossing the
/// receiver may put into it before the receiver is split (see `refine_root`).
pub(super) const SHADOW_TOLERANCE: f32 = 0.05;

/// Whether a link that gathers `gathered` into its receiver (radiance `recv_l`) with visible
/// fraction `visible` (partly hidden) puts more than [`SHADOW_TOLERANCE`] of what the receiver
/// gets on the wrong side of the shadow's edge: at most the smaller of the lit and the hidden
/// parts, against the light the link brings or the receiver's own radiance, the larger. Judged
/// against the light the link brings as well, so that the first pass, before any light has
/// arrived, resolves the shadows the emitters cast.
pub(super) fn shadow_edge_splits(gathered: f32, visible: f32, recv_l: f32) -> bool {
    let wrong = gathered * (1.0 - visible).min(visible) / visible;
    wrong > SHADOW_TOLERANCE * recv_l.max(gathered)
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn a_shadow_edge_splits_while_a_twentieth_lands_on_the_wrong_side() {
        // The link brings all the receiver's light: wrong = min(1 − v, v) / v of it.
        assert!(shadow_edge_splits(1.0, 0.94, 1.0));
        assert!(!shadow_edge_splits(1.0, 0.96, 1.0));
        // Mostly hidden: the lit part is what may land wrong.
        assert!(shadow_edge_splits(1.0, 0.5, 1.0));
        // A faint link onto a bright receiver: judged against the receiver.
        assert!(!shadow_edge_splits(0.1, 0.7, 1.0));
        assert!(shadow_edge_splits(0.3, 0.7, 1.0));
    }
}
