//! Topology of a welded triangle mesh and the control-mesh adjacency tables
//! ([`hce_format::ControlMesh`]) that Loop subdivision reads, on the CPU and on the GPU.
//!
//! # Non-manifold input: split, not refuse (by default)
//!
//! Real assets are often slightly non-manifold (Blender's Suzanne has an edge shared by three
//! faces). Loop subdivision is only defined on manifolds, so by default such input is split
//! into manifold pieces, deterministically:
//!
//! 1. Degenerate triangles (a repeated welded vertex) are dropped.
//! 2. Triangles are oriented consistently per connected component (a breadth-first walk over
//!    edges shared by exactly two triangles flips the triangles that disagree with the first
//!    triangle of their component).
//! 3. An edge is *paired* (interior) only when exactly two triangles share it in opposite
//!    directions. Every other edge use (three or more triangles, or two that still agree in
//!    direction on a non-orientable surface) becomes a boundary edge of each triangle: the
//!    surface is cut there.
//! 4. Around each vertex the triangles form fans connected through paired edges; a vertex with
//!    more than one fan (a non-manifold vertex, e.g. two cones touching at their tips or an end
//!    of a cut edge) becomes one control vertex per fan, at the same position.
//!
//! The result is always a manifold with boundary, the pieces are reported in
//! [`TopologyReport`], and [`NonManifold::Refuse`] turns the split into an error that names the
//! edge or vertex and its triangles instead.

use hce_format::{
    ControlMesh, NO_NEIGHBOUR, RULE_CORNER, RULE_CREASE, RULE_SMOOTH, SPOKE_BOUNDARY, SPOKE_SHARP,
    VERTEX_BOUNDARY, VERTEX_RULE_SHIFT,
};

/// Which edges are infinitely sharp creases, besides boundaries.
#[derive(Clone, Copy, Debug, Default, PartialEq)]
pub enum Creases {
    /// No creases: only boundary edges are sharp.
    #[default]
    None,
    /// Edges whose two sides have different input normals at either end (the author split the
    /// normals, i.e. made the edge hard). Input without normals gets no creases.
    Auto,
    /// Edges whose dihedral angle (between the two face normals) exceeds this many degrees.
    Angle(f32),
}

impl std::str::FromStr for Creases {
    type Err = String;
    fn from_str(s: &str) -> Result<Self, String> {
        match s {
            "none" => Ok(Creases::None),
            "auto" => Ok(Creases::Auto),
            _ => match s.strip_prefix("angle=").map(str::parse::<f32>) {
                Some(Ok(d)) if (0.0..=180.0).contains(&d) => Ok(Creases::Angle(d)),
                _ => Err(format!(
                    "unknown crease mode '{s}': use none, auto or angle=DEG with DEG in 0..=180"
                )),
            },
        }
    }
}

/// What to do with non-manifold edges and vertices.
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq)]
pub enum NonManifold {
    /// Cut the surface into manifold pieces (see the module documentation). Default.
    #[default]
    Split,
    /// Return [`TopologyError`] naming the first offending edge or vertex.
    Refuse,
}

/// Parameters of [`build_control_mesh`].
#[derive(Clone, Copy, Debug, Default, PartialEq)]
pub struct TopologyConfig {
    /// Crease tagging; default none.
    pub creases: Creases,
    /// Non-manifold handling; default split.
    pub non_manifold: NonManifold,
}

/// Errors of topology building.
#[derive(Debug, thiserror::Error, PartialEq)]
pub enum TopologyError {
    #[error("triangle {triangle} references vertex {vertex}, but there are only {count} vertices")]
    IndexOutOfRange {
        triangle: usize,
        vertex: u32,
        count: usize,
    },
    #[error("edge ({a}, {b}) is shared by triangles {triangles:?}; Loop subdivision needs a manifold mesh (split it into manifold pieces with the default non-manifold mode)")]
    NonManifoldEdge {
        a: u32,
        b: u32,
        triangles: Vec<usize>,
    },
    #[error("vertex {vertex} joins {fans} separate fans of triangles (first triangles {triangles:?}); Loop subdivision needs a manifold mesh (split it into manifold pieces with the default non-manifold mode)")]
    NonManifoldVertex {
        vertex: u32,
        fans: usize,
        triangles: Vec<usize>,
    },
    #[error("the mesh has no non-degenerate triangle")]
    Empty,
    #[error("the mesh is too large: {what}")]
    TooLarge { what: String },
}

/// What [`build_control_mesh`] found and did. Vertex and triangle numbers are those of the
/// welded input.
#[derive(Clone, Debug, Default, PartialEq)]
pub struct TopologyReport {
    pub welded_vertices: usize,
    pub input_triangles: usize,
    /// Welded vertices no triangle uses (dropped).
    pub unused_vertices: usize,
    /// Triangles with a repeated vertex (dropped).
    pub degenerate_triangles: usize,
    /// Triangles flipped to agree with the orientation of their component.
    pub flipped_triangles: usize,
    /// Edges shared by more than two triangles (cut), with their triangles; at most 16 listed.
    pub non_manifold_edges: usize,
    pub non_manifold_edge_examples: Vec<((u32, u32), Vec<usize>)>,
    /// Edges shared by two triangles in the same direction after orientation (cut).
    pub non_orientable_edges: usize,
    /// Welded vertices split into several control vertices (non-manifold vertices).
    pub split_vertices: usize,
    pub boundary_edges: usize,
    pub crease_edges: usize,
    /// Control mesh sizes.
    pub vertices: usize,
    pub edges: usize,
    pub triangles: usize,
    /// `valence_histogram[n]`: control vertices of valence `n` (ring length).
    pub valence_histogram: Vec<usize>,
}

impl std::fmt::Display for TopologyReport {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        writeln!(
            f,
            "input: {} welded vertices, {} triangles",
            self.welded_vertices, self.input_triangles
        )?;
        writeln!(
            f,
            "dropped: {} unused vertices, {} degenerate triangles; flipped {} triangles",
            self.unused_vertices, self.degenerate_triangles, self.flipped_triangles
        )?;
        writeln!(
            f,
            "non-manifold: {} edges cut, {} non-orientable edges cut, {} vertices split",
            self.non_manifold_edges, self.non_orientable_edges, self.split_vertices
        )?;
        for ((a, b), t) in &self.non_manifold_edge_examples {
            writeln!(f, "  edge ({a}, {b}) shared by triangles {t:?}")?;
        }
        writeln!(
            f,
            "control mesh: V={} E={} F={}, {} boundary edges, {} crease edges",
            self.vertices, self.edges, self.triangles, self.boundary_edges, self.crease_edges
        )?;
        write!(f, "valence histogram:")?;
        for (n, &c) in self.valence_histogram.iter().enumerate() {
            if c > 0 {
                write!(f, " {n}:{c}")?;
            }
        }
        writeln!(f)
    }
}

/// A control mesh and how it relates to the welded input.
#[derive(Clone, Debug, Default, PartialEq)]
pub struct Topology {
    pub mesh: ControlMesh,
    /// `control_to_welded[v]`: the welded input vertex of control vertex `v`.
    pub control_to_welded: Vec<u32>,
    /// `triangle_source[t]`: the input triangle of control triangle `t`.
    pub triangle_source: Vec<u32>,
    /// Whether control triangle `t` was flipped relative to its input triangle.
    pub triangle_flipped: Vec<bool>,
    pub report: TopologyReport,
}

/// Builds the control mesh and its adjacency tables from welded positions and triangles.
/// `corner_normals` (one per input triangle corner) drive [`Creases::Auto`].
pub fn build_control_mesh(
    positions: &[[f32; 3]],
    triangles: &[[u32; 3]],
    corner_normals: Option<&[[f32; 3]]>,
    config: &TopologyConfig,
) -> Result<Topology, TopologyError> {
    let nv = positions.len();
    if triangles.len() >= (u32::MAX / 4) as usize || nv >= u32::MAX as usize {
        return Err(TopologyError::TooLarge {
            what: format!("{} triangles, {} vertices", triangles.len(), nv),
        });
    }
    let mut report = TopologyReport {
        welded_vertices: nv,
        input_triangles: triangles.len(),
        ..Default::default()
    };
    // 1. Drop degenerate triangles.
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
    let f = tris.len();

    // 2. Orientation: breadth-first over edges shared by exactly two triangles.
    let mut groups = edge_groups(&tris);
    let partner = &groups.mate;
    let mut flip = vec![false; f];
    let mut seen = vec![false; f];
    let mut queue = std::collections::VecDeque::new();
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
        let s = source[t] as usize;
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

    // 3. Pairing: exactly two uses in opposite directions. Edges are visited in order of their
    // first half-edge, so reports and errors name the same edge whatever the grouping method.
    let mut pair = vec![u32::MAX; 3 * f];
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
                if config.non_manifold == NonManifold::Refuse {
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
            if config.non_manifold == NonManifold::Refuse {
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

    // 4. Fans around each vertex, through paired edges.
    let prev_ccw = |i: usize| -> Option<usize> {
        let p = pair[i];
        (p != u32::MAX).then(|| 3 * (p as usize / 3) + (p as usize % 3 + 1) % 3)
    };
    let next_ccw = |i: usize| -> Option<usize> {
        let p = pair[3 * (i / 3) + (i % 3 + 2) % 3];
        (p != u32::MAX).then_some(p as usize)
    };
    let mut fan_of = vec![u32::MAX; 3 * f];
    // (welded vertex, closed, corners in CCW order)
    // Fans as (welded vertex, closed, range of `fan_corners`), corners in CCW order.
    let mut fans: Vec<(u32, bool, std::ops::Range<usize>)> = Vec::new();
    let mut fan_corners: Vec<u32> = Vec::with_capacity(3 * f);
    for i in 0..3 * f {
        if fan_of[i] != u32::MAX {
            continue;
        }
        let mut start = i;
        let mut closed = false;
        let mut steps = 0;
        while let Some(p) = prev_ccw(start) {
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
        while let Some(n) = next_ccw(cur) {
            if n == start || fan_of[n] != u32::MAX {
                break;
            }
            fan_of[n] = fan_id;
            fan_corners.push(n as u32);
            cur = n;
        }
        fans.push((tris[i / 3][i % 3], closed, first..fan_corners.len()));
    }
    // Control vertices: welded order, then fans by their first corner.
    // (A counting sort by welded vertex, stable in fan order.)
    let mut used = vec![0u32; nv];
    for (w, _, _) in &fans {
        used[*w as usize] += 1;
    }
    let mut order_start = Vec::with_capacity(nv + 1);
    order_start.push(0u32);
    for &c in &used {
        order_start.push(order_start.last().expect("non-empty") + c);
    }
    let mut order = vec![0u32; fans.len()];
    for (k, (w, _, _)) in fans.iter().enumerate() {
        let slot = &mut order_start[*w as usize];
        order[*slot as usize] = k as u32;
        *slot += 1;
    }
    let mut fan_vertex = vec![0u32; fans.len()];
    let mut control_to_welded = Vec::with_capacity(fans.len());
    for (new, &k) in order.iter().enumerate() {
        fan_vertex[k as usize] = new as u32;
        control_to_welded.push(fans[k as usize].0);
    }
    report.unused_vertices = used.iter().filter(|&&c| c == 0).count();
    report.split_vertices = used.iter().filter(|&&c| c > 1).count();
    if config.non_manifold == NonManifold::Refuse {
        if let Some(w) = used.iter().position(|&c| c > 1) {
            let list: Vec<usize> = fans
                .iter()
                .filter(|fan| fan.0 == w as u32)
                .map(|fan| source[fan_corners[fan.2.start] as usize / 3] as usize)
                .collect();
            return Err(TopologyError::NonManifoldVertex {
                vertex: w as u32,
                fans: list.len(),
                triangles: list,
            });
        }
    }
    let corner_vertex: Vec<u32> = fan_of.iter().map(|&k| fan_vertex[k as usize]).collect();

    // 5. Creases, per half-edge (both halves of a paired edge agree).
    let mut sharp = vec![false; 3 * f];
    for i in 0..3 * f {
        let p = pair[i];
        if p == u32::MAX {
            sharp[i] = true;
            continue;
        }
        let p = p as usize;
        if p < i {
            continue;
        }
        let crease = match config.creases {
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

    // 6. Rings, flags and corner spokes.
    let nc = fans.len();
    let mut mesh = ControlMesh {
        positions: Vec::with_capacity(3 * nc),
        triangles: corner_vertex.clone(),
        ring_offsets: Vec::with_capacity(nc + 1),
        ring: Vec::with_capacity(3 * f + nc),
        vertex_flags: Vec::with_capacity(nc),
        spoke_flags: Vec::with_capacity(3 * f + nc),
        corner_spokes: vec![0; 3 * f],
        neighbours: vec![NO_NEIGHBOUR; 3 * f],
        edges: vec![0; 3 * f],
    };
    mesh.ring_offsets.push(0);
    let mut histogram = Vec::new();
    for &k in &order {
        let (w, closed, range) = &fans[k as usize];
        let corners = &fan_corners[range.clone()];
        mesh.positions.extend_from_slice(&positions[*w as usize]);
        let spoke_of =
            |i: u32, d: usize| corner_vertex[3 * (i as usize / 3) + (i as usize % 3 + d) % 3];
        let mut n_sharp = 0;
        if !closed {
            mesh.ring.push(spoke_of(corners[0], 1));
            mesh.spoke_flags.push(SPOKE_SHARP | SPOKE_BOUNDARY);
            n_sharp += 1;
        }
        for (j, &c) in corners.iter().enumerate() {
            mesh.corner_spokes[c as usize] = j as u32;
            if *closed {
                mesh.ring.push(spoke_of(c, 1));
                let s = sharp[c as usize];
                mesh.spoke_flags.push(if s { SPOKE_SHARP } else { 0 });
                n_sharp += s as usize;
            } else {
                mesh.ring.push(spoke_of(c, 2));
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
                mesh.spoke_flags.push(flag);
            }
        }
        let valence = mesh.ring.len() - *mesh.ring_offsets.last().unwrap() as usize;
        mesh.ring_offsets.push(mesh.ring.len() as u32);
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
        mesh.vertex_flags
            .push(boundary | (rule << VERTEX_RULE_SHIFT));
    }
    // 7. Neighbours and edge ids in first-appearance order.
    let mut next_edge = 0u32;
    for (i, &p) in pair.iter().enumerate() {
        if p == u32::MAX {
            mesh.edges[i] = next_edge;
            next_edge += 1;
            report.boundary_edges += 1;
        } else {
            mesh.neighbours[i] = p / 3;
            if (p as usize) > i {
                mesh.edges[i] = next_edge;
                next_edge += 1;
            } else {
                mesh.edges[i] = mesh.edges[p as usize];
            }
        }
    }
    report.vertices = nc;
    report.edges = next_edge as usize;
    report.triangles = f;
    report.valence_histogram = histogram;
    Ok(Topology {
        mesh,
        control_to_welded,
        triangle_source: source,
        triangle_flipped: flip,
        report,
    })
}

/// `EdgeGroups::mate` of a half-edge whose edge has no other use.
const EDGE_ALONE: u32 = u32::MAX;
/// `EdgeGroups::mate` of a half-edge whose edge has three or more uses.
const EDGE_MANY: u32 = u32::MAX - 1;

/// Half-edges `3 t + e` grouped by undirected edge.
struct EdgeGroups {
    /// The other half-edge of an edge with exactly two uses, else [`EDGE_ALONE`] or
    /// [`EDGE_MANY`].
    mate: Vec<u32>,
    /// The edges with three or more uses: each group's half-edges ascending, the groups in
    /// order of their first half-edge.
    many: Vec<Vec<u32>>,
}

impl EdgeGroups {
    /// Renames every half-edge `h` to `map(h)` (a permutation), keeping the invariants.
    fn relabel(&mut self, map: impl Fn(u32) -> u32) {
        let mut mate = vec![EDGE_ALONE; self.mate.len()];
        for (h, &m) in self.mate.iter().enumerate() {
            mate[map(h as u32) as usize] = if m < EDGE_MANY { map(m) } else { m };
        }
        self.mate = mate;
        for g in &mut self.many {
            for h in g.iter_mut() {
                *h = map(*h);
            }
            g.sort_unstable();
        }
        self.many.sort_unstable_by_key(|g| g[0]);
    }
}

/// Groups half-edges by undirected edge in linear time: a counting sort of the half-edges by
/// their smaller vertex (ascending half-edge within each bucket), then each bucket sorted by
/// the other vertex. Buckets hold the edges of one vertex, so they are small except at
/// high-valence vertices, where the sort keeps the cost `k log k` rather than `k²`.
fn edge_groups(tris: &[[u32; 3]]) -> EdgeGroups {
    let nh = 3 * tris.len();
    let nv = tris
        .iter()
        .flat_map(|t| t.iter())
        .max()
        .map_or(0, |&v| v as usize + 1);
    let ends = |h: usize| {
        let t = &tris[h / 3];
        let (a, b) = (t[h % 3], t[(h % 3 + 1) % 3]);
        (a.min(b), a.max(b))
    };
    let mut start = vec![0u32; nv + 1];
    for h in 0..nh {
        start[ends(h).0 as usize + 1] += 1;
    }
    for v in 0..nv {
        start[v + 1] += start[v];
    }
    // (other vertex << 32 | half-edge), bucketed by the smaller vertex.
    let mut keys = vec![0u64; nh];
    let mut fill = start.clone();
    for h in 0..nh {
        let (lo, hi) = ends(h);
        let slot = &mut fill[lo as usize];
        keys[*slot as usize] = (hi as u64) << 32 | h as u64;
        *slot += 1;
    }
    let mut mate = vec![EDGE_ALONE; nh];
    let mut many: Vec<Vec<u32>> = Vec::new();
    for v in 0..nv {
        let bucket = &mut keys[start[v] as usize..start[v + 1] as usize];
        bucket.sort_unstable();
        let mut i = 0;
        while i < bucket.len() {
            let mut j = i + 1;
            while j < bucket.len() && bucket[j] >> 32 == bucket[i] >> 32 {
                j += 1;
            }
            let run = &bucket[i..j];
            match run.len() {
                1 => {}
                2 => {
                    let (h0, h1) = (run[0] as u32, run[1] as u32);
                    mate[h0 as usize] = h1;
                    mate[h1 as usize] = h0;
                }
                _ => {
                    for &k in run {
                        mate[k as u32 as usize] = EDGE_MANY;
                    }
                    many.push(run.iter().map(|&k| k as u32).collect());
                }
            }
            i = j;
        }
    }
    many.sort_unstable_by_key(|g| g[0]);
    EdgeGroups { mate, many }
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

#[cfg(test)]
mod tests {
    use super::*;

    fn tetra() -> (Vec<[f32; 3]>, Vec<[u32; 3]>) {
        (
            vec![
                [0.0, 0.0, 0.0],
                [1.0, 0.0, 0.0],
                [0.0, 1.0, 0.0],
                [0.0, 0.0, 1.0],
            ],
            vec![[0, 2, 1], [0, 1, 3], [1, 2, 3], [2, 0, 3]],
        )
    }

    #[test]
    fn closed_tetrahedron_has_valence_three_rings_and_six_edges() {
        let (p, t) = tetra();
        let topo = build_control_mesh(&p, &t, None, &TopologyConfig::default()).unwrap();
        let m = &topo.mesh;
        assert_eq!(topo.report.edges, 6);
        assert_eq!(topo.report.boundary_edges, 0);
        assert_eq!(m.ring_offsets, vec![0, 3, 6, 9, 12]);
        assert!(m.neighbours.iter().all(|&n| n != NO_NEIGHBOUR));
        // corner spokes: spoke k is v_{c+1}, spoke k+1 is v_{c+2}.
        for tri in 0..4 {
            let v = m.triangle(tri);
            for c in 0..3 {
                let ring = m.ring_of(v[c]);
                let k = m.corner_spokes[3 * tri + c] as usize;
                assert_eq!(ring[k], v[(c + 1) % 3]);
                assert_eq!(ring[(k + 1) % ring.len()], v[(c + 2) % 3]);
            }
        }
    }

    #[test]
    fn single_triangle_has_corner_vertices_and_boundary_spokes() {
        let p = vec![[0.0, 0.0, 0.0], [1.0, 0.0, 0.0], [0.0, 1.0, 0.0]];
        let topo = build_control_mesh(&p, &[[0, 1, 2]], None, &TopologyConfig::default()).unwrap();
        let m = &topo.mesh;
        assert_eq!(m.ring, vec![1, 2, 2, 0, 0, 1]);
        assert!(m
            .spoke_flags
            .iter()
            .all(|&s| s == SPOKE_SHARP | SPOKE_BOUNDARY));
        assert!((0..3).all(|v| m.rule(v) == RULE_CORNER));
        assert_eq!(m.edges, vec![0, 1, 2]);
    }

    #[test]
    fn edge_shared_by_three_triangles_is_cut_or_refused() {
        let p = vec![
            [0.0, 0.0, 0.0],
            [1.0, 0.0, 0.0],
            [0.5, 1.0, 0.0],
            [0.5, -1.0, 0.0],
            [0.5, 0.0, 1.0],
        ];
        let t = vec![[0, 1, 2], [1, 0, 3], [0, 1, 4]];
        let topo = build_control_mesh(&p, &t, None, &TopologyConfig::default()).unwrap();
        assert_eq!(topo.report.non_manifold_edges, 1);
        assert_eq!(topo.report.boundary_edges, 9);
        assert!(topo.mesh.neighbours.iter().all(|&n| n == NO_NEIGHBOUR));
        // Vertices 0 and 1 are each split into three fans.
        assert_eq!(topo.report.split_vertices, 2);
        assert_eq!(topo.mesh.vertex_count(), 9);
        let err = build_control_mesh(
            &p,
            &t,
            None,
            &TopologyConfig {
                non_manifold: NonManifold::Refuse,
                ..Default::default()
            },
        )
        .unwrap_err();
        assert_eq!(
            err,
            TopologyError::NonManifoldEdge {
                a: 0,
                b: 1,
                triangles: vec![0, 1, 2]
            }
        );
    }

    #[test]
    fn inconsistent_orientation_is_fixed_and_degenerates_dropped() {
        let (p, mut t) = tetra();
        t[2] = [1, 3, 2];
        t.push([1, 1, 2]);
        let topo = build_control_mesh(&p, &t, None, &TopologyConfig::default()).unwrap();
        assert_eq!(topo.report.flipped_triangles, 1);
        assert_eq!(topo.report.degenerate_triangles, 1);
        assert_eq!(topo.report.boundary_edges, 0);
        assert_eq!(topo.report.non_orientable_edges, 0);
    }

    #[test]
    fn crease_modes_parse() {
        assert_eq!("auto".parse::<Creases>(), Ok(Creases::Auto));
        assert_eq!("angle=30".parse::<Creases>(), Ok(Creases::Angle(30.0)));
        assert!("angle=x".parse::<Creases>().is_err());
    }
}
