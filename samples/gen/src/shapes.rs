//! Flat building blocks: oriented quads, boxes with hard edges, rooms and tables.

use glam::DVec3;

use crate::mesh::Mesh;

/// A quad of the four corners given in order around it, turned so that its normal points
/// towards `towards` (a direction). Published scene data lists corners in either order.
pub fn quad_facing(corners: [DVec3; 4], towards: DVec3, group: u32) -> Mesh {
    let mut m = Mesh::default();
    let v = corners.map(|p| m.vertex(p));
    let n = (corners[1] - corners[0]).cross(corners[2] - corners[0])
        + (corners[2] - corners[0]).cross(corners[3] - corners[0]);
    if n.dot(towards) >= 0.0 {
        m.quad(v, group);
    } else {
        m.quad([v[0], v[3], v[2], v[1]], group);
    }
    m
}

/// Faces of an axis-aligned box, in the order -X, +X, -Y, +Y, -Z, +Z.
pub const FACES: usize = 6;

/// One face of the box `[lo, hi]`, facing outwards (`face` as in [`FACES`]).
pub fn box_face(lo: DVec3, hi: DVec3, face: usize) -> Mesh {
    let axis = face / 2;
    let positive = face % 2 == 1;
    let (u, v) = ((axis + 1) % 3, (axis + 2) % 3);
    let corner = |a: bool, b: bool| {
        let mut p = if positive { hi } else { lo };
        p[u] = if a { hi[u] } else { lo[u] };
        p[v] = if b { hi[v] } else { lo[v] };
        p
    };
    let mut dir = DVec3::ZERO;
    dir[axis] = if positive { 1.0 } else { -1.0 };
    quad_facing(
        [
            corner(false, false),
            corner(true, false),
            corner(true, true),
            corner(false, true),
        ],
        dir,
        0,
    )
}

/// A box with the faces whose flags are set, each face its own smoothing group (hard edges),
/// welded into one mesh.
pub fn cuboid(lo: DVec3, hi: DVec3, faces: [bool; FACES]) -> Mesh {
    let mut m = Mesh::default();
    for (f, &on) in faces.iter().enumerate() {
        if on {
            m.append(&box_face(lo, hi, f), f as u32);
        }
    }
    m.weld(1e-9);
    m
}

/// A table: a top of `size` (x, z) and `thickness` whose upper surface is at `height`, on four
/// square legs of side `leg` set in by `inset`. The legs have no top face (it would lie in the
/// underside of the top) and no bottom face (it would lie in the floor).
pub fn table(size: [f64; 2], height: f64, thickness: f64, leg: f64, inset: f64) -> Mesh {
    let (hx, hz) = (size[0] / 2.0, size[1] / 2.0);
    let mut m = cuboid(
        DVec3::new(-hx, height - thickness, -hz),
        DVec3::new(hx, height, hz),
        [true; FACES],
    );
    for (sx, sz) in [(-1.0, -1.0), (1.0, -1.0), (-1.0, 1.0), (1.0, 1.0)] {
        let cx = sx * (hx - inset - leg / 2.0);
        let cz = sz * (hz - inset - leg / 2.0);
        let leg_mesh = cuboid(
            DVec3::new(cx - leg / 2.0, 0.0, cz - leg / 2.0),
            DVec3::new(cx + leg / 2.0, height - thickness, cz + leg / 2.0),
            [true, true, false, false, true, true],
        );
        let groups = m.groups.iter().max().map_or(0, |g| g + 1);
        m.append(&leg_mesh, groups);
    }
    m
}

/// The inside of a room `[lo, hi]`: floor, walls and ceiling facing inwards, as separate
/// meshes `(floor, walls, ceiling)` so that each can have its own material.
pub fn room(lo: DVec3, hi: DVec3) -> (Mesh, Mesh, Mesh) {
    let inward = |f: usize| {
        let mut m = box_face(lo, hi, f);
        m.flip();
        m
    };
    let mut walls = Mesh::default();
    for (g, f) in [0, 1, 4, 5].into_iter().enumerate() {
        walls.append(&inward(f), g as u32);
    }
    walls.weld(1e-9);
    (inward(2), walls, inward(3))
}

/// A horizontal rectangle at height `y`, centred on `(x, z)`, facing down: an area light.
pub fn ceiling_light(centre: DVec3, size: [f64; 2]) -> Mesh {
    let (hx, hz) = (size[0] / 2.0, size[1] / 2.0);
    let c = centre;
    quad_facing(
        [
            c + DVec3::new(-hx, 0.0, -hz),
            c + DVec3::new(hx, 0.0, -hz),
            c + DVec3::new(hx, 0.0, hz),
            c + DVec3::new(-hx, 0.0, hz),
        ],
        -DVec3::Y,
        0,
    )
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn cuboid_is_closed_with_six_hard_faces() {
        let m = cuboid(DVec3::ZERO, DVec3::new(1.0, 2.0, 3.0), [true; FACES]);
        assert_eq!(m.triangles.len(), 12);
        assert_eq!(m.positions.len(), 8);
        let s = m.edge_stats();
        assert_eq!((s.boundary, s.non_manifold, s.inconsistent), (0, 0, 0));
        assert!((m.signed_volume() - 6.0).abs() < 1e-12);
        let mut g = m.groups.clone();
        g.dedup();
        assert_eq!(g, vec![0, 1, 2, 3, 4, 5]);
    }

    #[test]
    fn room_faces_inwards() {
        let (floor, walls, ceiling) = room(DVec3::ZERO, DVec3::new(4.0, 3.0, 5.0));
        assert!(floor.face_normal(&floor.triangles[0]).y > 0.0);
        assert!(ceiling.face_normal(&ceiling.triangles[0]).y < 0.0);
        assert_eq!(walls.triangles.len(), 8);
        // A closed inward room has negative signed volume.
        let mut all = floor.clone();
        all.append(&walls, 1);
        all.append(&ceiling, 5);
        all.weld(1e-9);
        assert!((all.signed_volume() + 60.0).abs() < 1e-9);
        assert_eq!(all.edge_stats().boundary, 0);
    }

    #[test]
    fn table_top_is_at_its_height_and_legs_are_open() {
        let m = table([1.2, 0.8], 0.75, 0.04, 0.06, 0.05);
        assert_eq!(m.triangles.len(), 12 + 4 * 8);
        let (lo, hi) = m.bounds().unwrap();
        assert_eq!((lo.y, hi.y), (0.0, 0.75));
        assert!((hi.x - 0.6).abs() < 1e-12 && (lo.z + 0.4).abs() < 1e-12);
        // Each leg has an open top and bottom loop: 4 + 4 boundary edges.
        assert_eq!(m.edge_stats().boundary, 4 * 8);
        assert_eq!(m.edge_stats().non_manifold, 0);
    }
}
