//! Position welding: glTF primitives split vertices at every attribute seam and OBJ files may
//! repeat positions, while topology must be built on shared vertices. Welding reconnects them,
//! deterministically (the result depends only on the input order).

use std::collections::HashMap;

/// The result of welding: unique positions and the map from input vertices to them.
#[derive(Clone, Debug, Default, PartialEq)]
pub struct Weld {
    /// Welded positions, in order of first occurrence in the input vertex list.
    pub positions: Vec<[f32; 3]>,
    /// `input_to_welded[i]`: the welded vertex of input vertex `i`.
    pub input_to_welded: Vec<u32>,
}

impl Weld {
    /// `triangles` (indices of input vertices, each in range) on the welded vertices.
    pub fn triangles(&self, triangles: &[[u32; 3]]) -> Vec<[u32; 3]> {
        triangles
            .iter()
            .map(|t| t.map(|i| self.input_to_welded[i as usize]))
            .collect()
    }
}

/// Welds input vertices whose positions are equal (`tolerance == 0`: bitwise equal, with `-0.0`
/// taken as `0.0`), or within `tolerance` (Euclidean) of the first vertex of a cluster. Each
/// input vertex joins the earliest welded vertex within reach, so the result depends only on the
/// input order.
pub fn weld(positions: &[[f32; 3]], tolerance: f32) -> Weld {
    let mut out = Weld {
        positions: Vec::new(),
        input_to_welded: Vec::with_capacity(positions.len()),
    };
    if tolerance <= 0.0 {
        let mut map: HashMap<[u32; 3], u32> = HashMap::with_capacity(positions.len());
        for p in positions {
            // Adding 0.0 turns -0.0 into +0.0 and leaves every other value unchanged.
            let key = p.map(|c| (c + 0.0).to_bits());
            let id = *map.entry(key).or_insert_with(|| {
                out.positions.push(*p);
                out.positions.len() as u32 - 1
            });
            out.input_to_welded.push(id);
        }
        return out;
    }
    // Uniform grid of cell size `tolerance`: a vertex within reach lies in one of 27 cells.
    let cell = |p: &[f32; 3]| p.map(|c| (c / tolerance).floor() as i64);
    let mut grid: HashMap<[i64; 3], Vec<u32>> = HashMap::new();
    let tol2 = tolerance * tolerance;
    for p in positions {
        let c = cell(p);
        let mut found: Option<u32> = None;
        for dx in -1..=1 {
            for dy in -1..=1 {
                for dz in -1..=1 {
                    if let Some(list) = grid.get(&[c[0] + dx, c[1] + dy, c[2] + dz]) {
                        for &w in list {
                            let q = out.positions[w as usize];
                            let d2 = (0..3).map(|k| (q[k] - p[k]) * (q[k] - p[k])).sum::<f32>();
                            if d2 <= tol2 && found.is_none_or(|f| w < f) {
                                found = Some(w);
                            }
                        }
                    }
                }
            }
        }
        let id = found.unwrap_or_else(|| {
            out.positions.push(*p);
            let id = out.positions.len() as u32 - 1;
            grid.entry(c).or_default().push(id);
            id
        });
        out.input_to_welded.push(id);
    }
    out
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn weld_merges_equal_positions_and_signed_zero() {
        let w = weld(
            &[
                [0.0, 0.0, 0.0],
                [1.0, 0.0, 0.0],
                [-0.0, 0.0, 0.0],
                [1.0, 0.0, 0.0],
            ],
            0.0,
        );
        assert_eq!(w.input_to_welded, vec![0, 1, 0, 1]);
        assert_eq!(w.positions.len(), 2);
    }

    #[test]
    fn weld_with_tolerance_joins_near_points_only() {
        let w = weld(
            &[[0.0, 0.0, 0.0], [0.0009, 0.0, 0.0], [0.01, 0.0, 0.0]],
            0.001,
        );
        assert_eq!(w.input_to_welded, vec![0, 0, 1]);
    }
}
