//! Emitting an octree's descriptors into ESVO's blocks (seed 000 §5.1): depth-first within a
//! block, far pointers where a 15-bit offset does not reach, subtrees placed whole where they fit
//! and split where no block holds them.

use super::Attributes;
use super::attributes::{encode_abgr, encode_normal};
use super::blocks::{Below, BlockWriter, OpenBlock, Slot};
use super::layout::limit;
use super::layout::*;
use crate::BuildError;
use crate::voxel::Octree;

/// Offsets predicted above this many slots get a far pointer. The prediction leaves out page
/// headers and the padding before a run that would straddle a page (at most 17 slots per page
/// crossed), so the margin keeps every near pointer within [`CHILD_PTR_MAX`].
const FAR_THRESHOLD: u64 = CHILD_PTR_MAX as u64 - 600;

/// Emits one octree's descriptors into a [`BlockWriter`]: a sub-cube's (from its root's group
/// down) or the trunk's (from the root's descriptor; its deepest descriptors' groups are the
/// sub-cubes', given as `externals`).
pub(super) struct Emitter<'a> {
    /// The trees emitted since the writer last settled; this emission's is `trees[id]`.
    trees: &'a [Octree],
    id: u32,
    tree: &'a Octree,
    contours: &'a [Vec<u32>],
    /// Global group slots of the voxels at `tree`'s deepest descriptor level, when their
    /// children are not leaves (the trunk).
    externals: &'a [u64],
    /// The leaf level `L`.
    leaves: usize,
    /// Per level from the subtree's root, per voxel with a group: what its subtree adds to a
    /// block, the group's far flags included.
    below: Vec<Vec<Below>>,
}

impl<'a> Emitter<'a> {
    /// `top`: the level of `tree`'s root.
    pub(super) fn new(
        trees: &'a [Octree],
        id: usize,
        contours: &'a [Vec<u32>],
        externals: &'a [u64],
        top: usize,
    ) -> Self {
        let tree = &trees[id];
        let leaves = tree.grid.level as usize;
        let depth = tree.levels.len() - 1;
        let mut e = Self { trees, id: id as u32, tree, contours, externals, leaves, below: vec![Vec::new(); depth] };
        // Bottom-up over the voxels with groups (children not leaves).
        for l in (top..depth.min(leaves - 1)).rev() {
            if e.is_external(l) {
                continue;
            }
            let level = &tree.levels[l];
            let below: Vec<Below> = (0..level.len())
                .map(|i| {
                    let (first, m) = (level.first_child[i] as usize, level.masks[i].count_ones() as usize);
                    let mut b = Below { slots: m as u64 + 1, ..Below::default() };
                    let subs: Vec<u64> = (first..first + m).map(|c| e.child_below(l + 1, c).slots).collect();
                    b.slots += far_flags(&subs, e.forced_far(l + 1, m)).count_ones() as u64;
                    for c in first..first + m {
                        b.add(e.descriptor_cost(l + 1, c));
                        b.add(e.child_below(l + 1, c));
                    }
                    b
                })
                .collect();
            e.below[l] = below;
        }
        e
    }

    /// Whether voxel `i` at `level` has a group of descriptors below it (its children are not
    /// leaves), and whether that group lies outside this tree.
    fn has_group(&self, level: usize) -> bool {
        level + 1 < self.leaves
    }

    fn is_external(&self, level: usize) -> bool {
        self.has_group(level) && level + 1 == self.tree.levels.len() - 1
    }

    fn child_below(&self, level: usize, i: usize) -> Below {
        if self.has_group(level) && !self.is_external(level) { self.below[level][i] } else { Below::default() }
    }

    /// The `m` children at `level` of one voxel that need a far pointer whatever the
    /// distance: those whose groups are external.
    fn forced_far(&self, level: usize, m: usize) -> u8 {
        if self.is_external(level) { ((1u32 << m) - 1) as u8 } else { 0 }
    }

    /// What the descriptor of voxel `i` at `level` brings into its block besides its slot: its
    /// children's contours and (raw) values.
    fn descriptor_cost(&self, level: usize, i: usize) -> Below {
        let node = &self.tree.levels[level];
        let (first, m) = (node.first_child[i] as usize, node.masks[i].count_ones() as usize);
        let contours = self.contours.get(level + 1).filter(|c| !c.is_empty());
        Below {
            slots: 0,
            contours: contours.map_or(0, |c| c[first..first + m].iter().filter(|&&w| w != 0).count() as u64),
            values: m as u64,
        }
    }

    /// The root's descriptor and everything below it; returns the root's global slot.
    pub(super) fn emit_root(&self, w: &mut BlockWriter) -> Result<u64, BuildError> {
        let mut whole = self.descriptor_cost(0, 0);
        whole.slots += 2;
        whole.add(self.child_below(0, 0));
        if !w.open.fits(whole, w.cap) && !w.open.is_empty() {
            w.next_block(self.trees)?;
        }
        // The root's group is never external: a tree of one sub-cube is emitted from its root,
        // and a trunk's root lies above its sub-cubes' roots.
        debug_assert!(!self.is_external(0));
        if !self.has_group(0) || w.open.fits(whole, w.cap) {
            // The common case: the root's group follows it in the same block.
            let slot = w.alloc(1);
            self.write_second_word(w, 0, 0, slot)?;
            self.link_inline(w, 0, 0, slot, None)?;
            return Ok(slot);
        }
        let slot = w.alloc(2);
        self.write_second_word(w, 0, 0, slot)?;
        w.reserve_far(slot + 1);
        let group = self.emit_group(w, 0, 0)?;
        self.link_far(w, 0, 0, slot, slot + 1, group)?;
        Ok(slot)
    }

    /// The group below voxel `i` at `level`, wherever it fits (see the module doc); returns its
    /// global slot.
    pub(super) fn emit_group(&self, w: &mut BlockWriter, level: usize, i: usize) -> Result<u64, BuildError> {
        let below = self.below[level][i];
        if !w.open.fits(below, w.cap) && !w.open.is_empty() && OpenBlock::new(0).fits(below, w.cap) {
            w.next_block(self.trees)?;
        }
        if w.open.fits(below, w.cap) {
            return self.inline_group(w, level, i);
        }
        // Larger than any block: the group here, each child's subtree placed on its own.
        let node = &self.tree.levels[level];
        let (first, m) = (node.first_child[i] as usize, node.masks[i].count_ones() as usize);
        let mut group_cost = Below { slots: 2 * m as u64 + 1, ..Below::default() };
        (first..first + m).for_each(|c| group_cost.add(self.descriptor_cost(level + 1, c)));
        if !w.open.fits(group_cost, w.cap) {
            w.next_block(self.trees)?;
        }
        let far_count = if self.has_group(level + 1) { m } else { 0 };
        let group = w.alloc(m + far_count);
        for k in 0..m {
            self.write_second_word(w, level + 1, first + k, group + k as u64)?;
        }
        if far_count == 0 {
            for k in 0..m {
                self.link_inline(w, level + 1, first + k, group + k as u64, None)?;
            }
            return Ok(group);
        }
        for k in 0..m {
            w.reserve_far(group + (m + k) as u64);
        }
        for k in 0..m {
            let child = first + k;
            let target =
                if self.is_external(level + 1) { self.externals[child] } else { self.emit_group(w, level + 1, child)? };
            self.link_far(w, level + 1, child, group + k as u64, group + (m + k) as u64, target)?;
        }
        Ok(group)
    }

    /// The group below voxel `i` at `level` and its whole subtree, in the open block (it fits).
    fn inline_group(&self, w: &mut BlockWriter, level: usize, i: usize) -> Result<u64, BuildError> {
        let node = &self.tree.levels[level];
        let (first, m) = (node.first_child[i] as usize, node.masks[i].count_ones() as usize);
        let subs: Vec<u64> = (first..first + m).map(|c| self.child_below(level + 1, c).slots).collect();
        let flags = far_flags(&subs, self.forced_far(level + 1, m));
        let f = flags.count_ones() as usize;
        let group = w.alloc(m + f);
        let mut next_far = group + m as u64;
        for k in 0..m {
            let far = (flags >> k & 1 == 1).then(|| {
                w.reserve_far(next_far);
                next_far += 1;
                next_far - 1
            });
            let slot = group + k as u64;
            self.write_second_word(w, level + 1, first + k, slot)?;
            self.link_inline(w, level + 1, first + k, slot, far)?;
        }
        Ok(group)
    }

    /// The descriptor of voxel `i` at `level` in `slot`: its children's contours and (raw) values
    /// go to the open block now, which holds `slot`.
    fn write_second_word(&self, w: &mut BlockWriter, level: usize, i: usize, slot: u64) -> Result<(), BuildError> {
        let node = &self.tree.levels[level];
        let mask = node.masks[i] as u32;
        let first = node.first_child[i] as usize;
        let s = w.local(slot).expect("a descriptor is written while its block is open");
        w.open.kinds[s] = Slot::Descriptor { tree: self.id, level: level as u8, voxel: i as u32 };
        w.stats.descriptors += 1;
        // Second word: the children's contours, consecutive (block-local index until the block
        // closes and the pointer becomes relative to the descriptor).
        let mut contour_mask = 0;
        let local = w.open.contours.len() as u32;
        if let Some(level_contours) = self.contours.get(level + 1).filter(|c| !c.is_empty()) {
            for (k, c) in (0..8).filter(|c| mask >> c & 1 == 1).enumerate() {
                let word = level_contours[first + k];
                if word != 0 {
                    contour_mask |= 1 << c;
                    w.open.contours.push(word);
                }
            }
        }
        w.open.slots[s][1] = if contour_mask != 0 { (local << CONTOUR_PTR_SHIFT) | contour_mask } else { 0 };
        // Raw attachment: one value per valid child.
        if w.attributes == Attributes::Raw {
            let value_ptr = (w.open.values.len() / 2) as u64;
            if value_ptr > VALUE_PTR_MAX as u64 {
                return Err(limit(format!(
                    "a value pointer needs {value_ptr}, past the 24-bit field ({VALUE_PTR_MAX}): \
                     the block was filled past its prediction"
                )));
            }
            let lookups = &mut w.open.lookups;
            lookups.resize(lookups.len().max(s + 1), 0);
            lookups[s] = ((value_ptr as u32) << VALUE_PTR_SHIFT) | mask;
            for k in 0..mask.count_ones() as usize {
                let a = self.tree.levels[level + 1].attrs[first + k];
                w.open.values.extend([encode_abgr(a.color), encode_normal(a.normal)]);
            }
        }
        Ok(())
    }

    /// The first word of the descriptor in `slot`, its group laid out right here (its whole
    /// subtree fits the open block), or external, through the far slot `far` its parent reserved.
    fn link_inline(
        &self,
        w: &mut BlockWriter,
        level: usize,
        i: usize,
        slot: u64,
        far: Option<u64>,
    ) -> Result<(), BuildError> {
        let mask = self.tree.levels[level].masks[i] as u32;
        if !self.has_group(level) {
            w.set_w0(slot, descriptor_w0(0, false, mask, mask));
            return Ok(());
        }
        let group = if self.is_external(level) { self.externals[i] } else { self.inline_group(w, level, i)? };
        match far {
            Some(far) => self.link_far(w, level, i, slot, far, group),
            None => {
                let offset = group - slot;
                assert!(
                    offset <= CHILD_PTR_MAX as u64,
                    "near child pointer {offset} overflows: far prediction is wrong"
                );
                w.set_w0(slot, descriptor_w0(offset as u32, false, mask, 0));
                Ok(())
            }
        }
    }

    /// The descriptor in `slot` points through the far slot `far` at the group at `group`: a
    /// signed 32-bit offset in slots from the descriptor.
    fn link_far(
        &self,
        w: &mut BlockWriter,
        level: usize,
        i: usize,
        slot: u64,
        far: u64,
        group: u64,
    ) -> Result<(), BuildError> {
        let mask = self.tree.levels[level].masks[i] as u32;
        let offset = group as i64 - slot as i64;
        let Ok(offset) = i32::try_from(offset) else {
            return Err(limit(format!("a far pointer needs {offset} slots, past its signed 32 bits")));
        };
        w.set_w0(far, offset as u32);
        w.set_w0(slot, descriptor_w0((far - slot) as u32, true, mask, 0));
        Ok(())
    }
}

/// Which of the children (with predicted subtree sizes `subs`, laid out in this order right after
/// their group and its far slots) need a far pointer: child `k`'s own group lands
/// `(m − k) + far + Σ_{j<k} subs[j]` slots after it; those in `forced` always do. Iterated to a
/// fixed point, since each far slot moves every later group by one.
fn far_flags(subs: &[u64], forced: u8) -> u8 {
    let m = subs.len() as u64;
    let mut flags = forced;
    loop {
        let far = flags.count_ones() as u64;
        let mut next = forced;
        let mut before = 0u64;
        for (k, &s) in subs.iter().enumerate() {
            // A child whose children are leaves has no group of its own to point at.
            if s > 0 && (m - k as u64) + far + before > FAR_THRESHOLD {
                next |= 1 << k;
            }
            before += s;
        }
        if next == flags {
            return flags;
        }
        flags = next;
    }
}
