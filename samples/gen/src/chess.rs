//! Chesstime's pieces and board.
//!
//! The pieces are coarse lathes (12 steps around) of Staunton-like profiles; the rings where a
//! turned piece has a sharp edge (the base's rim and top, the collar, the crown's rim) are
//! tagged as hard, so they keep their edge through Loop subdivision with `--creases auto`.
//! The board is 8 × 8 squares of 5 cm with a 2 cm frame.

use glam::DVec3;

use crate::lathe::{c, lathe, p, ProfilePoint};
use crate::mesh::Mesh;

/// Steps around the axis for every piece.
pub const SEGMENTS: u32 = 12;

/// The kinds of piece Chesstime shows.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum Piece {
    King,
    Queen,
    Bishop,
    Pawn,
}

/// The profile of `piece`, bottom to top, in metres.
pub fn profile(piece: Piece) -> Vec<ProfilePoint> {
    match piece {
        Piece::Pawn => vec![
            p(0.0, 0.0),
            c(0.016, 0.0),
            c(0.016, 0.004),
            p(0.013, 0.007),
            p(0.009, 0.012),
            p(0.006, 0.025),
            c(0.010, 0.028),
            c(0.010, 0.030),
            p(0.006, 0.032),
            p(0.009, 0.036),
            p(0.0095, 0.041),
            p(0.007, 0.047),
            p(0.0, 0.050),
        ],
        Piece::Bishop => vec![
            p(0.0, 0.0),
            c(0.017, 0.0),
            c(0.017, 0.005),
            p(0.013, 0.009),
            p(0.009, 0.015),
            p(0.006, 0.036),
            c(0.011, 0.039),
            c(0.011, 0.041),
            p(0.006, 0.044),
            p(0.009, 0.050),
            p(0.0095, 0.056),
            p(0.007, 0.062),
            p(0.003, 0.065),
            p(0.004, 0.068),
            p(0.0, 0.072),
        ],
        Piece::Queen => vec![
            p(0.0, 0.0),
            c(0.019, 0.0),
            c(0.019, 0.005),
            p(0.015, 0.010),
            p(0.010, 0.017),
            p(0.007, 0.045),
            c(0.012, 0.049),
            c(0.012, 0.051),
            p(0.007, 0.055),
            p(0.008, 0.065),
            c(0.012, 0.075),
            p(0.008, 0.077),
            p(0.004, 0.079),
            p(0.0045, 0.083),
            p(0.0, 0.088),
        ],
        Piece::King => vec![
            p(0.0, 0.0),
            c(0.019, 0.0),
            c(0.019, 0.005),
            p(0.015, 0.010),
            p(0.010, 0.018),
            p(0.007, 0.050),
            c(0.012, 0.054),
            c(0.012, 0.056),
            p(0.007, 0.060),
            p(0.008, 0.070),
            c(0.011, 0.079),
            c(0.011, 0.081),
            p(0.006, 0.082),
            p(0.003, 0.084),
            c(0.0045, 0.087),
            c(0.0045, 0.094),
            p(0.0, 0.095),
        ],
    }
}

/// The piece as a closed lathe standing on `y = 0`.
pub fn piece(piece: Piece) -> Mesh {
    lathe(&profile(piece), SEGMENTS)
}

/// Side of a square and width of the frame, in metres.
pub const SQUARE: f64 = 0.05;
pub const FRAME: f64 = 0.02;
/// Height of the board's playing surface above the floor.
pub const BOARD_HEIGHT: f64 = 0.02;

/// Centre of square `(file, rank)` (0-based) on the board centred at the origin.
pub fn square_centre(file: usize, rank: usize) -> DVec3 {
    let half = 4.0 * SQUARE;
    DVec3::new(
        -half + SQUARE * (file as f64 + 0.5),
        BOARD_HEIGHT,
        half - SQUARE * (rank as f64 + 0.5),
    )
}

/// The board's primitives: `squares[colour][rank]` holds the four squares of that colour on
/// that rank (colour 0 dark, 1 light; a1 is dark), and `frame` the frame's top, the four sides
/// (hard edges at the rim) and no bottom (the board rests on the floor).
///
/// Squares are grouped per rank so that no primitive has two squares meeting at a corner: a
/// vertex joining two triangle fans only at a point is not manifold, whether an importer welds
/// per primitive or per mesh.
pub struct Board {
    pub squares: [Vec<Mesh>; 2],
    pub frame: Mesh,
}

/// Builds the board, centred at the origin, standing on `y = 0`.
pub fn board() -> Board {
    let half = 4.0 * SQUARE;
    // Grid lines: the frame's outer edge, the 9 square edges, the frame's outer edge.
    let mut lines = vec![-half - FRAME];
    lines.extend((0..=8).map(|i| -half + SQUARE * i as f64));
    lines.push(half + FRAME);
    let y = BOARD_HEIGHT;
    let cell = |mesh: &mut Mesh, i: usize, k: usize| {
        let v = [(i, k), (i, k + 1), (i + 1, k + 1), (i + 1, k)]
            .map(|(a, b)| mesh.vertex(DVec3::new(lines[a], y, lines[b])));
        mesh.quad(v, 0);
    };
    let mut squares: [Vec<Mesh>; 2] = [Vec::new(), Vec::new()];
    for rank in 0..8 {
        let mut by_colour = [Mesh::default(), Mesh::default()];
        for file in 0..8 {
            // Rank 0 is at +Z (the grid's last rows); a1 (file 0, rank 0) is dark.
            let colour = (file + rank) % 2;
            cell(&mut by_colour[colour], file + 1, 8 - rank);
        }
        for (colour, m) in by_colour.into_iter().enumerate() {
            let mut m = m;
            m.weld(1e-9);
            squares[colour].push(m);
        }
    }
    let mut frame = Mesh::default();
    for i in 0..10 {
        for k in 0..10 {
            if i == 0 || i == 9 || k == 0 || k == 9 {
                cell(&mut frame, i, k);
            }
        }
    }
    // Sides: one quad per grid cell along each edge so that they meet the top's vertices.
    let (lo, hi) = (lines[0], lines[10]);
    for (g, face) in [0usize, 1, 4, 5].into_iter().enumerate() {
        for s in 0..10 {
            let (a, b) = (lines[s], lines[s + 1]);
            let (p0, p1) = match face {
                0 => (DVec3::new(lo, 0.0, a), DVec3::new(lo, 0.0, b)),
                1 => (DVec3::new(hi, 0.0, a), DVec3::new(hi, 0.0, b)),
                4 => (DVec3::new(a, 0.0, lo), DVec3::new(b, 0.0, lo)),
                _ => (DVec3::new(a, 0.0, hi), DVec3::new(b, 0.0, hi)),
            };
            let up = DVec3::Y * y;
            let mut dir = DVec3::ZERO;
            dir[face / 2] = if face % 2 == 1 { 1.0 } else { -1.0 };
            let side = crate::shapes::quad_facing([p0, p1, p1 + up, p0 + up], dir, 0);
            frame.append(&side, 1 + g as u32);
        }
    }
    frame.weld(1e-9);
    Board { squares, frame }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn pieces_are_closed_with_tagged_rings() {
        for (kind, height, hard_rings) in [
            (Piece::Pawn, 0.050, 4),
            (Piece::Bishop, 0.072, 4),
            (Piece::Queen, 0.088, 5),
            (Piece::King, 0.095, 8),
        ] {
            let m = piece(kind);
            let s = m.edge_stats();
            assert_eq!(
                (s.boundary, s.non_manifold, s.inconsistent),
                (0, 0, 0),
                "{kind:?}"
            );
            assert_eq!(m.non_manifold_vertices(), 0, "{kind:?}");
            assert!(m.signed_volume() > 0.0);
            let rings = profile(kind).len() - 2;
            // Two pole fans and a band of quads between consecutive rings.
            let expected = 2 * SEGMENTS as usize + 2 * SEGMENTS as usize * (rings - 1);
            assert_eq!(m.triangles.len(), expected, "{kind:?}");
            let (lo, hi) = m.bounds().unwrap();
            assert!(lo.y == 0.0 && (hi.y - height).abs() < 1e-12, "{kind:?}");
            // Bases fit in a 5 cm square.
            assert!(hi.x <= 0.02 && lo.x >= -0.02);
            // Smoothing groups change once per hard ring.
            assert_eq!(
                *m.groups.iter().max().unwrap() as usize,
                hard_rings,
                "{kind:?}"
            );
        }
    }

    #[test]
    fn board_is_a_manifold_chequer() {
        let b = board();
        let mut all = Mesh::default();
        for colour in &b.squares {
            assert_eq!(colour.len(), 8);
            for m in colour {
                assert_eq!(m.triangles.len(), 8);
                assert_eq!(m.non_manifold_vertices(), 0);
                all.append(m, 0);
            }
        }
        assert_eq!(b.frame.non_manifold_vertices(), 0);
        all.append(&b.frame, 0);
        all.weld(1e-9);
        // Welded together: 11 × 11 top grid vertices plus 40 along the bottom of the sides.
        assert_eq!(all.positions.len(), 121 + 40);
        let s = all.edge_stats();
        assert_eq!((s.non_manifold, s.inconsistent), (0, 0));
        assert_eq!(s.boundary, 40);
        assert_eq!(all.non_manifold_vertices(), 0);
        // a1 is dark and at the -X, +Z corner.
        let a1 = square_centre(0, 0);
        let dark_rank0 = &b.squares[0][0];
        let (lo, hi) = dark_rank0.bounds().unwrap();
        assert!((lo.x - (a1.x - SQUARE / 2.0)).abs() < 1e-12);
        assert!((hi.z - (a1.z + SQUARE / 2.0)).abs() < 1e-12);
    }
}
