//! The Teatime spoon: a loft of crescent-shaped cross-sections along the spoon's length.
//!
//! Each station along X has a half-width, a half-thickness, a sag (how far the middle of the
//! cross-section dips below its edges, which is what hollows the bowl) and a height (the handle
//! rises away from the table). The two ends close in single pole vertices, so the spoon is one
//! closed genus-0 surface: a thin shell Loop subdivision rounds into a spoon.

use std::f64::consts::TAU;

use glam::DVec3;

use crate::mesh::Mesh;

/// One cross-section of the spoon: position along X and its shape.
struct Station {
    x: f64,
    half_width: f64,
    half_thickness: f64,
    sag: f64,
    height: f64,
}

const fn st(x: f64, half_width: f64, half_thickness: f64, sag: f64, height: f64) -> Station {
    Station {
        x,
        half_width,
        half_thickness,
        sag,
        height,
    }
}

/// Points around each cross-section.
const AROUND: u32 = 8;

/// The spoon, bowl towards +X, resting on `y = 0`, 0.14 m long.
pub fn spoon() -> Mesh {
    let stations = [
        st(0.004, 0.0055, 0.0016, 0.0, 0.014),
        st(0.022, 0.0060, 0.0016, 0.0, 0.011),
        st(0.048, 0.0045, 0.0015, 0.0, 0.006),
        st(0.074, 0.0035, 0.0015, 0.0, 0.0025),
        st(0.088, 0.0060, 0.0014, 0.0015, 0.0008),
        st(0.100, 0.0130, 0.0013, 0.0045, 0.0),
        st(0.114, 0.0165, 0.0013, 0.0060, 0.0),
        st(0.127, 0.0150, 0.0013, 0.0050, 0.0),
        st(0.136, 0.0095, 0.0013, 0.0025, 0.0005),
    ];
    let mut mesh = Mesh::default();
    let start = mesh.vertex(DVec3::new(0.0, 0.0145, 0.0));
    let rings: Vec<Vec<u32>> = stations
        .iter()
        .map(|s| {
            (0..AROUND)
                .map(|k| {
                    let a = TAU * k as f64 / AROUND as f64;
                    let (sin, cos) = a.sin_cos();
                    let y = s.height + s.half_thickness * sin - s.sag * sin * sin;
                    mesh.vertex(DVec3::new(s.x, y, s.half_width * cos))
                })
                .collect()
        })
        .collect();
    let end = mesh.vertex(DVec3::new(0.1405, 0.0006, 0.0));
    let n = AROUND as usize;
    for k in 0..n {
        let k1 = (k + 1) % n;
        mesh.triangle([start, rings[0][k], rings[0][k1]], 0);
        for w in rings.windows(2) {
            mesh.quad([w[0][k], w[1][k], w[1][k1], w[0][k1]], 0);
        }
        let last = &rings[rings.len() - 1];
        mesh.triangle([end, last[k1], last[k]], 0);
    }
    // Rest the lowest point on the table.
    let lowest = mesh.bounds().map_or(0.0, |(lo, _)| lo.y);
    mesh.map_positions(|p| p - DVec3::Y * lowest);
    mesh
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn spoon_is_a_closed_thin_shell() {
        let m = spoon();
        assert_eq!(m.triangles.len(), 2 * 8 + 2 * 8 * 8);
        let s = m.edge_stats();
        assert_eq!((s.boundary, s.non_manifold, s.inconsistent), (0, 0, 0));
        assert_eq!(m.non_manifold_vertices(), 0);
        assert!(m.signed_volume() > 0.0);
        let (lo, hi) = m.bounds().unwrap();
        assert!(lo.y.abs() < 1e-12);
        assert!((hi.x - lo.x - 0.1405).abs() < 1e-9);
        // The bowl is 33 mm wide; the handle end rises 14 mm over the bowl's centre line,
        // which itself sags 7 mm below it.
        assert!((hi.z - 0.0165).abs() < 1e-9 && (lo.z + 0.0165).abs() < 1e-9);
        assert!((hi.y - 0.0229).abs() < 1e-4, "{hi}");
        assert!(m.min_triangle_area() > 1e-9);
    }

    #[test]
    fn bowl_is_hollow() {
        // The top of the bowl's middle station dips below the top of its rim.
        let m = spoon();
        let at_bowl: Vec<DVec3> = m
            .positions
            .iter()
            .copied()
            .filter(|p| (p.x - 0.114).abs() < 1e-9)
            .collect();
        assert_eq!(at_bowl.len(), 8);
        let rim = at_bowl.iter().map(|p| p.y).fold(f64::MIN, f64::max);
        let centre_top = at_bowl
            .iter()
            .filter(|p| p.z.abs() < 1e-9)
            .map(|p| p.y)
            .fold(f64::MIN, f64::max);
        assert!(rim - centre_top > 0.003, "rim {rim} centre {centre_top}");
    }
}
