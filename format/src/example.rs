//! The example container of SPEC.md Appendix D: one triangle, one normal, the 9-node tree of
//! SPEC.md B.2. Tests (ours and other crates') use it as a small valid file.

use crate::model::*;
use crate::tree::encode_tree;

/// The SPEC.md Appendix D container.
pub fn single_triangle() -> Container {
    let corners = [[0.0, 0.0, 0.0], [1.0, 0.0, 0.0], [0.0, 1.0, 0.0]];
    let hash = geometry_hash(corners);
    let flags = [1, 0, 0, 1, 0, 0, 0, 0, 0].map(|b| b == 1);
    // The flags are a complete tree of depth 2, so encoding cannot fail.
    let (bits, bit_len) = encode_tree(&flags).unwrap_or_default();
    // Node k gets the colour (k / 8, 1/2, 1/4): exact in RGB9E5.
    let colours = (0..9u8)
        .map(|k| rgb9e5::encode([f32::from(k) / 8.0, 0.5, 0.25]))
        .collect();
    let boundary_corner = VERTEX_BOUNDARY | (RULE_CORNER << VERTEX_RULE_SHIFT);
    Container {
        metadata: Metadata {
            generator: "hce".into(),
            bake_parameters: String::new(),
            source_hash: hash,
        },
        objects: vec![Object {
            name: "tri".into(),
            kind: ObjectKind::Multiresolution,
            geometry_hash: hash,
            mesh: ControlMesh {
                positions: corners.iter().flatten().copied().collect(),
                triangles: vec![0, 1, 2],
                ring_offsets: vec![0, 2, 4, 6],
                ring: vec![1, 2, 2, 0, 0, 1],
                vertex_flags: vec![boundary_corner; 3],
                spoke_flags: vec![SPOKE_SHARP | SPOKE_BOUNDARY; 6],
                corner_spokes: vec![0, 0, 0],
                neighbours: vec![NO_NEIGHBOUR; 3],
                edges: vec![0, 1, 2],
            },
            triangles: vec![TriangleRecord {
                bits_start: 0,
                colour_start: 0,
                normal_start: 0,
                normal_count: 1,
            }],
            normals: vec![[0.0, 0.0, 1.0]],
            bits,
            bit_len,
            colours,
        }],
    }
}
