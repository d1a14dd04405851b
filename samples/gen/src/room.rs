//! Test rooms for measuring a bake against ground truth: a closed room (floor, walls and
//! ceiling facing inwards, flat objects) lit by an emissive area light at the middle of its
//! ceiling, with one mesh from an OBJ file scaled to fit, standing on the floor, marked
//! multiresolution, and a camera node looking at it.
//!
//! The mesh is read as it is (Y up): positions and faces only, quads split along their shorter
//! diagonal (a fan can fold a non-planar quad onto its neighbour's triangle, as on Suzanne's
//! symmetry plane), larger polygons fanned, triangles repeating another's three
//! vertices dropped (both copies), positions welded, all in one smoothing group. It is scaled so that its largest
//! side is [`MESH_SIZE`], centred over the origin and lifted to rest just above the floor. The
//! camera looks at the middle of its bounding box from the front (+Z), a little to the right and
//! above, far enough that the bounding sphere fills the view with a small margin. The output
//! depends only on the OBJ's bytes.

use glam::DVec3;

use crate::mesh::Mesh;
use crate::scene::{Camera, Material, Object, Scene};
use crate::scenes::{room_with_light, REST_GAP};

/// Largest side of the mesh in the room, in metres.
pub const MESH_SIZE: f64 = 1.0;
/// The room: 6 m square, 3 m high, with a 1 m square light.
pub const ROOM_SIZE: [f64; 3] = [6.0, 3.0, 6.0];
const LIGHT_SIDE: f64 = 1.0;
const LIGHT_EMISSION: [f64; 3] = [16.0, 15.2, 13.6];
const FOV_DEGREES: f64 = 40.0;

/// Why an OBJ could not be read.
#[derive(Debug, thiserror::Error)]
pub enum ObjError {
    #[error("line {line}: {reason}")]
    Syntax { line: usize, reason: String },
    #[error("no triangles")]
    Empty,
}

/// Positions and faces of an OBJ (`v` and `f` lines; other lines ignored), quads split along
/// their shorter diagonal and larger polygons fanned from their first corner, welded.
pub fn parse_obj(text: &str) -> Result<Mesh, ObjError> {
    let mut m = Mesh::default();
    for (k, raw) in text.lines().enumerate() {
        let line = k + 1;
        let bad = |reason: String| ObjError::Syntax { line, reason };
        let mut words = raw.split_whitespace();
        match words.next() {
            Some("v") => {
                let xyz: Vec<f64> = words
                    .take(3)
                    .map(|w| w.parse::<f64>())
                    .collect::<Result<_, _>>()
                    .map_err(|e| bad(format!("bad vertex: {e}")))?;
                if xyz.len() != 3 || xyz.iter().any(|c| !c.is_finite()) {
                    return Err(bad("a vertex needs three finite coordinates".into()));
                }
                m.vertex(DVec3::new(xyz[0], xyz[1], xyz[2]));
            }
            Some("f") => {
                let n = m.positions.len() as i64;
                let corners: Vec<u32> = words
                    .map(|w| {
                        let i: i64 = w
                            .split('/')
                            .next()
                            .unwrap_or("")
                            .parse()
                            .map_err(|e| bad(format!("bad face index {w:?}: {e}")))?;
                        let i = if i < 0 { n + i } else { i - 1 };
                        if !(0..n).contains(&i) {
                            return Err(bad(format!("face index {w:?} out of range")));
                        }
                        Ok(i as u32)
                    })
                    .collect::<Result<_, _>>()?;
                if corners.len() < 3 {
                    return Err(bad("a face needs at least three corners".into()));
                }
                if let [a, b, c, d] = corners[..] {
                    m.quad([a, b, c, d], 0);
                } else {
                    for j in 1..corners.len() - 1 {
                        m.triangle([corners[0], corners[j], corners[j + 1]], 0);
                    }
                }
            }
            _ => {}
        }
    }
    m.weld(1e-12);
    // Triangles on the same three vertices (a fin folded back onto itself) have no inside and
    // leave zero vertex normals: drop every copy.
    let key = |t: &[u32; 3]| {
        let mut k = *t;
        k.sort_unstable();
        k
    };
    let mut uses: std::collections::HashMap<[u32; 3], u32> = std::collections::HashMap::new();
    for t in &m.triangles {
        *uses.entry(key(t)).or_default() += 1;
    }
    let keep: Vec<bool> = m.triangles.iter().map(|t| uses[&key(t)] == 1).collect();
    let mut k = keep.iter();
    m.groups.retain(|_| *k.next().unwrap_or(&false));
    let mut k = keep.iter();
    m.triangles.retain(|_| *k.next().unwrap_or(&false));
    m.compact();
    if m.triangles.is_empty() {
        return Err(ObjError::Empty);
    }
    Ok(m)
}

/// The room around `mesh` (see the module documentation), the mesh first turned by
/// `turn_degrees` about +Y (counter-clockwise seen from above) to face the camera; `name` names
/// the object.
pub fn room_with_mesh(name: &str, mesh: &Mesh, turn_degrees: f64) -> Scene {
    let mut mesh = mesh.clone();
    let turn = glam::DQuat::from_rotation_y(turn_degrees.to_radians());
    mesh.map_positions(|p| turn * p);
    let (lo, hi) = mesh.bounds().unwrap_or((DVec3::ZERO, DVec3::ONE));
    let scale = MESH_SIZE / (hi - lo).max_element().max(1e-12);
    let base = DVec3::new((lo.x + hi.x) / 2.0, lo.y, (lo.z + hi.z) / 2.0);
    mesh.map_positions(|p| (p - base) * scale);
    let size = DVec3::from_array(ROOM_SIZE);
    let at = DVec3::Y * REST_GAP;
    let centre = at + DVec3::Y * ((hi.y - lo.y) * scale / 2.0);
    let radius = (hi - lo).length() * scale / 2.0;
    // The narrower field of view is the vertical one (the images are wider than high).
    let distance = 1.15 * radius / (FOV_DEGREES / 2.0).to_radians().sin();
    let eye = centre + DVec3::new(0.35, 0.3, 1.0).normalize() * distance;
    let mut s = Scene {
        name: format!("Room with {name}"),
        camera: Some(Camera {
            name: "view".to_string(),
            eye,
            target: centre,
            yfov_degrees: FOV_DEGREES,
        }),
        ..Default::default()
    };
    room_with_light(&mut s, size, LIGHT_SIDE, LIGHT_EMISSION);
    let material = s.material(Material::diffuse(name, [0.75, 0.72, 0.68]));
    s.objects
        .push(Object::new(name, mesh, material).at(at).multires());
    s
}

/// Distance between the centres of neighbouring meshes in [`room_with_meshes`], in metres.
pub const MESH_SPACING: f64 = 1.5;
/// How far inside the walls and the ceiling the camera of [`room_with_meshes`] stays, in metres.
const CAMERA_MARGIN: f64 = 0.25;

/// The room around several meshes (`(name, mesh)`, each names its object): each is turned by
/// `turn_degrees` and scaled as in [`room_with_mesh`], and they stand on the floor in a row
/// along X, [`MESH_SPACING`] apart and centred on the room, each multiresolution with its own
/// material; the camera looks at the middle of the row from the front, from inside the room. A scene of several
/// objects that see and shade each other, as real assets are baked.
pub fn room_with_meshes(meshes: &[(&str, &Mesh)], turn_degrees: f64) -> Scene {
    let turn = glam::DQuat::from_rotation_y(turn_degrees.to_radians());
    let mut s = Scene {
        name: format!(
            "Room with {}",
            meshes.iter().map(|m| m.0).collect::<Vec<_>>().join(", ")
        ),
        ..Default::default()
    };
    room_with_light(
        &mut s,
        DVec3::from_array(ROOM_SIZE),
        LIGHT_SIDE,
        LIGHT_EMISSION,
    );
    let first_x = -MESH_SPACING * (meshes.len().max(1) - 1) as f64 / 2.0;
    let (mut lo_all, mut hi_all) = (DVec3::splat(f64::MAX), DVec3::splat(f64::MIN));
    for (i, (name, mesh)) in meshes.iter().enumerate() {
        let mut mesh = (*mesh).clone();
        mesh.map_positions(|p| turn * p);
        let (lo, hi) = mesh.bounds().unwrap_or((DVec3::ZERO, DVec3::ONE));
        let scale = MESH_SIZE / (hi - lo).max_element().max(1e-12);
        let base = DVec3::new((lo.x + hi.x) / 2.0, lo.y, (lo.z + hi.z) / 2.0);
        mesh.map_positions(|p| (p - base) * scale);
        let at = DVec3::new(first_x + MESH_SPACING * i as f64, REST_GAP, 0.0);
        if let Some((lo, hi)) = mesh.bounds() {
            lo_all = lo_all.min(lo + at);
            hi_all = hi_all.max(hi + at);
        }
        let material = s.material(Material::diffuse(name, [0.75, 0.72, 0.68]));
        s.objects
            .push(Object::new(name, mesh, material).at(at).multires());
    }
    if lo_all.x <= hi_all.x {
        let centre = (lo_all + hi_all) / 2.0;
        let radius = (hi_all - lo_all).length() / 2.0;
        let distance = 1.15 * radius / (FOV_DEGREES / 2.0).to_radians().sin();
        let dir = DVec3::new(0.35, 0.3, 1.0).normalize();
        // A row wider than the room's depth would put the fitted eye behind the front wall,
        // where it sees only the wall: it stops [`CAMERA_MARGIN`] inside the room instead, and
        // the row's ends may leave the view.
        let half = DVec3::from_array(ROOM_SIZE) / 2.0 - DVec3::splat(CAMERA_MARGIN);
        let room_limit = [
            (half.x - centre.x) / dir.x,
            (half.z - centre.z) / dir.z,
            (ROOM_SIZE[1] - CAMERA_MARGIN - centre.y) / dir.y,
        ]
        .into_iter()
        .fold(f64::MAX, f64::min)
        .max(0.0);
        s.camera = Some(Camera {
            name: "view".to_string(),
            eye: centre + dir * distance.min(room_limit),
            target: centre,
            yfov_degrees: FOV_DEGREES,
        });
    }
    s
}

/// Radiance every surface of [`furnace`] emits, and its reflectance.
pub const FURNACE_EMISSION: f64 = 0.4;
pub const FURNACE_REFLECTANCE: f64 = 0.5;

/// Turns `scene` into a closed furnace: every material emits [`FURNACE_EMISSION`] and reflects
/// [`FURNACE_REFLECTANCE`], so that the exact radiance everywhere is `E / (1 − ρ)` = 0.8,
/// whatever the geometry. A bake of the room around a mesh made so shows at every leaf and
/// refined vertex how far the solver's form factors are from summing to one (`hce compare
/// --constant 0.8`), with no path tracer's noise in the way.
pub fn furnace(scene: &mut Scene) {
    for m in &mut scene.materials {
        m.base_color = [FURNACE_REFLECTANCE; 3];
        m.emission = [FURNACE_EMISSION; 3];
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    const TETRA: &str = "# a tetrahedron, one face a quad-free triangle fan\n\
        v 0 0 0\nv 2 0 0\nv 0 2 0\nv 0 0 2\n\
        f 1 3 2\nf 1/1 2/2 4/3\nf -4 -1 -2\nf 2//1 3//2 4//3\n";

    #[test]
    fn the_mesh_fits_stands_on_the_floor_and_the_camera_is_inside() {
        let mesh = parse_obj(TETRA).unwrap();
        assert_eq!((mesh.positions.len(), mesh.triangles.len()), (4, 4));
        let s = room_with_mesh("tetra", &mesh, 30.0);
        let o = s.object("tetra").unwrap();
        assert!(o.multires);
        let (lo, hi) = o.primitives[0].mesh.bounds().unwrap();
        assert!(((hi - lo).max_element() - MESH_SIZE).abs() < 1e-12);
        assert!((lo.y + o.translation.y - REST_GAP).abs() < 1e-12);
        let eye = s.camera.as_ref().unwrap().eye;
        let half = DVec3::from_array(ROOM_SIZE) / 2.0;
        assert!(eye.x.abs() < half.x && eye.z.abs() < half.z && eye.y < ROOM_SIZE[1]);
        // Floor, walls, ceiling, light and the mesh; the light is the one emitter.
        assert_eq!(s.objects.len(), 5);
        assert_eq!(
            s.materials.iter().filter(|m| m.emission[0] > 0.0).count(),
            1
        );
        // A fin folded onto itself disappears, with the vertex only it used.
        let fin = format!("{TETRA}v 1 1 1\nf 1 2 5\nf 2 1 5\n");
        let m = parse_obj(&fin).unwrap();
        assert_eq!((m.positions.len(), m.triangles.len()), (4, 4));
        assert!(matches!(
            parse_obj("v 0 0 0\nf 1 2 3\n"),
            Err(ObjError::Syntax { line: 2, .. })
        ));
        assert!(matches!(
            parse_obj("v 0 0\n"),
            Err(ObjError::Syntax { line: 1, .. })
        ));
        assert!(matches!(parse_obj("# nothing\n"), Err(ObjError::Empty)));
    }

    #[test]
    fn several_meshes_stand_apart_on_the_floor() {
        let mesh = parse_obj(TETRA).unwrap();
        let s = room_with_meshes(&[("a", &mesh), ("b", &mesh), ("c", &mesh)], 0.0);
        let xs: Vec<f64> = ["a", "b", "c"]
            .iter()
            .map(|n| {
                let o = s.object(n).unwrap();
                assert!(o.multires);
                let (lo, hi) = o.primitives[0].mesh.bounds().unwrap();
                assert!(((hi - lo).max_element() - MESH_SIZE).abs() < 1e-12);
                assert!((lo.y + o.translation.y - REST_GAP).abs() < 1e-12);
                o.translation.x
            })
            .collect();
        assert_eq!(xs, [-MESH_SPACING, 0.0, MESH_SPACING]);
        // Floor, walls, ceiling, light and three meshes; the camera inside the room.
        assert_eq!(s.objects.len(), 7);
        let eye = s.camera.as_ref().unwrap().eye;
        let half = DVec3::from_array(ROOM_SIZE) / 2.0;
        assert!(eye.x.abs() < half.x && eye.z.abs() < half.z && eye.y < ROOM_SIZE[1]);
    }

    #[test]
    fn a_furnace_room_emits_and_reflects_alike_everywhere() {
        let mut s = room_with_mesh("tetra", &parse_obj(TETRA).unwrap(), 0.0);
        furnace(&mut s);
        assert!(s.materials.len() >= 5);
        for m in &s.materials {
            assert_eq!(m.emission, [FURNACE_EMISSION; 3], "{}", m.name);
            assert_eq!(m.base_color, [FURNACE_REFLECTANCE; 3], "{}", m.name);
        }
        let exact = FURNACE_EMISSION / (1.0 - FURNACE_REFLECTANCE);
        assert!((exact - 0.8).abs() < 1e-12);
    }
}
