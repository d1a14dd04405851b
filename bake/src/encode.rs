//! HCE (Hierarchical Color Encoding, Concheiro et al. 2012): writes each coarse triangle's
//! element tree into the bitstream, colour and normal arrays of an `hce_format::Object`.
//!
//! Per triangle the stream holds a start bit (root subdivided?) and then, for every subdivided
//! node in breadth-first order, four bits saying whether each child (Top, Left, Center, Right)
//! is subdivided. That is exactly the sequence of every node's "subdivided" flag in
//! breadth-first order, so a tree of `N` nodes takes `N` bits. Bits are packed least
//! significant first into 32-bit words; colours are node-major then normal, in RGB9E5.
//!
//! The bits are written by the format's tree codec ([`hce_format::BitWriter`]), which refuses a
//! tree the validator would reject (incomplete, or deeper than [`hce_format::MAX_TREE_DEPTH`]).

use hce_format::{rgb9e5, BitWriter, Object, TriangleRecord};

use crate::radiosity::TriangleSolution;
use crate::BakeError;

/// Appends the trees, colours and normals of `triangles` to `object` (whose mesh and other
/// fields the caller fills), one [`TriangleRecord`] per triangle.
pub fn encode_object(object: &mut Object, triangles: &[TriangleSolution]) -> Result<(), BakeError> {
    let mut bits = BitWriter::resume(std::mem::take(&mut object.bits), object.bit_len);
    let result = encode_triangles(object, &mut bits, triangles);
    (object.bits, object.bit_len) = bits.finish();
    result
}

/// [`encode_object`] with the object's bitstream held by `bits` meanwhile.
fn encode_triangles(
    object: &mut Object,
    bits: &mut BitWriter,
    triangles: &[TriangleSolution],
) -> Result<(), BakeError> {
    for (t, tri) in triangles.iter().enumerate() {
        let err = |reason: String| BakeError::Encode {
            object: object.name.clone(),
            triangle: t,
            reason,
        };
        let nn = tri.normals.len();
        let nodes = tri.subdivided.len();
        if nn == 0 {
            return Err(err(
                "no normals (the geometric normal must come first)".into()
            ));
        }
        if nodes == 0 || tri.colours.len() != nodes * nn {
            return Err(err(format!(
                "{} colours for {nodes} nodes and {nn} normals",
                tri.colours.len()
            )));
        }
        // Corner colours are all or nothing within an object (SPEC.md A.10).
        let corners = !tri.corner_colours.is_empty();
        let (before, had) = (
            !object.colours.is_empty(),
            !object.corner_colours.is_empty(),
        );
        if corners && tri.corner_colours.len() != 3 * tri.colours.len() || before && corners != had
        {
            return Err(err(format!(
                "{} corner colours for {} colours (none, or three each, in every triangle)",
                tri.corner_colours.len(),
                tri.colours.len()
            )));
        }
        let to_u32 = |v: usize, what: &str| {
            u32::try_from(v).map_err(|_| err(format!("{what} exceeds the 32-bit index range")))
        };
        let record = TriangleRecord {
            bits_start: u32::try_from(bits.bit_len())
                .map_err(|_| err("bit offset exceeds the 32-bit index range".into()))?,
            colour_start: to_u32(object.colours.len(), "colour offset")?,
            normal_start: to_u32(object.normals.len(), "normal offset")?,
            normal_count: to_u32(nn, "normal count")?,
        };
        bits.push_tree(&tri.subdivided)
            .map_err(|source| BakeError::Tree {
                object: object.name.clone(),
                triangle: t,
                source,
            })?;
        object
            .colours
            .extend(tri.colours.iter().map(|&c| rgb9e5::encode(c)));
        object
            .corner_colours
            .extend(tri.corner_colours.iter().map(|&c| rgb9e5::encode(c)));
        object.normals.extend_from_slice(&tri.normals);
        object.triangles.push(record);
    }
    Ok(())
}

/// Per-vertex fallback colours (glTF `COLOR_0`) for an object: the area-weighted average of
/// the root colours (normal 0) of the triangles around each vertex, welded by vertex index.
/// `positions` and `triangles` are the object's mesh; `solution` its baked triangles.
pub fn vertex_colours(
    positions: &[[f32; 3]],
    triangles: &[[u32; 3]],
    solution: &[TriangleSolution],
) -> Vec<[f32; 3]> {
    let mut sum = vec![[0.0f64; 4]; positions.len()];
    for (t, tri) in triangles.iter().enumerate() {
        let Some(sol) = solution.get(t) else { break };
        let p = tri.map(|v| glam::Vec3::from(positions[v as usize]));
        let area = f64::from((p[1] - p[0]).cross(p[2] - p[0]).length() * 0.5);
        let c = sol.colours.first().copied().unwrap_or([0.0; 3]);
        for &v in tri {
            let s = &mut sum[v as usize];
            for k in 0..3 {
                s[k] += area * f64::from(c[k]);
            }
            s[3] += area;
        }
    }
    sum.iter()
        .map(|s| {
            if s[3] > 0.0 {
                [0, 1, 2].map(|k| (s[k] / s[3]) as f32)
            } else {
                [0.0; 3]
            }
        })
        .collect()
}

#[cfg(test)]
mod tests {
    use super::*;
    use hce_format::Tree;

    fn flags(bits: &[u32], bit_len: u64, start: u64) -> Vec<bool> {
        let tree = Tree::new(bits, bit_len, start).unwrap();
        tree.nodes().map(|n| n.subdivided).collect()
    }

    fn tri(subdivided: Vec<bool>, nn: usize) -> TriangleSolution {
        let n = subdivided.len();
        TriangleSolution {
            normals: (0..nn).map(|j| [0.0, j as f32, 1.0]).collect(),
            nodes: Vec::new(),
            subdivided,
            colours: (0..n * nn).map(|i| [i as f32, 0.5, 0.25]).collect(),
            corner_colours: Vec::new(),
        }
    }

    #[test]
    fn trees_round_trip_through_the_bitstream() {
        // Root split; its Left child split: 1 + 4 + 4 = 9 nodes.
        let a = tri(
            vec![true, false, true, false, false, false, false, false, false],
            2,
        );
        let b = tri(vec![false], 1);
        let mut many = Vec::new();
        for _ in 0..5 {
            many.push(a.clone());
            many.push(b.clone());
        }
        let mut o = Object::default();
        encode_object(&mut o, &many).unwrap();
        assert_eq!(o.bit_len, 5 * 10);
        assert_eq!(o.bits.len(), 2);
        // Triangle 0: bits 1,0,1,0,0,0,0,0,0 LSB first = 0b101; triangle 1 at bit 9 is 0.
        assert_eq!(o.bits[0] & 0x3ff, 0b101);
        assert_eq!(o.triangles[1].bits_start, 9);
        assert_eq!(o.triangles[1].colour_start, 18);
        assert_eq!(o.triangles[2].normal_start, 3);
        for (t, rec) in o.triangles.iter().enumerate() {
            let got = flags(&o.bits, o.bit_len, u64::from(rec.bits_start));
            assert_eq!(got, many[t].subdivided);
            let last = many[t].colours.len() - 1;
            let c = rgb9e5::decode(o.colours[rec.colour_start as usize + last]);
            assert_eq!(c, [last as f32, 0.5, 0.25]);
        }
    }

    #[test]
    fn corner_colours_follow_their_colours_in_every_triangle_or_none() {
        let with = |mut t: TriangleSolution| {
            t.corner_colours = (0..3 * t.colours.len())
                .map(|x| [x as f32, 1.0, 2.0])
                .collect();
            t
        };
        let (a, b) = (
            with(tri(vec![true, false, false, false, false], 2)),
            with(tri(vec![false], 1)),
        );
        let mut o = Object::default();
        encode_object(&mut o, &[a.clone(), b.clone()]).unwrap();
        // Colour `i` has corner colours `3i`, `3i + 1`, `3i + 2` (SPEC.md A.10).
        assert_eq!(o.corner_colours.len(), 3 * o.colours.len());
        let start = o.triangles[1].colour_start as usize;
        assert_eq!(
            rgb9e5::decode(o.corner_colours[3 * start + 2]),
            [2.0, 1.0, 2.0]
        );
        // Some triangles with corner colours and some without, or too few, are refused.
        let mut o = Object::default();
        let err = encode_object(&mut o, &[a.clone(), tri(vec![false], 1)]).unwrap_err();
        assert!(err.to_string().contains("corner colours"), "{err}");
        let mut short = b;
        short.corner_colours.pop();
        let err = encode_object(&mut Object::default(), &[short]).unwrap_err();
        assert!(err.to_string().contains("corner colours"), "{err}");
    }

    #[test]
    fn vertex_colours_average_incident_triangles_by_area() {
        let pos = [
            [0.0, 0.0, 0.0],
            [1.0, 0.0, 0.0],
            [0.0, 1.0, 0.0],
            [3.0, 0.0, 0.0],
        ];
        // Triangle 1 has twice the area of triangle 0; they share vertices 1 and 2.
        let tris = [[0, 1, 2], [1, 3, 2]];
        let mut a = tri(vec![false], 1);
        a.colours = vec![[1.0, 0.0, 0.0]];
        let mut b = tri(vec![false], 1);
        b.colours = vec![[0.0, 1.0, 0.0]];
        let c = vertex_colours(&pos, &tris, &[a, b]);
        assert_eq!(c[0], [1.0, 0.0, 0.0]);
        assert_eq!(c[3], [0.0, 1.0, 0.0]);
        // Areas 0.5 and 1.0.
        let w = 0.5 / 1.5;
        assert!((c[1][0] - w).abs() < 1e-6 && (c[1][1] - (1.0 - w)).abs() < 1e-6);
    }

    #[test]
    fn malformed_trees_are_rejected_with_context() {
        let mut o = Object {
            name: "box".into(),
            ..Default::default()
        };
        let bad = tri(vec![true, false, false], 1);
        let e = encode_object(&mut o, &[bad]).unwrap_err().to_string();
        assert!(e.contains("box") && e.contains("triangle 0"), "{e}");
        assert!(o.bits.is_empty() && o.bit_len == 0 && o.triangles.is_empty());
        // A tree deeper than the format allows is refused before it reaches the file.
        let mut deep = vec![true];
        for d in 1..=hce_format::MAX_TREE_DEPTH + 1 {
            deep.extend([d <= hce_format::MAX_TREE_DEPTH, false, false, false]);
        }
        let e = encode_object(&mut o, &[tri(deep, 1)]).unwrap_err();
        assert!(
            matches!(
                e,
                BakeError::Tree {
                    source: hce_format::TreeError::TooDeep { .. },
                    ..
                }
            ),
            "{e}"
        );
    }
}
