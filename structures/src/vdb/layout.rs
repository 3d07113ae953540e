//! The VDB tree's words (Museth, "VDB: High-Resolution Sparse Volumes with Dynamic Topology",
//! ACM TOG 2013; NanoVDB's linearised layout), exactly as the CPU kernel reads them and the GPU
//! receives them: a root table of top nodes, fixed-size interior nodes level by level (OpenVDB's
//! `InternalNode`s, the upper and lower nodes of the default 5-4-3 tree), and bit-mask leaves
//! (`LeafNode<ValueMask>`, a mask grid: the voxelisation carries no values).
//!
//! Two arrays, reached by word offsets, never pointers:
//! - `words`: the root table, then every interior level's nodes in order (upper, lower, …), all
//!   nodes of a level the same size ([`Sizes`]);
//! - `leaves`: the leaves, all the same size.
//!
//! A child reference is a word index: into `words` for an interior child, into `leaves` for a
//! leaf. Child slots and voxel bits are numbered by local Morton code (x in bit 0; see
//! [`crate::voxel::wide::local_slot`]), so the voxeliser's stream meets every node's children in
//! slot order; NanoVDB numbers them row-major, which changes no byte count.
//!
//! **`dense` tables** (`vdb.tables=dense`, NanoVDB's layout, byte for byte; `PNanoVDB.h`'s
//! `pnanovdb_grid_type_constants`):
//! - root: a 16-word (64-byte) header, word 0 the tile count, then 8 words (32 bytes) per tile:
//!   key low, key high, child, then state and value words (zero);
//! - interior node with `b` bits per axis: 8 header words (the node's first voxel x, y, z, its
//!   level, then zero for the bounding box and flags), the value mask (zero: no active tiles in
//!   a surface voxelisation), the child mask, 8 words of statistics (zero), then the
//!   direct-access table of 2 words (8 bytes) per slot: `[child, 0]`, or `[0, 0]` for an empty
//!   slot. 5-4-3's upper node is 270,400 bytes, its lower node 33,856;
//! - leaf: its first voxel x, y, z and a flags word, the voxel mask, then zero words to a
//!   32-byte boundary: 96 bytes for an 8³ leaf.
//!
//! **`compact` tables** (`vdb.tables=compact`, PicoVDB's rank compression): the child mask with
//! a rank table and one offset per node instead of a table entry per slot:
//! - root: word 0 the tile count, then 3 words per tile: key low, key high, child;
//! - interior node: `[first child]`, the child mask, then one rank word per 64 slots (the set
//!   bits before them). Children are contiguous in slot order: child `s` is at
//!   `first + (rank[s / 64] + popcount(mask64[s / 64] & ((1 << s % 64) − 1))) · child size`
//!   ([`compact_child_index`]);
//! - leaf: the voxel mask alone.
//!
//! Root tiles are sorted by key, the Morton code of the top node's coordinates (`voxel >> S`,
//! `S` the sum of the levels' bits), and found by binary search.

use serde::Serialize;

use crate::voxel::wide::MAX_DDA_LEVELS;

/// How interior nodes find their children (`vdb.tables`).
#[derive(Clone, Copy, Debug, PartialEq, Eq, Serialize)]
#[serde(rename_all = "lowercase")]
pub enum Tables {
    /// NanoVDB's direct-access tables: 8 bytes per child slot.
    Dense,
    /// A child mask with popcount rank into a packed child list (PicoVDB).
    Compact,
}

impl Tables {
    pub fn name(self) -> &'static str {
        match self {
            Tables::Dense => "dense",
            Tables::Compact => "compact",
        }
    }
}

/// Header words of a dense interior node (NanoVDB: 24-byte bounding box, 8 bytes of flags).
pub const DENSE_HEADER: usize = 8;
/// Statistics words of a dense interior node, between the masks and the table.
pub const DENSE_STATS: usize = 8;
/// Header words of a dense leaf (origin and flags: 16 bytes).
pub const DENSE_LEAF_HEADER: usize = 4;
/// Dense nodes are padded to this many words (NanoVDB's 32-byte alignment).
pub const DENSE_ALIGN: usize = 8;
/// Words of the dense root's header, and per tile.
pub const DENSE_ROOT_HEADER: usize = 16;
pub const DENSE_TILE: usize = 8;
/// Words per tile of the compact root.
pub const COMPACT_TILE: usize = 3;

/// Mask words of a node with `bits` bits per axis (`2^(3·bits)` slots, at least one word).
pub fn mask_words(bits: u32) -> usize {
    (1usize << (3 * bits)).div_ceil(32)
}

/// Rank words of a compact node: one per 64 slots (at least one).
pub fn rank_words(bits: u32) -> usize {
    (1usize << (3 * bits)).div_ceil(64)
}

/// The word layout of one tree: node and leaf sizes and where their fields are.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub struct Sizes {
    pub tables: Tables,
}

impl Sizes {
    /// Words of an interior node with `bits` bits per axis.
    pub fn node_words(self, bits: u32) -> usize {
        let m = mask_words(bits);
        match self.tables {
            Tables::Dense => DENSE_HEADER + 2 * m + DENSE_STATS + 2 * (1 << (3 * bits)),
            Tables::Compact => 1 + m + rank_words(bits),
        }
    }

    /// Words of a leaf with `bits` bits per axis.
    pub fn leaf_words(self, bits: u32) -> usize {
        let m = mask_words(bits);
        match self.tables {
            Tables::Dense => (DENSE_LEAF_HEADER + m).next_multiple_of(DENSE_ALIGN),
            Tables::Compact => m,
        }
    }

    /// Offset of an interior node's child mask.
    pub fn child_mask(self, bits: u32) -> usize {
        match self.tables {
            Tables::Dense => DENSE_HEADER + mask_words(bits),
            Tables::Compact => 1,
        }
    }

    /// Offset of a dense node's table (or a compact node's rank words).
    pub fn table(self, bits: u32) -> usize {
        match self.tables {
            Tables::Dense => DENSE_HEADER + 2 * mask_words(bits) + DENSE_STATS,
            Tables::Compact => 1 + mask_words(bits),
        }
    }

    /// Offset of a leaf's voxel mask.
    pub fn leaf_mask(self) -> usize {
        match self.tables {
            Tables::Dense => DENSE_LEAF_HEADER,
            Tables::Compact => 0,
        }
    }

    /// Words of the root table with `tiles` tiles, and of each tile.
    pub fn root_words(self, tiles: usize) -> usize {
        match self.tables {
            Tables::Dense => DENSE_ROOT_HEADER + DENSE_TILE * tiles,
            Tables::Compact => 1 + COMPACT_TILE * tiles,
        }
    }

    /// Word of tile `i`'s key (low word; the high word follows, then the child).
    pub fn tile(self, i: usize) -> usize {
        match self.tables {
            Tables::Dense => DENSE_ROOT_HEADER + DENSE_TILE * i,
            Tables::Compact => 1 + COMPACT_TILE * i,
        }
    }
}

impl Sizes {
    /// The word offset of child `slot` of the interior node at word `node` (with `bits` bits per
    /// axis), `None` if the slot is empty; `child_words` is the size of one child (a compact
    /// node's children are a packed list of them).
    #[inline(always)]
    pub fn child(self, words: &[u32], node: usize, bits: u32, slot: u32, child_words: u32) -> Option<u32> {
        let mask = &words[node + self.child_mask(bits)..];
        if !bit(mask, slot) {
            return None;
        }
        let table = node + self.table(bits);
        Some(match self.tables {
            Tables::Dense => words[table + 2 * slot as usize],
            Tables::Compact => words[node] + compact_child_index(mask, &words[table..], slot) * child_words,
        })
    }

    /// The child of the root tile whose key is `key` (binary search over the sorted keys), `None`
    /// if there is no such tile.
    #[inline]
    pub fn find_tile(self, words: &[u32], key: u64) -> Option<u32> {
        let tiles = *words.first()? as usize;
        let key_at = |i: usize| words[self.tile(i)] as u64 | (words[self.tile(i) + 1] as u64) << 32;
        let (mut lo, mut hi) = (0, tiles);
        while lo < hi {
            let mid = (lo + hi) / 2;
            match key_at(mid).cmp(&key) {
                std::cmp::Ordering::Less => lo = mid + 1,
                std::cmp::Ordering::Greater => hi = mid,
                std::cmp::Ordering::Equal => return Some(words[self.tile(mid) + 2]),
            }
        }
        None
    }

    /// [`Self::find_tile`], telling `read` each run of words it reads (first word, count) in
    /// order — the tile count, each probed key, the child found — for a GPU memory model. Its own
    /// body: `find_tile` written as this with a no-op `read` compiled differently (±2 % of a
    /// traversal's instructions under callgrind), and `find_tile` is on the timed path.
    #[inline]
    pub fn find_tile_reading(self, words: &[u32], key: u64, mut read: impl FnMut(usize, usize)) -> Option<u32> {
        let tiles = *words.first()? as usize;
        read(0, 1);
        let (mut lo, mut hi) = (0, tiles);
        while lo < hi {
            let mid = (lo + hi) / 2;
            let at = self.tile(mid);
            read(at, 2);
            match (words[at] as u64 | (words[at + 1] as u64) << 32).cmp(&key) {
                std::cmp::Ordering::Less => lo = mid + 1,
                std::cmp::Ordering::Greater => hi = mid,
                std::cmp::Ordering::Equal => {
                    read(at + 2, 1);
                    return Some(words[at + 2]);
                }
            }
        }
        None
    }
}

/// Where a traversal finds each level's cells, per level of cells `k` (0 = the top nodes, read
/// from the root table; the last, the voxels): the bits per axis of a cell in its parent, where
/// the parent's child mask and table (or rank words) are, and the size of one cell's node (a
/// compact parent's children are a packed list of them; 0 for the voxels).
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub struct LevelOffsets {
    pub bits: [u32; MAX_DDA_LEVELS],
    pub mask_at: [u32; MAX_DDA_LEVELS],
    pub table_at: [u32; MAX_DDA_LEVELS],
    pub child_words: [u32; MAX_DDA_LEVELS],
}

impl LevelOffsets {
    /// The offsets of a tree with `log2` bits per level (top nodes first, leaves last).
    pub fn new(sizes: Sizes, log2: &[u32]) -> Self {
        let voxels = log2.len();
        let mut o = Self {
            bits: [0; MAX_DDA_LEVELS],
            mask_at: [0; MAX_DDA_LEVELS],
            table_at: [0; MAX_DDA_LEVELS],
            child_words: [0; MAX_DDA_LEVELS],
        };
        for k in 1..=voxels {
            let b = log2[k - 1];
            o.bits[k] = b;
            o.mask_at[k] = if k == voxels { sizes.leaf_mask() } else { sizes.child_mask(b) } as u32;
            o.table_at[k] = sizes.table(b) as u32;
            o.child_words[k] = match k + 1 {
                next if next == voxels => sizes.leaf_words(log2[k]),
                next if next < voxels => sizes.node_words(log2[k]),
                _ => 0,
            } as u32;
        }
        o
    }
}

/// Whether bit `s` of a mask stored as `u32` words is set.
#[inline(always)]
pub fn bit(mask: &[u32], s: u32) -> bool {
    mask[(s >> 5) as usize] >> (s & 31) & 1 == 1
}

/// Index in its node's packed child list of child `s` of a compact node whose child mask and rank
/// words are `mask` and `rank` (the child must be set).
#[inline(always)]
pub fn compact_child_index(mask: &[u32], rank: &[u32], s: u32) -> u32 {
    let g = (s >> 6) as usize;
    let within = s & 63;
    let low = mask[2 * g];
    let below = |w: u32, n: u32| (w & ((1u32 << n) - 1)).count_ones();
    rank[g] + if within < 32 { below(low, within) } else { low.count_ones() + below(mask[2 * g + 1], within - 32) }
}

#[cfg(test)]
mod tests {
    use super::*;

    /// NanoVDB's node sizes for a mask grid (`PNanoVDB.h`): the default tree's dense nodes are
    /// byte for byte the same size.
    #[test]
    fn dense_nodes_are_nanovdbs_sizes() {
        let dense = Sizes { tables: Tables::Dense };
        assert_eq!(dense.node_words(5) * 4, 270_400);
        assert_eq!(dense.node_words(4) * 4, 33_856);
        assert_eq!(dense.leaf_words(3) * 4, 96);
        assert_eq!(dense.table(5) * 4, 8256);
        assert_eq!(dense.table(4) * 4, 1088);
        assert_eq!(dense.root_words(3) * 4, 64 + 3 * 32);
        let compact = Sizes { tables: Tables::Compact };
        assert_eq!(compact.node_words(4) * 4, 4 + 512 + 256);
        assert_eq!(compact.leaf_words(3) * 4, 64);
        assert_eq!(compact.node_words(1), 3);
    }

    #[test]
    fn compact_rank_counts_the_set_slots_before() {
        // 128 slots: bits 3, 40, 64, 100, 127.
        let set = [3u32, 40, 64, 100, 127];
        let mut mask = [0u32; 4];
        for &s in &set {
            mask[(s >> 5) as usize] |= 1 << (s & 31);
        }
        let rank = [0, 2];
        for (i, &s) in set.iter().enumerate() {
            assert!(bit(&mask, s));
            assert_eq!(compact_child_index(&mask, &rank, s), i as u32);
        }
        assert!(!bit(&mask, 4));
    }
}
