//! Half-edges grouped by undirected edge, in linear time: what orientation (step 2) walks and
//! pairing (step 3) decides on.

/// `EdgeGroups::mate` of a half-edge whose edge has no other use.
pub(super) const EDGE_ALONE: u32 = u32::MAX;
/// `EdgeGroups::mate` of a half-edge whose edge has three or more uses.
pub(super) const EDGE_MANY: u32 = u32::MAX - 1;

/// Half-edges `3 t + e` grouped by undirected edge.
pub(super) struct EdgeGroups {
    /// The other half-edge of an edge with exactly two uses, else [`EDGE_ALONE`] or
    /// [`EDGE_MANY`].
    pub mate: Vec<u32>,
    /// The edges with three or more uses: each group's half-edges ascending, the groups in
    /// order of their first half-edge.
    pub many: Vec<Vec<u32>>,
}

impl EdgeGroups {
    /// Groups half-edges by undirected edge in linear time: a counting sort of the half-edges
    /// by their smaller vertex (ascending half-edge within each bucket), then each bucket sorted
    /// by the other vertex. Buckets hold the edges of one vertex, so they are small except at
    /// high-valence vertices, where the sort keeps the cost `k log k` rather than `k²`.
    pub fn new(tris: &[[u32; 3]]) -> EdgeGroups {
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

    /// Renames every half-edge `h` to `map(h)` (a permutation), keeping the invariants.
    pub fn relabel(&mut self, map: impl Fn(u32) -> u32) {
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
