//! ESVO's blocks being written (seed 000 §5.1): the open block's descriptor slots, contour data
//! and attachment, closed into the output words — page headers, contour pointers resolved, info
//! section — when the next subtree would not fit.

use std::time::Instant;

use rayon::prelude::*;

use super::attributes::CompressedBlock;
use super::compress::compress_block;
use super::layout::limit;
use super::layout::*;
use super::{Attributes, EsvoStats};
use crate::BuildError;
use crate::ms_since;
use crate::voxel::Octree;

/// What a block may hold: its contour pointers (24 bits, relative to the descriptor) must reach
/// past all its descriptors to its contours, and its raw value pointers (24 bits) all its
/// values. `esvo.block_words` lowers the first (tests force many blocks with it).
#[derive(Clone, Copy, Debug)]
pub(super) struct BlockCap {
    words: u64,
    values: u64,
}

impl BlockCap {
    /// Raw values are bounded by their pointer; compressed attributes have none.
    pub(super) fn new(block_words: u32, attributes: Attributes) -> Self {
        let words = (block_words as u64).min(CONTOUR_PTR_MAX as u64 - INFO_WORDS as u64);
        let values = match attributes {
            Attributes::Raw => words.min(VALUE_PTR_MAX as u64),
            Attributes::Compressed => u64::MAX,
        };
        Self { words, values }
    }
}

/// Words of an info section with its one attachment.
pub(super) const INFO_WORDS: usize = INFO_HEADER_WORDS + 2;

/// What a subtree below a voxel adds to a block, predicted: descriptor slots (far pointers and
/// a slot of alignment per group included, page headers and page padding not), contour words,
/// raw values.
#[derive(Clone, Copy, Debug, Default)]
pub(super) struct Below {
    pub(super) slots: u64,
    pub(super) contours: u64,
    pub(super) values: u64,
}

impl Below {
    pub(super) fn add(&mut self, o: Below) {
        self.slots += o.slots;
        self.contours += o.contours;
        self.values += o.values;
    }
}

/// What a slot of the open block holds (contour pointers and compressed blocks need it).
#[derive(Clone, Copy, PartialEq)]
pub(super) enum Slot {
    Header,
    /// Voxel `voxel` at `level` of the emission's `tree` (an index into the trees the writer
    /// is settled with).
    Descriptor {
        tree: u32,
        level: u8,
        voxel: u32,
    },
    Far,
    Pad,
}

/// The block being filled.
pub(super) struct OpenBlock {
    /// Global slot of its first slot (page-aligned).
    pub(super) base: u64,
    pub(super) slots: Vec<[u32; 2]>,
    pub(super) kinds: Vec<Slot>,
    pub(super) contours: Vec<u32>,
    pub(super) lookups: Vec<u32>,
    pub(super) values: Vec<u32>,
    pub(super) compressed: Vec<CompressedBlock>,
}

impl OpenBlock {
    pub(super) fn new(base: u64) -> Self {
        Self {
            base,
            slots: Vec::new(),
            kinds: Vec::new(),
            contours: Vec::new(),
            lookups: Vec::new(),
            values: Vec::new(),
            compressed: Vec::new(),
        }
    }

    pub(super) fn is_empty(&self) -> bool {
        self.slots.is_empty()
    }

    /// Whether `more` still fits (with an eighth of slack for page headers and padding).
    pub(super) fn fits(&self, more: Below, cap: BlockCap) -> bool {
        let slots = self.slots.len() as u64 + more.slots + more.slots / 8 + 32;
        2 * slots + self.contours.len() as u64 + more.contours <= cap.words
            && (self.values.len() / 2) as u64 + more.values <= cap.values
    }
}

/// The finished words (closed blocks) and the open block; a subtree's emission asks it for
/// room, and it closes blocks as they fill.
pub(super) struct BlockWriter {
    pub(super) attributes: Attributes,
    pub(super) cap: BlockCap,
    pub(super) out: Vec<u32>,
    pub(super) open: OpenBlock,
    pub(super) stats: EsvoStats,
}

impl BlockWriter {
    pub(super) fn new(attributes: Attributes, cap: BlockCap) -> Self {
        Self { attributes, cap, out: Vec::new(), open: OpenBlock::new(0), stats: EsvoStats::default() }
    }

    /// Appends `n` contiguous slots to the open block, first inserting the page header where a
    /// page starts and padding so the run neither straddles a page nor (compressed attributes)
    /// starts odd. Returns the run's global slot.
    pub(super) fn alloc(&mut self, n: usize) -> u64 {
        debug_assert!(n < PAGE_SLOTS / 2);
        let even = self.attributes == Attributes::Compressed;
        loop {
            let s = self.open.slots.len();
            if s.is_multiple_of(PAGE_SLOTS) {
                self.push(Slot::Header);
            } else if (even && s % 2 == 1) || s / PAGE_SLOTS != (s + n - 1) / PAGE_SLOTS {
                self.push(Slot::Pad);
            } else {
                for _ in 0..n {
                    self.push(Slot::Pad);
                }
                return self.open.base + s as u64;
            }
        }
    }

    fn push(&mut self, kind: Slot) {
        self.open.slots.push([0, 0]);
        self.open.kinds.push(kind);
    }

    /// The open block's index of global slot `slot`, if it is there.
    pub(super) fn local(&self, slot: u64) -> Option<usize> {
        slot.checked_sub(self.open.base).map(|s| s as usize).filter(|&s| s < self.open.slots.len())
    }

    /// Writes the first word of global slot `slot` (open or closed block).
    pub(super) fn set_w0(&mut self, slot: u64, w0: u32) {
        match self.local(slot) {
            Some(s) => self.open.slots[s][0] = w0,
            None => self.out[slot as usize * 2] = w0,
        }
    }

    pub(super) fn set_kind(&mut self, slot: u64, kind: Slot) {
        let s = self.local(slot).expect("a new slot is in the open block");
        self.open.kinds[s] = kind;
    }

    /// Marks the new slot `slot` as a far pointer (its value is written when its target is).
    pub(super) fn reserve_far(&mut self, slot: u64) {
        self.set_kind(slot, Slot::Far);
        self.stats.far_pointers += 1;
    }

    /// Closes the open block (computing the compressed blocks it still owes from `tree`) and opens
    /// an empty one.
    pub(super) fn next_block(&mut self, trees: &[Octree]) -> Result<(), BuildError> {
        self.settle(trees);
        self.close()
    }

    /// The compressed blocks of the open block's slot pairs written so far, read from `tree`
    /// (whose voxels its descriptors since the last settle name). A pair never straddles two
    /// emissions: every group starts at an even slot.
    pub(super) fn settle(&mut self, trees: &[Octree]) {
        if self.attributes != Attributes::Compressed {
            return;
        }
        let t = Instant::now();
        let b = &mut self.open;
        let from = b.compressed.len();
        let to = b.slots.len().div_ceil(2);
        let kinds = &b.kinds;
        let blocks: Vec<CompressedBlock> = (from..to)
            .into_par_iter()
            .with_min_len(256)
            .map(|j| {
                let mut values = [None; 16];
                for half in 0..2 {
                    let Some(Slot::Descriptor { tree, level, voxel }) = kinds.get(2 * j + half).copied() else {
                        continue;
                    };
                    let tree = &trees[tree as usize];
                    let node = &tree.levels[level as usize];
                    let mask = node.masks[voxel as usize] as u32;
                    let first = node.first_child[voxel as usize] as usize;
                    let children = &tree.levels[level as usize + 1].attrs;
                    for (k, s) in (0..8).filter(|s| mask >> s & 1 == 1).enumerate() {
                        let a = children[first + k];
                        values[half * 8 + s] = Some((a.color, a.normal));
                    }
                }
                compress_block(&values)
            })
            .collect();
        b.compressed.extend(blocks);
        self.stats.attributes_ms += ms_since(t);
    }

    /// Appends the open block to `out` — descriptors (page headers and contour pointers resolved),
    /// info section, contour data, attachment — and opens the next at the next page boundary.
    fn close(&mut self) -> Result<(), BuildError> {
        if self.open.is_empty() {
            return Ok(());
        }
        let b = std::mem::replace(&mut self.open, OpenBlock::new(0));
        let n = b.slots.len();
        // The block's descriptors start on a page (its page headers find its info section).
        let start = b.base as usize * 2;
        let stats = &mut self.stats;
        let need = start - self.out.len()
            + 2 * n
            + INFO_WORDS
            + b.contours.len()
            + b.lookups.len().max(n)
            + b.compressed.len() * COMPRESSED_BLOCK_WORDS
            + b.values.len();
        // Grown by a quarter at a time, not doubled: the words are most of the build's peak.
        if self.out.capacity() - self.out.len() < need {
            self.out.reserve_exact(need.max(self.out.len() / 4));
        }
        stats.block_padding_bytes += ((start - self.out.len()) * 4) as u64;
        self.out.resize(start, 0);
        for (s, (slot, kind)) in b.slots.iter().zip(&b.kinds).enumerate() {
            // Words from this slot to the info section, which follows the last slot.
            let to_info = 2 * (n - s);
            match kind {
                Slot::Header => {
                    stats.page_headers += 1;
                    self.out.extend([to_info as u32, 0]);
                }
                Slot::Descriptor { .. } if contour_mask(slot[1]) != 0 => {
                    // Emitted as the block-local index of the first contour.
                    let ptr = (to_info + INFO_WORDS) as u64 + contour_ptr(slot[1]) as u64;
                    if ptr > CONTOUR_PTR_MAX as u64 {
                        return Err(limit(format!(
                            "a contour pointer needs {ptr} words, past the 24-bit field ({CONTOUR_PTR_MAX}): \
                             the block was filled past its prediction"
                        )));
                    }
                    self.out.extend([slot[0], (ptr as u32) << CONTOUR_PTR_SHIFT | contour_mask(slot[1])]);
                }
                Slot::Pad => {
                    stats.padding_slots += 1;
                    self.out.extend(slot);
                }
                _ => self.out.extend(slot),
            }
        }
        // Info section: block pointer (signed, words from the info section back to the
        // descriptors), contour pointer, attachment count, then (type, pointer) per attachment.
        let info = self.out.len();
        let attach_type = match self.attributes {
            Attributes::Raw => ATTACH_RAW,
            Attributes::Compressed => ATTACH_COMPRESSED,
        };
        let attach = INFO_WORDS + b.contours.len();
        self.out.extend([(-(2 * n as i64)) as i32 as u32, INFO_WORDS as u32, 1, attach_type, attach as u32]);
        stats.contours += b.contours.len() as u64;
        self.out.extend(&b.contours);
        match self.attributes {
            Attributes::Raw => {
                let mut lookups = b.lookups;
                lookups.resize(n, 0);
                debug_assert_eq!(self.out.len(), info + attach);
                self.out.extend(&lookups);
                self.out.extend(&b.values);
                stats.colour_bytes += b.values.len() as u64 * 2;
                stats.normal_bytes += b.values.len() as u64 * 2;
                stats.lookup_bytes += n as u64 * 4;
            }
            Attributes::Compressed => {
                debug_assert_eq!(b.compressed.len(), n.div_ceil(2), "settled before closing");
                for c in &b.compressed {
                    self.out.extend(c.0);
                }
                stats.colour_bytes += b.compressed.len() as u64 * 8;
                stats.normal_bytes += b.compressed.len() as u64 * 16;
            }
        }
        stats.desc_slots += n as u64;
        stats.blocks += 1;
        stats.largest_block_bytes = stats.largest_block_bytes.max(((self.out.len() - start) * 4) as u64);
        stats.info_bytes += (INFO_WORDS * 4) as u64;
        self.open = OpenBlock::new(self.out.len().next_multiple_of(PAGE_SLOTS * 2) as u64 / 2);
        Ok(())
    }

    /// Closes the last block; the words and the layout counts.
    pub(super) fn finish(mut self) -> Result<(Vec<u32>, EsvoStats), BuildError> {
        self.close()?;
        if self.out.len() as u64 >= 1 << 33 {
            return Err(limit(format!("{} words: slots past the 32-bit slot index", self.out.len())));
        }
        Ok((self.out, self.stats))
    }
}
