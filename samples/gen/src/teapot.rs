//! The Utah teapot tessellated coarsely from Newell's bicubic Bézier patches.
//!
//! Each of the 32 patches is sampled on a regular `(n + 1) × (n + 1)` parameter grid and split
//! into triangles; coincident samples on shared patch boundaries are welded so that the teapot
//! is one connected manifold mesh, and the triangles that collapse at the poles of the lid and
//! the bottom (where a whole patch row is a single control point) are dropped rather than
//! emitted. The result is deliberately coarse: Loop subdivision at render time is what makes it
//! smooth, which is the point of the Teatime sample (Concheiro et al., GRAPP 2012).
//!
//! The surface is not closed, as in the original: the rim and the lid each end in an open edge
//! (there is a gap between them), and the handle and the spout are tubes whose open ends sit
//! against the body.

use glam::DVec3;

use crate::mesh::Mesh;
use crate::teapot_data::{PATCHES, VERTICES};

/// Patches of the handle, and the body control point its lower end shares.
const HANDLE: std::ops::Range<usize> = 12..16;
const HANDLE_FOOT: usize = 68;

/// How to tessellate the teapot.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct TeapotParams {
    /// Segments along each side of a patch (default 3: 552 triangles), clamped to 1..=64.
    /// 1 gives a shape too degenerate to recognise; 2-4 are what subdivision needs.
    pub segments: u32,
    /// Metres per data unit (default 0.05: the teapot is 0.1575 m tall).
    pub scale: f64,
}

impl Default for TeapotParams {
    fn default() -> Self {
        Self {
            segments: 3,
            scale: 0.05,
        }
    }
}

/// The cubic Bernstein basis at `t`.
fn bernstein(t: f64) -> [f64; 4] {
    let s = 1.0 - t;
    [s * s * s, 3.0 * t * s * s, 3.0 * t * t * s, t * t * t]
}

/// Evaluates patch `patch` at `(u, v)`: `u` runs over the rows, `v` along a row.
fn evaluate(patch: &[u16; 16], u: f64, v: f64) -> DVec3 {
    let (bu, bv) = (bernstein(u), bernstein(v));
    let mut p = DVec3::ZERO;
    for (r, wu) in bu.iter().enumerate() {
        for (c, wv) in bv.iter().enumerate() {
            p += DVec3::from_array(VERTICES[patch[4 * r + c] as usize]) * (wu * wv);
        }
    }
    p
}

/// Builds the teapot, Y up, standing on `y = 0`, centred on the Y axis, spout towards +X.
pub fn teapot(params: &TeapotParams) -> Mesh {
    let n = params.segments.clamp(1, 64);
    let mut mesh = Mesh::default();
    let handle_foot = DVec3::from_array(VERTICES[HANDLE_FOOT]);
    for (k, patch) in PATCHES.iter().enumerate() {
        let base = mesh.positions.len() as u32;
        for i in 0..=n {
            for j in 0..=n {
                let mut p = evaluate(patch, i as f64 / n as f64, j as f64 / n as f64);
                if HANDLE.contains(&k) && p.distance(handle_foot) < 1e-9 {
                    // The handle's lower end touches the body in exactly one control point;
                    // welded, that point would join two separate fans (a non-manifold vertex
                    // Loop subdivision cannot take). Push the handle's copy 1% into the body.
                    p = DVec3::new(p.x * 0.99, p.y * 0.99, p.z);
                }
                // Newell's data is Z up; rotate -90° about X so that it is Y up (right-handed).
                mesh.vertex(DVec3::new(p.x, p.z, -p.y));
            }
        }
        let at = |i: u32, j: u32| base + i * (n + 1) + j;
        for i in 0..n {
            for j in 0..n {
                // (u, v) = (row, column) is counter-clockwise seen from outside.
                mesh.quad([at(i, j), at(i, j + 1), at(i + 1, j + 1), at(i + 1, j)], 0);
            }
        }
    }
    // Shared boundaries are evaluated from the same control points (sometimes in reverse
    // order), so they agree to a few ulps; the tolerance is far below the sample spacing.
    mesh.weld(1e-6);
    mesh.map_positions(|p| p * params.scale);
    mesh
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn coarse_teapot_is_one_consistent_manifold() {
        for n in 2..=4u32 {
            let m = teapot(&TeapotParams {
                segments: n,
                scale: 1.0,
            });
            // 32 patches of 2n² triangles, less the n triangles of each of the 8 pole patches
            // that collapse (the count three.js's TeapotGeometry documents: 32·2n² - 8n).
            assert_eq!(m.triangles.len() as u32, 64 * n * n - 8 * n, "n = {n}");
            let s = m.edge_stats();
            assert_eq!(s.non_manifold, 0, "n = {n}");
            assert_eq!(m.non_manifold_vertices(), 0, "n = {n}");
            assert_eq!(s.inconsistent, 0, "n = {n}");
            assert!(m.min_triangle_area() > 1e-4, "n = {n}");
            assert!(!m.has_coincident_positions(1e-6));
        }
    }

    #[test]
    fn boundaries_are_the_rim_lid_handle_and_spout_openings() {
        let n = 3;
        let m = teapot(&TeapotParams {
            segments: n,
            scale: 1.0,
        });
        // Open loops: the rim's inner edge and the lid's outer edge (4 patches × n edges each),
        // the handle's two ends and the spout's two ends (2 patches × n edges each).
        assert_eq!(m.edge_stats().boundary as u32, 2 * 4 * n + 4 * 2 * n);
        // Body+rim+bottom, lid, handle and spout are separate pieces, as in Newell's data.
        assert_eq!(m.components(), 4);
    }

    #[test]
    fn teapot_faces_outwards_and_has_the_classic_extent() {
        let m = teapot(&TeapotParams {
            segments: 3,
            scale: 1.0,
        });
        let (lo, hi) = m.bounds().unwrap();
        // Bottom at 0, lid knob at 3.15, handle at x = -3, spout tip near x = 3.4.
        assert!(lo.y.abs() < 1e-9 && (hi.y - 3.15).abs() < 1e-9, "{lo} {hi}");
        assert!(lo.x < -2.8 && lo.x > -3.0 - 1e-9, "{lo}");
        assert!(hi.x > 3.3 && hi.x < 3.525, "{hi}");
        // Outward orientation: on the body, normals point away from the Y axis.
        let outward: f64 = m
            .triangles
            .iter()
            .map(|t| {
                let c = t.iter().map(|&i| m.positions[i as usize]).sum::<DVec3>() / 3.0;
                m.face_normal(t).dot(DVec3::new(c.x, 0.0, c.z))
            })
            .sum();
        assert!(outward > 0.0);
        assert!(m.signed_volume() > 0.0);
    }
}
