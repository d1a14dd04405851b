use glam::Vec3;
use hce_bake::*;
fn quad(o: Vec3, u: Vec3, v: Vec3) -> (Vec<[f32; 3]>, Vec<[u32; 3]>) {
    let p = [o, o + u, o + u + v, o + v].map(|x| x.to_array()).to_vec();
    (p, vec![[0, 1, 2], [0, 2, 3]])
}
fn main() {
    let parts = vec![
        (Vec3::ZERO, Vec3::X, Vec3::Y),
        (Vec3::Z, Vec3::Y, Vec3::X),
        (Vec3::ZERO, Vec3::Y, Vec3::Z),
        (Vec3::X, Vec3::Z, Vec3::Y),
        (Vec3::ZERO, Vec3::Z, Vec3::X),
        (Vec3::Y, Vec3::X, Vec3::Z),
    ];
    let (mut pos, mut tris) = (Vec::new(), Vec::new());
    for &(o, u, v) in &parts {
        let (p, t) = quad(o, u, v);
        let base = pos.len() as u32;
        pos.extend(p);
        tris.extend(t.iter().map(|t| t.map(|i| i + base)));
    }
    {
        let obj = SceneObject::new("box", pos.clone(), tris.clone(), [0.5;3]);
        for (lvl, path) in [(4u32, 255u32), (2, 15), (4, 0), (4, 85)] {
        let key = element::ElemKey { root: 0, level: lvl, path };
        let rt = key.corners(obj.corners(2));
        let n = (rt[1]-rt[0]).cross(rt[2]-rt[0]).normalize();
        for lev in [1u32, 3, 5] {
            let pts = formfactor::stratified_points(rt, lev);
            let mut tot = 0.0f64;
            for t in 0..12 { let st = obj.corners(t); for p in &pts { tot += formfactor::point_to_polygon(*p, n, &st) as f64; } }
            println!("elem {lvl} {path} pts level {lev}: sum F = {}", tot / pts.len() as f64);
        }}
    }
    let scene = Scene { objects: vec![SceneObject::new("box", pos, tris, [0.5;3]).with_emission([1.0;3])], lights: vec![] };
    for (vr, ml, eps) in [(0, 4, 1e-4), (0, 3, 1e-4), (0, 4, 1e-2), (0, 4, 1e-1)] {
        let p = BakeParams { visibility_rays: vr, max_level: ml, bf_epsilon: eps, cluster_opening: 0.01, ..Default::default() };
        let r = bake(&scene, &p).unwrap();
        let mut worst = (0.0f32, 0, 0, 0);
        for (ti, t) in r.objects[0].triangles.iter().enumerate() {
            for (i, c) in t.colours.iter().enumerate() {
                let e = (c[0] - 2.0).abs() / 2.0;
                if e > worst.0 { worst = (e, ti, t.nodes[i].0, t.nodes[i].1); println!("  {:?} {:?} sub {}", c, t.nodes[i], t.subdivided[i]); }
            }
        }
        println!("vr {vr} ml {ml} eps {eps}: worst {worst:?} links {} elems {}", r.stats.links, r.stats.elements);
    }
}
#[allow(dead_code)]
fn check() {}
