//! The narrow shadow rule: a flat receiver in a light's shadow is split below `detail_level`
//! where the shadow may be narrower than the receiver (a surface met between the receiver and
//! the light close enough that its penumbra is narrower than the receiver), and the receiver's
//! other links go down with the light's. Shown by Teatime's spoon and the base of its teapot
//! (`samples/teatime.glb`).

use std::collections::HashSet;

use glam::Vec3;
use hce_format::MAX_TREE_DEPTH;

use super::coefficients::inset_corners;
use super::context::Ctx;
use super::element::ElemKey;

/// How many levels below [`BakeParams::detail_level`](super::params::BakeParams::detail_level) an
/// emitter's narrow shadow splits a
/// flat receiver ([`Ctx::narrow_shadow_splittable`]).
pub(super) const NARROW_SHADOW_LEVELS: u32 = 2;

/// The least area [`Ctx::narrow_shadow_splittable`] splits to, as a fraction of the object's
/// least element area.
pub(super) const NARROW_SHADOW_AREA: f32 = 16.0;

impl Ctx<'_> {
    /// Whether the shadow that a light `st` ([`Ctx::lights`]) casts across flat receiver `k`
    /// (corners `rt`), which the link's rays found partly hidden, may be narrower than the
    /// receiver, which then draws it blurred over its whole width: below
    /// [`BakeParams::detail_level`](super::params::BakeParams::detail_level) (down to
    /// [`NARROW_SHADOW_LEVELS`] more levels and a
    /// sixteenth of the least area), a surface met between the receiver and the light nearer
    /// than `s·D/W` (receiver size `s`, light distance `D` and width `W`), where its penumbra
    /// is narrower than `s`. Judged by the geometry, from the receiver's centre and inset
    /// corners towards the light's centre and corners, and with no threshold on the light the
    /// link brings, so that the receivers along one shadow edge split alike. Split only where
    /// that light passed a threshold, a thin shadow (Teatime's spoon) was drawn as dashes, sharp
    /// where a receiver passed and blurred between; kept to where the light was a quarter to
    /// three quarters hidden, a contact shadow's outline was ragged. The refinement takes the
    /// receiver's other links down with the light's ([`taken_down_with`]).
    pub(super) fn narrow_shadow_splittable(
        &self,
        k: ElemKey,
        area: f32,
        rt: [Vec3; 3],
        st: [Vec3; 3],
    ) -> bool {
        let object = self.roots[k.root as usize].object;
        if self.scene.objects[object].multires
            || !narrow_shadow_may_split(
                k.level,
                area,
                self.params.detail_level,
                self.min_area_of(k),
            )
        {
            return false;
        }
        // Part of it shut in (under a block standing on it): the shadow's edge there is the
        // footprint's, which the open fraction already draws ([`Ctx::shown`]).
        if self.memo(k, |m| &mut m.open, || self.open_fraction(k)) < 1.0 {
            return false;
        }
        let longest = |t: [Vec3; 3]| {
            (0..3)
                .map(|i| (t[(i + 1) % 3] - t[i]).length())
                .fold(0.0, f32::max)
        };
        let rc = (rt[0] + rt[1] + rt[2]) / 3.0;
        let sc = (st[0] + st[1] + st[2]) / 3.0;
        let (size, width, dist) = (longest(rt), longest(st), (sc - rc).length());
        if width <= 0.0 {
            return false;
        }
        let reach = size * dist / width;
        let n = self.roots[k.root as usize].normal;
        let [c0, c1, c2] = inset_corners(rt);
        [rc, c0, c1, c2].iter().any(|&p| {
            [sc, st[0], st[1], st[2]].iter().any(|&q| {
                let d = q - p;
                let len = d.length();
                len > 0.0
                    && n.dot(d) > 0.0
                    && self
                        .occ
                        .first_hit_from(p, n, d / len, reach.min(len * 0.99), |_| false)
                        .is_some()
            })
        })
    }
}

/// Whether the narrow shadow rule may split a receiver of `level` and `area`: down to
/// [`NARROW_SHADOW_LEVELS`] below `detail_level` and to a [`NARROW_SHADOW_AREA`]th of the
/// object's least element area `min_area`.
pub(super) fn narrow_shadow_may_split(
    level: u32,
    area: f32,
    detail_level: u32,
    min_area: f32,
) -> bool {
    level < (detail_level + NARROW_SHADOW_LEVELS).min(MAX_TREE_DEPTH)
        && area * 0.25 * NARROW_SHADOW_AREA >= min_area
}

/// The receivers whose links go down with those of the receivers in `narrow`, which the rule
/// split: the elements above them (`above`; there only a link to a near source, the object
/// casting the shadow, goes down: near the point of contact its form factor is far from linear
/// over that receiver), and the ancestors of their edge neighbours (`graded`), so that the
/// elements beside a split receiver exist at its level.
///
/// Every other link of a split receiver goes down with the light's, to the same leaves: the
/// links of one leaf sum to what it sees only at one resolution. In a closed furnace the walls'
/// links, split beside an object resting on the floor, saw the object hide them leaf by leaf,
/// while the object's own link, on the larger receiver, spread its share linearly, and the
/// leaves at the point of contact read -13% to +10%. Graded along the shadow's edge, its dark
/// side is as fine as its lit side: otherwise the leaves just inside the umbra, whose light link
/// every ray found hidden and which no rule splits, stayed two or three levels larger than the
/// split ones beside them, and the field drawn along the edge followed their sides (a serrated
/// outline, and the lit leaves' corners pulled dark at the T-vertices on those sides).
pub(super) fn taken_down_with(narrow: &HashSet<ElemKey>) -> (HashSet<ElemKey>, HashSet<ElemKey>) {
    let mut above: HashSet<ElemKey> = HashSet::new();
    for k in narrow {
        let mut k = k.parent();
        while let Some(x) = k {
            if !above.insert(x) {
                break;
            }
            k = x.parent();
        }
    }
    let mut graded: HashSet<ElemKey> = HashSet::new();
    for k in narrow {
        for beside in k.edge_neighbours() {
            let mut x = beside.parent();
            while let Some(a) = x {
                if !graded.insert(a) {
                    break;
                }
                x = a.parent();
            }
        }
    }
    (above, graded)
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn narrow_shadows_split_two_levels_deeper_down_to_a_sixteenth_of_the_least_area() {
        // Two levels below detail level 5.
        assert!(narrow_shadow_may_split(6, 1.0, 5, 1e-3));
        assert!(!narrow_shadow_may_split(7, 1.0, 5, 1e-3));
        // Its children may be a sixteenth of the least area: the element itself a quarter.
        assert!(narrow_shadow_may_split(3, 0.25, 5, 1.0));
        assert!(!narrow_shadow_may_split(3, 0.2, 5, 1.0));
        // Never below the format's deepest tree.
        assert!(!narrow_shadow_may_split(
            MAX_TREE_DEPTH,
            1.0,
            MAX_TREE_DEPTH,
            1e-3
        ));
    }

    #[test]
    fn a_split_receivers_ancestors_and_its_neighbours_ancestors_go_down() {
        // The centre child of the centre child: its neighbours are the three corner children
        // around it, inside the same parent.
        let k = ElemKey::root(3).child(2).child(2);
        let (above, graded) = taken_down_with(&HashSet::from([k]));
        assert_eq!(
            above,
            HashSet::from([ElemKey::root(3).child(2), ElemKey::root(3)])
        );
        for beside in k.edge_neighbours() {
            let parent = beside.parent().unwrap();
            assert!(graded.contains(&parent), "{parent:?}");
        }
        assert!(!graded.contains(&k));
        assert!(taken_down_with(&HashSet::new()).0.is_empty());
    }
}
