//! A multiresolution object's refined surface under its coarse triangles: a point of a coarse
//! triangle maps to the refined triangle's point with the same lattice coordinates, so that rays
//! and form factors leave from the surface that is drawn, and cast shadows with it.

use std::sync::OnceLock;

use glam::Vec3;

use super::context::Ctx;
use super::element::{split, ElemKey};

/// The point of the refined triangles `surface` over the coarse triangle `corners` (by path at
/// their level, as `hce_geometry::lattice` numbers them) with the lattice coordinates of `p`, a
/// point of the coarse triangle, and the refined triangle's normal there; `(p, normal)` when
/// `surface` is empty or `p` lies in none of them.
pub(super) fn surface_point(
    corners: [Vec3; 3],
    normal: Vec3,
    surface: &[[Vec3; 3]],
    p: Vec3,
) -> (Vec3, Vec3) {
    surface_point_in(corners, lattice_frame(corners), normal, surface, p)
}

/// The Gram matrix of a coarse triangle's two edges from its corner 0, `[d11, d12, d22, den]`
/// (`den` its determinant), which carries a point to lattice coordinates ([`surface_point`]):
/// found once per root, not for every point carried.
pub(super) fn lattice_frame(corners: [Vec3; 3]) -> [f32; 4] {
    let [v0, v1, v2] = corners;
    let (e1, e2) = (v1 - v0, v2 - v0);
    let (d11, d12, d22) = (e1.dot(e1), e1.dot(e2), e2.dot(e2));
    [d11, d12, d22, d11 * d22 - d12 * d12]
}

/// [`surface_point`] with the coarse triangle's [`lattice_frame`] given.
pub(super) fn surface_point_in(
    corners: [Vec3; 3],
    [d11, d12, d22, den]: [f32; 4],
    normal: Vec3,
    surface: &[[Vec3; 3]],
    p: Vec3,
) -> (Vec3, Vec3) {
    if surface.is_empty() {
        return (p, normal);
    }
    let level = (surface.len().trailing_zeros() / 2).min(hce_format::MAX_TREE_DEPTH);
    let n = (1u32 << level) as f32;
    // Lattice coordinates (b, c) of p: p = v0 + (b (v1 - v0) + c (v2 - v0)) / n.
    let [v0, v1, v2] = corners;
    let (e1, e2, d) = (v1 - v0, v2 - v0, p - v0);
    if den <= 0.0 {
        return (p, normal);
    }
    let (d1, d2) = (d.dot(e1), d.dot(e2));
    let q = [
        n * (d22 * d1 - d12 * d2) / den,
        n * (d11 * d2 - d12 * d1) / den,
    ];
    // Descend the 1-to-4 split to the refined triangle that holds q (children Top, Left,
    // Center, Right, as `hce_geometry::lattice` numbers them), then weigh its corners.
    let (mut u, mut v) = (q[0].clamp(0.0, n), q[1].clamp(0.0, n));
    let (mut side, mut path) = (n, 0usize);
    for _ in 0..level {
        let h = side * 0.5;
        let child;
        (child, u, v) = hce_geometry::lattice::child_toward(u, v, h);
        path = path * 4 + child as usize;
        side = h;
    }
    if let Some(tri) = surface.get(path) {
        let c = lattice_cells(level)[path];
        // Barycentric weights of q in the lattice triangle c.
        let a = [c[1][0] - c[0][0], c[1][1] - c[0][1]];
        let b = [c[2][0] - c[0][0], c[2][1] - c[0][1]];
        let det = a[0] * b[1] - a[1] * b[0];
        let (x, y) = (q[0] - c[0][0], q[1] - c[0][1]);
        let w1 = (x * b[1] - y * b[0]) / det;
        let w2 = (a[0] * y - a[1] * x) / det;
        let w0 = 1.0 - w1 - w2;
        let at = tri[0] * w0 + tri[1] * w1 + tri[2] * w2;
        let refined = (tri[1] - tri[0])
            .cross(tri[2] - tri[0])
            .try_normalize()
            .unwrap_or(normal);
        return (at, refined);
    }
    (p, normal)
}

/// The lattice corners of every level-`level` subtriangle, by path
/// ([`hce_geometry::lattice::subtriangle_cells`]), found once per level: every ray's two ends
/// and every link's points are carried onto the surface, and each took a second descent of
/// the split to find its cell's corners. Only the levels refined surfaces have are built.
fn lattice_cells(level: u32) -> &'static [[[f32; 2]; 3]] {
    const LEVELS: usize = hce_format::MAX_TREE_DEPTH as usize + 1;
    static CELLS: [OnceLock<Vec<[[f32; 2]; 3]>>; LEVELS] = [const { OnceLock::new() }; LEVELS];
    CELLS[level as usize].get_or_init(|| {
        hce_geometry::lattice::subtriangle_cells(level)
            .into_iter()
            .map(|c| c.map(|x| [x[0] as f32, x[1] as f32]))
            .collect()
    })
}

impl Ctx<'_> {
    /// The Loop level of root `r`'s refined surface ([`Ctx::on_surface`]), if it has one.
    pub(super) fn surface_level(&self, r: u32) -> Option<u32> {
        let surf = &self.surface[r as usize];
        (!surf.is_empty()).then(|| surf.len().trailing_zeros() / 2)
    }

    /// The point of root `r`'s occluding surface ([`SolverObject::occluder`]) that corresponds
    /// to point `p` of the root, and that surface's normal there: the same lattice coordinates
    /// on the refined triangle as on the flat subtriangle. `(p, the root's normal)` where the
    /// root casts shadows with its own triangle.
    ///
    /// [`SolverObject::occluder`]: crate::scene::SolverObject::occluder
    pub(super) fn on_surface(&self, r: u32, p: Vec3) -> (Vec3, Vec3) {
        let root = &self.roots[r as usize];
        let surface = &self.surface[r as usize];
        if surface.is_empty() {
            return (p, root.normal);
        }
        surface_point_in(
            root.corners,
            self.frames[r as usize],
            root.normal,
            surface,
            p,
        )
    }

    /// The triangles that stand for source element `k` (corners `st`) in form factors. For an
    /// object that casts shadows with a refined surface ([`Ctx::on_surface`]) that surface:
    /// where the source is `near` its receiver, the refined triangles under an element one
    /// level above theirs, the four children of one further above with their corners carried
    /// onto the surface, and below their level the element's corners carried onto its refined
    /// triangle; where it is far, the triangle through its corners carried onto the surface.
    /// Else the element itself.
    ///
    /// The surface drawn sends the light, as it casts the shadows. With the control mesh as
    /// the source and the refined surface as the occluder a receiver counted the control
    /// mesh's points both as a source and as a hole through which it saw what lies behind (a
    /// wall in a closed furnace 5% too bright in front of a refined star's point), and at a
    /// concave fold of one object each coarse triangle saw the other over a wider angle than
    /// the refined surface does (the creases of curved objects 5-27% too bright).
    pub(super) fn source_shape<'s>(
        &'s self,
        k: ElemKey,
        st: [Vec3; 3],
        near: bool,
        buf: &'s mut [[Vec3; 3]; 4],
    ) -> &'s [[Vec3; 3]] {
        let surf = &self.surface[k.root as usize];
        let level = surf.len().trailing_zeros() / 2;
        if surf.is_empty() {
            buf[0] = st;
        } else if !near || k.level >= level {
            buf[0] = st.map(|q| self.on_surface(k.root, q).0);
        } else if k.level + 1 == level {
            // Paths number the refined triangles as they number elements (first choice most
            // significant), so the four under `k` are one run.
            let first = (k.path as usize) << 2;
            return &surf[first..first + 4];
        } else {
            // Further above the refined triangles: the element's four children, their corners
            // carried onto the surface (four form factors where the refined triangles under
            // it would take sixteen: the same surface, a level coarser).
            for (b, c) in buf.iter_mut().zip(split(st)) {
                *b = c.map(|q| self.on_surface(k.root, q).0);
            }
            return &buf[..];
        }
        &buf[..1]
    }

    /// Which normal of source element `sk`'s set stands for the surface that sends light
    /// towards `p`: the one nearest the mean normal of its refined triangles, each weighed by
    /// its area turned towards `p`. 0 where the root has one normal or no refined surface.
    pub(super) fn facing_normal(&self, sk: ElemKey, p: Vec3) -> u8 {
        let root = &self.roots[sk.root as usize];
        let surf = &self.surface[sk.root as usize];
        if root.normals.len() < 2 || surf.is_empty() {
            return 0;
        }
        let level = surf.len().trailing_zeros() / 2;
        let tris = if sk.level >= level {
            let i = (sk.path >> (2 * (sk.level - level))) as usize;
            &surf[i..i + 1]
        } else {
            let span = 1usize << (2 * (level - sk.level));
            let first = sk.path as usize * span;
            &surf[first..first + span]
        };
        let mut m = Vec3::ZERO;
        for t in tris {
            let n2 = (t[1] - t[0]).cross(t[2] - t[0]);
            let d = (p - (t[0] + t[1] + t[2]) / 3.0).normalize_or_zero();
            m += n2.normalize_or_zero() * n2.dot(d).max(0.0);
        }
        let mut best = (0u8, root.normals[0].dot(m));
        for (j, n) in root.normals.iter().enumerate().skip(1) {
            let d = n.dot(m);
            if d > best.1 {
                best = (j as u8, d);
            }
        }
        best.0
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    /// The level-`level` surface over `corners` whose lattice point `(b, c)` is at
    /// `at(b, c)`, by path as `hce_geometry::lattice` numbers the fine triangles.
    fn surface(level: u32, at: impl Fn(f32, f32) -> Vec3) -> Vec<[Vec3; 3]> {
        (0..1u32 << (2 * level))
            .map(|path| {
                hce_geometry::lattice::fine_corners(level, path)
                    .map(|[b, c]| at(b as f32, c as f32))
            })
            .collect()
    }

    #[test]
    fn points_map_to_the_occluding_surface_at_their_lattice_coordinates() {
        let corners = [
            Vec3::new(0.0, 0.0, 0.0),
            Vec3::new(2.0, 0.0, 0.1),
            Vec3::new(0.3, 1.5, -0.2),
        ];
        let normal = (corners[1] - corners[0])
            .cross(corners[2] - corners[0])
            .normalize();
        let n = 4.0;
        let flat = |b: f32, c: f32| {
            corners[0] + (corners[1] - corners[0]) * (b / n) + (corners[2] - corners[0]) * (c / n)
        };
        // A bump that differs on every lattice point, so that a point mapped through the wrong
        // fine triangle or the wrong corner lands elsewhere.
        let bump = |b: f32, c: f32| flat(b, c) + normal * (0.05 * b + 0.11 * c + 0.02 * b * c);
        let mut rng = crate::radiosity::element::Rng::new(1, 2, 3);
        for _ in 0..200 {
            let (mut u, mut v) = (rng.next_f32(), rng.next_f32());
            if u + v > 1.0 {
                (u, v) = (1.0 - u, 1.0 - v);
            }
            let p = flat(n * u, n * v);
            // In its own plane, a point is where it is, with the triangle's normal.
            let (q, m) = surface_point(corners, normal, &surface(2, flat), p);
            assert!((q - p).length() < 1e-5, "{p} went to {q}");
            assert!(m.dot(normal) > 0.9999);
            // Lifted, it follows the surface: linear within each fine triangle.
            let (q, _) = surface_point(corners, normal, &surface(2, bump), p);
            let (b, c) = (n * u, n * v);
            let lift = (q - p).dot(normal);
            let (lo, hi) = {
                // The bump at the corners of the lattice cell around (b, c) bounds it.
                let (b0, c0) = (b.floor(), c.floor());
                let h = |b: f32, c: f32| 0.05 * b + 0.11 * c + 0.02 * b * c;
                let hs = [
                    h(b0, c0),
                    h(b0 + 1.0, c0),
                    h(b0, c0 + 1.0),
                    h(b0 + 1.0, c0 + 1.0),
                ];
                (
                    hs.iter().copied().fold(f32::MAX, f32::min),
                    hs.iter().copied().fold(f32::MIN, f32::max),
                )
            };
            assert!(
                lift >= lo - 1e-4 && lift <= hi + 1e-4,
                "({b}, {c}) lifted by {lift}, outside [{lo}, {hi}]"
            );
            assert!(
                (q - p - normal * lift).length() < 1e-4,
                "moved off the normal"
            );
        }
        // The lattice points themselves land exactly on the surface's.
        for (b, c) in [
            (0.0, 0.0),
            (4.0, 0.0),
            (0.0, 4.0),
            (1.0, 2.0),
            (3.0, 1.0),
            (2.0, 2.0),
        ] {
            let (q, _) = surface_point(corners, normal, &surface(2, bump), flat(b, c));
            assert!(
                (q - bump(b, c)).length() < 1e-4,
                "({b}, {c}): {q} against {}",
                bump(b, c)
            );
        }
        // Without a surface of its own a root is its own.
        let p = flat(1.0, 1.0);
        assert_eq!(surface_point(corners, normal, &[], p), (p, normal));
    }

    /// The occluder the pipeline hands the solver lists each coarse triangle's Loop triangles
    /// by path with their corners in `fine_corners` order, as `surface_point` reads them: on a
    /// planar grid, which Loop subdivision leaves where it is away from its boundary (whose
    /// rules move the boundary's points along it), every refined corner of a triangle two rings
    /// in is the flat lattice point.
    #[test]
    fn loop_triangles_follow_the_lattice_order() {
        let (w, h) = (8u32, 7u32);
        let positions: Vec<[f32; 3]> = (0..=h)
            .flat_map(|y| (0..=w).map(move |x| [x as f32, y as f32 * 0.7, 0.0]))
            .collect();
        let at = |x: u32, y: u32| y * (w + 1) + x;
        let mut triangles = Vec::new();
        for y in 0..h {
            for x in 0..w {
                triangles.push([at(x, y), at(x + 1, y), at(x + 1, y + 1)]);
                triangles.push([at(x, y), at(x + 1, y + 1), at(x, y + 1)]);
            }
        }
        let top = hce_geometry::build_control_mesh(
            &positions,
            &triangles,
            None,
            &hce_geometry::TopologyConfig::default(),
        )
        .unwrap();
        let level = 2;
        let refined = hce_geometry::subdivide(&top.mesh, level).unwrap();
        let per = 1usize << (2 * level);
        let n = (1u32 << level) as f32;
        let mut checked = 0;
        for t in 0..top.mesh.triangle_count() {
            let [v0, v1, v2] = top
                .mesh
                .triangle(t)
                .map(|v| Vec3::from(top.mesh.position(v)));
            let inside = |v: Vec3| {
                let (x, y) = (v.x, v.y / 0.7);
                x >= 2.0 && x <= (w - 2) as f32 && y >= 2.0 && y <= (h - 2) as f32
            };
            if ![v0, v1, v2].into_iter().all(inside) {
                continue;
            }
            checked += 1;
            for path in 0..per {
                let want = hce_geometry::lattice::fine_corners(level, path as u32)
                    .map(|[b, c]| v0 + (v1 - v0) * (b as f32 / n) + (v2 - v0) * (c as f32 / n));
                let got = refined.indices[t * per + path]
                    .map(|v| Vec3::from(refined.positions[v as usize]));
                for k in 0..3 {
                    assert!(
                        (got[k] - want[k]).length() < 1e-4,
                        "triangle {t} path {path} corner {k}: {} against {}",
                        got[k],
                        want[k]
                    );
                }
            }
        }
        assert!(
            checked >= 10,
            "only {checked} triangles away from the boundary"
        );
    }
}
