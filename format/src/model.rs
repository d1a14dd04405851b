//! The in-memory model of a `.hce` container.
//!
//! These types are the contract between the crates: the baker (`hce-bake`) fills them, the writer
//! serialises them byte for byte as SPEC.md describes, the reader and validator rebuild them from
//! bytes, and the runtime (`hce-runtime`) subdivides and colours from them, on the CPU and on the
//! GPU. Every bulk array is a flat `Vec` of plain little-endian values so that it maps one-to-one
//! onto a section of the file and onto a GPU storage buffer.
//!
//! # Conventions shared by every crate
//!
//! * Triangles are counter-clockwise seen from outside: corners `(v0, v1, v2)`.
//! * The 1-to-4 split of a triangle `(v0, v1, v2)` with edge midpoints `m01`, `m12`, `m20` gives
//!   four children, numbered in this order (the order of the HCE tree and of Loop subdivision
//!   paths), each again counter-clockwise:
//!
//!   | index | child  | corners             |
//!   |-------|--------|---------------------|
//!   | 0     | Top    | `(v0, m01, m20)`    |
//!   | 1     | Left   | `(m01, v1, m12)`    |
//!   | 2     | Center | `(m12, m20, m01)`   |
//!   | 3     | Right  | `(m20, m12, v2)`    |
//!
//! * The path of a subtriangle at subdivision level `d` is the sequence of `d` child indices from
//!   the coarse triangle down; as a number it is `Σ child_k · 4^(d-1-k)` (first choice most
//!   significant), and the level-`d` subtriangles of coarse triangle `t` are numbered
//!   `t · 4^d + path`.

/// A whole container: metadata and the objects of one scene.
#[derive(Clone, Debug, Default, PartialEq)]
pub struct Container {
    pub metadata: Metadata,
    pub objects: Vec<Object>,
}

/// Who wrote the file and from what.
#[derive(Clone, Debug, Default, PartialEq)]
pub struct Metadata {
    /// Tool and version that wrote the file, e.g. `"hce 0.1.0"`.
    pub generator: String,
    /// Bake parameters as a JSON object text (documented in SPEC.md); empty when not baked.
    pub bake_parameters: String,
    /// Hash of the whole source scene's geometry (see [`geometry_hash`] for the per-object one).
    pub source_hash: u64,
}

/// How an object is refined at render time.
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq, Hash)]
pub enum ObjectKind {
    /// Loop-subdivided at render time; colours chosen per subtriangle by normal.
    #[default]
    Multiresolution,
    /// Drawn as its coarse triangles split linearly 1-to-4 down to its tree depth, never
    /// smoothed; exactly one colour per tree node.
    Flat,
}

/// One object of the scene: its control mesh and adjacency tables, normal sets, HCE trees and
/// colours. All indices are local to the object.
#[derive(Clone, Debug, Default, PartialEq)]
pub struct Object {
    pub name: String,
    pub kind: ObjectKind,
    /// Hash of the geometry the object was baked from (see [`geometry_hash`]), so that a loader
    /// can tell that a mesh was edited after baking.
    pub geometry_hash: u64,
    pub mesh: ControlMesh,
    /// One record per coarse triangle, in triangle order.
    pub triangles: Vec<TriangleRecord>,
    /// Unit normals, `[x, y, z]`; triangle `t` owns
    /// `normals[t.normal_start .. t.normal_start + t.normal_count]`, its geometric normal first.
    pub normals: Vec<[f32; 3]>,
    /// The HCE bitstream of all triangles, bits packed least significant bit first into
    /// little-endian 32-bit words: bit `i` is `(bits[i / 32] >> (i % 32)) & 1`.
    pub bits: Vec<u32>,
    /// Total number of meaningful bits in `bits` (the tail of the last word is zero).
    pub bit_len: u64,
    /// Colours in RGB9E5 (see [`rgb9e5`]): triangle `t`'s tree node `k` (breadth-first) and
    /// normal `j` is `colours[t.colour_start + k * t.normal_count + j]`.
    pub colours: Vec<u32>,
    /// Colours at the corners of the nodes (SPEC.md A.10), in RGB9E5: colour `i` of
    /// [`Object::colours`] has three, at its node's corners 0, 1, 2:
    /// `corner_colours[3 * i + c]`. Empty when the object has none (a version 1.0 file).
    pub corner_colours: Vec<u32>,
}

/// Per coarse triangle: where its tree, colours and normals start. 16 bytes, GPU-uploadable.
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq, Hash)]
#[repr(C)]
pub struct TriangleRecord {
    /// Bit index of the triangle's start bit in [`Object::bits`].
    pub bits_start: u32,
    /// Index of the colour of node 0, normal 0 in [`Object::colours`].
    pub colour_start: u32,
    /// Index of the triangle's first (geometric) normal in [`Object::normals`].
    pub normal_start: u32,
    /// Number of normals (and so colours per node): 1 + m, at least 1.
    pub normal_count: u32,
}

/// The welded control mesh and the adjacency tables the Loop subdivision kernels read.
///
/// Built by `hce-runtime`'s topology module from any manifold (or split-into-manifold) triangle
/// mesh; serialised as-is. Invariants (checked by the validator):
///
/// * `positions.len() == 3 * V`; `triangles.len() == 3 * F`, every index `< V`; no degenerate
///   triangle (repeated index).
/// * `ring_offsets.len() == V + 1`, non-decreasing, `ring_offsets[0] == 0`,
///   `ring_offsets[V] == ring.len() == spoke_flags.len()`. Vertex `v`'s ring is
///   `ring[ring_offsets[v] .. ring_offsets[v + 1]]`: its neighbours (spokes) in counter-clockwise
///   order. For an interior vertex the faces are between consecutive spokes, the last and first
///   included. For a boundary vertex the first and last spokes are its boundary edges and there
///   is no face between the last spoke and the first. Valence = ring length (every vertex is
///   used by at least one triangle, so valence >= 2).
/// * `vertex_flags[v]`: see the `VERTEX_*` constants.
/// * `spoke_flags[s]`: see the `SPOKE_*` constants; bit 0 marks the spoke's edge infinitely
///   sharp (boundary edges always are).
/// * `corner_spokes[3 * t + c]`: the position `k` in corner `c`'s ring (0-based, relative to
///   `ring_offsets[v_c]`) whose spoke is `v_{c+1}`; the spoke after it, `k + 1`, is `v_{c+2}`
///   (indices of corners mod 3).
/// * `neighbours[3 * t + e]`: the triangle across edge `e` = `(v_e, v_{e+1})`, or
///   [`NO_NEIGHBOUR`] on a boundary.
/// * `edges[3 * t + e]`: the id of edge `e` of triangle `t`. Ids are dense, `0 .. E`, numbered in
///   order of first appearance when scanning `(t, e)` in increasing order; an interior edge's id
///   appears exactly twice (in `t` and in `neighbours[3 * t + e]`), a boundary edge's once. The
///   triangle where an edge first appears owns it: refined vertices on the edge are numbered
///   and written from that triangle's side, from its `v_e` towards its `v_{e+1}`.
#[derive(Clone, Debug, Default, PartialEq)]
pub struct ControlMesh {
    pub positions: Vec<f32>,
    pub triangles: Vec<u32>,
    pub ring_offsets: Vec<u32>,
    pub ring: Vec<u32>,
    pub vertex_flags: Vec<u32>,
    pub spoke_flags: Vec<u32>,
    pub corner_spokes: Vec<u32>,
    pub neighbours: Vec<u32>,
    pub edges: Vec<u32>,
}

/// `neighbours` entry for a boundary edge.
pub const NO_NEIGHBOUR: u32 = u32::MAX;

/// `vertex_flags` bit: the vertex lies on a boundary (its ring is open).
pub const VERTEX_BOUNDARY: u32 = 1;
/// `vertex_flags` bits 1..=2: the vertex rule, one of the `RULE_*` values.
pub const VERTEX_RULE_SHIFT: u32 = 1;
pub const VERTEX_RULE_MASK: u32 = 0b11 << VERTEX_RULE_SHIFT;
/// Smooth (Loop's interior weights): fewer than two sharp incident edges.
pub const RULE_SMOOTH: u32 = 0;
/// Crease: exactly two sharp incident edges (boundary vertices included): 3/4, 1/8, 1/8.
pub const RULE_CREASE: u32 = 1;
/// Corner: three or more sharp incident edges, or a boundary vertex with a single incident
/// triangle (OpenSubdiv's VTX_BOUNDARY_EDGE_AND_CORNER): the vertex does not move.
pub const RULE_CORNER: u32 = 2;

/// `spoke_flags` bit: the spoke's edge is infinitely sharp (a boundary or a tagged crease).
pub const SPOKE_SHARP: u32 = 1;
/// `spoke_flags` bit: the spoke's edge is a boundary edge (also has [`SPOKE_SHARP`]).
pub const SPOKE_BOUNDARY: u32 = 2;

impl ControlMesh {
    pub fn vertex_count(&self) -> usize {
        self.positions.len() / 3
    }

    pub fn triangle_count(&self) -> usize {
        self.triangles.len() / 3
    }

    pub fn position(&self, v: u32) -> [f32; 3] {
        let i = v as usize * 3;
        [
            self.positions[i],
            self.positions[i + 1],
            self.positions[i + 2],
        ]
    }

    pub fn triangle(&self, t: usize) -> [u32; 3] {
        [
            self.triangles[3 * t],
            self.triangles[3 * t + 1],
            self.triangles[3 * t + 2],
        ]
    }

    pub fn ring_of(&self, v: u32) -> &[u32] {
        let v = v as usize;
        &self.ring[self.ring_offsets[v] as usize..self.ring_offsets[v + 1] as usize]
    }

    pub fn rule(&self, v: u32) -> u32 {
        (self.vertex_flags[v as usize] & VERTEX_RULE_MASK) >> VERTEX_RULE_SHIFT
    }
}

/// FNV-1a, 64-bit, over the little-endian bytes of `f32` positions taken three per triangle
/// corner in triangle order: the object's geometry hash. Any loader can recompute it from the
/// glTF primitive it references (positions read through its indices).
pub fn geometry_hash(corner_positions: impl IntoIterator<Item = [f32; 3]>) -> u64 {
    let mut h: u64 = 0xcbf2_9ce4_8422_2325;
    for p in corner_positions {
        for c in p {
            for b in c.to_le_bytes() {
                h ^= u64::from(b);
                h = h.wrapping_mul(0x0000_0100_0000_01b3);
            }
        }
    }
    h
}

/// The shared-exponent colour encoding of the colour section (as in
/// `GL_EXT_texture_shared_exponent` / `VK_FORMAT_E5B9G9R9_UFLOAT_PACK32`): three 9-bit mantissas
/// and a 5-bit exponent with bias 15. Non-negative and finite by construction.
pub mod rgb9e5 {
    const MANTISSA_BITS: i32 = 9;
    const EXP_BIAS: i32 = 15;
    const MAX_EXP: i32 = 31;
    /// The largest encodable channel value, 65408.
    pub const MAX: f32 = ((1 << MANTISSA_BITS) - 1) as f32 / (1 << MANTISSA_BITS) as f32
        * (1u32 << (MAX_EXP - EXP_BIAS)) as f32;

    /// Encodes a linear RGB colour. Negative and NaN channels become 0, channels above
    /// [`MAX`] are clamped. Rounds to nearest.
    pub fn encode(rgb: [f32; 3]) -> u32 {
        let c = rgb.map(|x| {
            if x.is_nan() || x <= 0.0 {
                0.0
            } else {
                x.min(MAX)
            }
        });
        let max_c = c[0].max(c[1]).max(c[2]);
        if max_c == 0.0 {
            return 0;
        }
        // Exponent such that max_c < 2^(exp - bias) (as the Vulkan specification computes it).
        let mut exp_shared = (max_c.log2().floor() as i32).max(-EXP_BIAS - 1) + 1 + EXP_BIAS;
        let mut denom = 2f64.powi(exp_shared - EXP_BIAS - MANTISSA_BITS);
        let max_m = (f64::from(max_c) / denom + 0.5).floor() as i32;
        if max_m == 1 << MANTISSA_BITS {
            denom *= 2.0;
            exp_shared += 1;
        }
        let exp_shared = exp_shared.clamp(0, MAX_EXP);
        let m = c.map(|x| ((f64::from(x) / denom + 0.5).floor() as u32).min(511));
        m[0] | (m[1] << 9) | (m[2] << 18) | ((exp_shared as u32) << 27)
    }

    /// Decodes to linear RGB.
    pub fn decode(v: u32) -> [f32; 3] {
        let exp = (v >> 27) as i32 - EXP_BIAS - MANTISSA_BITS;
        let scale = 2f32.powi(exp);
        [
            (v & 0x1ff) as f32 * scale,
            ((v >> 9) & 0x1ff) as f32 * scale,
            ((v >> 18) & 0x1ff) as f32 * scale,
        ]
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn rgb9e5_round_trips_within_half_a_mantissa_step() {
        for &c in &[
            [1.0, 0.5, 0.25],
            [0.001, 0.002, 0.0],
            [100.0, 3.0, 0.0],
            [65000.0, 1.0, 2.0],
        ] {
            let d = rgb9e5::decode(rgb9e5::encode(c));
            let max = c.iter().cloned().fold(0.0f32, f32::max);
            for k in 0..3 {
                // A 9-bit mantissa on the shared (largest) exponent: error <= max / 512.
                assert!((d[k] - c[k]).abs() <= max / 512.0 + 1e-12, "{c:?} -> {d:?}");
            }
        }
        assert_eq!(
            rgb9e5::decode(rgb9e5::encode([1.0, 1.0, 1.0])),
            [1.0, 1.0, 1.0]
        );
        assert_eq!(rgb9e5::encode([-1.0, f32::NAN, 0.0]), 0);
        assert_eq!(
            rgb9e5::decode(rgb9e5::encode([1e9, 0.0, 0.0]))[0],
            rgb9e5::MAX
        );
    }

    #[test]
    fn geometry_hash_changes_with_any_coordinate() {
        let a = geometry_hash([[0.0, 0.0, 0.0], [1.0, 0.0, 0.0], [0.0, 1.0, 0.0]]);
        let b = geometry_hash([[0.0, 0.0, 0.0], [1.0, 0.0, 0.0], [0.0, 1.0, 1e-7]]);
        assert_ne!(a, b);
        assert_eq!(geometry_hash(std::iter::empty()), 0xcbf2_9ce4_8422_2325);
    }
}
