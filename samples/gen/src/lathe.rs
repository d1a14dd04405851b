//! Surfaces of revolution from a profile, with tagged hard rings, and the Teatime cup.
//!
//! A profile runs from the bottom of the axis to the top, `(radius, height)` per point; a point
//! on the axis becomes a single pole vertex, so a profile that starts and ends on the axis
//! gives a closed surface. A point marked `crease` starts a new smoothing group: the ring of
//! edges there gets split normals in the glTF, which `hce bake --creases auto` keeps sharp.

use std::f64::consts::TAU;

use glam::DVec3;

use crate::mesh::Mesh;

/// One point of a lathe profile.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct ProfilePoint {
    /// Distance from the Y axis in metres; 0 makes a pole.
    pub r: f64,
    /// Height in metres.
    pub y: f64,
    /// Whether the ring at this point is a hard edge.
    pub crease: bool,
}

/// Smooth profile point.
pub const fn p(r: f64, y: f64) -> ProfilePoint {
    ProfilePoint {
        r,
        y,
        crease: false,
    }
}

/// Profile point whose ring is a hard edge.
pub const fn c(r: f64, y: f64) -> ProfilePoint {
    ProfilePoint { r, y, crease: true }
}

/// The vertex indices of a lathe, ring by ring, for callers that cut holes or attach parts.
pub struct Lathe {
    pub mesh: Mesh,
    /// `rings[k][j]`: profile point `k` at angle step `j` (a pole repeats one index).
    pub rings: Vec<Vec<u32>>,
    /// Smoothing group of the band between profile points `k` and `k + 1`.
    pub band_groups: Vec<u32>,
}

/// Revolves `profile` around the Y axis in `segments` steps (at least 3), counter-clockwise
/// seen from above, starting at +X. `skip(k, j)` leaves out the quad between profile points `k`, `k + 1`
/// and angle steps `j`, `j + 1` (to cut a hole for a handle).
pub fn lathe_with_holes(
    profile: &[ProfilePoint],
    segments: u32,
    skip: impl Fn(usize, u32) -> bool,
) -> Lathe {
    let segments = segments.max(3);
    let mut mesh = Mesh::default();
    let rings: Vec<Vec<u32>> = profile
        .iter()
        .map(|q| {
            if q.r == 0.0 {
                vec![mesh.vertex(DVec3::new(0.0, q.y, 0.0)); segments as usize]
            } else {
                (0..segments)
                    .map(|j| {
                        // z = -r sin(a) turns counter-clockwise seen from above (+Y).
                        let a = TAU * j as f64 / segments as f64;
                        mesh.vertex(DVec3::new(q.r * a.cos(), q.y, -q.r * a.sin()))
                    })
                    .collect()
            }
        })
        .collect();
    let mut group = 0;
    let mut band_groups = Vec::new();
    for k in 0..profile.len().saturating_sub(1) {
        if k > 0 && profile[k].crease {
            group += 1;
        }
        band_groups.push(group);
        for j in 0..segments {
            if skip(k, j) {
                continue;
            }
            let j1 = (j + 1) % segments;
            let (lo, hi) = (&rings[k], &rings[k + 1]);
            // Up the profile then around: outward for a profile that runs bottom to top.
            mesh.quad(
                [
                    lo[j as usize],
                    lo[j1 as usize],
                    hi[j1 as usize],
                    hi[j as usize],
                ],
                group,
            );
        }
    }
    Lathe {
        mesh,
        rings,
        band_groups,
    }
}

/// Revolves `profile` around the Y axis (see [`lathe_with_holes`]).
pub fn lathe(profile: &[ProfilePoint], segments: u32) -> Mesh {
    lathe_with_holes(profile, segments, |_, _| false).mesh
}

/// The Teatime cup: a lathed cup with wall thickness and a foot rim (a hard edge), and a
/// handle that is part of the same surface: a four-sided tube leaving the wall through one
/// quad and entering it again through another, so the cup is a single closed surface of genus
/// one. Loop subdivision rounds the square tube into a handle. Standing on `y = 0`, handle
/// towards +X.
pub fn cup() -> Mesh {
    const SEGMENTS: u32 = 12;
    let profile = [
        p(0.0, 0.0),
        c(0.030, 0.0),
        p(0.034, 0.016),
        p(0.038, 0.036),
        p(0.041, 0.056),
        p(0.044, 0.076),
        p(0.046, 0.089),
        p(0.0445, 0.093),
        p(0.042, 0.089),
        p(0.038, 0.056),
        p(0.031, 0.016),
        p(0.0, 0.010),
    ];
    // The handle joins the wall at the quads between profile points UPPER..UPPER+1 and
    // LOWER..LOWER+1 in the angle step facing +X (steps 11..0 straddle the X axis).
    const UPPER: usize = 4;
    const LOWER: usize = 2;
    const STEP: u32 = SEGMENTS - 1;
    let l = lathe_with_holes(&profile, SEGMENTS, |k, j| {
        j == STEP && (k == UPPER || k == LOWER)
    });
    let mut mesh = l.mesh;
    let group = l.band_groups[UPPER];
    let (j0, j1) = (STEP as usize, 0usize);
    let r = &l.rings;
    // Corner q of the upper hole runs to corner q of the lower one; the top edge of the upper
    // hole becomes the outside of the handle's curve and ends at the bottom edge of the lower.
    let upper = [
        r[UPPER][j0],
        r[UPPER][j1],
        r[UPPER + 1][j1],
        r[UPPER + 1][j0],
    ];
    let lower = [
        r[LOWER + 1][j0],
        r[LOWER + 1][j1],
        r[LOWER][j1],
        r[LOWER][j0],
    ];
    const STEPS: usize = 6;
    const REACH: f64 = 0.014;
    let outward = DVec3::X;
    let mut rings = vec![upper];
    for s in 1..STEPS {
        let t = std::f64::consts::PI * s as f64 / STEPS as f64;
        let ring = std::array::from_fn(|q| {
            let a = mesh.positions[upper[q] as usize];
            let b = mesh.positions[lower[q] as usize];
            let centre = (a + b) / 2.0;
            let half = a - centre;
            // A half-ellipse from a to b bulging outwards; corners far from the centre (the
            // outside of the curve) swing wider, so the tube keeps its thickness.
            mesh.vertex(centre + half * t.cos() + outward * (half.length() + REACH) * t.sin())
        });
        rings.push(ring);
    }
    rings.push(lower);
    for w in rings.windows(2) {
        for q in 0..4 {
            let q1 = (q + 1) % 4;
            mesh.quad([w[0][q], w[0][q1], w[1][q1], w[1][q]], group);
        }
    }
    mesh
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn closed_lathe_is_a_sphere_with_poles() {
        let profile = [p(0.0, 0.0), c(1.0, 0.0), c(1.0, 1.0), p(0.0, 1.0)];
        let m = lathe(&profile, 8);
        // Two pole fans of 8 triangles and one band of 8 quads.
        assert_eq!(m.triangles.len(), 8 + 16 + 8);
        assert_eq!(m.positions.len(), 2 + 16);
        let s = m.edge_stats();
        assert_eq!((s.boundary, s.non_manifold, s.inconsistent), (0, 0, 0));
        assert!(m.signed_volume() > 0.0);
        // Three smoothing groups: bottom disk, side, top disk (two hard rings).
        let mut groups = m.groups.clone();
        groups.dedup();
        assert_eq!(groups, vec![0, 1, 2]);
        // The volume of a cylinder approximated by an octagonal prism: 8 · ½ sin(45°).
        let expected = 8.0 * 0.5 * (std::f64::consts::FRAC_PI_4).sin();
        assert!((m.signed_volume() - expected).abs() < 1e-12);
    }

    #[test]
    fn cup_is_a_closed_torus_like_surface() {
        let m = cup();
        let s = m.edge_stats();
        assert_eq!(s.boundary, 0);
        assert_eq!(s.non_manifold, 0);
        assert_eq!(s.inconsistent, 0);
        assert_eq!(m.non_manifold_vertices(), 0);
        // Euler characteristic V - E + F = 2 - 2g; the handle makes genus 1.
        let v = m.positions.len() as i64;
        let e = s.interior as i64;
        let f = m.triangles.len() as i64;
        assert_eq!(v - e + f, 0);
        assert!(m.signed_volume() > 0.0);
        let (lo, hi) = m.bounds().unwrap();
        assert!(lo.y.abs() < 1e-12 && (hi.y - 0.093).abs() < 1e-12);
        // The handle reaches past the rim on the +X side only.
        assert!(hi.x > 0.06 && hi.x < 0.09, "{hi}");
        assert!((lo.x + 0.046).abs() < 1e-3, "{lo}");
        assert!(m.min_triangle_area() > 1e-7);
    }
}
