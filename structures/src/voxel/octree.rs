//! The canonical voxel octree every voxel structure converts from (svo → svo-naive, esvo, svdag;
//! STYLE.md's "one canonical build, many layouts").
//!
//! Levels run from the root (level 0, one voxel) to the leaves (level L, the voxels of the
//! voxelisation). Each level is in Morton order, and the children of a level-`l` voxel are a
//! contiguous run of level `l + 1`, so the level arrays concatenated are the breadth-first order
//! with Morton order inside a level (seed 001 §2.1).
//!
//! [`OctreeBuilder`] is fed leaves in increasing Morton order (the voxeliser's chunks) and closes
//! each interior voxel as soon as the stream leaves it, bottom-up, so it never holds more than
//! one open voxel per level besides the finished arrays.

use glam::Vec3;

use super::{VoxelAttr, VoxelChunk, VoxelGrid};

/// One level of the octree.
#[derive(Clone, Debug, Default)]
pub struct OctreeLevel {
    /// Morton codes at this level (empty for the leaf level, whose codes follow from their
    /// parents' masks).
    pub codes: Vec<u64>,
    /// Child masks, bit `i` = child slot `i` is set (interior levels only).
    pub masks: Vec<u8>,
    /// Index of the first child in the next level's arrays (interior levels only).
    pub first_child: Vec<u32>,
    /// Attributes: the voxelisation's for leaves, the mean of the children's for interior voxels.
    pub attrs: Vec<VoxelAttr>,
}

impl OctreeLevel {
    pub fn len(&self) -> usize {
        self.attrs.len()
    }

    pub fn is_empty(&self) -> bool {
        self.attrs.is_empty()
    }
}

/// A voxel octree, level by level.
#[derive(Clone, Debug)]
pub struct Octree {
    pub grid: VoxelGrid,
    /// `grid.level + 1` levels; level 0 holds the root unless the octree is empty.
    pub levels: Vec<OctreeLevel>,
}

impl Octree {
    /// Leaf voxels.
    pub fn voxel_count(&self) -> u64 {
        self.levels.last().map_or(0, |l| l.len() as u64)
    }

    /// Interior voxels (every level but the last).
    pub fn interior_count(&self) -> u64 {
        self.levels[..self.levels.len() - 1].iter().map(|l| l.len() as u64).sum()
    }

    pub fn is_empty(&self) -> bool {
        self.levels[0].is_empty()
    }

    /// Morton code (at level `l + 1`) of child slot `slot` of voxel `i` at level `l`.
    pub fn child_code(&self, l: usize, i: usize, slot: u32) -> u64 {
        (self.levels[l].codes[i] << 3) | slot as u64
    }
}

/// An interior voxel whose children are still arriving.
#[derive(Clone, Copy, Debug)]
struct OpenVoxel {
    code: u64,
    mask: u8,
    first_child: u32,
    normal_sum: Vec3,
    color_sum: Vec3,
    children: u32,
}

/// Builds an [`Octree`] from leaves streamed in strictly increasing Morton order.
pub struct OctreeBuilder {
    grid: VoxelGrid,
    levels: Vec<OctreeLevel>,
    open: Vec<Option<OpenVoxel>>,
    last_leaf: Option<u64>,
    /// The level of the subtree's root: levels above it stay empty (see [`OctreeBuilder::subtree`]).
    top: usize,
}

impl OctreeBuilder {
    pub fn new(grid: VoxelGrid) -> Self {
        let n = grid.level as usize + 1;
        Self { grid, levels: vec![OctreeLevel::default(); n], open: vec![None; n], last_leaf: None, top: 0 }
    }

    /// A builder of the subtree under one voxel at level `top`: every leaf pushed must lie in that
    /// voxel's cube. The result keeps the grid's level numbering, with levels above `top` empty
    /// and the subtree's root alone at level `top` (ESVO's build converts the voxeliser's
    /// sub-cubes one at a time this way).
    pub fn subtree(grid: VoxelGrid, top: u32) -> Self {
        assert!(top <= grid.level, "subtree root level {top} is below the leaves ({})", grid.level);
        Self { top: top as usize, ..Self::new(grid) }
    }

    /// Adds a chunk of leaves; its codes must continue the strictly increasing order.
    pub fn push_chunk(&mut self, chunk: &VoxelChunk) {
        for (&code, attr) in chunk.codes.iter().zip(&chunk.attrs) {
            self.push_leaf(code, *attr);
        }
    }

    pub fn push_leaf(&mut self, code: u64, attr: VoxelAttr) {
        assert!(self.last_leaf.is_none_or(|last| code > last), "leaves must arrive in increasing Morton order");
        self.last_leaf = Some(code);
        let leaf = self.grid.level as usize;
        let index = self.levels[leaf].len() as u32;
        self.levels[leaf].attrs.push(attr);
        self.add_to_parent(leaf, code, index, attr);
    }

    /// Records the finished voxel `code` (at `level`, stored at `index`) in its parent, closing
    /// the parent's predecessor first if the stream has left it.
    fn add_to_parent(&mut self, level: usize, code: u64, index: u32, attr: VoxelAttr) {
        if level == self.top {
            return;
        }
        let parent = code >> 3;
        let slot = (code & 7) as u8;
        match &mut self.open[level - 1] {
            Some(open) if open.code == parent => {
                open.mask |= 1 << slot;
                open.normal_sum += attr.normal;
                open.color_sum += attr.color;
                open.children += 1;
            }
            _ => {
                self.close(level - 1);
                self.open[level - 1] = Some(OpenVoxel {
                    code: parent,
                    mask: 1 << slot,
                    first_child: index,
                    normal_sum: attr.normal,
                    color_sum: attr.color,
                    children: 1,
                });
            }
        }
    }

    /// Finishes the open voxel at `level`, if any, appending it to its level.
    fn close(&mut self, level: usize) {
        let Some(open) = self.open[level].take() else { return };
        let attr =
            VoxelAttr { normal: open.normal_sum.normalize_or_zero(), color: open.color_sum / open.children as f32 };
        let out = &mut self.levels[level];
        let index = out.len() as u32;
        out.codes.push(open.code);
        out.masks.push(open.mask);
        out.first_child.push(open.first_child);
        out.attrs.push(attr);
        self.add_to_parent(level, open.code, index, attr);
    }

    pub fn finish(mut self) -> Octree {
        for level in (self.top..self.grid.level as usize).rev() {
            self.close(level);
        }
        Octree { grid: self.grid, levels: self.levels }
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::voxel::morton;

    fn grid(level: u32) -> VoxelGrid {
        VoxelGrid { origin: Vec3::ZERO, size: 1.0, level }
    }

    #[test]
    fn levels_are_breadth_first_in_morton_order_with_consistent_masks() {
        let level = 4;
        let mut codes: Vec<u64> = (0..300u64).map(|i| (i * 2654435761) % (1 << (3 * level))).collect();
        codes.sort_unstable();
        codes.dedup();
        let mut b = OctreeBuilder::new(grid(level));
        for &c in &codes {
            b.push_leaf(c, VoxelAttr { normal: Vec3::X, color: Vec3::ONE });
        }
        let tree = b.finish();
        assert_eq!(tree.levels[0].len(), 1);
        assert_eq!(tree.voxel_count(), codes.len() as u64);
        // Walking the masks from the root reproduces exactly the leaf codes, in order.
        let mut frontier = vec![(0u64, 0usize)];
        for l in 0..level as usize {
            let mut next = Vec::new();
            for &(code, i) in &frontier {
                assert_eq!(tree.levels[l].codes[i], code);
                let mask = tree.levels[l].masks[i];
                let mut child = tree.levels[l].first_child[i] as usize;
                for slot in 0..8u64 {
                    if mask >> slot & 1 == 1 {
                        next.push(((code << 3) | slot, child));
                        child += 1;
                    }
                }
            }
            assert_eq!(next.len(), tree.levels[l + 1].len(), "level {} is exactly the children", l + 1);
            frontier = next;
        }
        let leaves: Vec<u64> = frontier.iter().map(|&(c, _)| c).collect();
        assert_eq!(leaves, codes);
        assert!(frontier.iter().enumerate().all(|(k, &(_, i))| i == k), "leaf indices are Morton order");
        assert_eq!(morton::decode(codes[0]).len(), 3);
    }

    #[test]
    fn empty_stream_gives_an_empty_tree() {
        let tree = OctreeBuilder::new(grid(3)).finish();
        assert!(tree.is_empty());
        assert_eq!(tree.voxel_count(), 0);
    }
}
