//! The power rule (Hanrahan, Salzman & Aupperle 1991): a link is refined while its
//! brightness-weighted estimate (form factor × source radiance × receiver area, as power)
//! exceeds `bf_epsilon` times the scene's reference power, splitting the larger of the receiver
//! and the source. It resolves what carries much light: the receivers near a lamp, the floor
//! under it (`tests/solver.rs`, the furnace and open scenes that conserve energy).

/// Which of a pair the power rule splits.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub(super) enum Split {
    Receiver,
    Source,
}

/// What the power rule splits of a pair whose link would carry `est` against the threshold
/// `eps_power`: the receiver where it is the larger (or the source cannot split), else the
/// source; nothing where the link carries little or neither can split. `receiver` and `source`
/// are each whether it may split and its area.
pub(super) fn power_split(
    est: f32,
    eps_power: f32,
    (receiver_splittable, r_area): (bool, f32),
    (source_splittable, s_area): (bool, f32),
) -> Option<Split> {
    if est <= eps_power {
        return None;
    }
    if receiver_splittable && (r_area >= s_area || !source_splittable) {
        Some(Split::Receiver)
    } else if source_splittable {
        Some(Split::Source)
    } else {
        None
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn a_link_over_the_threshold_splits_the_larger_of_the_two() {
        let eps = 1e-3;
        let both = |r_area, s_area| power_split(eps * 1.01, eps, (true, r_area), (true, s_area));
        assert_eq!(both(2.0, 1.0), Some(Split::Receiver));
        assert_eq!(both(1.0, 1.0), Some(Split::Receiver));
        assert_eq!(both(1.0, 2.0), Some(Split::Source));
        // Just under the threshold, or at it, nothing splits.
        assert_eq!(power_split(eps * 0.99, eps, (true, 1.0), (true, 1.0)), None);
        assert_eq!(power_split(eps, eps, (true, 1.0), (true, 1.0)), None);
        // Whichever can split does; neither, and the link is made.
        assert_eq!(
            power_split(1.0, eps, (true, 1.0), (false, 2.0)),
            Some(Split::Receiver)
        );
        assert_eq!(
            power_split(1.0, eps, (false, 2.0), (true, 1.0)),
            Some(Split::Source)
        );
        assert_eq!(power_split(1.0, eps, (false, 1.0), (false, 1.0)), None);
    }
}
