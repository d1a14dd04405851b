//! The three sample scenes, assembled from the generators. Y up, metres.

use glam::DVec3;

use crate::chess::{self, Piece};
use crate::cornell;
use crate::lathe;
use crate::scene::{Camera, Material, Object, Primitive, Scene};
use crate::shapes;
use crate::spoon;
use crate::teapot::{self, TeapotParams};

/// Gap left under objects that stand on a surface, so that their bottom is not coplanar with
/// it (coplanar, overlapping faces make radiosity and depth testing ambiguous).
pub(crate) const REST_GAP: f64 = 0.0005;

/// A room of size `size` (x, y, z) around the origin on the floor, with an area light of side
/// `light` at the middle of its ceiling; returns the objects and adds their materials.
pub(crate) fn room_with_light(scene: &mut Scene, size: DVec3, light: f64, emission: [f64; 3]) {
    let floor_m = scene.material(Material::diffuse("floor", [0.45, 0.42, 0.38]));
    let wall_m = scene.material(Material::diffuse("wall", [0.72, 0.70, 0.66]));
    let ceiling_m = scene.material(Material::diffuse("ceiling", [0.80, 0.80, 0.80]));
    let light_m = scene.material(Material::emitter("light", emission));
    let lo = DVec3::new(-size.x / 2.0, 0.0, -size.z / 2.0);
    let hi = DVec3::new(size.x / 2.0, size.y, size.z / 2.0);
    let (floor, walls, ceiling) = shapes::room(lo, hi);
    scene.objects.push(Object::new("floor", floor, floor_m));
    scene.objects.push(Object::new("walls", walls, wall_m));
    scene
        .objects
        .push(Object::new("ceiling", ceiling, ceiling_m));
    // 1 mm below the ceiling: not coplanar with it.
    let centre = DVec3::new(0.0, size.y - 0.001, 0.0);
    scene.objects.push(Object::new(
        "light",
        shapes::ceiling_light(centre, [light, light]),
        light_m,
    ));
}

/// Teatime (Concheiro et al. 2012): the Utah teapot, a cup and a spoon on a table in a room
/// lit by an area light; the three objects are multiresolution.
pub fn teatime() -> Scene {
    let mut s = Scene {
        name: "Teatime".to_string(),
        camera: Some(Camera {
            name: "view".to_string(),
            eye: DVec3::new(0.35, 1.08, 0.85),
            target: DVec3::new(0.02, 0.80, 0.06),
            yfov_degrees: 40.0,
        }),
        ..Default::default()
    };
    room_with_light(&mut s, DVec3::new(4.0, 2.6, 4.0), 0.8, [12.0, 11.4, 10.2]);
    let table_m = s.material(Material::diffuse("table wood", [0.42, 0.27, 0.15]));
    let porcelain = s.material(Material::diffuse("porcelain", [0.80, 0.80, 0.78]));
    let cup_m = s.material(Material::diffuse("cup glaze", [0.35, 0.50, 0.70]));
    let steel = s.material(Material::diffuse("spoon steel", [0.60, 0.60, 0.62]));
    const TOP: f64 = 0.75;
    s.objects.push(Object::new(
        "table",
        shapes::table([1.2, 0.8], TOP, 0.04, 0.06, 0.05),
        table_m,
    ));
    let on_table = |x: f64, z: f64| DVec3::new(x, TOP + REST_GAP, z);
    s.objects.push(
        Object::new(
            "teapot",
            teapot::teapot(&TeapotParams::default()),
            porcelain,
        )
        .at(on_table(-0.15, -0.05))
        .multires(),
    );
    s.objects.push(
        Object::new("cup", lathe::cup(), cup_m)
            .at(on_table(0.22, 0.12))
            .multires(),
    );
    s.objects.push(
        Object::new("spoon", spoon::spoon(), steel)
            .at(on_table(0.16, 0.26))
            .multires(),
    );
    s
}

/// Chesstime (Concheiro et al. 2012): two kings, two queens, a pawn and a bishop on a
/// chequered board, lit by an area light; the pieces are multiresolution.
pub fn chesstime() -> Scene {
    let mut s = Scene {
        name: "Chesstime".to_string(),
        camera: Some(Camera {
            name: "view".to_string(),
            eye: DVec3::new(0.35, 0.32, 0.45),
            target: DVec3::new(0.0, 0.04, 0.0),
            yfov_degrees: 45.0,
        }),
        ..Default::default()
    };
    room_with_light(&mut s, DVec3::new(1.6, 1.2, 1.6), 0.5, [10.0, 9.6, 8.8]);
    let dark = s.material(Material::diffuse("dark square", [0.22, 0.13, 0.07]));
    let light = s.material(Material::diffuse("light square", [0.80, 0.72, 0.58]));
    let frame = s.material(Material::diffuse("board frame", [0.35, 0.21, 0.10]));
    let white = s.material(Material::diffuse("white piece", [0.82, 0.79, 0.72]));
    let black = s.material(Material::diffuse("black piece", [0.09, 0.08, 0.07]));
    let board = chess::board();
    let mut primitives = Vec::new();
    for rank in 0..8 {
        for (colour, material) in [(0, dark), (1, light)] {
            primitives.push(Primitive {
                mesh: board.squares[colour][rank].clone(),
                material,
            });
        }
    }
    primitives.push(Primitive {
        mesh: board.frame,
        material: frame,
    });
    s.objects.push(Object {
        name: "board".to_string(),
        translation: DVec3::ZERO,
        primitives,
        multires: false,
    });
    let pieces = [
        ("king_white", Piece::King, white, (4, 0)),
        ("queen_white", Piece::Queen, white, (3, 1)),
        ("pawn_white", Piece::Pawn, white, (4, 3)),
        ("king_black", Piece::King, black, (4, 7)),
        ("queen_black", Piece::Queen, black, (2, 5)),
        ("bishop_black", Piece::Bishop, black, (5, 4)),
    ];
    for (name, kind, material, (file, rank)) in pieces {
        let at = chess::square_centre(file, rank) + DVec3::Y * REST_GAP;
        s.objects.push(
            Object::new(name, chess::piece(kind), material)
                .at(at)
                .multires(),
        );
    }
    s
}

/// The Cornell box: every object flat (none multiresolution). The blocks have split normals
/// at their edges, so `hce bake --multires short_block --creases auto` turns the short block
/// into a test of a multiresolution object made of flat faces.
pub fn cornell_box() -> Scene {
    let mut s = Scene {
        name: "Cornell box".to_string(),
        // The published camera: at (278, 273, -800) mm looking towards +Z, 39.3° field of view
        // (35 mm focal length on a 25 mm film).
        camera: Some(Camera {
            name: "view".to_string(),
            eye: DVec3::new(0.278, 0.273, -0.8),
            target: DVec3::new(0.278, 0.273, 0.0),
            yfov_degrees: 39.3077,
        }),
        ..Default::default()
    };
    let white = s.material(Material::diffuse("white", cornell::WHITE));
    let red = s.material(Material::diffuse("red", cornell::RED));
    let green = s.material(Material::diffuse("green", cornell::GREEN));
    let light = s.material(Material::emitter("light", cornell::LIGHT));
    let objects = [
        ("floor", cornell::wall(&cornell::FLOOR), white),
        ("ceiling", cornell::wall(&cornell::CEILING), white),
        ("back_wall", cornell::wall(&cornell::BACK_WALL), white),
        ("left_wall_red", cornell::wall(&cornell::LEFT_WALL), red),
        (
            "right_wall_green",
            cornell::wall(&cornell::RIGHT_WALL),
            green,
        ),
        ("short_block", cornell::block(&cornell::SHORT_BLOCK), white),
        ("tall_block", cornell::block(&cornell::TALL_BLOCK), white),
        ("light", cornell::light(), light),
    ];
    for (name, mesh, material) in objects {
        s.objects.push(Object::new(name, mesh, material));
    }
    s
}

/// Every sample with the file name it is committed under in `samples/`.
pub fn all() -> Vec<(&'static str, Scene)> {
    vec![
        ("teatime.glb", teatime()),
        ("chesstime.glb", chesstime()),
        ("cornell-box.glb", cornell_box()),
    ]
}
