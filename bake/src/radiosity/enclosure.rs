//! Which parts of the scene are shut in or closed: the open fraction of an element (the part not
//! under other geometry, which neither receives nor sends light), and what a leaf's form factors
//! must sum to where every ray from it meets the front of a surface (a closed room).

use glam::Vec3;

use super::context::Ctx;
use super::element::ElemKey;
use super::formfactor::{stratified_16, stratified_points};

/// Cosine-weighted rings and azimuths of the directions [`Ctx::root_closed`] casts from each
/// of a root's four points (and [`Ctx::enclosure`] from each of a partly shut leaf's sixteen).
pub(super) const ENCLOSURE_RINGS: u32 = 4;

pub(super) const ENCLOSURE_AZIMUTHS: u32 = 4;

/// A closed leaf's gathered radiance for one normal, at its centre or at a corner: its form
/// factors sum, for every normal, to the part of its hemisphere that meets the front of a
/// surface (`enclosed`, [`Ctx::enclosure`]; its open fraction). The lights' links are the most
/// carefully found (analytic form factors, many rays), so what they bring (`fixed`, of the
/// `gathered` total; their form factors `from_lights`) stays as it is; the rest take up the
/// difference between what all links `seen` and what is `enclosed`. What they lack is filled
/// with `rest_radiance` ([`rest_radiance`]): a normal turned away from the geometric one sees,
/// below the element's plane, surface that the coarse scene does not have there (on a refined
/// surface, the object's own neighbouring patches). What they have too much (visibility from a
/// few rays, a cluster's area from a bound, linear functions pushed down from coarser
/// receivers, up to 3% and 6% off in a closed furnace) is taken off in proportion. So a closed
/// furnace is exact at every leaf, corner and normal (SPEC.md G.1).
pub(super) fn closed_sum(
    fixed: Vec3,
    gathered: Vec3,
    from_lights: f32,
    seen: f32,
    enclosed: f32,
    rest_radiance: Vec3,
) -> Vec3 {
    let due = (enclosed - from_lights).max(0.0);
    let rest = gathered - fixed;
    fixed
        + if seen > due {
            rest * (due / seen)
        } else {
            rest + rest_radiance * (due - seen)
        }
}

/// The radiance that fills a closed leaf's missing form factors ([`closed_sum`]): the mean the
/// geometric normal gathers from the links that are not the lights' (`g0_rest` over their
/// form factors `rest0`), or from all links (`g0` over `f0`) where the lights' are all it has.
pub(super) fn rest_radiance(g0_rest: Vec3, rest0: f32, g0: Vec3, f0: f32) -> Vec3 {
    if rest0 > 0.0 {
        g0_rest / rest0
    } else {
        g0 / f0
    }
}

/// The form factor a tilted normal (or, on a refined surface, any normal) lacks against `full`,
/// the geometric normal's or the surface's own ([`super::tree::Tree::closure`]), given its own
/// links' `seen` and what its patch sees of itself (`view`); filled with the mean radiance the
/// geometric normal gathers.
pub(super) fn missing_view(full: f32, seen: f32, view: f32) -> f32 {
    (full - seen - view).max(0.0)
}

/// How many roots [`Ctx::boundary_closed`] casts its rays from.
pub(super) const BOUNDARY_PROBES: usize = 64;

/// Fixed directions over the hemisphere around unit normal `n`, `rings` × `azimuths` strata of
/// equal cosine-weighted measure, ring by ring from the normal outwards: the sin² of each
/// direction's angle from `n` is the middle of one of `rings` equal parts of [0, 1], and each
/// ring's azimuths are turned half a step from the previous ring's, and all by `turn` steps.
pub(super) fn cosine_strata(
    n: Vec3,
    rings: u32,
    azimuths: u32,
    turn: f32,
) -> impl Iterator<Item = Vec3> {
    let a = if n.x.abs() < 0.9 { Vec3::X } else { Vec3::Y };
    let tu = n.cross(a).normalize();
    let tv = n.cross(tu);
    (0..rings).flat_map(move |ring| {
        let s2 = (2 * ring + 1) as f32 / (2 * rings) as f32;
        let (sin, cos) = (s2.sqrt(), (1.0 - s2).sqrt());
        (0..azimuths).map(move |az| {
            let phi =
                std::f32::consts::TAU / azimuths as f32 * (az as f32 + 0.5 * ring as f32 + turn);
            tu * (sin * phi.cos()) + tv * (sin * phi.sin()) + n * cos
        })
    })
}

impl Ctx<'_> {
    /// Fraction of element `k` that is open, from four stratified points: a point is shut
    /// in when the first surface met along its normal and along four directions 30 degrees
    /// above its plane is, every time, the back of a triangle (a floor point under a block,
    /// a ceiling point just above a one-sided lamp). The area average the solver stores
    /// counts such a part as dark, and rightly so (it is part of the element), but it
    /// can neither receive nor send light.
    pub(super) fn open_fraction(&self, k: ElemKey) -> f32 {
        let tri = self.elem_corners(k);
        let open_at = |level: u32| {
            let pts = stratified_points(tri, level);
            let shut = pts.iter().filter(|&&p| self.shut_at(k.root, p)).count();
            1.0 - shut as f32 / pts.len() as f32
        };
        // Four points; sixteen where the four disagree (the edge of a block's footprint): the
        // value drawn for a leaf partly shut in is its open part's ([`Ctx::shown`]), so a
        // coarse fraction shows.
        let o = open_at(1);
        if o > 0.0 && o < 1.0 {
            open_at(2)
        } else {
            o
        }
    }

    /// Whether point `p` of root `r` is shut in ([`Ctx::open_fraction`]): the first surface
    /// met along the root's normal and along four directions 30 degrees above its plane is,
    /// every time, the back of a triangle.
    pub(super) fn shut_at(&self, r: u32, p: Vec3) -> bool {
        let n = self.roots[r as usize].normal;
        let a = if n.x.abs() < 0.9 { Vec3::X } else { Vec3::Y };
        let t = n.cross(a).normalize();
        let b = n.cross(t);
        let (p, _) = self.on_surface(r, p);
        [
            n,
            (n + t * 1.7).normalize(),
            (n - t * 1.7).normalize(),
            (n + b * 1.7).normalize(),
            (n - b * 1.7).normalize(),
        ]
        .iter()
        .all(|&d| self.occ.first_hit_is_back(p, d))
    }

    /// Whether every ray from root `r`'s open surface meets the front of a surface: the rays
    /// of [`ENCLOSURE_RINGS`] × [`ENCLOSURE_AZIMUTHS`] cosine-weighted directions from each of
    /// its four stratified points that is not shut in ([`Ctx::shut_at`]), turned from point to
    /// point. In a closed room a root that sees no back (of a one-sided lamp, through a gap in
    /// an object) is closed; one that sees out of an open scene is not, and the first ray that
    /// shows it ends the search. A root with nothing but the scene's outer boundary in front
    /// of it (the convex side of an object, `unobstructed`) is closed where the boundary is.
    pub(super) fn root_closed(&self, r: u32) -> bool {
        let corners = self.roots[r as usize].corners;
        if self.unobstructed[r as usize] {
            return *self.boundary_closed.get_or_init(|| self.boundary_closed());
        }
        stratified_points(corners, 1)
            .iter()
            .enumerate()
            .all(|(s, &p)| self.shut_at(r, p) || self.point_closed(r, p, s))
    }

    /// Whether the scene's outer boundary closes it: the rays of [`Ctx::root_closed`] from the
    /// centroids of up to [`BOUNDARY_PROBES`] roots with nothing but the boundary in front of
    /// them, spread over the scene's roots, all meet the front of a surface (which can only be
    /// the boundary's). A room whose walls close it sees no sky from any point inside.
    pub(super) fn boundary_closed(&self) -> bool {
        let inside: Vec<u32> = (0..self.roots.len() as u32)
            .filter(|&r| self.unobstructed[r as usize])
            .collect();
        let step = inside.len().div_ceil(BOUNDARY_PROBES).max(1);
        inside.iter().step_by(step).enumerate().all(|(s, &r)| {
            let c = self.roots[r as usize].corners;
            self.point_closed(r, (c[0] + c[1] + c[2]) / 3.0, s)
        })
    }

    /// Whether every ray of [`Ctx::root_closed`]'s directions from point `p` of root `r` (the
    /// `s`-th of its set) meets the front of a surface.
    pub(super) fn point_closed(&self, r: u32, p: Vec3, s: usize) -> bool {
        let (a, n) = self.on_surface(r, p);
        // Turned by the golden ratio's fraction of a stratum from point to point: never a
        // simple fraction, so that no set of rays lines up with a grid of faces and meets
        // them along their shared edges.
        let turn = (s as f32 + 0.5) * 0.618_034;
        cosine_strata(n, ENCLOSURE_RINGS, ENCLOSURE_AZIMUTHS, turn)
            .all(|d| self.occ.meets_front_from(a, n, d))
    }

    /// The part of leaf `k`'s hemisphere that meets the front of a surface, weighed by the
    /// cosine, where it is known exactly: what the form factors of its links must sum to.
    /// `open` is its open fraction ([`Ctx::open_fraction`]). In a closed root
    /// ([`Ctx::root_closed`]) an open leaf's is one. A leaf partly shut in takes the sixteen
    /// points its open fraction was judged by: where the rays from every open one meet fronts,
    /// its part is its open fraction exactly, the shut ones meeting nothing. Elsewhere (a leaf
    /// that sees out of an open scene, or the back of a one-sided surface) it is not known
    /// well enough from rays (a few per cent off, where the links' form factors are analytic),
    /// and is negative.
    pub(super) fn enclosure(&self, k: ElemKey, open: f32) -> f32 {
        if open <= 0.0 {
            return 0.0;
        }
        if open >= 1.0 {
            let root = ElemKey::root(k.root);
            let closed = self.memo(root, |m| &mut m.closed, || self.root_closed(k.root));
            return if closed { 1.0 } else { -1.0 };
        }
        let all_open_closed = stratified_16(self.elem_corners(k))
            .iter()
            .enumerate()
            .all(|(s, &p)| self.shut_at(k.root, p) || self.point_closed(k.root, p, s));
        if all_open_closed {
            open
        } else {
            -1.0
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    /// In a closed furnace every surface shows the same radiance `l`: whatever the links see,
    /// too much or too little, a closed leaf gathers `l` times its enclosure.
    #[test]
    fn a_closed_leaf_gathers_its_enclosure_whatever_its_links_see() {
        let l = Vec3::new(0.8, 0.6, 0.4);
        let (enclosed, from_lights) = (0.9, 0.2);
        for seen_rest in [0.3f32, 0.7, 0.75, 1.1] {
            let fixed = l * from_lights;
            // `seen_rest`: what the links other than the lights' see.
            let gathered = fixed + l * seen_rest;
            let q = closed_sum(fixed, gathered, from_lights, seen_rest, enclosed, l);
            assert!(
                (q - l * enclosed).abs().max_element() < 1e-6,
                "{seen_rest}: {q}"
            );
        }
    }

    #[test]
    fn the_lights_share_stays_and_the_rest_is_scaled_or_filled() {
        let fixed = Vec3::splat(0.5);
        let rest = Vec3::splat(0.2);
        // Twice what is due (the rest sees 1.0 where 0.5 is due): the rest is halved, the
        // lights' part kept.
        let q = closed_sum(fixed, fixed + rest, 0.1, 1.0, 0.6, Vec3::ONE);
        assert!((q - (fixed + rest * 0.5)).abs().max_element() < 1e-6);
        // A tenth short (0.4 where 0.5 is due): filled with the rest's radiance.
        let q = closed_sum(fixed, fixed + rest, 0.1, 0.4, 0.6, Vec3::splat(0.3));
        assert!(
            (q - (fixed + rest + Vec3::splat(0.3 * 0.1)))
                .abs()
                .max_element()
                < 1e-6
        );
        // No links but the lights': the rest's radiance is all links'.
        assert_eq!(
            rest_radiance(Vec3::ONE, 0.0, Vec3::splat(2.0), 4.0),
            Vec3::splat(0.5)
        );
        assert_eq!(
            rest_radiance(Vec3::ONE, 0.5, Vec3::splat(2.0), 4.0),
            Vec3::splat(2.0)
        );
        assert!((missing_view(0.9, 0.5, 0.1) - 0.3).abs() < 1e-6);
        assert_eq!(missing_view(0.9, 0.95, 0.1), 0.0);
    }
}
