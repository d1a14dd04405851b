//! The 1-to-4 lattice of a refined coarse triangle and its numbering, shared by flat refinement,
//! Loop subdivision, the colour reconstruction and (in WGSL, `hce_lattice.wgsl`) the GPU kernels.
//!
//! The split orders children Top `(v0, m01, m20)`, Left `(m01, v1, m12)`, Center
//! `(m12, m20, m01)`, Right `(m20, m12, v2)` (SPEC.md, Appendix F), so the level-`L` subtriangle
//! `t · 4^L + path` is the HCE tree node reached by following `path`.
//!
//! # Refined-mesh numbering
//! At level `L` with `n = 2^L`, a point of coarse triangle `(v0, v1, v2)` has lattice coordinates
//! `(a, b, c)`, `a + b + c = n`, position `(a p0 + b p1 + c p2) / n`. Output vertices are:
//! `[coarse vertices (V)] [edge points: E × (n − 1)] [interior points: F × (n − 1)(n − 2) / 2]`.
//! Edge `id`'s point `k` (`1 ≤ k < n`) is `V + id (n − 1) + k − 1`, counted from the owning
//! triangle's `v_e` towards its `v_{e+1}` ([`hce_format::ControlMesh::edges`]). Triangle `t`'s interior point
//! `(b, c)` is `V + E (n − 1) + t I + I − j (j + 1) / 2 + b − 1` with `I = (n − 1)(n − 2) / 2`
//! and `j = n − 1 − c` (rows of constant `c` in increasing `c`, each in increasing `b`: the
//! numbering of [`crate::subdivide`], so flat and Loop refinements number vertices alike).
//! Fine triangle `t · 4^L + path`.

/// Interior lattice points of one triangle at `n = 2^L` segments per edge: `(n − 1)(n − 2) / 2`.
pub fn interior_per_triangle(n: u64) -> u64 {
    if n < 2 {
        0
    } else {
        (n - 1) * (n - 2) / 2
    }
}

/// The lattice corners `(b, c)` of fine triangle `path` at level `level` (`n = 2^level`), found
/// by descending the 1-to-4 split: a triangle is `(C0, σ, s)` with corners `C0`, `C0 + σ s e_b`,
/// `C0 + σ s e_c`; the Center child flips `σ`.
pub fn fine_corners(level: u32, path: u32) -> [[i32; 2]; 3] {
    let mut c0 = [0i32, 0i32];
    let mut sigma = 1i32;
    let mut s = 1i32 << level;
    for k in 0..level {
        let h = s / 2;
        let child = (path >> (2 * (level - 1 - k))) & 3;
        match child {
            0 => {}
            1 => c0[0] += sigma * h,
            2 => {
                c0 = [c0[0] + sigma * h, c0[1] + sigma * h];
                sigma = -sigma;
            }
            _ => c0[1] += sigma * h,
        }
        s = h;
    }
    [c0, [c0[0] + sigma, c0[1]], [c0[0], c0[1] + sigma]]
}

/// The path of the fine triangle whose centroid, times 3, is `q` (lattice `(b, c)` units).
pub fn locate(level: u32, q: [i32; 2]) -> u32 {
    let mut c0 = [0i32, 0i32];
    let mut sigma = 1i32;
    let mut s = 1i32 << level;
    let mut path = 0u32;
    for _ in 0..level {
        let h = s / 2;
        let l1 = sigma * (q[0] - 3 * c0[0]);
        let l2 = sigma * (q[1] - 3 * c0[1]);
        let l0 = 3 * s - l1 - l2;
        let child = if l0 > 3 * h {
            0
        } else if l1 > 3 * h {
            c0[0] += sigma * h;
            1
        } else if l2 > 3 * h {
            c0[1] += sigma * h;
            3
        } else {
            c0 = [c0[0] + sigma * h, c0[1] + sigma * h];
            sigma = -sigma;
            2
        };
        path = path * 4 + child;
        s = h;
    }
    path
}

/// Paths of the fine triangles around lattice point `(b, c)` inside one coarse triangle, in the
/// fixed order the kernels sum them: up triangles anchored at `(b, c)`, `(b − 1, c)`,
/// `(b, c − 1)`, then down triangles anchored at `(b, c)`, `(b + 1, c)`, `(b, c + 1)`.
pub fn incident_paths(level: u32, b: i32, c: i32) -> impl Iterator<Item = u32> {
    let n = 1i32 << level;
    let ups = [(b, c), (b - 1, c), (b, c - 1)];
    let downs = [(b, c), (b + 1, c), (b, c + 1)];
    let up = ups
        .into_iter()
        .filter(move |&(x, y)| x >= 0 && y >= 0 && x + y < n)
        .map(move |(x, y)| locate(level, [3 * x + 1, 3 * y + 1]));
    let down = downs
        .into_iter()
        .filter(move |&(x, y)| x >= 1 && y >= 1 && x + y <= n)
        .map(move |(x, y)| locate(level, [3 * x - 1, 3 * y - 1]));
    up.chain(down)
}

/// The lattice point of edge `e` of a triangle at `k` steps from its `v_e`.
pub fn edge_point(n: i32, e: u32, k: i32) -> [i32; 2] {
    match e {
        0 => [k, 0],
        1 => [n - k, k],
        _ => [0, n - k],
    }
}

/// `(b, c)` of interior point `local` (inverse of the numbering in the module docs).
pub fn interior_coords(n: i32, local: u32) -> (i32, i32) {
    let ip = interior_per_triangle(n as u64) as u32;
    // Counted from the last point, rows have 1, 2, 3, ... points: the row of length j holds
    // r = ip − 1 − local when j (j − 1) / 2 <= r < j (j + 1) / 2. Start from the float root,
    // correct exactly.
    let r = ip - 1 - local;
    let mut j = ((1.0 + (1.0 + 8.0 * r as f64).sqrt()) / 2.0).floor() as u32;
    while j * (j - 1) / 2 > r {
        j -= 1;
    }
    while (j + 1) * j / 2 <= r {
        j += 1;
    }
    let b = (local - (ip - j * (j + 1) / 2)) as i32 + 1;
    (b, n - 1 - j as i32)
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn locate_inverts_fine_corners() {
        for level in 0..5 {
            for path in 0..(1u32 << (2 * level)) {
                let [p0, p1, p2] = fine_corners(level, path);
                let q = [p0[0] + p1[0] + p2[0], p0[1] + p1[1] + p2[1]];
                assert_eq!(locate(level, q), path, "level {level}");
            }
        }
    }

    #[test]
    fn first_level_children_have_the_model_corners() {
        // n = 2: v0 = (0,0), v1 = (2,0), v2 = (0,2), m01 = (1,0), m12 = (1,1), m20 = (0,1).
        assert_eq!(fine_corners(1, 0), [[0, 0], [1, 0], [0, 1]]); // Top (v0, m01, m20)
        assert_eq!(fine_corners(1, 1), [[1, 0], [2, 0], [1, 1]]); // Left (m01, v1, m12)
        assert_eq!(fine_corners(1, 2), [[1, 1], [0, 1], [1, 0]]); // Center (m12, m20, m01)
        assert_eq!(fine_corners(1, 3), [[0, 1], [1, 1], [0, 2]]); // Right (m20, m12, v2)
    }

    #[test]
    fn interior_numbering_is_a_bijection() {
        for level in 2..6 {
            let n = 1i32 << level;
            let ip = interior_per_triangle(n as u64) as u32;
            let mut seen = std::collections::HashSet::new();
            for local in 0..ip {
                let (b, c) = interior_coords(n, local);
                assert!(b >= 1 && c >= 1 && b + c < n, "({b}, {c}) at level {level}");
                let j = (n - 1 - c) as u32;
                assert_eq!(ip - j * (j + 1) / 2 + b as u32 - 1, local);
                assert!(seen.insert((b, c)));
            }
            // The order of crate::subdivide: rows of increasing c, each of increasing b.
            let order: Vec<(i32, i32)> = (1..n)
                .flat_map(|c| (1..n - c).map(move |b| (b, c)))
                .collect();
            let ours: Vec<(i32, i32)> = (0..ip).map(|l| interior_coords(n, l)).collect();
            assert_eq!(ours, order, "level {level}");
        }
    }

    #[test]
    fn every_lattice_point_has_its_incident_fine_triangles() {
        let level = 3;
        let n = 8;
        // Interior points touch 6 fine triangles, edge points 3, corners 1.
        assert_eq!(incident_paths(level, 3, 2).count(), 6);
        assert_eq!(incident_paths(level, 3, 0).count(), 3);
        assert_eq!(incident_paths(level, 0, 0).count(), 1);
        assert_eq!(incident_paths(level, n, 0).count(), 1);
        for path in incident_paths(level, 3, 2) {
            assert!(fine_corners(level, path).contains(&[3, 2]));
        }
    }
}
