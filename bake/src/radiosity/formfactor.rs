//! Form factors: the analytic point-to-polygon form factor (Lambert 1760; in the contour form of
//! Baum, Rushmeier & Winget, "Improving radiosity solutions through the use of analytically
//! determined form-factors", SIGGRAPH 1989), clipped to the receiver's hemisphere so that it
//! stays correct for any receiver normal (the enrichment of Padrón et al. 2010 evaluates the
//! receiver cosine with normals other than the geometric one), and an area-to-area estimate
//! that integrates it over stratified receiver points.

use glam::{DVec3, Vec3};

/// Form factor from a differential area at `p` with unit normal `n` to the planar convex
/// polygon `poly` (counter-clockwise seen from its front), unoccluded. Zero when `p` is behind
/// the polygon; the part of the polygon below `p`'s tangent plane is clipped away.
pub fn point_to_polygon(p: Vec3, n: Vec3, poly: &[Vec3]) -> f32 {
    if poly.len() < 3 {
        return 0.0;
    }
    let pd = p.as_dvec3();
    let src_n = (poly[1] - poly[0]).cross(poly[2] - poly[0]).as_dvec3();
    // One-sided source: seen from behind (or edge-on) it sends nothing.
    if src_n.dot(pd - poly[0].as_dvec3()) <= 0.0 {
        return 0.0;
    }
    let (rel, k) = relative(pd, poly);
    clipped_contour(&rel[..k], n.as_dvec3(), None)
}

/// The vertices of `poly` (at most [`MAX_VERTICES`] of them) relative to `p`, and their count.
#[inline(always)]
fn relative(p: DVec3, poly: &[Vec3]) -> ([DVec3; MAX_VERTICES], usize) {
    let mut rel = [DVec3::ZERO; MAX_VERTICES];
    for (r, v) in rel.iter_mut().zip(poly) {
        *r = v.as_dvec3() - p;
    }
    (rel, poly.len().min(MAX_VERTICES))
}

/// Most polygon vertices a form factor reads; the rest are ignored.
const MAX_VERTICES: usize = 7;

/// One edge of a contour, from `a` to `b` (relative to the receiving point): the angle it
/// subtends, `a × b` and that product's length.
type Edge = (f64, DVec3, f64);

#[inline(always)]
fn edge(a: DVec3, b: DVec3) -> Edge {
    let c = a.cross(b);
    let lc = c.length();
    // The angle between `a` and `b`: atan2(|a × b|, a · b) needs neither length and stays
    // accurate for small angles, where the arc cosine of their normalised dot product loses
    // half its digits.
    (angle(lc, a.dot(b)), c, lc)
}

/// The form factor at the receiving point (the origin of `rel`, the polygon's vertices) for
/// unit normal `n`, of the polygon clipped to the half-space `n · x >= 0`. `whole`, where given,
/// holds the unclipped polygon's edges ([`edge`] of vertex `i` and `i + 1`): an edge the plane
/// leaves whole is read from it rather than found again, the same value bit for bit.
#[inline(always)]
fn clipped_contour(rel: &[DVec3], n: DVec3, whole: Option<&[Edge; MAX_VERTICES]>) -> f32 {
    let k = rel.len();
    // The clipped polygon, with the polygon's index of each vertex it keeps (`usize::MAX` for
    // the points where the plane cuts an edge).
    let mut clipped = [DVec3::ZERO; MAX_VERTICES + 1];
    let mut from = [usize::MAX; MAX_VERTICES + 1];
    let mut len = 0;
    for i in 0..k {
        let a = rel[i];
        let b = rel[(i + 1) % k];
        let (da, db) = (n.dot(a), n.dot(b));
        if da >= 0.0 {
            clipped[len] = a;
            from[len] = i;
            len += 1;
        }
        if (da >= 0.0) != (db >= 0.0) && len < clipped.len() {
            let t = da / (da - db);
            clipped[len] = a + (b - a) * t;
            len += 1;
        }
    }
    if len < 3 {
        return 0.0;
    }
    // F = 1/(2π) Σ γ_i n·(r_i × r_{i+1}) / |r_i × r_{i+1}|, γ_i the angle subtended by edge i.
    // Counter-clockwise seen from the front means the sum is negative from the front side.
    let mut sum = 0.0f64;
    for i in 0..len {
        let next = (i + 1) % len;
        let kept = from[i] != usize::MAX && from[next] == (from[i] + 1) % k;
        let (gamma, c, lc) = match whole {
            Some(e) if kept => e[from[i]],
            _ => edge(clipped[i], clipped[next]),
        };
        if lc < 1e-300 {
            continue;
        }
        sum += gamma * n.dot(c) / lc;
    }
    ((-sum / (2.0 * std::f64::consts::PI)).max(0.0)) as f32
}

/// [`point_to_polygon`] from one point `p` to `poly` for each of `normals`, handed to
/// `out(j, value)` in order, each value bit for bit the one [`point_to_polygon`] gives. The
/// contour's edges (their cross products and angles, most of the cost) do not depend on the
/// normal: they are found once, and a normal whose tangent plane clips nothing reads them all,
/// one that clips the polygon those the plane leaves whole. A multiresolution receiver
/// evaluates every source for up to eight normals at once, and each took the whole contour
/// again.
pub fn point_to_polygon_each(
    p: Vec3,
    normals: &[Vec3],
    poly: &[Vec3],
    mut out: impl FnMut(usize, f32),
) {
    if poly.len() < 3 || normals.len() < 2 {
        for (j, n) in normals.iter().enumerate() {
            out(j, point_to_polygon(p, *n, poly));
        }
        return;
    }
    let pd = p.as_dvec3();
    let src_n = (poly[1] - poly[0]).cross(poly[2] - poly[0]).as_dvec3();
    if src_n.dot(pd - poly[0].as_dvec3()) <= 0.0 {
        for j in 0..normals.len() {
            out(j, 0.0);
        }
        return;
    }
    let (rel, k) = relative(pd, poly);
    let mut edges = [(0.0, DVec3::ZERO, 0.0); MAX_VERTICES];
    for i in 0..k {
        edges[i] = edge(rel[i], rel[(i + 1) % k]);
    }
    for (j, n) in normals.iter().enumerate() {
        let nd = n.as_dvec3();
        if !rel[..k].iter().all(|a| nd.dot(*a) >= 0.0) {
            out(j, clipped_contour(&rel[..k], nd, Some(&edges)));
            continue;
        }
        let mut sum = 0.0f64;
        for &(gamma, c, lc) in &edges[..k] {
            if lc < 1e-300 {
                continue;
            }
            sum += gamma * nd.dot(c) / lc;
        }
        out(j, ((-sum / (2.0 * std::f64::consts::PI)).max(0.0)) as f32);
    }
}

/// `atan2(y, x)` for `y ≥ 0` (an angle in `0..=π`), to within 1e-9 rad: the library's `atan2`
/// took a twelfth of a bake's time in [`point_to_polygon`]. Reduced to `|t| ≤ tan(π/8)` by
/// `atan t = π/2 − atan(1/t)` and `atan t = π/4 + atan((t − 1)/(t + 1))`, then the Taylor
/// series to `t¹⁹` (its remainder below `0.4143²¹ / 21`).
#[inline(always)]
fn angle(y: f64, x: f64) -> f64 {
    /// The Taylor coefficients of `atan u / u` in `u²`: `(−1)ᵏ / (2k + 1)`.
    const ATAN_SERIES: [f64; 10] = {
        let mut c = [0.0f64; 10];
        let mut k = 0;
        while k < 10 {
            let sign = if k % 2 == 0 { 1.0 } else { -1.0 };
            c[k] = sign / (2 * k + 1) as f64;
            k += 1;
        }
        c
    };
    use std::f64::consts::{FRAC_PI_2, FRAC_PI_4, PI};
    let ax = x.abs();
    if y == 0.0 && ax == 0.0 {
        return 0.0;
    }
    // t = min / max in 0..=1, and whether the arguments were swapped.
    let (t, swapped) = if y <= ax {
        (y / ax, false)
    } else {
        (ax / y, true)
    };
    const TAN_PI_8: f64 = 0.414_213_562_373_095_1;
    let (u, base) = if t > TAN_PI_8 {
        ((t - 1.0) / (t + 1.0), FRAC_PI_4)
    } else {
        (t, 0.0)
    };
    let u2 = u * u;
    let series = ATAN_SERIES.iter().rev().fold(0.0f64, |s, c| s * u2 + c);
    let mut r = base + u * series;
    if swapped {
        r = FRAC_PI_2 - r;
    }
    if x < 0.0 {
        r = PI - r;
    }
    r
}

/// Stratified sample points of a triangle: the centroids of its `4^level` subtriangles after
/// `level` rounds of the 1-to-4 split (so the points tile the triangle evenly), in the order of
/// their paths (first choice most significant).
pub fn stratified_points(tri: [Vec3; 3], level: u32) -> Vec<Vec3> {
    fn rec(t: [Vec3; 3], level: u32, out: &mut Vec<Vec3>) {
        if level == 0 {
            out.push((t[0] + t[1] + t[2]) / 3.0);
            return;
        }
        for child in super::element::split(t) {
            rec(child, level - 1, out);
        }
    }
    let mut out = Vec::with_capacity(1 << (2 * level.min(12)));
    rec(tri, level, &mut out);
    out
}

/// [`stratified_points`] at level 2, on the stack: a near link's sixteen receiver points,
/// found for every such link.
pub fn stratified_16(tri: [Vec3; 3]) -> [Vec3; 16] {
    let mut out = [Vec3::ZERO; 16];
    for (i, a) in super::element::split(tri).into_iter().enumerate() {
        for (j, b) in super::element::split(a).into_iter().enumerate() {
            out[i * 4 + j] = (b[0] + b[1] + b[2]) / 3.0;
        }
    }
    out
}

/// Area-to-area form factor from triangle `recv` to triangle `src`, unoccluded: the
/// point-to-polygon form factor averaged over `4^level` stratified receiver points.
#[cfg(test)]
pub fn triangle_to_triangle(recv: [Vec3; 3], src: [Vec3; 3], level: u32) -> f32 {
    let n = (recv[1] - recv[0]).cross(recv[2] - recv[0]).normalize();
    let pts = stratified_points(recv, level);
    let sum: f64 = pts
        .iter()
        .map(|&p| f64::from(point_to_polygon(p, n, &src)))
        .sum();
    (sum / pts.len() as f64) as f32
}

/// Area-to-area form factor between two triangulated patches (area-weighted over the receiver
/// triangles, summed over the source triangles).
#[cfg(test)]
pub fn patch_to_patch(recv: &[[Vec3; 3]], src: &[[Vec3; 3]], level: u32) -> f32 {
    let area = |t: &[Vec3; 3]| f64::from((t[1] - t[0]).cross(t[2] - t[0]).length() * 0.5);
    let total: f64 = recv.iter().map(area).sum();
    let mut f = 0.0f64;
    for r in recv {
        for s in src {
            f += area(r) * f64::from(triangle_to_triangle(*r, *s, level));
        }
    }
    (f / total) as f32
}

/// Cheap unoccluded estimate used by the refinement oracle: the disc approximation
/// `A_s cosθ_r cosθ_s / (π d² + A_s)`, bounded by 1 even for nearby elements.
pub fn disc_estimate(cos_r: f32, cos_s: f32, src_area: f32, dist2: f32) -> f32 {
    (src_area * cos_r.max(0.0) * cos_s.max(0.0) / (std::f32::consts::PI * dist2 + src_area))
        .min(1.0)
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn sixteen_stratified_points_on_the_stack_are_level_twos() {
        let tri = [
            Vec3::new(0.3, -1.0, 2.0),
            Vec3::new(4.0, 0.1, -0.7),
            Vec3::new(-2.0, 3.0, 0.9),
        ];
        assert_eq!(stratified_16(tri).to_vec(), stratified_points(tri, 2));
        assert_eq!(
            stratified_points(tri, 0),
            vec![(tri[0] + tri[1] + tri[2]) / 3.0]
        );
        assert_eq!(stratified_points(tri, 3).len(), 64);
    }

    #[test]
    fn angle_is_atan2_over_the_upper_half_plane() {
        let mut worst = 0.0f64;
        for i in 0..=2000 {
            let phi = std::f64::consts::PI * f64::from(i) / 2000.0;
            for r in [1e-12, 1e-3, 1.0, 7.5e5] {
                let (y, x) = (r * phi.sin().abs(), r * phi.cos());
                worst = worst.max((angle(y, x) - y.atan2(x)).abs());
            }
        }
        assert!(worst < 1e-9, "{worst}");
        assert_eq!(angle(0.0, 0.0), 0.0);
        assert_eq!(angle(0.0, 2.0), 0.0);
        assert!((angle(0.0, -2.0) - std::f64::consts::PI).abs() < 1e-15);
    }

    #[test]
    fn each_normal_gets_the_single_normals_value_bit_for_bit() {
        let mut rng = crate::radiosity::element::Rng::new(4, 5, 6);
        let mut v = || {
            Vec3::new(
                rng.next_f32() * 2.0 - 1.0,
                rng.next_f32() * 2.0 - 1.0,
                rng.next_f32() * 2.0 - 1.0,
            )
        };
        let mut clipped = 0;
        for i in 0..4000 {
            // Triangles, and parallelograms (four vertices: a contour the plane can cut into
            // five edges, two of them kept).
            let (a, b, c) = (v() + Vec3::Z, v() + Vec3::Z, v() + Vec3::Z);
            let poly = if i % 2 == 0 {
                vec![a, b, c]
            } else {
                vec![a, b, c, a + c - b]
            };
            let p = v() * 0.5;
            let normals: Vec<Vec3> = (0..5).map(|_| v().normalize_or(Vec3::Z)).collect();
            let mut got = vec![f32::NAN; normals.len()];
            point_to_polygon_each(p, &normals, &poly, |j, f| got[j] = f);
            for (j, n) in normals.iter().enumerate() {
                let want = point_to_polygon(p, *n, &poly);
                assert_eq!(got[j].to_bits(), want.to_bits(), "{p} {n} {poly:?}");
                clipped += usize::from(poly.iter().any(|q| n.dot(*q - p) < 0.0));
            }
        }
        // Both paths were taken: normals that clip the polygon and normals that do not.
        assert!(clipped > 2000 && clipped < 18000, "{clipped}");
    }

    fn square(o: Vec3, u: Vec3, v: Vec3) -> Vec<[Vec3; 3]> {
        // Counter-clockwise seen from u × v.
        vec![[o, o + u, o + u + v], [o, o + u + v, o + v]]
    }

    #[test]
    fn perpendicular_unit_squares_sharing_an_edge() {
        // Floor in z = 0 facing +z; wall in x = 0 facing +x, sharing the edge along y.
        let floor = square(Vec3::ZERO, Vec3::X, Vec3::Y);
        let wall = square(Vec3::ZERO, Vec3::Y, Vec3::Z);
        let f = patch_to_patch(&floor, &wall, 5);
        assert!((f - 0.20004).abs() / 0.20004 < 0.01, "F = {f}");
    }

    #[test]
    fn parallel_unit_squares_one_apart() {
        let bottom = square(Vec3::ZERO, Vec3::X, Vec3::Y);
        // Facing down: counter-clockwise seen from below.
        let top = square(Vec3::Z, Vec3::Y, Vec3::X);
        let f = patch_to_patch(&bottom, &top, 4);
        assert!((f - 0.19982).abs() / 0.19982 < 0.01, "F = {f}");
    }

    #[test]
    fn hemisphere_clipping_and_back_faces() {
        // A huge polygon above p covers the whole hemisphere: F -> 1.
        let big = [
            Vec3::new(-1e4, -1e4, 1.0),
            Vec3::new(-1e4, 1e4, 1.0),
            Vec3::new(1e4, 1e4, 1.0),
            Vec3::new(1e4, -1e4, 1.0),
        ];
        let f = point_to_polygon(Vec3::ZERO, Vec3::Z, &big);
        assert!((f - 1.0).abs() < 1e-3, "{f}");
        // Tilted 90 degrees the receiver sees half of it, with half of the cosine weight.
        let f = point_to_polygon(Vec3::ZERO, Vec3::X, &big);
        assert!((f - 0.5).abs() < 1e-3, "{f}");
        // From behind the polygon nothing arrives.
        let f = point_to_polygon(Vec3::new(0.0, 0.0, 2.0), Vec3::NEG_Z, &big);
        assert_eq!(f, 0.0);
    }
}
