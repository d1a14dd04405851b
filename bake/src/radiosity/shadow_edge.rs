//! The shadow edge rule: a receiver that a shadow's edge crosses (part of the source hidden from
//! part of the receiver) is split while the light the link puts on the wrong side of the edge is
//! a visible fraction of what the receiver gets. Shown by the floor beside the block of
//! `tests/contact_shadows.rs` and the Cornell box's floor.

/// Largest error, relative to the receiver's radiance, that a shadow edge crossing the
/// receiver may put into it before the receiver is split (see `refine_root`).
pub(super) const SHADOW_TOLERANCE: f32 = 0.05;
