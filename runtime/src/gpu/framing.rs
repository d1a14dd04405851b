//! Automatic camera placement that sees a scene from where a person would stand.
//!
//! Framing a scene's bounding sphere from outside ([`auto_camera`]) suits a single object but,
//! for a room, shows the outside of its walls. So we first probe the scene from its centre with
//! six axis-aligned rays against its coarse triangles (Möller & Trumbore, "Fast, minimum storage
//! ray-triangle intersection", 1997, both sides counted):
//!
//! * every ray hits: a closed room. The eye stands inside, near the wall on +Z (the side a glTF
//!   camera faces from by convention) or on +X when the room is longer along X, at 55% of the
//!   room's height, and looks at the far wall slightly downwards, with a 65° vertical field of
//!   view;
//! * the four rays along ±X, ±Z and the two along ±Y hit except one horizontal ray: a box open on
//!   one side (a Cornell box). The eye stands outside the opening on its axis, far enough for
//!   the opening to fill a 40° view, and looks at the centre;
//! * anything else: an object or an open scene, framed from outside by [`auto_camera`].

use glam::Vec3;

use super::lod::Camera;

/// The camera [`Framing::Auto`](super::render::Framing::Auto) uses for these bounds and aspect ratio (width / height).
pub(crate) fn auto_camera(lo: [f32; 3], hi: [f32; 3], aspect: f32) -> Camera {
    let fov = 40.0f32;
    let centre = (Vec3::from(lo) + Vec3::from(hi)) * 0.5;
    let radius = ((Vec3::from(hi) - Vec3::from(lo)).length() * 0.5).max(1e-6);
    // Fit the sphere in the narrower of the two fields of view, with 10% margin.
    let half_v = (fov * 0.5).to_radians();
    let half_h = (half_v.tan() * aspect.min(1.0)).atan();
    let distance = 1.1 * radius / half_h.sin();
    let dir = Vec3::new(0.55, 0.45, 1.0).normalize();
    Camera {
        eye: (centre + dir * distance).into(),
        target: centre.into(),
        fov_y_degrees: fov,
    }
}

/// Where [`auto_scene_camera`] placed the eye.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum Placement {
    /// Outside the bounds, framing them (an object or an open scene).
    Outside,
    /// Inside a closed room.
    Inside,
    /// In front of the one open side of a box.
    Opening,
}

/// Distance along `dir` from `origin` to triangle `t`, either side, if the ray hits it.
fn ray_hit(origin: Vec3, dir: Vec3, t: &[[f32; 3]; 3]) -> Option<f32> {
    let [a, b, c] = t.map(Vec3::from);
    let e1 = b - a;
    let e2 = c - a;
    let p = dir.cross(e2);
    let det = e1.dot(p);
    if det.abs() < 1e-12 {
        return None;
    }
    let inv = 1.0 / det;
    let s = origin - a;
    let u = s.dot(p) * inv;
    if !(0.0..=1.0).contains(&u) {
        return None;
    }
    let q = s.cross(e1);
    let v = dir.dot(q) * inv;
    if v < 0.0 || u + v > 1.0 {
        return None;
    }
    let d = e2.dot(q) * inv;
    (d > 0.0).then_some(d)
}

fn hits(origin: Vec3, dir: Vec3, triangles: &[[[f32; 3]; 3]]) -> bool {
    triangles.iter().any(|t| ray_hit(origin, dir, t).is_some())
}

/// A camera for a scene made of `triangles` (world space) inside bounds `[lo, hi]`, for an
/// image of aspect ratio `aspect` (width / height). See the module documentation.
pub fn auto_scene_camera(
    triangles: &[[[f32; 3]; 3]],
    lo: [f32; 3],
    hi: [f32; 3],
    aspect: f32,
) -> (Camera, Placement) {
    let (lo_v, hi_v) = (Vec3::from(lo), Vec3::from(hi));
    let centre = (lo_v + hi_v) * 0.5;
    let size = hi_v - lo_v;
    let horizontal = [Vec3::X, Vec3::NEG_X, Vec3::Z, Vec3::NEG_Z];
    let open: Vec<Vec3> = horizontal
        .into_iter()
        .filter(|&d| !hits(centre, d, triangles))
        .collect();
    let floor_and_ceiling =
        hits(centre, Vec3::Y, triangles) && hits(centre, Vec3::NEG_Y, triangles);
    if !floor_and_ceiling || open.len() > 1 || size.min_element() <= 0.0 {
        return (auto_camera(lo, hi, aspect), Placement::Outside);
    }
    if let [out] = open[..] {
        let fov = 40.0f32;
        let tan_v = (fov * 0.5).to_radians().tan();
        // The opening's half width (the other horizontal axis) and half height.
        let half_w = 0.5 * if out.x != 0.0 { size.z } else { size.x };
        let half_h = 0.5 * size.y;
        let depth = 0.5 * out.abs().dot(size);
        let distance = 1.05 * (half_h / tan_v).max(half_w / (tan_v * aspect.max(1e-3)));
        let eye = centre + out * (depth + distance);
        return (
            Camera {
                eye: eye.into(),
                target: centre.into(),
                fov_y_degrees: fov,
            },
            Placement::Opening,
        );
    }
    // Closed: stand inside near one wall, looking along the room's longer horizontal axis.
    let axis = if size.x > size.z { Vec3::X } else { Vec3::Z };
    let half = 0.5 * axis.dot(size);
    let mut eye = centre + axis * (0.9 * half);
    eye.y = lo[1] + 0.55 * size.y;
    let mut target = centre - axis * half;
    target.y = lo[1] + 0.4 * size.y;
    (
        Camera {
            eye: eye.into(),
            target: target.into(),
            fov_y_degrees: 65.0,
        },
        Placement::Inside,
    )
}

#[cfg(test)]
mod tests {
    use super::*;

    /// The two triangles of an axis-aligned box face: `axis` fixed at `at`.
    fn face(axis: usize, at: f32) -> [[[f32; 3]; 3]; 2] {
        let p = |u: f32, v: f32| {
            let mut q = [0.0; 3];
            q[axis] = at;
            q[(axis + 1) % 3] = u;
            q[(axis + 2) % 3] = v;
            q
        };
        [
            [p(0.0, 0.0), p(1.0, 0.0), p(1.0, 1.0)],
            [p(0.0, 0.0), p(1.0, 1.0), p(0.0, 1.0)],
        ]
    }

    fn room(skip: Option<(usize, f32)>) -> Vec<[[f32; 3]; 3]> {
        let mut out = Vec::new();
        for axis in 0..3 {
            for at in [0.0, 1.0] {
                if skip != Some((axis, at)) {
                    out.extend(face(axis, at));
                }
            }
        }
        out
    }

    #[test]
    fn closed_room_puts_the_eye_inside() {
        let (cam, placement) = auto_scene_camera(&room(None), [0.0; 3], [1.0; 3], 4.0 / 3.0);
        assert_eq!(placement, Placement::Inside);
        assert!(cam.eye.iter().all(|&c| c > 0.0 && c < 1.0), "{:?}", cam.eye);
        // Looking at the far wall (−Z) from near the +Z one.
        assert!(cam.eye[2] > 0.9 && cam.target[2] == 0.0, "{cam:?}");
    }

    #[test]
    fn box_open_on_one_side_is_seen_through_the_opening() {
        let tris = room(Some((2, 0.0)));
        let (cam, placement) = auto_scene_camera(&tris, [0.0; 3], [1.0; 3], 1.0);
        assert_eq!(placement, Placement::Opening);
        assert!(cam.eye[2] < 0.0, "{:?}", cam.eye);
        assert_eq!(cam.target, [0.5; 3]);
        // The opening (half size 0.5 at distance eye→face) fits the 40° view.
        let d = -cam.eye[2];
        assert!(0.5 / d <= (20f32).to_radians().tan() + 1e-6, "{d}");
    }

    #[test]
    fn a_lone_object_is_framed_from_outside() {
        let tris = face(1, 0.0).to_vec();
        let (cam, placement) = auto_scene_camera(&tris, [0.0, 0.0, 0.0], [1.0, 0.0, 1.0], 1.0);
        assert_eq!(placement, Placement::Outside);
        assert_eq!(cam, auto_camera([0.0, 0.0, 0.0], [1.0, 0.0, 1.0], 1.0));
    }
}
