//! Reading a built ESVO back from its words alone, for the tests and checks that compare builds:
//! the descriptors from the root down (child, far and contour pointers as the caster follows
//! them), and each voxel's contour and attributes through its block's page header, info section
//! and attachment, as seed 000 Fig. 8 finds them. It shares no code with the builder.

use glam::Vec3;

use super::attributes::CompressedBlock;
use super::{Attributes, Esvo};

/// A voxel's attributes as stored: raw words, or a compressed block's decoded values.
#[derive(Clone, Copy, Debug, PartialEq)]
pub enum StoredAttr {
    Raw { abgr: u32, normal: u32 },
    Compressed { color: Vec3, normal: Vec3 },
}

/// One voxel below the root as its parent's descriptor describes it.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct StoredVoxel {
    /// Level (1 = the root's children) and Morton code at that level.
    pub level: u32,
    pub code: u64,
    /// Its contour word, 0 when its parent's contour mask has no bit for it.
    pub contour: u32,
    pub attr: StoredAttr,
}

fn below(mask: u32, slot: u32) -> usize {
    (mask & ((1 << slot) - 1)).count_ones() as usize
}

/// Calls `f` for every voxel below the root, depth-first with children in slot order (so the
/// leaves come in increasing Morton order).
///
/// # Panics
/// If a pointer leads outside the words or a descriptor outside the block its page header names.
pub fn for_each_voxel(e: &Esvo, mut f: impl FnMut(StoredVoxel)) {
    if e.is_empty() {
        return;
    }
    let w = &e.words;
    let mut stack = vec![(e.root_slot as usize, 0u32, 0u64)];
    while let Some((n, level, code)) = stack.pop() {
        let (w0, w1) = (w[2 * n], w[2 * n + 1]);
        let (valid, leaf) = ((w0 >> 8) & 0xff, w0 & 0xff);
        let mut offset = w0 >> 17;
        if w0 >> 16 & 1 == 1 {
            offset = w[2 * (n + offset as usize)];
        }
        let children = (n as u32).wrapping_add(offset) as usize;
        // Fig. 8: the page header leads to the block's info section.
        let page = (n & !1023) * 2;
        let info = page + w[page] as usize;
        let block = (info as i64 + w[info] as i32 as i64) as usize;
        assert!(block <= 2 * n && 2 * n < info, "slot {n} lies outside the block its page header names");
        let index = n - block / 2;
        let attach = info + w[info + 4] as usize;
        let mut next = Vec::new();
        for slot in (0..8).filter(|s| valid >> s & 1 == 1) {
            let contour = if w1 >> slot & 1 == 1 { w[2 * n + (w1 >> 8) as usize + below(w1 & 0xff, slot)] } else { 0 };
            let attr = match e.attributes {
                Attributes::Raw => {
                    let entry = w[attach + index];
                    assert_eq!(entry & 0xff, valid, "slot {n}: the lookup entry's mask is the valid mask");
                    let value = attach + (info - block) / 2 + 2 * ((entry >> 8) as usize + below(entry & 0xff, slot));
                    StoredAttr::Raw { abgr: w[value], normal: w[value + 1] }
                }
                Attributes::Compressed => {
                    let b = attach + index / 2 * 6;
                    let block = CompressedBlock(w[b..b + 6].try_into().expect("six words"));
                    let k = (index & 1) * 8 + slot as usize;
                    StoredAttr::Compressed { color: block.color(k), normal: block.normal(k) }
                }
            };
            let child = (code << 3) | slot as u64;
            f(StoredVoxel { level: level + 1, code: child, contour, attr });
            if leaf >> slot & 1 == 0 {
                next.push((children + below(valid & !leaf, slot), level + 1, child));
            }
        }
        stack.extend(next.into_iter().rev());
    }
}
