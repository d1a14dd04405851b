//! The same-geometry rule (SPEC.md 2.6): does a glTF primitive, as an optimiser left it, still
//! describe the surface of its container object's triangle range? Written once; the validator,
//! the runtime's loader and the browser (through hce-wasm) all call [`same_surface`] through
//! [`crate::check_links`].
//!
//! Optimisers reorder triangles and vertices, weld, rotate corners and quantize (moving the
//! dequantization into the node's transform). None of that changes which oriented triangles
//! make up the surface, so the test pairs triangles by their corner positions: the primitive is
//! first placed onto the object by the scale and translation that map its bounding box onto the
//! object's ([`Placement`]), then each container triangle is paired one-to-one
//! with a primitive triangle whose corners, under a cyclic rotation (the winding kept), lie
//! within the tolerance `τ` of 2.6. Candidates are found through a grid of cells of side `2τ`
//! over the centroids, sorted by cell: `O(T log T)` time and `O(T)` memory, whatever the input.

use crate::accessor::PrimitiveMesh;

/// The most candidates kept per container triangle, and the most primitive triangles examined
/// for one (SPEC.md 2.6): the bound on memory and time when many triangles coincide.
pub const KEPT_CANDIDATES: usize = 8;
pub const EXAMINED_CANDIDATES: usize = 1024;

/// The map from a primitive's positions onto its object's (SPEC.md 2.6, `M`): per axis
/// `x_k = scale · x_p + offset_a`, one scale for every axis, as quantizers dequantize. A loader that draws the object in the primitive's node places
/// it with the node's transform times [`Placement::inverse_columns`].
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Placement {
    pub scale: f64,
    pub offset: [f64; 3],
    /// The tolerance `τ` the triangles were matched within (object units).
    pub tolerance: f64,
    /// The primitive's bounding box (min, max), in its own units.
    pub primitive_box: [[f64; 3]; 2],
}

impl Placement {
    /// The identity placement of a primitive whose bounding box is `primitive_box` (the fast
    /// path of 2.6: the primitive hashes to its `geometryHash`).
    pub fn identity(primitive_box: [[f64; 3]; 2]) -> Self {
        Self {
            scale: 1.0,
            offset: [0.0; 3],
            tolerance: 0.0,
            primitive_box,
        }
    }

    pub fn is_identity(&self) -> bool {
        self.scale == 1.0 && self.offset == [0.0; 3]
    }

    /// A primitive-space point in object space.
    pub fn apply(&self, p: [f64; 3]) -> [f64; 3] {
        std::array::from_fn(|a| self.scale * p[a] + self.offset[a])
    }

    /// `M⁻¹` (object space to the primitive's) as a column-major 4×4 matrix.
    pub fn inverse_columns(&self) -> [f32; 16] {
        let mut m = [0f32; 16];
        let s = 1.0 / self.scale;
        for a in 0..3 {
            m[5 * a] = s as f32;
            m[12 + a] = (-self.offset[a] * s) as f32;
        }
        m[15] = 1.0;
        m
    }

    /// Whether two placements of primitives of one object agree (SPEC.md 3.3, rule 15): each
    /// corner of either primitive box maps to points within the larger tolerance.
    pub fn agrees_with(&self, other: &Placement) -> bool {
        let tolerance = self.tolerance.max(other.tolerance);
        [self.primitive_box, other.primitive_box]
            .iter()
            .flat_map(|b| (0..8).map(move |c| std::array::from_fn(|a| b[(c >> a) & 1][a])))
            .all(|p: [f64; 3]| distance(self.apply(p), other.apply(p)) <= tolerance)
    }
}

/// Why a primitive is not the same geometry as its triangle range (SPEC.md 2.6).
#[derive(Clone, Debug, PartialEq)]
pub enum Mismatch {
    /// The primitive has `primitive` triangles, the range `range`.
    TriangleCount { primitive: usize, range: usize },
    /// A position of the primitive (or an index of the range) is not finite (or out of range).
    Unreadable,
    /// Container triangle `triangle` (of the object, not of the range) has no primitive
    /// triangle left within `tolerance` of its corners.
    Unpaired { triangle: usize, tolerance: f64 },
}

impl std::fmt::Display for Mismatch {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        match self {
            Mismatch::TriangleCount { primitive, range } => write!(
                f,
                "the primitive has {primitive} triangles, the object's range {range}"
            ),
            Mismatch::Unreadable => write!(f, "a position is not finite"),
            Mismatch::Unpaired {
                triangle,
                tolerance,
            } => write!(
                f,
                "container triangle {triangle} has no primitive triangle within {tolerance:.3e} of its corners"
            ),
        }
    }
}

fn distance(a: [f64; 3], b: [f64; 3]) -> f64 {
    ((a[0] - b[0]).powi(2) + (a[1] - b[1]).powi(2) + (a[2] - b[2]).powi(2)).sqrt()
}

/// The bounding box (min, max) of points; `None` for none.
fn bounding_box(points: impl Iterator<Item = [f64; 3]>) -> Option<[[f64; 3]; 2]> {
    points.fold(None, |b, p| {
        let [lo, hi] = b.unwrap_or([p, p]);
        Some([
            std::array::from_fn(|a| lo[a].min(p[a])),
            std::array::from_fn(|a| hi[a].max(p[a])),
        ])
    })
}

/// The bounding box of the positions a primitive's triangles use (the empty box at the origin
/// for none).
pub fn primitive_box(mesh: &PrimitiveMesh) -> [[f64; 3]; 2] {
    bounding_box(
        mesh.triangles
            .iter()
            .flatten()
            .filter_map(|&v| mesh.positions.get(v as usize).copied()),
    )
    .unwrap_or([[0.0; 3]; 2])
}

/// The placement of 2.6: one scale, the ratio of the boxes' largest extents (1 when either box
/// is a point), and per axis the offset that maps the primitive box's centre onto the object's.
fn placement(object: [[f64; 3]; 2], primitive: [[f64; 3]; 2]) -> (f64, [f64; 3]) {
    let largest = |b: [[f64; 3]; 2]| (0..3).map(|a| b[1][a] - b[0][a]).fold(0.0, f64::max);
    let (ek, ep) = (largest(object), largest(primitive));
    let scale = if ek > 0.0 && ep > 0.0 { ek / ep } else { 1.0 };
    let offset = std::array::from_fn(|a| {
        (object[0][a] + object[1][a]) / 2.0 - scale * (primitive[0][a] + primitive[1][a]) / 2.0
    });
    (scale, offset)
}

type Triangle = [[f64; 3]; 3];

fn centroid(t: &Triangle) -> [f64; 3] {
    std::array::from_fn(|a| (t[0][a] + t[1][a] + t[2][a]) / 3.0)
}

/// The pair error of 2.6: the largest corner distance under the best cyclic rotation of `p`.
fn pair_error(k: &Triangle, p: &Triangle) -> f64 {
    (0..3)
        .map(|r| {
            (0..3)
                .map(|c| distance(k[c], p[(c + r) % 3]))
                .fold(0.0, f64::max)
        })
        .fold(f64::INFINITY, f64::min)
}

/// Grid cell of a point; saturating, so far-away points share the outermost cell instead of
/// wrapping (they still only pair within `τ`).
fn cell(p: [f64; 3], side: f64) -> [i64; 3] {
    std::array::from_fn(|a| (p[a] / side).floor() as i64)
}

/// SPEC.md 2.6, surface match: whether `mesh` (the primitive, in its own units) has the same
/// geometry as the container triangles `triangles` (flat, three indices each, into `positions`,
/// the object's `POSN`, three floats per vertex), and if so the placement of the primitive.
pub fn same_surface(
    positions: &[f32],
    triangles: &[u32],
    mesh: &PrimitiveMesh,
    first_triangle: usize,
) -> Result<Placement, Mismatch> {
    let range = triangles.len() / 3;
    if mesh.triangles.len() != range {
        return Err(Mismatch::TriangleCount {
            primitive: mesh.triangles.len(),
            range,
        });
    }
    let vertex = |v: u32| -> Option<[f64; 3]> {
        let at = 3 * v as usize;
        let p = positions.get(at..at + 3)?;
        Some([f64::from(p[0]), f64::from(p[1]), f64::from(p[2])])
    };
    let object: Vec<Triangle> = triangles
        .chunks_exact(3)
        .map(|t| Some([vertex(t[0])?, vertex(t[1])?, vertex(t[2])?]))
        .collect::<Option<_>>()
        .ok_or(Mismatch::Unreadable)?;
    let prim: Vec<Triangle> = mesh
        .triangles
        .iter()
        .map(|t| t.map(|v| mesh.positions.get(v as usize).copied()))
        .map(|[a, b, c]| Some([a?, b?, c?]))
        .collect::<Option<_>>()
        .ok_or(Mismatch::Unreadable)?;
    let finite = |t: &Triangle| t.iter().flatten().all(|x| x.is_finite());
    if !object.iter().all(finite) || !prim.iter().all(finite) {
        return Err(Mismatch::Unreadable);
    }
    let pbox = primitive_box(mesh);
    let Some(kbox) = bounding_box(object.iter().flatten().copied()) else {
        return Ok(Placement::identity(pbox));
    };
    let (scale, offset) = placement(kbox, pbox);
    let diagonal = distance(kbox[0], kbox[1]);
    let reach = kbox.iter().flatten().fold(0.0f64, |m, x| m.max(x.abs()));
    let tolerance = (diagonal / 512.0)
        .max(16.0 * mesh.grid * scale)
        .max(reach * 2f64.powi(-16))
        .max(f64::MIN_POSITIVE);
    let place = Placement {
        scale,
        offset,
        tolerance,
        primitive_box: pbox,
    };
    let prim: Vec<Triangle> = prim.iter().map(|t| t.map(|p| place.apply(p))).collect();
    if !prim.iter().all(finite) {
        return Err(Mismatch::Unreadable);
    }

    // The primitive's triangles sorted by the cell of their centroid.
    let side = 2.0 * tolerance;
    let mut cells: Vec<([i64; 3], u32)> = prim
        .iter()
        .enumerate()
        .map(|(i, t)| (cell(centroid(t), side), i as u32))
        .collect();
    cells.sort_unstable();

    // Up to KEPT_CANDIDATES pairs within τ per container triangle: (error, container, primitive).
    let mut pairs: Vec<(f64, u32, u32)> = Vec::new();
    let mut best: Vec<(f64, u32)> = Vec::with_capacity(KEPT_CANDIDATES + 1);
    for (k, t) in object.iter().enumerate() {
        best.clear();
        let c = cell(centroid(t), side);
        let mut examined = 0usize;
        'cells: for dx in -1i64..=1 {
            for dy in -1i64..=1 {
                for dz in -1i64..=1 {
                    let key = [
                        c[0].saturating_add(dx),
                        c[1].saturating_add(dy),
                        c[2].saturating_add(dz),
                    ];
                    let start = cells.partition_point(|e| e.0 < key);
                    for &(ck, p) in &cells[start..] {
                        if ck != key {
                            break;
                        }
                        if examined == EXAMINED_CANDIDATES {
                            break 'cells;
                        }
                        examined += 1;
                        let e = pair_error(t, &prim[p as usize]);
                        if e <= tolerance {
                            best.push((e, p));
                            best.sort_unstable_by(|a, b| a.0.total_cmp(&b.0).then(a.1.cmp(&b.1)));
                            best.truncate(KEPT_CANDIDATES);
                        }
                    }
                }
            }
        }
        pairs.extend(best.iter().map(|&(e, p)| (e, k as u32, p)));
    }
    pairs.sort_unstable_by(|a, b| a.0.total_cmp(&b.0).then(a.1.cmp(&b.1)).then(a.2.cmp(&b.2)));
    let mut container_paired = vec![false; range];
    let mut primitive_paired = vec![false; range];
    for &(_, k, p) in &pairs {
        let (k, p) = (k as usize, p as usize);
        if !container_paired[k] && !primitive_paired[p] {
            container_paired[k] = true;
            primitive_paired[p] = true;
        }
    }
    match container_paired.iter().position(|&paired| !paired) {
        Some(k) => Err(Mismatch::Unpaired {
            triangle: first_triangle + k,
            tolerance,
        }),
        None => Ok(place),
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use proptest::prelude::*;

    /// A bumpy grid of `n × n` quads, two triangles each, counter-clockwise from +z: a surface
    /// with every triangle distinct, like a baked object's.
    fn grid(n: usize) -> (Vec<f32>, Vec<u32>) {
        let mut positions = Vec::new();
        for j in 0..=n {
            for i in 0..=n {
                let (x, y) = (i as f32 / n as f32, j as f32 / n as f32);
                positions.extend([
                    x * 2.0 - 0.5,
                    y * 1.5 + 3.0,
                    (x * 7.0).sin() * (y * 5.0).cos() * 0.3,
                ]);
            }
        }
        let mut triangles = Vec::new();
        let at = |i: usize, j: usize| (j * (n + 1) + i) as u32;
        for j in 0..n {
            for i in 0..n {
                triangles.extend([at(i, j), at(i + 1, j), at(i + 1, j + 1)]);
                triangles.extend([at(i, j), at(i + 1, j + 1), at(i, j + 1)]);
            }
        }
        (positions, triangles)
    }

    /// The container's mesh as a primitive: unwelded (three vertices per triangle), `f32`.
    fn as_primitive(positions: &[f32], triangles: &[u32]) -> PrimitiveMesh {
        let mut mesh = PrimitiveMesh {
            positions: Vec::new(),
            triangles: Vec::new(),
            grid: 0.0,
        };
        for t in triangles.chunks_exact(3) {
            let base = mesh.positions.len() as u32;
            for &v in t {
                let p = &positions[3 * v as usize..3 * v as usize + 3];
                mesh.positions.push([p[0].into(), p[1].into(), p[2].into()]);
            }
            mesh.triangles.push([base, base + 1, base + 2]);
        }
        mesh
    }

    /// Welds equal positions into one vertex, as `gltf-transform weld` does.
    fn weld(mesh: &PrimitiveMesh) -> PrimitiveMesh {
        let mut seen: std::collections::HashMap<[u64; 3], u32> = Default::default();
        let mut out = PrimitiveMesh {
            positions: Vec::new(),
            triangles: Vec::new(),
            grid: mesh.grid,
        };
        for t in &mesh.triangles {
            out.triangles.push(t.map(|v| {
                let p = mesh.positions[v as usize];
                *seen.entry(p.map(f64::to_bits)).or_insert_with(|| {
                    out.positions.push(p);
                    out.positions.len() as u32 - 1
                })
            }));
        }
        out
    }

    /// Quantizes to `bits` (signed normalized, in a `SHORT` or `BYTE`) over the box, as
    /// gltf-transform's `quantize` does: one uniform scale, the centre as offset; returns the
    /// primitive in its quantized units (the dequantization goes into the node).
    fn quantize(mesh: &PrimitiveMesh, bits: u32, component_bits: u32) -> PrimitiveMesh {
        let b = primitive_box(mesh);
        let half = (0..3)
            .map(|a| (b[1][a] - b[0][a]) / 2.0)
            .fold(0.0, f64::max);
        let centre: [f64; 3] = std::array::from_fn(|a| (b[0][a] + b[1][a]) / 2.0);
        let levels = f64::from((1u32 << (bits - 1)) - 1);
        let max = f64::from((1u32 << (component_bits - 1)) - 1);
        PrimitiveMesh {
            positions: mesh
                .positions
                .iter()
                .map(|p| {
                    std::array::from_fn(|a| {
                        let q = ((p[a] - centre[a]) / half * levels).round();
                        // Stored in the component type's range, read back normalized.
                        (q * (max / levels)).round() / max
                    })
                })
                .collect(),
            triangles: mesh.triangles.clone(),
            grid: 1.0 / max,
        }
    }

    #[test]
    fn the_container_mesh_itself_is_the_same_with_the_identity() {
        let (p, t) = grid(6);
        let place = same_surface(&p, &t, &as_primitive(&p, &t), 0).unwrap();
        assert!(place.is_identity(), "{place:?}");
    }

    #[test]
    fn quantized_primitives_pair_and_their_placement_undoes_the_quantization() {
        let (p, t) = grid(8);
        for (bits, component) in [(14, 16), (12, 16), (16, 16), (8, 8)] {
            let q = quantize(&as_primitive(&p, &t), bits, component);
            let place = same_surface(&p, &t, &q, 0)
                .unwrap_or_else(|e| panic!("{bits} bits in {component}: {e}"));
            // The placement maps the quantized corner of vertex 0 back near POSN's.
            let back = place.apply(q.positions[0]);
            let posn = [p[0] as f64, p[1] as f64, p[2] as f64];
            assert!(
                distance(back, posn) <= place.tolerance,
                "{back:?} vs {posn:?}"
            );
            assert!(!place.is_identity());
        }
    }

    #[test]
    fn a_moved_vertex_a_removed_triangle_and_a_flipped_one_are_caught() {
        let (p, t) = grid(8);
        let prim = weld(&as_primitive(&p, &t));
        let mut moved = prim.clone();
        // 1% of the box diagonal (2.8), five times τ = D/512.
        moved.positions[10][2] += 0.028;
        assert!(matches!(
            same_surface(&p, &t, &moved, 0),
            Err(Mismatch::Unpaired { .. })
        ));
        let mut removed = prim.clone();
        removed.triangles.pop();
        assert_eq!(
            same_surface(&p, &t, &removed, 0),
            Err(Mismatch::TriangleCount {
                primitive: 127,
                range: 128
            })
        );
        let mut flipped = prim.clone();
        flipped.triangles[5].swap(1, 2);
        assert_eq!(
            same_surface(&p, &t, &flipped, 3),
            Err(Mismatch::Unpaired {
                triangle: 8,
                tolerance: same_surface(&p, &t, &prim, 0).unwrap().tolerance
            })
        );
        // A re-triangulated quad: the same corners, the other diagonal.
        let mut turned = prim.clone();
        let [a, b, c] = turned.triangles[0];
        let d = turned.triangles[1][2];
        turned.triangles[0] = [a, b, d];
        turned.triangles[1] = [b, c, d];
        assert!(matches!(
            same_surface(&p, &t, &turned, 0),
            Err(Mismatch::Unpaired { .. })
        ));
    }

    #[test]
    fn a_mirrored_mesh_does_not_pair() {
        let (p, t) = grid(5);
        let mut mirrored = as_primitive(&p, &t);
        for q in &mut mirrored.positions {
            q[0] = -q[0];
        }
        assert!(same_surface(&p, &t, &mirrored, 0).is_err());
    }

    #[test]
    fn non_finite_and_out_of_range_inputs_are_mismatches_not_panics() {
        let (p, t) = grid(2);
        let mut nan = as_primitive(&p, &t);
        nan.positions[0][0] = f64::NAN;
        assert_eq!(same_surface(&p, &t, &nan, 0), Err(Mismatch::Unreadable));
        let mut far = as_primitive(&p, &t);
        far.triangles[0][0] = 999;
        assert_eq!(same_surface(&p, &t, &far, 0), Err(Mismatch::Unreadable));
        let bad = [0u32, 1, 99];
        let one = PrimitiveMesh {
            positions: vec![[0.0; 3]; 3],
            triangles: vec![[0, 1, 2]],
            grid: 0.0,
        };
        assert_eq!(same_surface(&p, &bad, &one, 0), Err(Mismatch::Unreadable));
        // Every triangle at one point: pairs, and no division by zero.
        let point = PrimitiveMesh {
            positions: vec![[0.0; 3]; 3],
            triangles: vec![[0, 1, 2]; 3],
            grid: 0.0,
        };
        let zeros = [0f32; 9];
        let place = same_surface(&zeros, &[0, 1, 2, 0, 1, 2, 0, 1, 2], &point, 0).unwrap();
        assert!(place.tolerance > 0.0 && place.is_identity());
    }

    #[test]
    fn placements_agree_within_tolerance_only() {
        let (p, t) = grid(4);
        let prim = as_primitive(&p, &t);
        let a = same_surface(&p, &t, &prim, 0).unwrap();
        let mut b = a;
        b.offset[1] += a.tolerance / 2.0;
        assert!(a.agrees_with(&b));
        b.offset[1] += 2.0 * a.tolerance;
        assert!(!a.agrees_with(&b));
        let m = a.inverse_columns();
        assert_eq!((m[0], m[5], m[10], m[15], m[12]), (1.0, 1.0, 1.0, 1.0, 0.0));
    }

    proptest! {
        #![proptest_config(ProptestConfig::with_cases(48))]

        /// Reordering triangles and vertices, rotating corners, welding and quantizing at the
        /// depths optimisers use never breaks the pairing.
        #[test]
        fn optimiser_rewrites_pair(
            n in 1usize..7,
            seed in any::<u64>(),
            welded in any::<bool>(),
            quantized in 0usize..4,
        ) {
            let (p, t) = grid(n);
            let mut prim = as_primitive(&p, &t);
            if welded {
                prim = weld(&prim);
            }
            let mut rng = seed | 1;
            let mut next = |m: usize| {
                rng ^= rng << 13; rng ^= rng >> 7; rng ^= rng << 17;
                (rng % m as u64) as usize
            };
            // Shuffle the triangles, rotate each one's corners, renumber the vertices.
            for i in (1..prim.triangles.len()).rev() {
                prim.triangles.swap(i, next(i + 1));
            }
            for tri in &mut prim.triangles {
                tri.rotate_left(next(3));
            }
            let mut order: Vec<u32> = (0..prim.positions.len() as u32).collect();
            for i in (1..order.len()).rev() {
                order.swap(i, next(i + 1));
            }
            let mut positions = vec![[0.0; 3]; prim.positions.len()];
            for (old, &new) in order.iter().enumerate() {
                positions[new as usize] = prim.positions[old];
            }
            prim.positions = positions;
            for tri in &mut prim.triangles {
                *tri = tri.map(|v| order[v as usize]);
            }
            let prim = match quantized {
                1 => quantize(&prim, 14, 16),
                2 => quantize(&prim, 12, 16),
                3 => quantize(&prim, 8, 8),
                _ => prim,
            };
            prop_assert!(same_surface(&p, &t, &prim, 0).is_ok());
        }

        /// Moving any one vertex by more than 4τ, or dropping any one triangle, is caught.
        #[test]
        fn edits_are_caught(n in 2usize..7, which in any::<usize>(), axis in 0usize..3, up in any::<bool>()) {
            let (p, t) = grid(n);
            let prim = weld(&as_primitive(&p, &t));
            let tolerance = same_surface(&p, &t, &prim, 0).unwrap().tolerance;
            let mut moved = prim.clone();
            let v = which % moved.positions.len();
            moved.positions[v][axis] += if up { 4.0 } else { -4.0 } * tolerance;
            // A move along the surface of a flat box face can leave the box, changing M; any
            // change is caught either way.
            prop_assert!(same_surface(&p, &t, &moved, 0).is_err());
            let mut removed = prim.clone();
            removed.triangles.remove(which % removed.triangles.len());
            prop_assert!(same_surface(&p, &t, &removed, 0).is_err());
        }
    }
}
