//! The tables the GPU Loop kernel reads beside the control mesh's own: one flags word per
//! triangle (which side owns its edge and its corner's vertex, which sides have a neighbour and
//! a sharp spoke), the two sharp spokes of every crease vertex, and Loop's per-valence weights
//! rounded to `f32` as the CPU subdivision ([`crate::subdivide`]) rounds them. Built here, with
//! no GPU, so that the native runtime and the browser (through `hce-wasm`) upload the same words.

use hce_format::{ControlMesh, NO_NEIGHBOUR, SPOKE_SHARP};

use crate::subdivide::{prepare, SubdivError};

/// Bits of the per-triangle flags word (`OWNS_EDGE` … in `hce_constants.wgsl`), shifted by the
/// side or corner `e` they describe.
pub const OWNS_EDGE: u32 = 1;
pub const OWNS_VERTEX: u32 = 8;
pub const INTERIOR: u32 = 64;
pub const SHARP: u32 = 512;

/// What the Loop kernel reads of an object beyond its control mesh.
#[derive(Clone, Debug, Default, PartialEq, Eq)]
pub struct LoopKernelTables {
    /// Per triangle, the [`OWNS_EDGE`] … [`SHARP`] bits of its three sides.
    pub tri_flags: Vec<u32>,
    /// Per vertex, the ring positions of its two sharp spokes (0, 0 unless a crease vertex).
    pub crease: Vec<u32>,
    /// Per valence `k` from 0 to `max(max_valence, 6)`: the `f32` bits of Loop's correction
    /// factor and of `0.75 / k` (0 below valence 2). A WGSL division need not be correctly
    /// rounded, so the kernel reads them instead of dividing.
    pub weights: Vec<u32>,
    /// The largest ring.
    pub max_valence: u32,
    /// The most ring points of one triangle's three corners, a multiple of 8, at least 8.
    pub ring_points: u32,
}

impl LoopKernelTables {
    /// Checks every table Loop subdivision reads ([`prepare`]) and derives the kernel's.
    pub fn new(mesh: &ControlMesh) -> Result<Self, SubdivError> {
        let prep = prepare(mesh)?;
        let nv = mesh.vertex_count();
        let nf = mesh.triangle_count();
        let valence = |v: u32| mesh.ring_offsets[v as usize + 1] - mesh.ring_offsets[v as usize];
        let max_valence = (0..nv as u32).map(valence).max().unwrap_or(0);
        let ring_points = (0..nf)
            .map(|t| mesh.triangle(t).iter().map(|&v| valence(v)).sum::<u32>())
            .max()
            .unwrap_or(0)
            .next_multiple_of(8)
            .max(8);
        let mut tri_flags = vec![0u32; nf];
        for (t, flags) in tri_flags.iter_mut().enumerate() {
            let tri = mesh.triangle(t);
            // `e` is both a corner and an edge index (edge e starts at corner e).
            #[allow(clippy::needless_range_loop)]
            for e in 0..3 {
                let s = 3 * t + e;
                if prep.owns_edge[s] {
                    *flags |= OWNS_EDGE << e;
                }
                if prep.vertex_owner[tri[e] as usize] == s as u32 {
                    *flags |= OWNS_VERTEX << e;
                }
                if mesh.neighbours[s] != NO_NEIGHBOUR {
                    *flags |= INTERIOR << e;
                }
                let spoke = mesh.ring_offsets[tri[e] as usize] + mesh.corner_spokes[s];
                if mesh.spoke_flags[spoke as usize] & SPOKE_SHARP != 0 {
                    *flags |= SHARP << e;
                }
            }
        }
        let crease = prep.crease_spokes.iter().flatten().copied().collect();
        let weights = (0..=max_valence.max(6) as usize)
            .flat_map(|k| {
                let w = if k < 2 { 0.0 } else { 0.75 / k as f32 };
                [
                    prep.cf.get(k).copied().unwrap_or(0.0).to_bits(),
                    w.to_bits(),
                ]
            })
            .collect();
        Ok(Self {
            tri_flags,
            crease,
            weights,
            max_valence,
            ring_points,
        })
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::topology::{build_control_mesh, TopologyConfig};

    /// A square pyramid without its base: four boundary vertices around an apex of valence 4.
    fn open_pyramid() -> ControlMesh {
        let positions = [
            [0.0, 0.0, 1.0],
            [1.0, 0.0, 0.0],
            [0.0, 1.0, 0.0],
            [-1.0, 0.0, 0.0],
            [0.0, -1.0, 0.0],
        ];
        let triangles = [[0, 1, 2], [0, 2, 3], [0, 3, 4], [0, 4, 1]];
        build_control_mesh(&positions, &triangles, None, &TopologyConfig::default())
            .expect("a manifold mesh")
            .mesh
    }

    #[test]
    fn flags_mark_owners_neighbours_and_boundary_spokes() {
        let mesh = open_pyramid();
        let t = LoopKernelTables::new(&mesh).unwrap();
        assert_eq!(t.tri_flags.len(), 4);
        // Every vertex and every edge has exactly one owner side.
        let owned = |bit: u32| -> u32 {
            t.tri_flags
                .iter()
                .map(|f| (0..3).filter(|e| f & (bit << e) != 0).count() as u32)
                .sum()
        };
        assert_eq!(owned(OWNS_VERTEX), 5);
        assert_eq!(owned(OWNS_EDGE), 8);
        // Four interior edges, each seen from both sides; the four base edges are boundaries,
        // and a boundary edge's spoke is sharp.
        assert_eq!(owned(INTERIOR), 8);
        for f in &t.tri_flags {
            for e in 0..3 {
                assert_eq!(
                    f & (INTERIOR << e) == 0,
                    f & (SHARP << e) != 0,
                    "flags {f:#x}"
                );
            }
        }
        assert_eq!(t.max_valence, 4);
        // Apex 4 plus two boundary vertices of valence 3: 10, rounded up to 16.
        assert_eq!(t.ring_points, 16);
        assert_eq!(t.crease.len(), 2 * 5);
        assert_eq!(t.weights.len(), 2 * 7);
        assert_eq!(f32::from_bits(t.weights[2 * 4 + 1]), 0.75 / 4.0);
        assert_eq!(t.weights[..4], [0; 4]);
    }

    #[test]
    fn a_bad_ring_is_an_error() {
        let mut mesh = open_pyramid();
        mesh.ring_offsets[1] = mesh.ring_offsets[0];
        assert!(LoopKernelTables::new(&mesh).is_err());
    }
}
