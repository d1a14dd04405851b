//! The HCE tree bitstream (SPEC.md Appendix B; Concheiro et al., "Synthesis of multiresolution
//! scenes with global illumination on a GPU", GRAPP 2012): breadth-first subdivided flags, one
//! bit per node, where the children of subdivided node `k` are nodes `1 + 4·rank(k) + c`.
//!
//! The one codec of the tree: the baker writes with [`BitWriter`] (which refuses any tree the
//! validator would reject), the validator and every reader decode with [`decode_shape`] and walk
//! with [`Tree`] (the runtime's lighting and the CPU reference of the GPU kernels). Only the GPU
//! walk in `runtime/src/gpu/hce_tree.wgsl` is a second implementation, and the GPU tests compare
//! it with this one.

/// A node of this depth is always a leaf (SPEC.md B.2): the deepest tree a file may hold, so the
/// deepest element level a baker may write.
pub const MAX_TREE_DEPTH: u32 = 12;

/// Largest node count of a tree of depth at most [`MAX_TREE_DEPTH`]: `(4^13 - 1) / 3`.
pub const MAX_NODES: u32 = ((1u64 << (2 * (MAX_TREE_DEPTH + 1))) / 3) as u32;

/// Why a tree cannot be decoded or encoded.
#[derive(Clone, Debug, PartialEq, Eq, thiserror::Error)]
pub enum TreeError {
    #[error("bitstream ends inside node {node} (bit {bit} of {bit_len}) (SPEC.md B.2)")]
    Truncated { node: u32, bit: u64, bit_len: u64 },
    #[error("node {node} at depth {depth} is subdivided; the maximum depth is {max} (SPEC.md B.2)", max = MAX_TREE_DEPTH)]
    TooDeep { node: u32, depth: u32 },
    #[error("tree overlaps the tree starting at bit {limit}; trees of different triangles must not overlap (SPEC.md A.9)")]
    Overlap { limit: u64 },
    #[error("{flags} flags do not form a complete tree with {subdivided} subdivided nodes, which needs 1 + 4 x {subdivided} (SPEC.md B.2)")]
    Incomplete { flags: usize, subdivided: usize },
}

/// Sizes of a decoded tree.
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq)]
pub struct TreeShape {
    /// Nodes `N = 1 + 4·subdivided`, also the number of bits the tree uses.
    pub node_count: u32,
    pub subdivided: u32,
    /// Depth of the deepest node (0 for a single leaf).
    pub depth: u32,
}

fn bit(bits: &[u32], i: u64) -> bool {
    bits.get((i >> 5) as usize)
        .is_some_and(|w| (w >> (i & 31)) & 1 == 1)
}

/// Decodes the shape of the tree starting at bit `start`, reading no bit at or after `limit`
/// (the end of the stream, or where the next tree starts) nor past the words stored. Bounded by
/// `limit - start` and by [`MAX_NODES`] steps.
pub fn decode_shape(bits: &[u32], limit: u64, start: u64) -> Result<TreeShape, TreeError> {
    let limit = limit.min(bits.len() as u64 * 32);
    let mut nodes: u64 = 1;
    let mut subdivided: u32 = 0;
    let mut depth: u32 = 0;
    let mut level_end: u64 = 1;
    let mut next_level: u64 = 0;
    let mut k: u64 = 0;
    while k < nodes {
        if k == level_end {
            depth += 1;
            level_end += next_level;
            next_level = 0;
        }
        let i = start.saturating_add(k);
        if i >= limit {
            return Err(TreeError::Truncated {
                node: k as u32,
                bit: i,
                bit_len: limit,
            });
        }
        if bit(bits, i) {
            if depth >= MAX_TREE_DEPTH {
                return Err(TreeError::TooDeep {
                    node: k as u32,
                    depth,
                });
            }
            nodes += 4;
            next_level += 4;
            subdivided += 1;
        }
        k += 1;
    }
    Ok(TreeShape {
        node_count: nodes as u32,
        subdivided,
        depth,
    })
}

/// Decodes the shape of every triangle's tree of an object, in triangle order. Trees are decoded
/// in `bits_start` order, each bounded by the next distinct start, so the work is linear in the
/// stream whatever the records say; a tree that runs into the next one is [`TreeError::Overlap`].
pub fn triangle_trees(o: &crate::model::Object) -> Vec<Result<TreeShape, TreeError>> {
    let mut starts: Vec<u64> = o
        .triangles
        .iter()
        .map(|t| u64::from(t.bits_start))
        .collect();
    starts.sort_unstable();
    starts.dedup();
    let stream_end = o.bit_len.min(o.bits.len() as u64 * 32);
    let mut shapes = std::collections::HashMap::with_capacity(starts.len());
    for (i, &s) in starts.iter().enumerate() {
        let limit = starts
            .get(i + 1)
            .copied()
            .unwrap_or(stream_end)
            .min(stream_end);
        let shape = match decode_shape(&o.bits, limit, s) {
            Err(TreeError::Truncated { .. }) if limit < stream_end => {
                Err(TreeError::Overlap { limit })
            }
            other => other,
        };
        shapes.insert(s, shape);
    }
    o.triangles
        .iter()
        .map(|t| {
            shapes
                .get(&u64::from(t.bits_start))
                .cloned()
                .unwrap_or(Err(TreeError::Overlap { limit: 0 }))
        })
        .collect()
}

/// A decoded tree inside an object's bitstream: node queries without allocation.
#[derive(Clone, Copy, Debug)]
pub struct Tree<'a> {
    bits: &'a [u32],
    start: u64,
    shape: TreeShape,
}

/// One node met by [`Tree::nodes`].
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub struct NodeInfo {
    pub index: u32,
    pub depth: u32,
    pub subdivided: bool,
}

impl<'a> Tree<'a> {
    /// Decodes the tree of a triangle whose start bit is `start` in a stream of `bit_len` bits.
    pub fn new(bits: &'a [u32], bit_len: u64, start: u64) -> Result<Self, TreeError> {
        let shape = decode_shape(bits, bit_len, start)?;
        Ok(Self { bits, start, shape })
    }

    pub fn shape(&self) -> TreeShape {
        self.shape
    }

    pub fn node_count(&self) -> u32 {
        self.shape.node_count
    }

    pub fn depth(&self) -> u32 {
        self.shape.depth
    }

    /// Whether node `k` is subdivided (false for `k` outside the tree).
    pub fn is_subdivided(&self, k: u32) -> bool {
        k < self.shape.node_count && bit(self.bits, self.start + u64::from(k))
    }

    /// The number of subdivided nodes numbered before `k`.
    pub fn rank(&self, k: u32) -> u32 {
        let k = k.min(self.shape.node_count);
        let (mut i, end) = (self.start, self.start + u64::from(k));
        let mut count = 0;
        while i < end {
            let word = self.bits.get((i >> 5) as usize).copied().unwrap_or(0);
            let from = (i & 31) as u32;
            let take = (32 - from).min((end - i) as u32);
            let mask = if take == 32 {
                u32::MAX
            } else {
                (1u32 << take) - 1
            };
            count += ((word >> from) & mask).count_ones();
            i += u64::from(take);
        }
        count
    }

    /// Child `c` (0 Top, 1 Left, 2 Center, 3 Right) of node `k`, or `None` if `k` is a leaf.
    pub fn child(&self, k: u32, c: u8) -> Option<u32> {
        if c > 3 || !self.is_subdivided(k) {
            return None;
        }
        Some(1 + 4 * self.rank(k) + u32::from(c))
    }

    /// The node that holds the subtriangle with the given path (child indices from the root),
    /// stopping at the first leaf: `(node, depth reached)` (SPEC.md B.3).
    pub fn find(&self, path: impl IntoIterator<Item = u8>) -> (u32, u32) {
        let mut k = 0;
        let mut depth = 0;
        for c in path {
            match self.child(k, c & 3) {
                Some(child) => {
                    k = child;
                    depth += 1;
                }
                None => break,
            }
        }
        (k, depth)
    }

    /// [`Tree::find`] for a path given as a number at subdivision level `level` (SPEC.md 2.3).
    pub fn find_path(&self, level: u32, path: u64) -> (u32, u32) {
        let level = level.min(32);
        self.find((0..level).rev().map(|d| ((path >> (2 * d)) & 3) as u8))
    }

    /// Every node in breadth-first order with its depth.
    pub fn nodes(&self) -> impl Iterator<Item = NodeInfo> + 'a {
        let tree = *self;
        let mut depth = 0;
        let mut level_end: u32 = 1;
        let mut next_level: u32 = 0;
        (0..tree.shape.node_count).map(move |k| {
            if k == level_end {
                depth += 1;
                level_end += next_level;
                next_level = 0;
            }
            let subdivided = tree.is_subdivided(k);
            if subdivided {
                next_level += 4;
            }
            NodeInfo {
                index: k,
                depth,
                subdivided,
            }
        })
    }
}

/// Appends trees to an object's bitstream, least significant bit first (SPEC.md B.1). Whole
/// trees only, each checked first, so a stream it writes always decodes.
#[derive(Clone, Debug, Default, PartialEq, Eq)]
pub struct BitWriter {
    words: Vec<u32>,
    bit_len: u64,
}

impl BitWriter {
    pub fn new() -> Self {
        Self::default()
    }

    /// Continues the stream `words[..bit_len]` (an object's `bits` and `bit_len`). Words past
    /// `bit_len` and bits past it in the last word are dropped, so appended trees start at
    /// `bit_len` and read back as written.
    pub fn resume(mut words: Vec<u32>, bit_len: u64) -> Self {
        let bit_len = bit_len.min(words.len() as u64 * 32);
        words.truncate(bit_len.div_ceil(32) as usize);
        if bit_len % 32 != 0 {
            if let Some(last) = words.last_mut() {
                *last &= (1u32 << (bit_len % 32)) - 1;
            }
        }
        Self { words, bit_len }
    }

    /// Bits written so far: where the next tree will start.
    pub fn bit_len(&self) -> u64 {
        self.bit_len
    }

    fn push(&mut self, b: bool) {
        let word = (self.bit_len >> 5) as usize;
        if word == self.words.len() {
            self.words.push(0);
        }
        if b {
            self.words[word] |= 1 << (self.bit_len & 31);
        }
        self.bit_len += 1;
    }

    /// Appends one triangle's tree given its breadth-first subdivided flags and returns its
    /// `bits_start`. Flags that are not one complete tree of depth at most [`MAX_TREE_DEPTH`] are
    /// refused ([`TreeError::Incomplete`], [`TreeError::TooDeep`]) and nothing is written.
    pub fn push_tree(&mut self, subdivided: &[bool]) -> Result<u64, TreeError> {
        check_flags(subdivided)?;
        let start = self.bit_len;
        for &f in subdivided {
            self.push(f);
        }
        Ok(start)
    }

    /// The words and bit length, for [`crate::Object::bits`] and [`crate::Object::bit_len`].
    pub fn finish(self) -> (Vec<u32>, u64) {
        (self.words, self.bit_len)
    }
}

/// Checks that breadth-first flags describe one complete tree within the depth bound.
pub fn check_flags(subdivided: &[bool]) -> Result<TreeShape, TreeError> {
    let s = subdivided.iter().filter(|&&f| f).count();
    if subdivided.len() != 1 + 4 * s {
        return Err(TreeError::Incomplete {
            flags: subdivided.len(),
            subdivided: s,
        });
    }
    let mut w = BitWriter::new();
    for &f in subdivided {
        w.push(f);
    }
    decode_shape(&w.words, w.bit_len, 0)
}

/// Encodes one tree into a fresh stream: `(words, bit_len)`.
pub fn encode_tree(subdivided: &[bool]) -> Result<(Vec<u32>, u64), TreeError> {
    let mut w = BitWriter::new();
    w.push_tree(subdivided)?;
    Ok(w.finish())
}

#[cfg(test)]
mod tests {
    use super::*;

    fn spec_example() -> Vec<bool> {
        [1, 0, 0, 1, 0, 0, 0, 0, 0].map(|b| b == 1).to_vec()
    }

    #[test]
    fn spec_example_decodes_as_documented() {
        let (words, len) = encode_tree(&spec_example()).unwrap();
        assert_eq!(words, vec![0b1001]);
        let t = Tree::new(&words, len, 0).unwrap();
        assert_eq!(
            t.shape(),
            TreeShape {
                node_count: 9,
                subdivided: 2,
                depth: 2
            }
        );
        assert_eq!(t.child(0, 2), Some(3));
        assert_eq!(t.child(3, 0), Some(5));
        assert_eq!(t.child(3, 3), Some(8));
        assert_eq!(t.child(1, 0), None);
        // Path Center, Right, then anything: node 8 at depth 2.
        assert_eq!(t.find([2, 3, 1, 1]), (8, 2));
        assert_eq!(t.find_path(3, 0b10_11_01), (8, 2));
        assert_eq!(t.find([1, 2]), (2, 1));
        let depths: Vec<u32> = t.nodes().map(|n| n.depth).collect();
        assert_eq!(depths, vec![0, 1, 1, 1, 1, 2, 2, 2, 2]);
    }

    #[test]
    fn incomplete_and_too_deep_trees_are_rejected() {
        assert_eq!(
            encode_tree(&[true, false]),
            Err(TreeError::Incomplete {
                flags: 2,
                subdivided: 1
            })
        );
        // Bits that keep subdividing the first child hit the depth bound.
        let words = vec![u32::MAX; 64];
        let err = decode_shape(&words, 64 * 32, 0).unwrap_err();
        assert!(matches!(err, TreeError::Truncated { .. }), "{err:?}");
        let words = vec![u32::MAX; (MAX_NODES as usize).div_ceil(32)];
        let err = decode_shape(&words, words.len() as u64 * 32, 0).unwrap_err();
        assert_eq!(
            err,
            TreeError::TooDeep {
                node: (MAX_NODES - (1 << 24)),
                depth: 12
            }
        );
    }

    /// A chain of first children: every node's first child subdivided, `depth` levels deep.
    fn chain(depth: u32) -> Vec<bool> {
        let mut flags = vec![depth > 0];
        for d in 1..=depth {
            flags.extend([d < depth, false, false, false]);
        }
        flags
    }

    #[test]
    fn the_writer_refuses_what_the_validator_rejects() {
        let mut w = BitWriter::new();
        assert_eq!(w.push_tree(&chain(MAX_TREE_DEPTH)), Ok(0));
        let len = w.bit_len();
        assert_eq!(len, 1 + 4 * u64::from(MAX_TREE_DEPTH));
        assert_eq!(
            w.push_tree(&chain(MAX_TREE_DEPTH + 1)),
            Err(TreeError::TooDeep {
                node: 1 + 4 * (MAX_TREE_DEPTH - 1),
                depth: MAX_TREE_DEPTH
            })
        );
        assert_eq!(
            w.push_tree(&[true, false, false]),
            Err(TreeError::Incomplete {
                flags: 3,
                subdivided: 1
            })
        );
        // A refused tree writes nothing.
        assert_eq!(w.bit_len(), len);
        let (words, bit_len) = w.finish();
        assert_eq!(
            Tree::new(&words, bit_len, 0).unwrap().depth(),
            MAX_TREE_DEPTH
        );
    }

    #[test]
    fn resumed_streams_append_after_bit_len() {
        // Garbage past bit_len (3 bits) in the last word and a spare word are dropped.
        let mut w = BitWriter::resume(vec![0xffff_fff5, 7], 3);
        assert_eq!(w.push_tree(&[true, false, false, false, false]), Ok(3));
        let (words, bit_len) = w.finish();
        assert_eq!((words, bit_len), (vec![0b1_101], 8));
        // A bit length beyond the words stored is clamped to them.
        assert_eq!(BitWriter::resume(vec![1], 40).bit_len(), 32);
    }

    #[test]
    fn reading_stops_at_the_words_stored() {
        // A bit length larger than the words hold is a truncated tree, not zeros.
        assert!(matches!(
            Tree::new(&[u32::MAX], 1000, 0),
            Err(TreeError::Truncated {
                bit: 32,
                bit_len: 32,
                ..
            })
        ));
    }

    #[test]
    fn truncated_stream_names_the_node() {
        let (words, _) = encode_tree(&spec_example()).unwrap();
        assert_eq!(
            decode_shape(&words, 6, 0),
            Err(TreeError::Truncated {
                node: 6,
                bit: 6,
                bit_len: 6
            })
        );
    }

    #[test]
    fn rank_crosses_word_boundaries() {
        // A uniform tree of depth 3: 1 + 4 + 16 subdivided, 85 nodes.
        let flags: Vec<bool> = (0..85).map(|k| k < 21).collect();
        let mut w = BitWriter::new();
        w.push(true); // offset the tree so it straddles words.
        w.push(false);
        let start = w.push_tree(&flags).unwrap();
        let (words, len) = w.finish();
        let t = Tree::new(&words, len, start).unwrap();
        assert_eq!(t.node_count(), 85);
        assert_eq!(t.depth(), 3);
        assert_eq!(t.rank(40), 21);
        assert_eq!(t.child(20, 3), Some(84));
        // The last level-3 node along the path Right, Right, Right.
        assert_eq!(t.find([3, 3, 3]), (84, 3));
    }
}
