//! The Cornell box, from the measurements the Cornell Program of Computer Graphics publishes
//! (<https://www.graphics.cornell.edu/online/box/data.html>), in millimetres scaled to metres.
//!
//! The data's frame is right-handed with Y up: the camera stands at z = -800 mm looking
//! towards +Z, so the red wall (x ≈ 556 mm) is on the left and the green one (x = 0) on the
//! right. The light is the published 130 × 105 mm opening, lowered 0.5 mm below the ceiling so
//! that the two surfaces are not coplanar. Reflectances are the usual RGB reductions of the
//! published spectra; the emission is the customary radiance (17, 12, 4) of the PBRT and
//! Mitsuba versions of the scene.

use glam::DVec3;

use crate::mesh::Mesh;
use crate::shapes::quad_facing;

/// Millimetres to metres.
const MM: f64 = 0.001;

/// Diffuse reflectances.
pub const WHITE: [f64; 3] = [0.73, 0.73, 0.73];
pub const RED: [f64; 3] = [0.63, 0.065, 0.05];
pub const GREEN: [f64; 3] = [0.14, 0.45, 0.091];
/// Emitted radiance of the light.
pub const LIGHT: [f64; 3] = [17.0, 12.0, 4.0];

type Quad = [[f64; 3]; 4];

pub const FLOOR: Quad = [
    [552.8, 0.0, 0.0],
    [0.0, 0.0, 0.0],
    [0.0, 0.0, 559.2],
    [549.6, 0.0, 559.2],
];
pub const CEILING: Quad = [
    [556.0, 548.8, 0.0],
    [556.0, 548.8, 559.2],
    [0.0, 548.8, 559.2],
    [0.0, 548.8, 0.0],
];
pub const BACK_WALL: Quad = [
    [549.6, 0.0, 559.2],
    [0.0, 0.0, 559.2],
    [0.0, 548.8, 559.2],
    [556.0, 548.8, 559.2],
];
pub const RIGHT_WALL: Quad = [
    [0.0, 0.0, 559.2],
    [0.0, 0.0, 0.0],
    [0.0, 548.8, 0.0],
    [0.0, 548.8, 559.2],
];
pub const LEFT_WALL: Quad = [
    [552.8, 0.0, 0.0],
    [549.6, 0.0, 559.2],
    [556.0, 548.8, 559.2],
    [556.0, 548.8, 0.0],
];
/// The light, 0.5 mm below the ceiling's 548.8.
pub const LIGHT_QUAD: Quad = [
    [343.0, 548.3, 227.0],
    [343.0, 548.3, 332.0],
    [213.0, 548.3, 332.0],
    [213.0, 548.3, 227.0],
];
/// Top and four sides of each block (they stand on the floor, so no bottom).
pub const SHORT_BLOCK: [Quad; 5] = [
    [
        [130.0, 165.0, 65.0],
        [82.0, 165.0, 225.0],
        [240.0, 165.0, 272.0],
        [290.0, 165.0, 114.0],
    ],
    [
        [290.0, 0.0, 114.0],
        [290.0, 165.0, 114.0],
        [240.0, 165.0, 272.0],
        [240.0, 0.0, 272.0],
    ],
    [
        [130.0, 0.0, 65.0],
        [130.0, 165.0, 65.0],
        [290.0, 165.0, 114.0],
        [290.0, 0.0, 114.0],
    ],
    [
        [82.0, 0.0, 225.0],
        [82.0, 165.0, 225.0],
        [130.0, 165.0, 65.0],
        [130.0, 0.0, 65.0],
    ],
    [
        [240.0, 0.0, 272.0],
        [240.0, 165.0, 272.0],
        [82.0, 165.0, 225.0],
        [82.0, 0.0, 225.0],
    ],
];
pub const TALL_BLOCK: [Quad; 5] = [
    [
        [423.0, 330.0, 247.0],
        [265.0, 330.0, 296.0],
        [314.0, 330.0, 456.0],
        [472.0, 330.0, 406.0],
    ],
    [
        [423.0, 0.0, 247.0],
        [423.0, 330.0, 247.0],
        [472.0, 330.0, 406.0],
        [472.0, 0.0, 406.0],
    ],
    [
        [472.0, 0.0, 406.0],
        [472.0, 330.0, 406.0],
        [314.0, 330.0, 456.0],
        [314.0, 0.0, 456.0],
    ],
    [
        [314.0, 0.0, 456.0],
        [314.0, 330.0, 456.0],
        [265.0, 330.0, 296.0],
        [265.0, 0.0, 296.0],
    ],
    [
        [265.0, 0.0, 296.0],
        [265.0, 330.0, 296.0],
        [423.0, 330.0, 247.0],
        [423.0, 0.0, 247.0],
    ],
];

fn metres(q: &Quad) -> [DVec3; 4] {
    q.map(|p| DVec3::from_array(p) * MM)
}

/// Centre of the box's interior, in metres: walls face towards it.
pub fn interior_centre() -> DVec3 {
    DVec3::new(278.0, 274.4, 279.6) * MM
}

/// A wall quad facing the inside of the box.
pub fn wall(q: &Quad) -> Mesh {
    let corners = metres(q);
    let centre = corners.iter().sum::<DVec3>() / 4.0;
    quad_facing(corners, interior_centre() - centre, 0)
}

/// A block: its five quads facing outwards, each face a smoothing group (hard edges), welded.
pub fn block(quads: &[Quad; 5]) -> Mesh {
    let all: Vec<DVec3> = quads.iter().flat_map(metres).collect();
    let centre = all.iter().sum::<DVec3>() / all.len() as f64;
    let mut m = Mesh::default();
    for (g, q) in quads.iter().enumerate() {
        let corners = metres(q);
        let face_centre = corners.iter().sum::<DVec3>() / 4.0;
        m.append(&quad_facing(corners, face_centre - centre, 0), g as u32);
    }
    m.weld(1e-9);
    m
}

/// The light quad, facing down.
pub fn light() -> Mesh {
    quad_facing(metres(&LIGHT_QUAD), -DVec3::Y, 0)
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn blocks_are_open_boxes_facing_out() {
        for (quads, height) in [(&SHORT_BLOCK, 0.165), (&TALL_BLOCK, 0.330)] {
            let m = block(quads);
            assert_eq!(m.triangles.len(), 10);
            assert_eq!(m.positions.len(), 8);
            let s = m.edge_stats();
            // The open bottom is a loop of 4 edges.
            assert_eq!((s.boundary, s.non_manifold, s.inconsistent), (4, 0, 0));
            let (lo, hi) = m.bounds().unwrap();
            assert_eq!(lo.y, 0.0);
            assert!((hi.y - height).abs() < 1e-12);
            // Closing the bottom would give a positive volume: the top faces up.
            let top = m
                .triangles
                .iter()
                .filter(|t| t.iter().all(|&i| m.positions[i as usize].y > 0.0))
                .map(|t| m.face_normal(t).y)
                .sum::<f64>();
            assert!(top > 0.0);
        }
    }

    #[test]
    fn walls_face_the_inside_and_the_light_faces_down() {
        let n = |m: &Mesh| m.face_normal(&m.triangles[0]).normalize();
        assert!(n(&wall(&FLOOR)).y > 0.99);
        assert!(n(&wall(&CEILING)).y < -0.99);
        assert!(n(&wall(&BACK_WALL)).z < -0.99);
        // Red on the left (+X side) faces -X, green faces +X.
        assert!(n(&wall(&LEFT_WALL)).x < -0.99);
        assert!(n(&wall(&RIGHT_WALL)).x > 0.99);
        assert!(n(&light()).y < -0.99);
        let (lo, hi) = light().bounds().unwrap();
        assert!((hi.x - lo.x - 0.130).abs() < 1e-12 && (hi.z - lo.z - 0.105).abs() < 1e-12);
        assert!((lo.y - 0.5483).abs() < 1e-12);
    }
}
