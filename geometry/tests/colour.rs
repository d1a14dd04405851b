//! Applying baked colours on the CPU (`hce_geometry::colour`) to the example containers of
//! hce-format, against colours worked out by hand from their trees: the paper's nearest-normal
//! rule and the smooth reconstruction (SPEC.md, Appendix G).

use hce_format::{encode_tree, example, rgb9e5, Object};
use hce_geometry::colour::{apply_baked_colours, apply_baked_colours_with, ColourError};
use hce_geometry::lighting::LightingError;
use hce_geometry::lighting::{LightingTable, Reconstruction};
use hce_geometry::subdivide::{subdivide, Refined};

fn area(r: &Refined, f: usize) -> f64 {
    let p = r.indices[f].map(|i| r.positions[i as usize].map(f64::from));
    let e1 = [0, 1, 2].map(|k| p[1][k] - p[0][k]);
    let e2 = [0, 1, 2].map(|k| p[2][k] - p[0][k]);
    let c = [
        e1[1] * e2[2] - e1[2] * e2[1],
        e1[2] * e2[0] - e1[0] * e2[2],
        e1[0] * e2[1] - e1[1] * e2[0],
    ];
    0.5 * (c[0] * c[0] + c[1] * c[1] + c[2] * c[2]).sqrt()
}

/// The area-weighted mean at each vertex of the given per-subtriangle colours.
fn vertex_means(r: &Refined, face: impl Fn(usize) -> [f32; 3]) -> Vec<[f64; 3]> {
    let mut sum = vec![[0.0; 3]; r.positions.len()];
    let mut w = vec![0.0; r.positions.len()];
    for f in 0..r.indices.len() {
        let a = area(r, f);
        let c = face(f);
        for &i in &r.indices[f] {
            for k in 0..3 {
                sum[i as usize][k] += a * f64::from(c[k]);
            }
            w[i as usize] += a;
        }
    }
    sum.iter().zip(&w).map(|(s, w)| s.map(|x| x / w)).collect()
}

fn close(a: [f32; 3], b: [f64; 3]) -> bool {
    (0..3).all(|k| (f64::from(a[k]) - b[k]).abs() < 1e-5)
}

/// `grid(3, 0)` (single-node trees, normals (0,0,1) and (0.6,0,0.8) with red 0.0 and 0.01)
/// with its bumps steepened (z x 5), so that some subtriangles face tilted normals.
fn bumpy_grid() -> Object {
    let mut c = example::grid(3, 0);
    for z in c.objects[0].mesh.positions.iter_mut().skip(2).step_by(3) {
        *z *= 5.0;
    }
    c.objects.swap_remove(0)
}

/// A colour that is a linear function of the normal.
fn linear(n: [f32; 3]) -> [f32; 3] {
    [1.0 + 0.5 * n[0] + 0.25 * n[1], 0.5, 0.5 - 0.125 * n[0]]
}

/// The bumpy grid with every triangle carrying the same four normals, coloured by [`linear`].
fn four_normal_grid() -> Object {
    let mut o = bumpy_grid();
    let normals = [
        [0.0, 0.0, 1.0],
        [0.6, 0.0, 0.8],
        [0.0, 0.6, 0.8],
        [-0.6, 0.0, 0.8],
    ];
    o.normals = normals.to_vec();
    o.colours = normals.iter().map(|&n| rgb9e5::encode(linear(n))).collect();
    for rec in &mut o.triangles {
        rec.normal_start = 0;
        rec.normal_count = 4;
        rec.colour_start = 0;
    }
    o
}

#[test]
fn single_node_tree_colours_every_vertex_with_its_colour() {
    let mut c = example::single_triangle();
    let o = &mut c.objects[0];
    let (bits, bit_len) = encode_tree(&[false]).unwrap();
    o.bits = bits;
    o.bit_len = bit_len;
    let colour = [0.75, 0.125, 2.5];
    o.colours = vec![rgb9e5::encode(colour)];
    for level in 0..=3 {
        let r = subdivide(&o.mesh, level).unwrap();
        let rgb = apply_baked_colours(o, &r, level).unwrap();
        assert_eq!(rgb.len(), r.positions.len());
        for v in &rgb {
            assert_eq!(*v, colour, "level {level}");
        }
    }
}

#[test]
fn nearest_level_one_subtriangles_take_their_childs_colour() {
    // The Appendix D tree: root split; Top, Left, Right leaves (nodes 1, 2, 4); Center (node 3)
    // split into nodes 5..8. Node k's colour is (k / 8, 1/2, 1/4).
    let c = example::single_triangle();
    let o = &c.objects[0];
    let node = |k: u32| [k as f32 / 8.0, 0.5, 0.25];
    let r = subdivide(&o.mesh, 1).unwrap();
    let rgb = apply_baked_colours_with(o, &r, 1, Reconstruction::NearestNormal).unwrap();
    // Subtriangle with path p (Top, Left, Center, Right) lies in node 1 + p.
    let expected = vertex_means(&r, |f| node(1 + r.path(f)));
    for (v, (got, want)) in rgb.iter().zip(&expected).enumerate() {
        assert!(close(*got, *want), "vertex {v}: {got:?} vs {want:?}");
    }
    // The coarse corners lie in one subtriangle each: Top, Left and Right.
    let corner = |p: [f32; 3]| r.positions.iter().position(|q| *q == p).unwrap();
    assert_eq!(rgb[corner([0.0, 0.0, 0.0])], node(1));
    assert_eq!(rgb[corner([1.0, 0.0, 0.0])], node(2));
    assert_eq!(rgb[corner([0.0, 1.0, 0.0])], node(4));
}

#[test]
fn nearest_level_two_paths_stop_at_leaves_and_descend_where_split() {
    let c = example::single_triangle();
    let o = &c.objects[0];
    let node = |k: u32| [k as f32 / 8.0, 0.5, 0.25];
    let r = subdivide(&o.mesh, 2).unwrap();
    let rgb = apply_baked_colours_with(o, &r, 2, Reconstruction::NearestNormal).unwrap();
    // Paths 0..3 (Top's children) stop at leaf 1; 8..11 (Center's children) reach 5..8.
    let face_node = |p: u32| match p >> 2 {
        0 => 1,
        1 => 2,
        2 => 5 + (p & 3),
        _ => 4,
    };
    let expected = vertex_means(&r, |f| node(face_node(r.path(f))));
    for (v, (got, want)) in rgb.iter().zip(&expected).enumerate() {
        assert!(close(*got, *want), "vertex {v}: {got:?} vs {want:?}");
    }
}

#[test]
fn nearest_subtriangles_pick_the_normal_closest_to_their_own_across_borders() {
    // grid(3, 0): single-node trees, normals (0,0,1) and (0.6,0,0.8) with red 0.0 and 0.01.
    let o = &bumpy_grid();
    let r = subdivide(&o.mesh, 2).unwrap();
    let rgb = apply_baked_colours_with(o, &r, 2, Reconstruction::NearestNormal).unwrap();
    let mut picked = [0usize; 2];
    let face = |f: usize| {
        let p = r.indices[f].map(|i| r.positions[i as usize]);
        let e1 = [0, 1, 2].map(|k| p[1][k] - p[0][k]);
        let e2 = [0, 1, 2].map(|k| p[2][k] - p[0][k]);
        let n = [
            e1[1] * e2[2] - e1[2] * e2[1],
            e1[2] * e2[0] - e1[0] * e2[2],
            e1[0] * e2[1] - e1[1] * e2[0],
        ];
        let t = r.coarse_triangle(f);
        let j = usize::from(0.6 * n[0] + 0.8 * n[2] > n[2]);
        let rec = o.triangles[t];
        rgb9e5::decode(o.colours[rec.colour_start as usize + j])
    };
    for f in 0..r.indices.len() {
        picked[usize::from(face(f)[0] > 0.0)] += 1;
    }
    // The tilted grid makes both choices occur.
    assert!(picked[0] > 0 && picked[1] > 0, "{picked:?}");
    let expected = vertex_means(&r, face);
    for (v, (got, want)) in rgb.iter().zip(&expected).enumerate() {
        assert!(close(*got, *want), "vertex {v}: {got:?} vs {want:?}");
    }
}

#[test]
fn mismatched_or_damaged_input_is_an_error() {
    let c = example::single_triangle();
    let other = example::two_triangles();
    let r = subdivide(&other.objects[0].mesh, 1).unwrap();
    assert!(matches!(
        apply_baked_colours(&c.objects[0], &r, 1),
        Err(ColourError::TriangleCount {
            records: 1,
            refined: 2,
            ..
        })
    ));
    let r = subdivide(&c.objects[0].mesh, 1).unwrap();
    assert!(matches!(
        apply_baked_colours(&c.objects[0], &r, 2),
        Err(ColourError::Level { .. })
    ));
    let mut o = c.objects[0].clone();
    o.colours.truncate(4);
    assert!(matches!(
        apply_baked_colours(&o, &r, 1),
        Err(ColourError::Lighting(LightingError::Record {
            triangle: 0,
            ..
        }))
    ));
    let mut o = c.objects[0].clone();
    o.triangles[0].normal_start = 5;
    assert!(matches!(
        apply_baked_colours(&o, &r, 1),
        Err(ColourError::Lighting(LightingError::Record {
            triangle: 0,
            ..
        }))
    ));
}

/// The vertex of `r` at `p`.
fn vertex_at(r: &Refined, p: [f32; 2]) -> usize {
    r.positions
        .iter()
        .position(|q| q[0] == p[0] && q[1] == p[1])
        .unwrap_or_else(|| panic!("no vertex at {p:?}"))
}

#[test]
fn smooth_field_averages_leaf_corners_and_interpolates_t_vertices() {
    // The Appendix D tree on the unit right triangle (v0 at the origin, v1 = (1,0), v2 = (0,1)):
    // Top, Left, Right leaves of depth 1 (nodes 1, 2, 4); Center split into leaves 5..8. One
    // normal per triangle, so the fit is the nodal average of the red channel k / 8, which the
    // correction (G.3) then moves by the mean of its leaves' residuals.
    let c = example::single_triangle();
    let o = &c.objects[0];
    assert_eq!(o.triangles[0].normal_count, 1);
    let red = |k: f64| k / 8.0;
    let (big, small) = (0.25, 0.0625);
    // Corner points: the coarse corners lie in one leaf each, whose residual the limit to
    // the colours there (that leaf's alone) takes away.
    let v0 = red(1.0);
    let v1 = red(2.0);
    let v2 = red(4.0);
    // Edge midpoints: two depth-1 leaves and the depth-2 corner leaf of Center there.
    let m01 = (big * red(1.0) + big * red(2.0) + small * red(8.0)) / (2.0 * big + small);
    let m12 = (big * red(2.0) + big * red(4.0) + small * red(5.0)) / (2.0 * big + small);
    let m20 = (big * red(1.0) + big * red(4.0) + small * red(6.0)) / (2.0 * big + small);
    // The T-vertices inside the big leaves' inner edges (Top's, Left's, Right's).
    let (tt, tl, tr) = (0.5 * (m01 + m20), 0.5 * (m01 + m12), 0.5 * (m20 + m12));
    // Each leaf's residual: its colour less the mean of its corners' models.
    let r1 = red(1.0) - (v0 + m01 + m20) / 3.0;
    let r2 = red(2.0) - (m01 + v1 + m12) / 3.0;
    let r4 = red(4.0) - (m20 + m12 + v2) / 3.0;
    let r5 = red(5.0) - (m12 + tr + tl) / 3.0;
    let r6 = red(6.0) - (tr + m20 + tt) / 3.0;
    let r8 = red(8.0) - (tl + tt + m01) / 3.0;
    // A point moves by the weighted mean of its leaves' residuals, kept between their colours.
    let moved = |v: f64, r: [f64; 3], k: [f64; 3]| {
        let mean = (big * r[0] + big * r[1] + small * r[2]) / (2.0 * big + small);
        let (lo, hi) = (
            k.iter().copied().map(red).fold(1.0, f64::min),
            k.iter().copied().map(red).fold(0.0, f64::max),
        );
        v + mean.clamp(lo - v, hi - v)
    };
    let m01 = moved(m01, [r1, r2, r8], [1.0, 2.0, 8.0]);
    let m12 = moved(m12, [r2, r4, r5], [2.0, 4.0, 5.0]);
    let m20 = moved(m20, [r1, r4, r6], [1.0, 4.0, 6.0]);
    for level in 1..=4 {
        let r = subdivide(&o.mesh, level).unwrap();
        let rgb = apply_baked_colours(o, &r, level).unwrap();
        let at = |p: [f32; 2]| f64::from(rgb[vertex_at(&r, p)][0]);
        let near = |got: f64, want: f64, what: &str| {
            assert!(
                (got - want).abs() < 1e-6,
                "level {level}, {what}: {got} vs {want}"
            )
        };
        near(at([0.0, 0.0]), v0, "v0");
        near(at([1.0, 0.0]), v1, "v1");
        near(at([0.0, 1.0]), v2, "v2");
        near(at([0.5, 0.0]), m01, "m01");
        near(at([0.5, 0.5]), m12, "m12");
        near(at([0.0, 0.5]), m20, "m20");
        if level >= 2 {
            // T-vertices: the midpoints of the big leaves' inner edges take the mean of the
            // edge's ends, not the average of the small leaves meeting there.
            near(
                at([0.25, 0.25]),
                0.5 * (m01 + m20),
                "T-vertex in Top's edge",
            );
            near(
                at([0.5, 0.25]),
                0.5 * (m01 + m12),
                "T-vertex in Left's edge",
            );
            near(
                at([0.25, 0.5]),
                0.5 * (m20 + m12),
                "T-vertex in Right's edge",
            );
            // Inside Top: linear between its corners.
            near(at([0.25, 0.0]), 0.5 * (v0 + m01), "inside Top");
        }
        // Every channel but red is constant.
        for c in &rgb {
            assert!((c[1] - 0.5).abs() < 1e-6 && (c[2] - 0.25).abs() < 1e-6);
        }
    }
}

#[test]
fn smooth_reconstruction_is_linear_in_the_normal() {
    // Every triangle of a bumpy grid carries the same four normals with colours that are a linear
    // function of the normal: the reconstruction must give each refined vertex that function of
    // its own normal, to the quantisation of RGB9E5 and the slight shrinkage of the ridge term.
    let o = &four_normal_grid();
    for level in 1..=3 {
        let r = subdivide(&o.mesh, level).unwrap();
        let smooth = apply_baked_colours(o, &r, level).unwrap();
        let mut worst = 0.0f32;
        for (got, n) in smooth.iter().zip(&r.normals) {
            let want = linear(*n);
            for k in 0..3 {
                worst = worst.max((got[k] - want[k]).abs() / want[k]);
            }
        }
        assert!(worst < 0.005, "level {level}: worst relative error {worst}");
    }
}

#[test]
fn smooth_reconstruction_keeps_one_colour_trees_exact_and_is_the_default() {
    let c = example::grid(3, 0);
    let o = &c.objects[0];
    let r = subdivide(&o.mesh, 2).unwrap();
    assert_eq!(
        apply_baked_colours(o, &r, 2).unwrap(),
        apply_baked_colours_with(o, &r, 2, Reconstruction::Smooth).unwrap()
    );
    assert_ne!(
        apply_baked_colours(o, &r, 2).unwrap(),
        apply_baked_colours_with(o, &r, 2, Reconstruction::NearestNormal).unwrap()
    );
    assert_eq!("nearest".parse(), Ok(Reconstruction::NearestNormal));
    assert_eq!("smooth".parse(), Ok(Reconstruction::Smooth));
    assert!("bilinear".parse::<Reconstruction>().is_err());
}

/// The bumpy 3×3 grid of the tests above, each triangle carrying its geometric normal alone
/// with the colour `f(n0)`.
fn one_normal_grid(f: impl Fn([f32; 3]) -> [f32; 3]) -> Object {
    let mut o = bumpy_grid();
    let p = |v: u32| {
        let i = 3 * v as usize;
        glam::Vec3::from_slice(&o.mesh.positions[i..i + 3])
    };
    let normals: Vec<[f32; 3]> = o
        .mesh
        .triangles
        .chunks(3)
        .map(|t| {
            let (a, b, c) = (p(t[0]), p(t[1]), p(t[2]));
            (b - a).cross(c - a).normalize().to_array()
        })
        .collect();
    o.colours = normals.iter().map(|&n| rgb9e5::encode(f(n))).collect();
    for (t, rec) in o.triangles.iter_mut().enumerate() {
        rec.normal_start = t as u32;
        rec.normal_count = 1;
        rec.colour_start = t as u32;
    }
    o.normals = normals;
    o
}

#[test]
fn smooth_fit_pools_the_normals_of_the_triangles_around_a_point() {
    // One normal per triangle, colours a linear function of it: no triangle's own set spans a
    // slope, but the samples pooled at a vertex (SPEC.md G.3) do. At the grid's interior vertex
    // (1, 1), corner 0 of triangle 8, whose fan of six triangles spans the normals around it,
    // the field must change with the normal as the function does; drawn without slopes
    // (`gouraud`) it does not change at all.
    let f = linear;
    let o = one_normal_grid(f);
    assert_eq!(
        o.mesh.triangles[24], 5,
        "triangle 8 starts at vertex (1, 1)"
    );
    let smooth = LightingTable::build(&o).unwrap();
    let gouraud = LightingTable::build_with(&o, Reconstruction::Gouraud).unwrap();
    let unit = |v: [f32; 3]| glam::Vec3::from(v).normalize().to_array();
    let (a, b) = (unit([0.3, -0.2, 1.0]), unit([-0.2, 0.3, 1.0]));
    let want = [0, 1, 2].map(|ch| f(a)[ch] - f(b)[ch]);
    let (sa, sb) = (smooth.evaluate(8, 0, 0, a), smooth.evaluate(8, 0, 0, b));
    for ch in 0..3 {
        let got = sa[ch] - sb[ch];
        assert!(
            (got - want[ch]).abs() < 0.05 * 0.25,
            "channel {ch}: the field changes by {got} between two normals, the function by {}",
            want[ch]
        );
    }
    assert_eq!(gouraud.evaluate(8, 0, 0, a), gouraud.evaluate(8, 0, 0, b));
}

#[test]
fn gouraud_draws_the_geometric_normals_colours_without_slopes() {
    // Four normals per triangle, the same colours everywhere: the smooth field follows the
    // refined normals, the Gouraud one is the colour of the geometric normal (the first) alone.
    let o = &four_normal_grid();
    let first = rgb9e5::decode(o.colours[0]);
    let r = subdivide(&o.mesh, 2).unwrap();
    let gouraud = apply_baked_colours_with(o, &r, 2, Reconstruction::Gouraud).unwrap();
    for got in &gouraud {
        for k in 0..3 {
            assert!((got[k] - first[k]).abs() < 1e-6, "{got:?} vs {first:?}");
        }
    }
    assert_ne!(gouraud, apply_baked_colours(o, &r, 2).unwrap());
    assert_eq!("gouraud".parse(), Ok(Reconstruction::Gouraud));
}

/// Gives `o`'s first triangle the full tree of `depth` and returns its nodes' cells in
/// breadth-first order (the leaves last, `4^depth` of them).
fn full_tree(o: &mut Object, depth: u32) -> Vec<hce_geometry::lattice::LatticeTriangle> {
    let mut nodes = vec![hce_geometry::lattice::LatticeTriangle::root(4096)];
    let mut flags = Vec::new();
    let mut level = 0..1;
    for d in 0..=depth {
        for k in level.clone() {
            flags.push(d < depth);
            if d < depth {
                let cell = nodes[k];
                nodes.extend((0..4).map(|c| cell.child(c)));
            }
        }
        level = level.end..nodes.len();
    }
    let (bits, bit_len) = encode_tree(&flags).unwrap();
    o.bits = bits;
    o.bit_len = bit_len;
    nodes
}

#[test]
fn correction_sharpens_a_penumbra_and_stays_within_the_colours_around() {
    // A full tree of depth 4 on the unit right triangle, its leaves holding the mean over their
    // area of a penumbra: bright left of x = 0.3, dim right of x = 0.45, linear between (about
    // two leaves wide). The fit alone is the mean of the leaves at each corner; the correction
    // (G.3) must bring every leaf's drawn mean (the mean of its corners' values: the field is
    // linear over it) closer to its colour, and draw nothing brighter or darker than the leaves
    // around a point.
    use hce_format::ObjectKind;
    use hce_geometry::lattice::LatticeTriangle;
    use std::collections::HashMap;
    const DEPTH: u32 = 4;
    let (bright, dim) = (1.0f32, 0.125f32);
    for kind in [ObjectKind::Flat, ObjectKind::Multiresolution] {
        let mut c = example::single_triangle();
        let o = &mut c.objects[0];
        o.kind = kind;
        let nodes = full_tree(o, DEPTH);
        let inner = nodes.len() - 4usize.pow(DEPTH);
        let leaves = &nodes[inner..];
        let light = |x: f32| {
            let t = ((x / 4096.0 - 0.3) / 0.15).clamp(0.0, 1.0);
            bright + (dim - bright) * t
        };
        // The mean over the leaf, from a barycentric grid of 45 points.
        let colour_of = |cell: &LatticeTriangle| {
            let [a, b, c] = cell.corners().map(|p| p[0] as f32);
            let mut sum = 0.0;
            let mut count = 0.0;
            for i in 0..9 {
                for j in 0..9 - i {
                    let (u, v) = ((i as f32 + 1.0 / 3.0) / 9.0, (j as f32 + 1.0 / 3.0) / 9.0);
                    sum += light(a + (b - a) * u + (c - a) * v);
                    count += 1.0;
                }
            }
            sum / count
        };
        o.colours = (0..inner)
            .map(|_| rgb9e5::encode([0.5, 0.5, 0.5]))
            .chain(leaves.iter().map(|l| rgb9e5::encode([colour_of(l); 3])))
            .collect();
        let table = LightingTable::build(o).unwrap();
        let normal = o.normals[0];
        let drawn = |p: [i32; 2]| table.evaluate(0, p[0] as u32 * 16, p[1] as u32 * 16, normal)[0];
        // The fit alone: every leaf has the same area, so a corner's value is its leaves' mean.
        let mut around: HashMap<[i32; 2], Vec<f32>> = HashMap::new();
        for l in leaves {
            for p in l.corners() {
                around.entry(p).or_default().push(colour_of(l));
            }
        }
        let fitted = |p: [i32; 2]| around[&p].iter().sum::<f32>() / around[&p].len() as f32;
        let (mut before, mut after) = (0.0f64, 0.0f64);
        for l in leaves {
            let mean =
                |f: &dyn Fn([i32; 2]) -> f32| l.corners().iter().map(|&p| f(p)).sum::<f32>() / 3.0;
            before += f64::from(mean(&fitted) - colour_of(l)).powi(2);
            after += f64::from(mean(&drawn) - colour_of(l)).powi(2);
        }
        assert!(before > 0.0, "{kind:?}: the penumbra must blur");
        assert!(
            after < 0.5 * before,
            "{kind:?}: drawn leaf means {after:.5} from their colours, the fit alone {before:.5}"
        );
        for (p, colours) in &around {
            let (lo, hi) = colours
                .iter()
                .fold((f32::MAX, f32::MIN), |(a, b), &c| (a.min(c), b.max(c)));
            let v = drawn(*p);
            assert!(
                v >= lo * (1.0 - 1e-5) && v <= hi * (1.0 + 1e-5),
                "{kind:?}: point {p:?} draws {v}, its leaves hold {lo} to {hi}"
            );
        }
    }
}

#[test]
fn corner_colours_are_drawn_where_they_lie_without_correction() {
    // A full tree of depth 3 whose leaves store the light at their corners (SPEC.md A.10): a
    // penumbra, and means that say otherwise (a constant). Every leaf corner must draw the light
    // there (all the leaves meeting at a point agree on it), not the means nor a correction
    // towards them; a point inside a leaf, the mean of its corners.
    use hce_format::ObjectKind;
    const DEPTH: u32 = 3;
    for kind in [ObjectKind::Flat, ObjectKind::Multiresolution] {
        let mut c = example::single_triangle();
        let o = &mut c.objects[0];
        o.kind = kind;
        let nodes = full_tree(o, DEPTH);
        let light = |p: [i32; 2]| {
            let t = ((p[0] as f32 / 4096.0 - 0.3) / 0.3).clamp(0.0, 1.0);
            rgb9e5::decode(rgb9e5::encode([1.0 - 0.875 * t, 0.5, 0.25 + t]))
        };
        o.colours = vec![rgb9e5::encode([0.5; 3]); nodes.len()];
        o.corner_colours = nodes
            .iter()
            .flat_map(|cell| cell.corners().map(|p| rgb9e5::encode(light(p))))
            .collect();
        let table = LightingTable::build(o).unwrap();
        let normal = o.normals[0];
        let drawn = |p: [i32; 2]| table.evaluate(0, p[0] as u32 * 16, p[1] as u32 * 16, normal);
        let near = |a: [f32; 3], b: [f32; 3]| (0..3).all(|k| (a[k] - b[k]).abs() < 1e-5);
        for cell in nodes.iter().skip(nodes.len() - 4usize.pow(DEPTH)) {
            let corners = cell.corners();
            for p in corners {
                assert!(
                    near(drawn(p), light(p)),
                    "{kind:?} at {p:?}: {:?} against {:?}",
                    drawn(p),
                    light(p)
                );
            }
            let centre = [0, 1].map(|k| corners.iter().map(|p| p[k]).sum::<i32>() / 3);
            let mean = [0, 1, 2].map(|ch| corners.iter().map(|&p| light(p)[ch]).sum::<f32>() / 3.0);
            let at = drawn(centre);
            // The centre on the lattice is within a 4096th of the true one.
            assert!(
                (0..3).all(|k| (at[k] - mean[k]).abs() < 2e-3),
                "{kind:?} at {centre:?}"
            );
        }
    }
}
