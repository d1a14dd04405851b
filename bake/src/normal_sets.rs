//! Stage 1: the representative normal set of each coarse triangle of a multiresolution object
//! (Padrón et al., "Hierarchical radiosity for multiresolution systems based on normal tests",
//! The Computer Journal 2010; Concheiro et al., GRAPP 2012).
//!
//! Method: greedy k-centre on the unit sphere (farthest-point insertion, Gonzalez 1985). The set
//! starts with the coarse triangle's geometric normal n0; while the budget allows and some
//! subtriangle normal is farther than the tolerance from every representative, the farthest
//! such normal (ties: the lowest index) joins the set. Farthest-point insertion is within a
//! factor two of the optimal covering radius for the same budget, is deterministic and costs
//! O(k · n) per triangle. Zero-area subtriangles carry no light and are ignored.

use glam::Vec3;

/// Selection parameters.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct NormalSetParams {
    /// Most normals added to n0 (so a set holds at most `1 + max_normals`). Default 7.
    pub max_normals: usize,
    /// Target covering angle in degrees. Default 5: at 10 (the previous default) the sets of
    /// strongly curved coarse triangles left a blotch of each triangle's shape in the light
    /// (the face of the spot, the forehead of suzanne): 3.0% RMS against path-traced images on
    /// the spot, 2.6% at 5, for files about a quarter larger (BENCHMARKS.md, issue 20).
    pub normal_tolerance_deg: f32,
}

impl Default for NormalSetParams {
    fn default() -> Self {
        NormalSetParams {
            max_normals: 7,
            normal_tolerance_deg: 5.0,
        }
    }
}

/// The set chosen for one coarse triangle.
#[derive(Clone, Debug, PartialEq)]
pub struct NormalSet {
    /// Unit normals, the coarse normal first.
    pub normals: Vec<[f32; 3]>,
    /// Largest angle (degrees) between a subtriangle normal and its nearest representative.
    pub worst_angle_deg: f32,
}

/// Statistics over many triangles.
#[derive(Clone, Debug, Default, PartialEq)]
pub struct NormalSetReport {
    /// `histogram[k]`: number of triangles whose set holds `k` normals (n0 included).
    pub histogram: Vec<usize>,
    /// Largest remaining angle over all triangles, degrees.
    pub worst_angle_deg: f32,
    /// Triangles whose worst angle exceeds the tolerance because the budget ran out.
    pub over_tolerance: usize,
}

fn angle_deg(cos: f32) -> f32 {
    cos.clamp(-1.0, 1.0).acos().to_degrees()
}

/// Selects the set for one coarse triangle from its subtriangles' `(normal, area)` pairs.
pub fn select_normal_set(
    coarse_normal: [f32; 3],
    subtriangles: &[([f32; 3], f32)],
    params: &NormalSetParams,
) -> NormalSet {
    let n0 = Vec3::from(coarse_normal).normalize_or_zero();
    let n0 = if n0 == Vec3::ZERO { Vec3::Z } else { n0 };
    let subs: Vec<Vec3> = subtriangles
        .iter()
        .filter(|(n, a)| *a > 0.0 && a.is_finite() && n.iter().all(|c| c.is_finite()))
        .map(|(n, _)| Vec3::from(*n).normalize_or_zero())
        .filter(|n| *n != Vec3::ZERO)
        .collect();
    let cos_tol = params.normal_tolerance_deg.to_radians().cos();
    let mut reps = vec![n0];
    // Best cosine from every subtriangle normal to its nearest representative so far.
    let mut best: Vec<f32> = subs.iter().map(|n| n.dot(n0)).collect();
    while reps.len() <= params.max_normals {
        let mut worst: Option<(usize, f32)> = None;
        for (i, &c) in best.iter().enumerate() {
            if worst.is_none_or(|(_, w)| c < w) {
                worst = Some((i, c));
            }
        }
        let Some((i, c)) = worst else { break };
        if c >= cos_tol {
            break;
        }
        let r = subs[i];
        reps.push(r);
        for (b, n) in best.iter_mut().zip(&subs) {
            *b = b.max(n.dot(r));
        }
    }
    let worst_cos = best.iter().copied().fold(1.0f32, f32::min);
    NormalSet {
        normals: reps.iter().map(|n| n.to_array()).collect(),
        worst_angle_deg: angle_deg(worst_cos),
    }
}

/// Selects a set per coarse triangle and summarises them.
pub fn select_normal_sets<'a>(
    triangles: impl IntoIterator<Item = ([f32; 3], &'a [([f32; 3], f32)])>,
    params: &NormalSetParams,
) -> (Vec<NormalSet>, NormalSetReport) {
    let mut report = NormalSetReport {
        histogram: vec![0; params.max_normals + 2],
        ..Default::default()
    };
    let sets: Vec<NormalSet> = triangles
        .into_iter()
        .map(|(n0, subs)| select_normal_set(n0, subs, params))
        .collect();
    for s in &sets {
        report.histogram[s.normals.len()] += 1;
        report.worst_angle_deg = report.worst_angle_deg.max(s.worst_angle_deg);
        if s.worst_angle_deg > params.normal_tolerance_deg {
            report.over_tolerance += 1;
        }
    }
    (sets, report)
}

#[cfg(test)]
mod tests {
    use super::*;

    fn dir(theta_deg: f32, phi_deg: f32) -> [f32; 3] {
        let (t, p) = (theta_deg.to_radians(), phi_deg.to_radians());
        [t.sin() * p.cos(), t.sin() * p.sin(), t.cos()]
    }

    #[test]
    fn flat_triangle_keeps_only_the_coarse_normal() {
        let subs = vec![([0.0, 0.0, 1.0], 1.0); 16];
        let s = select_normal_set([0.0, 0.0, 2.0], &subs, &NormalSetParams::default());
        assert_eq!(s.normals, vec![[0.0, 0.0, 1.0]]);
        assert!(s.worst_angle_deg < 1e-3);
    }

    #[test]
    fn clusters_of_normals_get_one_representative_each() {
        // Three tight clusters 40 degrees off the axis, 120 degrees apart.
        let mut subs = Vec::new();
        for phi in [0.0, 120.0, 240.0] {
            for d in [-2.0, 0.0, 2.0] {
                subs.push((dir(40.0 + d, phi + d), 1.0));
            }
        }
        let s = select_normal_set([0.0, 0.0, 1.0], &subs, &NormalSetParams::default());
        assert_eq!(s.normals.len(), 4, "{s:?}");
        assert!(s.worst_angle_deg <= 10.0, "{s:?}");
        assert_eq!(s.normals[0], [0.0, 0.0, 1.0]);
    }

    #[test]
    fn budget_limits_the_set_and_reports_the_remaining_angle() {
        let subs: Vec<_> = (0..36).map(|k| (dir(60.0, k as f32 * 10.0), 1.0)).collect();
        let p = NormalSetParams {
            max_normals: 2,
            normal_tolerance_deg: 10.0,
        };
        let s = select_normal_set([0.0, 0.0, 1.0], &subs, &p);
        assert_eq!(s.normals.len(), 3);
        // Two opposite representatives on the 60-degree cone leave normals 90 degrees of
        // azimuth away: their angle to the nearest representative is about 60 degrees.
        assert!(
            s.worst_angle_deg > 40.0 && s.worst_angle_deg < 61.0,
            "{s:?}"
        );
        let (sets, rep) = select_normal_sets([([0.0, 0.0, 1.0], &subs[..])], &p);
        assert_eq!(sets[0], s);
        assert_eq!(rep.histogram, vec![0, 0, 0, 1]);
        assert_eq!(rep.over_tolerance, 1);
    }

    #[test]
    fn zero_area_subtriangles_are_ignored() {
        let subs = vec![([1.0, 0.0, 0.0], 0.0), ([0.0, 0.0, 1.0], 1.0)];
        let s = select_normal_set([0.0, 0.0, 1.0], &subs, &NormalSetParams::default());
        assert_eq!(s.normals.len(), 1);
    }
}
