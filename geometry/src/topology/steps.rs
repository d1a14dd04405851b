//! The seven steps of [`build_control_mesh`](super::build_control_mesh), in order. Each takes
//! what the earlier steps produced, adds to the [`TopologyReport`], and states what its output
//! guarantees to the steps after it.
//!
//! Half-edge `h = 3 t + e` of a triangle runs from its corner `e` to its corner `e + 1`; corner
//! `i = 3 t + c` is the use of vertex `tris[t][c]` by triangle `t`. Both number the same slots
//! of the final `triangles`, `corner_spokes`, `neighbours` and `edges` tables.

use std::collections::VecDeque;
use std::ops::Range;

use hce_format::{
    RULE_CORNER, RULE_CREASE, RULE_SMOOTH, SPOKE_BOUNDARY, SPOKE_SHARP, VERTEX_BOUNDARY,
    VERTEX_RULE_SHIFT,
};

use super::edge_groups::{EdgeGroups, EDGE_MANY};
use super::{Creases, NonManifold, TopologyError, TopologyReport};

/// The triangles that survive step 1.
pub(super) struct Faces {
    /// Welded vertex triples, three distinct vertices each; counter-clockwise consistently
    /// within each connected component once [`orient`] has run.
    pub tris: Vec<[u32; 3]>,
    /// `source[t]`: the input triangle of triangle `t`, increasing in `t`.
    pub source: Vec<u32>,
}

/// Step 1: drops degenerate triangles (a repeated welded vertex), keeping the others in input
/// order.
///
/// Guarantees: every vertex index is below `nv` (or the input is refused with
/// [`TopologyError::IndexOutOfRange`] naming the first bad triangle), no triangle repeats a
/// vertex, and at least one triangle remains ([`TopologyError::Empty`] otherwise).
pub(super) fn drop_degenerates(
    nv: usize,
    triangles: &[[u32; 3]],
    report: &mut TopologyReport,
) -> Result<Faces, TopologyError> {
    let mut tris: Vec<[u32; 3]> = Vec::with_capacity(triangles.len());
    let mut source: Vec<u32> = Vec::with_capacity(triangles.len());
    for (t, tri) in triangles.iter().enumerate() {
        if let Some(&v) = tri.iter().find(|&&v| v as usize >= nv) {
            return Err(TopologyError::IndexOutOfRange {
                triangle: t,
                vertex: v,
                count: nv,
            });
        }
        if tri[0] == tri[1] || tri[1] == tri[2] || tri[2] == tri[0] {
            report.degenerate_triangles += 1;
            continue;
        }
        tris.push(*tri);
        source.push(t as u32);
    }
    if tris.is_empty() {
        return Err(TopologyError::Empty);
    }
    Ok(Faces { tris, source })
}

/// What orientation did to the triangles.
pub(super) struct Orientation {
    /// `flip[t]`: whether corners 1 and 2 of triangle `t` were swapped.
    pub flip: Vec<bool>,
    /// `corner_src[t][c]`: the input corner (`3 source + k`) that corner `c` of `t` came from,
    /// so per-corner input data (normals) follows the flips.
    pub corner_src: Vec<[usize; 3]>,
    /// The half-edges grouped by undirected edge, relabelled to the flipped triangles.
    pub groups: EdgeGroups,
}

/// Step 2: orients the triangles consistently per connected component: a breadth-first walk over
/// edges shared by exactly two triangles flips the triangles that disagree with the first triangle
/// (lowest index) of their component.
///
/// Guarantees: two triangles sharing an edge that no third triangle uses run along it in
/// opposite directions unless their component is non-orientable; `groups` describes the
/// flipped `faces`.
pub(super) fn orient(faces: &mut Faces, report: &mut TopologyReport) -> Orientation {
    let tris = &mut faces.tris;
    let f = tris.len();
    let mut groups = EdgeGroups::new(tris);
    let partner = &groups.mate;
    let mut flip = vec![false; f];
    let mut seen = vec![false; f];
    let mut queue = VecDeque::new();
    for start in 0..f {
        if seen[start] {
            continue;
        }
        seen[start] = true;
        queue.push_back(start);
        while let Some(t) = queue.pop_front() {
            for e in 0..3 {
                let p = partner[3 * t + e];
                if p >= EDGE_MANY {
                    continue;
                }
                let (t2, e2) = (p as usize / 3, p as usize % 3);
                if seen[t2] {
                    continue;
                }
                let same_dir = tris[t][e] == tris[t2][e2];
                seen[t2] = true;
                flip[t2] = flip[t] ^ same_dir;
                queue.push_back(t2);
            }
        }
    }
    let mut corner_src: Vec<[usize; 3]> = Vec::with_capacity(f);
    for t in 0..f {
        let s = faces.source[t] as usize;
        if flip[t] {
            tris[t].swap(1, 2);
            corner_src.push([3 * s, 3 * s + 2, 3 * s + 1]);
            report.flipped_triangles += 1;
        } else {
            corner_src.push([3 * s, 3 * s + 1, 3 * s + 2]);
        }
    }
    // The flips permute half-edges within their triangle (the swap of corners 1 and 2 turns
    // edge 0 into edge 2 and back, and reverses edge 1), so the edge groups are relabelled
    // rather than rebuilt.
    if report.flipped_triangles > 0 {
        groups.relabel(|h| {
            let (t, e) = (h as usize / 3, h % 3);
            if flip[t] {
                3 * t as u32 + (2 - e)
            } else {
                h
            }
        });
    }
    Orientation {
        flip,
        corner_src,
        groups,
    }
}

/// [`Pairs::mate`] of a half-edge on a boundary or a cut.
const UNPAIRED: u32 = u32::MAX;

/// Which half-edges are the two sides of one interior edge.
pub(super) struct Pairs {
    /// `mate[h]`: the opposite half-edge of `h` across a paired edge, or [`UNPAIRED`].
    pub mate: Vec<u32>,
}

impl Pairs {
    /// The corner before corner `i` in counter-clockwise order around its vertex (the same
    /// vertex's corner in the triangle across `i`'s outgoing edge), if that edge is paired.
    fn prev_ccw(&self, i: usize) -> Option<usize> {
        let p = self.mate[i];
        (p != UNPAIRED).then(|| 3 * (p as usize / 3) + (p as usize % 3 + 1) % 3)
    }

    /// The corner after corner `i` counter-clockwise around its vertex (across `i`'s incoming
    /// edge), if that edge is paired.
    fn next_ccw(&self, i: usize) -> Option<usize> {
        let p = self.mate[3 * (i / 3) + (i % 3 + 2) % 3];
        (p != UNPAIRED).then_some(p as usize)
    }
}

/// Step 3: pairs half-edges: an edge is interior exactly when two triangles use it in opposite
/// directions. Every other use (three or more triangles, or two that still agree in direction on a
/// non-orientable surface) becomes a boundary edge of each triangle: the surface is cut there.
/// Edges are visited in order of their first half-edge, so reports and errors name the same edge
/// whatever the grouping method.
///
/// Guarantees: `mate` is an involution on the paired half-edges, each pair joins the same two
/// vertices in opposite directions, and under [`NonManifold::Refuse`] nothing was cut (the
/// first cut edge is the error otherwise).
pub(super) fn pair_edges(
    faces: &Faces,
    groups: &EdgeGroups,
    non_manifold: NonManifold,
    report: &mut TopologyReport,
) -> Result<Pairs, TopologyError> {
    let (tris, source) = (&faces.tris, &faces.source);
    let f = tris.len();
    let mut pair = vec![UNPAIRED; 3 * f];
    let mut many = groups.many.iter().peekable();
    for h in 0..3 * f {
        let m = groups.mate[h];
        let (t0, e0) = (h / 3, h % 3);
        let (a, b) = (tris[t0][e0], tris[t0][(e0 + 1) % 3]);
        if m < EDGE_MANY {
            if (m as usize) < h {
                continue;
            }
            let (t1, e1) = (m as usize / 3, m as usize % 3);
            if tris[t1][e1] == b {
                pair[h] = m;
                pair[m as usize] = h as u32;
            } else {
                report.non_orientable_edges += 1;
                if non_manifold == NonManifold::Refuse {
                    return Err(TopologyError::NonManifoldEdge {
                        a,
                        b,
                        triangles: vec![source[t0] as usize, source[t1] as usize],
                    });
                }
            }
        } else if m == EDGE_MANY && many.peek().is_some_and(|g| g[0] as usize == h) {
            let g = many.next().expect("peeked");
            let list: Vec<usize> = g.iter().map(|&i| source[i as usize / 3] as usize).collect();
            if non_manifold == NonManifold::Refuse {
                return Err(TopologyError::NonManifoldEdge {
                    a: a.min(b),
                    b: a.max(b),
                    triangles: list,
                });
            }
            report.non_manifold_edges += 1;
            if report.non_manifold_edge_examples.len() < 16 {
                report
                    .non_manifold_edge_examples
                    .push(((a.min(b), a.max(b)), list));
            }
        }
    }
    Ok(Pairs { mate: pair })
}

/// One fan: the corners around one welded vertex that are connected through paired edges.
pub(super) struct Fan {
    pub welded: u32,
    /// Whether the fan goes all the way round (its vertex is interior).
    pub closed: bool,
    /// Its corners in counter-clockwise order, as a range of [`Fans::corners`]; an open fan
    /// starts at the corner whose outgoing edge is a boundary.
    pub corners: Range<usize>,
}

/// The control vertices: one per fan.
pub(super) struct Fans {
    /// Fans in order of their first corner (the lowest corner not in an earlier fan).
    pub fans: Vec<Fan>,
    /// The corners of every fan, fan after fan.
    pub corners: Vec<u32>,
    /// Fans in control-vertex order: by welded vertex, then by first corner.
    pub order: Vec<u32>,
    /// `control_to_welded[v]`: the welded vertex of control vertex `v`.
    pub control_to_welded: Vec<u32>,
    /// `corner_vertex[3 t + c]`: the control vertex of corner `c` of triangle `t` (the
    /// control mesh's `triangles` table).
    pub corner_vertex: Vec<u32>,
}

/// Step 4: gathers the corners around each vertex into fans connected through paired edges and
/// numbers one control vertex per fan: welded order, then fans by their first corner. A welded
/// vertex with more than one fan (two cones touching at their tips, an end of a cut edge) becomes
/// several control vertices at the same position.
///
/// Guarantees: every corner is in exactly one fan, consecutive corners of a fan share a paired
/// edge, and under [`NonManifold::Refuse`] no welded vertex has two fans
/// ([`TopologyError::NonManifoldVertex`] names the first otherwise).
pub(super) fn fans(
    faces: &Faces,
    pairs: &Pairs,
    nv: usize,
    non_manifold: NonManifold,
    report: &mut TopologyReport,
) -> Result<Fans, TopologyError> {
    let (tris, source) = (&faces.tris, &faces.source);
    let f = tris.len();
    let mut fan_of = vec![u32::MAX; 3 * f];
    let mut fans: Vec<Fan> = Vec::new();
    let mut fan_corners: Vec<u32> = Vec::with_capacity(3 * f);
    for i in 0..3 * f {
        if fan_of[i] != u32::MAX {
            continue;
        }
        let mut start = i;
        let mut closed = false;
        let mut steps = 0;
        while let Some(p) = pairs.prev_ccw(start) {
            if p == i {
                closed = true;
                break;
            }
            start = p;
            steps += 1;
            if steps > 3 * f {
                break;
            }
        }
        let fan_id = fans.len() as u32;
        let first = fan_corners.len();
        fan_corners.push(start as u32);
        fan_of[start] = fan_id;
        let mut cur = start;
        while let Some(n) = pairs.next_ccw(cur) {
            if n == start || fan_of[n] != u32::MAX {
                break;
            }
            fan_of[n] = fan_id;
            fan_corners.push(n as u32);
            cur = n;
        }
        fans.push(Fan {
            welded: tris[i / 3][i % 3],
            closed,
            corners: first..fan_corners.len(),
        });
    }
    // Control vertices: welded order, then fans by their first corner.
    // (A counting sort by welded vertex, stable in fan order.)
    let mut used = vec![0u32; nv];
    for fan in &fans {
        used[fan.welded as usize] += 1;
    }
    let mut order_start = Vec::with_capacity(nv + 1);
    order_start.push(0u32);
    for &c in &used {
        order_start.push(order_start.last().expect("non-empty") + c);
    }
    let mut order = vec![0u32; fans.len()];
    for (k, fan) in fans.iter().enumerate() {
        let slot = &mut order_start[fan.welded as usize];
        order[*slot as usize] = k as u32;
        *slot += 1;
    }
    let mut fan_vertex = vec![0u32; fans.len()];
    let mut control_to_welded = Vec::with_capacity(fans.len());
    for (new, &k) in order.iter().enumerate() {
        fan_vertex[k as usize] = new as u32;
        control_to_welded.push(fans[k as usize].welded);
    }
    report.unused_vertices = used.iter().filter(|&&c| c == 0).count();
    report.split_vertices = used.iter().filter(|&&c| c > 1).count();
    if non_manifold == NonManifold::Refuse {
        if let Some(w) = used.iter().position(|&c| c > 1) {
            let list: Vec<usize> = fans
                .iter()
                .filter(|fan| fan.welded == w as u32)
                .map(|fan| source[fan_corners[fan.corners.start] as usize / 3] as usize)
                .collect();
            return Err(TopologyError::NonManifoldVertex {
                vertex: w as u32,
                fans: list.len(),
                triangles: list,
            });
        }
    }
    let corner_vertex: Vec<u32> = fan_of.iter().map(|&k| fan_vertex[k as usize]).collect();
    Ok(Fans {
        fans,
        corners: fan_corners,
        order,
        control_to_welded,
        corner_vertex,
    })
}

/// Step 5: tags the sharp half-edges: every unpaired one (a boundary or a cut), and both halves of
/// each paired edge that `creases` calls a crease.
///
/// Guarantees: the two halves of a paired edge agree; [`Creases::Auto`] compares the input
/// corner normals bit for bit (so it is independent of the orientation step), and input
/// without normals gets no creases.
pub(super) fn sharp_edges(
    positions: &[[f32; 3]],
    corner_normals: Option<&[[f32; 3]]>,
    creases: Creases,
    faces: &Faces,
    orientation: &Orientation,
    pairs: &Pairs,
    report: &mut TopologyReport,
) -> Vec<bool> {
    let (tris, corner_src) = (&faces.tris, &orientation.corner_src);
    let f = tris.len();
    let mut sharp = vec![false; 3 * f];
    for i in 0..3 * f {
        let p = pairs.mate[i];
        if p == UNPAIRED {
            sharp[i] = true;
            continue;
        }
        let p = p as usize;
        if p < i {
            continue;
        }
        let crease = match creases {
            Creases::None => false,
            Creases::Auto => corner_normals.is_some_and(|n| {
                let (t, e) = (i / 3, i % 3);
                let (t2, e2) = (p / 3, p % 3);
                let a1 = n[corner_src[t][e]];
                let b1 = n[corner_src[t][(e + 1) % 3]];
                let b2 = n[corner_src[t2][e2]];
                let a2 = n[corner_src[t2][(e2 + 1) % 3]];
                a1.map(f32::to_bits) != a2.map(f32::to_bits)
                    || b1.map(f32::to_bits) != b2.map(f32::to_bits)
            }),
            Creases::Angle(deg) => {
                let n1 = face_normal(positions, tris[i / 3]);
                let n2 = face_normal(positions, tris[p / 3]);
                match (n1, n2) {
                    (Some(n1), Some(n2)) => {
                        let c = (n1[0] * n2[0] + n1[1] * n2[1] + n1[2] * n2[2]).clamp(-1.0, 1.0);
                        c.acos().to_degrees() > deg
                    }
                    _ => false,
                }
            }
        };
        if crease {
            sharp[i] = true;
            sharp[p] = true;
            report.crease_edges += 1;
        }
    }
    sharp
}

/// The per-vertex tables of the control mesh and the corners' spoke positions.
pub(super) struct Rings {
    pub positions: Vec<f32>,
    pub ring_offsets: Vec<u32>,
    pub ring: Vec<u32>,
    pub vertex_flags: Vec<u32>,
    pub spoke_flags: Vec<u32>,
    pub corner_spokes: Vec<u32>,
}

/// Step 6: writes each control vertex's ring, its flags and every corner's first spoke. A closed
/// fan's ring lists, per corner in counter-clockwise order, the corner's next vertex; an open fan's
/// starts with the first corner's next vertex (a boundary spoke) and then lists each corner's
/// previous vertex, the last of them a boundary spoke too.
///
/// Guarantees: spoke `corner_spokes[3 t + c]` of `tris[t][c]`'s ring is the triangle's next
/// corner and the spoke after it (cyclically when the vertex is closed) its previous corner;
/// boundary spokes are sharp; the rule is corner for three or more sharp spokes or a boundary
/// vertex of a single triangle, crease for two, smooth otherwise. Sets the valence histogram.
pub(super) fn rings(
    positions: &[[f32; 3]],
    fans: &Fans,
    sharp: &[bool],
    report: &mut TopologyReport,
) -> Rings {
    let nc = fans.fans.len();
    let nh = fans.corner_vertex.len();
    let corner_vertex = &fans.corner_vertex;
    let mut out = Rings {
        positions: Vec::with_capacity(3 * nc),
        ring_offsets: Vec::with_capacity(nc + 1),
        ring: Vec::with_capacity(nh + nc),
        vertex_flags: Vec::with_capacity(nc),
        spoke_flags: Vec::with_capacity(nh + nc),
        corner_spokes: vec![0; nh],
    };
    out.ring_offsets.push(0);
    let mut histogram = Vec::new();
    for &k in &fans.order {
        let Fan {
            welded: w,
            closed,
            corners: range,
        } = &fans.fans[k as usize];
        let corners = &fans.corners[range.clone()];
        out.positions.extend_from_slice(&positions[*w as usize]);
        let spoke_of =
            |i: u32, d: usize| corner_vertex[3 * (i as usize / 3) + (i as usize % 3 + d) % 3];
        let mut n_sharp = 0;
        if !closed {
            out.ring.push(spoke_of(corners[0], 1));
            out.spoke_flags.push(SPOKE_SHARP | SPOKE_BOUNDARY);
            n_sharp += 1;
        }
        for (j, &c) in corners.iter().enumerate() {
            out.corner_spokes[c as usize] = j as u32;
            if *closed {
                out.ring.push(spoke_of(c, 1));
                let s = sharp[c as usize];
                out.spoke_flags.push(if s { SPOKE_SHARP } else { 0 });
                n_sharp += s as usize;
            } else {
                out.ring.push(spoke_of(c, 2));
                let he = 3 * (c as usize / 3) + (c as usize % 3 + 2) % 3;
                let last = j + 1 == corners.len();
                let flag = if last {
                    SPOKE_SHARP | SPOKE_BOUNDARY
                } else if sharp[he] {
                    SPOKE_SHARP
                } else {
                    0
                };
                n_sharp += (flag & SPOKE_SHARP != 0) as usize;
                out.spoke_flags.push(flag);
            }
        }
        let valence = out.ring.len() - *out.ring_offsets.last().unwrap() as usize;
        out.ring_offsets.push(out.ring.len() as u32);
        if histogram.len() <= valence {
            histogram.resize(valence + 1, 0);
        }
        histogram[valence] += 1;
        let rule = if n_sharp >= 3 || (!closed && corners.len() == 1) {
            RULE_CORNER
        } else if n_sharp == 2 {
            RULE_CREASE
        } else {
            RULE_SMOOTH
        };
        let boundary = if *closed { 0 } else { VERTEX_BOUNDARY };
        out.vertex_flags
            .push(boundary | (rule << VERTEX_RULE_SHIFT));
    }
    report.valence_histogram = histogram;
    out
}

/// The per-triangle-edge tables of the control mesh.
pub(super) struct EdgeTables {
    pub neighbours: Vec<u32>,
    pub edges: Vec<u32>,
}

/// Step 7: writes each triangle edge's neighbour and numbers the edges in order of first appearance
/// (scanning `3 t + e`), which makes the first triangle to use an edge its owner.
///
/// Guarantees: the two sides of a paired edge share one id and name each other's triangle;
/// unpaired sides have [`hce_format::NO_NEIGHBOUR`] and an id of their own; ids are dense.
pub(super) fn neighbours_and_edges(pairs: &Pairs, report: &mut TopologyReport) -> EdgeTables {
    let n = pairs.mate.len();
    let mut out = EdgeTables {
        neighbours: vec![hce_format::NO_NEIGHBOUR; n],
        edges: vec![0; n],
    };
    let mut next_edge = 0u32;
    for (i, &p) in pairs.mate.iter().enumerate() {
        if p == UNPAIRED {
            out.edges[i] = next_edge;
            next_edge += 1;
            report.boundary_edges += 1;
        } else {
            out.neighbours[i] = p / 3;
            if (p as usize) > i {
                out.edges[i] = next_edge;
                next_edge += 1;
            } else {
                out.edges[i] = out.edges[p as usize];
            }
        }
    }
    report.edges = next_edge as usize;
    out
}

fn face_normal(p: &[[f32; 3]], t: [u32; 3]) -> Option<[f32; 3]> {
    let [a, b, c] = t.map(|i| p[i as usize]);
    let u = [b[0] - a[0], b[1] - a[1], b[2] - a[2]];
    let v = [c[0] - a[0], c[1] - a[1], c[2] - a[2]];
    let n = [
        u[1] * v[2] - u[2] * v[1],
        u[2] * v[0] - u[0] * v[2],
        u[0] * v[1] - u[1] * v[0],
    ];
    let l = (n[0] * n[0] + n[1] * n[1] + n[2] * n[2]).sqrt();
    (l > 0.0).then(|| n.map(|x| x / l))
}
