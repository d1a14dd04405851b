//! HCE (Hierarchical Color Encoding, Concheiro et al. 2012): writes each coarse triangle's
//! element tree into the bitstream, colour and normal arrays of an `hce_format::Object`.
//!
//! Per triangle the stream holds a start bit (root subdivided?) and then, for every subdivided
//! node in breadth-first order, four bits saying whether each child (Top, Left, Center, Right)
//! is subdivided. That is exactly the sequence of every node's "subdivided" flag in
//! breadth-first order, so a tree of `N` nodes takes `N` bits. Bits are packed least
//! significant first into 32-bit words; colours are node-major then normal, in RGB9E5.

use hce_format::{rgb9e5, Object, TriangleRecord};

use crate::hierarchical::TriangleSolution;
use crate::BakeError;

/// Appends the trees, colours and normals of `triangles` to `object` (whose mesh and other
/// fields the caller fills), one [`TriangleRecord`] per triangle.
pub fn encode_object(object: &mut Object, triangles: &[TriangleSolution]) -> Result<(), BakeError> {
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
        check_tree_shape(&tri.subdivided).map_err(err)?;
        let to_u32 = |v: usize, what: &str| {
            u32::try_from(v).map_err(|_| err(format!("{what} exceeds the 32-bit index range")))
        };
        let record = TriangleRecord {
            bits_start: to_u32(object.bit_len as usize, "bit offset")?,
            colour_start: to_u32(object.colours.len(), "colour offset")?,
            normal_start: to_u32(object.normals.len(), "normal offset")?,
            normal_count: to_u32(nn, "normal count")?,
        };
        for &s in &tri.subdivided {
            push_bit(&mut object.bits, &mut object.bit_len, s);
        }
        object
            .colours
            .extend(tri.colours.iter().map(|&c| rgb9e5::encode(c)));
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

fn push_bit(bits: &mut Vec<u32>, len: &mut u64, bit: bool) {
    let i = *len as usize;
    if i / 32 >= bits.len() {
        bits.push(0);
    }
    if bit {
        bits[i / 32] |= 1 << (i % 32);
    }
    *len += 1;
}

/// A breadth-first flag sequence is a complete 4-ary tree iff after the root every split
/// node contributes exactly four further nodes.
fn check_tree_shape(subdivided: &[bool]) -> Result<(), String> {
    let splits = subdivided.iter().filter(|&&s| s).count();
    if subdivided.len() != 1 + 4 * splits {
        return Err(format!(
            "{} nodes with {splits} subdivided ones is not a complete 1-to-4 tree",
            subdivided.len()
        ));
    }
    Ok(())
}

/// A decoded tree (for tests and tools): subdivided flags in breadth-first order.
pub fn decode_tree(bits: &[u32], bit_len: u64, start: u64) -> Result<Vec<bool>, String> {
    let read = |i: u64| -> Result<bool, String> {
        let word = usize::try_from(i / 32).ok().and_then(|w| bits.get(w));
        match word {
            Some(w) if i < bit_len => Ok((w >> (i % 32)) & 1 == 1),
            _ => Err(format!("tree runs past the end of the bitstream (bit {i})")),
        }
    };
    let mut flags = vec![read(start)?];
    // Nodes still to be read: four per split node seen so far.
    let mut pending: u64 = if flags[0] { 4 } else { 0 };
    let mut i = start + 1;
    while pending > 0 {
        let f = read(i)?;
        flags.push(f);
        i += 1;
        pending -= 1;
        if f {
            pending += 4;
        }
    }
    Ok(flags)
}

#[cfg(test)]
mod tests {
    use super::*;

    fn tri(subdivided: Vec<bool>, nn: usize) -> TriangleSolution {
        let n = subdivided.len();
        TriangleSolution {
            normals: (0..nn).map(|j| [0.0, j as f32, 1.0]).collect(),
            nodes: Vec::new(),
            subdivided,
            colours: (0..n * nn).map(|i| [i as f32, 0.5, 0.25]).collect(),
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
            let flags = decode_tree(&o.bits, o.bit_len, u64::from(rec.bits_start)).unwrap();
            assert_eq!(flags, many[t].subdivided);
            let last = many[t].colours.len() - 1;
            let c = rgb9e5::decode(o.colours[rec.colour_start as usize + last]);
            assert_eq!(c, [last as f32, 0.5, 0.25]);
        }
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
        assert!(decode_tree(&[0b1], 3, 0).is_err());
        // A bit length larger than the words hold is an error, not a panic.
        assert!(decode_tree(&[u32::MAX], 1000, 0).is_err());
    }
}
