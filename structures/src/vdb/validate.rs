//! Checks of a built [`Vdb`] that do not trust the builder: the root's tiles are sorted, inside the
//! grid and point at top nodes; every interior node's mask is non-empty, its children (table
//! entries, or the packed list its offset and rank words describe) are nodes or leaves of the
//! level below, each reached exactly once; a dense node's empty slots and value mask are zero and
//! its header names its first voxel; no leaf is empty, and the leaves hold the build's voxels.
//! Plus the voxels the tree stands for, by full expansion or point query.

use super::Vdb;
use super::layout::{Tables, bit, mask_words, rank_words};
use crate::voxel::morton;
use crate::voxel::morton::CellOrder;
use crate::voxel::wide::{slot_coords, slot_in};

/// The structural checks above; `Err` says what is wrong and where.
pub fn validate(v: &Vdb) -> Result<(), String> {
    let sizes = v.params.sizes();
    let shape = v.shape();
    let bits = &v.params.log2;
    let interior = bits.len() - 1;
    let tiles = v.tiles();
    if v.words.first().copied() != Some(tiles as u32)
        || v.level_starts.first() != Some(&(sizes.root_words(tiles) as u32))
    {
        return Err(format!("the root table does not hold {tiles} tiles"));
    }
    if v.level_starts.len() != interior + 1 || v.level_starts[interior] as usize != v.words.len() {
        return Err(format!("level starts {:?} do not frame {} words", v.level_starts, v.words.len()));
    }
    let leaf_bits = bits[interior];
    let leaf_words = sizes.leaf_words(leaf_bits);
    if !v.leaves.len().is_multiple_of(leaf_words) {
        return Err(format!("{} leaf words is not whole leaves of {leaf_words}", v.leaves.len()));
    }
    // Per level: the nodes' expected first voxels, set by their parents (None: not reached yet).
    let count = |l: usize| match l < interior {
        true => (v.level_starts[l + 1] - v.level_starts[l]) as usize / sizes.node_words(bits[l]),
        false => v.leaves.len() / leaf_words,
    };
    let start_of = |l: usize| if l < interior { v.level_starts[l] as usize } else { 0 };
    let size_of = |l: usize| if l < interior { sizes.node_words(bits[l]) } else { leaf_words };
    // The index at level `l` of the node at word `w`, if `w` is one's start.
    let index_at = |l: usize, w: u32| -> Option<usize> {
        let rel = (w as usize).checked_sub(start_of(l))?;
        (rel.is_multiple_of(size_of(l)) && rel / size_of(l) < count(l)).then(|| rel / size_of(l))
    };
    let mut origins: Vec<Option<[u32; 3]>> = vec![None; count(0)];
    let top = shape.shifts[0];
    let mut last_key = None;
    for i in 0..tiles {
        let at = sizes.tile(i);
        let key = v.words[at] as u64 | (v.words[at + 1] as u64) << 32;
        if last_key.is_some_and(|k| key <= k) {
            return Err(format!("root tile {i}: key {key} is not above the previous one"));
        }
        last_key = Some(key);
        let corner = if top >= v.grid.level { (key == 0).then_some([0; 3]) } else { Some(morton::decode(key)) };
        let Some(corner) = corner.filter(|c| c.iter().all(|&x| (x as u64) << top < 1u64 << v.grid.level.max(top)))
        else {
            return Err(format!("root tile {i}: key {key} lies outside the grid"));
        };
        if sizes.tables == Tables::Dense && v.words[at + 3..at + 8].iter().any(|&w| w != 0) {
            return Err(format!("root tile {i}: state and value words are not zero"));
        }
        let Some(k) = index_at(0, v.words[at + 2]).filter(|&k| origins.get(k) == Some(&None)) else {
            return Err(format!("root tile {i}: child {} is not an unreached node of level 0", v.words[at + 2]));
        };
        origins[k] = Some(corner.map(|x| x << top));
    }
    for (l, &b) in bits.iter().enumerate().take(interior) {
        let (mask_at, table) = (sizes.child_mask(b), sizes.table(b));
        let mut below: Vec<Option<[u32; 3]>> = vec![None; count(l + 1)];
        for (k, origin) in origins.iter().enumerate() {
            let at = start_of(l) + k * size_of(l);
            let node = &v.words[at..at + size_of(l)];
            let here = format!("level {l} node {k} (word {at})");
            let Some(origin) = origin else { return Err(format!("{here} is reached by no parent")) };
            let mask = &node[mask_at..mask_at + mask_words(b)];
            let set: Vec<u32> = (0..1u32 << (3 * b)).filter(|&s| bit(mask, s)).collect();
            if set.is_empty() {
                return Err(format!("{here} has an empty child mask"));
            }
            let children: Vec<u32> = match sizes.tables {
                Tables::Dense => {
                    if node[..3] != *origin || node[3] != l as u32 || node[4..8].iter().any(|&w| w != 0) {
                        return Err(format!(
                            "{here}: header {:?} does not name its first voxel {origin:?}",
                            &node[..8]
                        ));
                    }
                    if node[8..8 + mask_words(b)].iter().any(|&w| w != 0) {
                        return Err(format!("{here}: the value mask is not empty"));
                    }
                    for s in 0..1usize << (3 * b) {
                        let entry = &node[table + 2 * s..table + 2 * s + 2];
                        if entry[1] != 0 || (!bit(mask, s as u32) && entry[0] != 0) {
                            return Err(format!(
                                "{here}: table entry {s} {entry:?} for a slot the mask says is {}",
                                if bit(mask, s as u32) { "a child" } else { "empty" }
                            ));
                        }
                    }
                    set.iter().map(|&s| node[table + 2 * s as usize]).collect()
                }
                Tables::Compact => {
                    let mut rank = 0;
                    for g in 0..rank_words(b) {
                        if node[table + g] != rank {
                            return Err(format!("{here}: rank word {g} is {}, the mask says {rank}", node[table + g]));
                        }
                        rank += (0..64)
                            .filter(|i| (64 * g + i) < 1 << (3 * b) && bit(mask, (64 * g + i) as u32))
                            .count() as u32;
                    }
                    (0..set.len() as u32).map(|i| node[0] + i * size_of(l + 1) as u32).collect()
                }
            };
            let mut previous = None;
            for (&s, &child) in set.iter().zip(&children) {
                let Some(c) = index_at(l + 1, child) else {
                    return Err(format!("{here}: child {s} at word {child} is not a node of level {}", l + 1));
                };
                // Siblings sit one after another in the node's slot order (either order's).
                if previous.is_some_and(|p| c != p + 1) {
                    return Err(format!("{here}: child {s} is node {c} of level {}, not next to its sibling", l + 1));
                }
                previous = Some(c);
                if below[c].is_some() {
                    return Err(format!("{here}: child {s} at word {child} is reached twice"));
                }
                let local = slot_coords(v.params.order, s, b);
                below[c] = Some(std::array::from_fn(|a| origin[a] + (local[a] << shape.shifts[l + 1])));
            }
        }
        origins = below;
    }
    // The leaves.
    let mut voxels = 0u64;
    for (k, origin) in origins.iter().enumerate() {
        let leaf = &v.leaves[k * leaf_words..(k + 1) * leaf_words];
        let Some(origin) = origin else { return Err(format!("leaf {k} is reached by no node")) };
        let mask = &leaf[sizes.leaf_mask()..sizes.leaf_mask() + mask_words(leaf_bits)];
        let n: u32 = mask.iter().map(|w| w.count_ones()).sum();
        if n == 0 {
            return Err(format!("leaf {k} is empty"));
        }
        if sizes.tables == Tables::Dense {
            let pad = &leaf[sizes.leaf_mask() + mask_words(leaf_bits)..];
            if leaf[..3] != *origin || leaf[3] != 0 || pad.iter().any(|&w| w != 0) {
                return Err(format!("leaf {k}: header {:?} does not name its first voxel {origin:?}", &leaf[..4]));
            }
        }
        voxels += u64::from(n);
    }
    if voxels != v.voxels {
        return Err(format!("the leaves hold {voxels} voxels, the build met {}", v.voxels));
    }
    Ok(())
}

/// Every voxel's Morton code, increasing (tiles by key, then depth first in local Morton order).
pub fn expand(v: &Vdb) -> Vec<u64> {
    let sizes = v.params.sizes();
    let mut out = Vec::with_capacity(v.voxels as usize);
    for i in 0..v.tiles() {
        let at = sizes.tile(i);
        let key = v.words[at] as u64 | (v.words[at + 1] as u64) << 32;
        walk(v, 0, v.words[at + 2] as usize, key, &mut out);
    }
    out
}

fn walk(v: &Vdb, level: usize, at: usize, code: u64, out: &mut Vec<u64>) {
    let sizes = v.params.sizes();
    let bits = &v.params.log2;
    let b = bits[level];
    if level + 1 == bits.len() {
        let mask = &v.leaves[at + sizes.leaf_mask()..];
        out.extend((0..1u32 << (3 * b)).filter(|&m| bit(mask, slot_of(v, m, b))).map(|m| code << (3 * b) | m as u64));
        return;
    }
    let child_words = match level + 2 == bits.len() {
        true => sizes.leaf_words(bits[level + 1]),
        false => sizes.node_words(bits[level + 1]),
    } as u32;
    for m in 0..1u32 << (3 * b) {
        if let Some(child) = sizes.child(&v.words, at, b, slot_of(v, m, b), child_words) {
            walk(v, level + 1, child as usize, code << (3 * b) | m as u64, out);
        }
    }
}

/// The slot, in the tree's order, of the cell whose local Morton code is `m` (so the expansion
/// walks in Morton order whatever the tree's).
fn slot_of(v: &Vdb, m: u32, bits: u32) -> u32 {
    slot_in(v.params.order, slot_coords(CellOrder::Morton, m, bits), bits)
}

/// Whether the voxel at integer coordinates `c` is set: the root tile, then one slot per level.
pub fn contains(v: &Vdb, c: [u32; 3]) -> bool {
    let sizes = v.params.sizes();
    let bits = &v.params.log2;
    let shifts = v.shape().dda_shifts();
    let Some(mut at) = sizes.find_tile(&v.words, morton::encode(c.map(|x| x >> shifts[0]))) else { return false };
    for (l, &b) in bits.iter().enumerate() {
        let slot = slot_in(v.params.order, c.map(|x| (x >> shifts[l + 1]) & ((1 << b) - 1)), b);
        if l + 1 == bits.len() {
            return bit(&v.leaves[at as usize + sizes.leaf_mask()..], slot);
        }
        let child_words = match l + 2 == bits.len() {
            true => sizes.leaf_words(bits[l + 1]),
            false => sizes.node_words(bits[l + 1]),
        } as u32;
        match sizes.child(&v.words, at as usize, b, slot, child_words) {
            Some(child) => at = child,
            None => return false,
        }
    }
    false
}
