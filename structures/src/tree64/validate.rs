//! Checks of a built [`Tree64`] that do not trust the builder: every descriptor's child list lies
//! in the level below and the lists cover each level exactly (each stored entry reached; in a
//! tree, by exactly one parent); no mask or brick is empty; with `dag` on, no two stored lists
//! are equal (minimality); and the voxels below the root are exactly the build's count. Plus the
//! voxels the tree stands for, by full expansion or point query.

use std::collections::HashSet;

use super::Tree64;
use super::layout::{BRICK_WORDS, CHILD_BITS, DESCRIPTOR_WORDS, PTR, child_index, mask};
use crate::voxel::wide::local_slot;

/// The structural checks above; `Err` says what is wrong and where.
pub fn validate(t: &Tree64) -> Result<(), String> {
    let n = t.shape().levels();
    let starts = &t.level_starts;
    if starts.len() != n {
        return Err(format!("{} level starts for {n} levels", starts.len()));
    }
    if t.words.is_empty() {
        let empty = t.bricks.is_empty() && t.voxels == 0;
        return if empty { Ok(()) } else { Err("no root, but bricks or voxels".into()) };
    }
    if starts[0] != 0 || starts[1] != DESCRIPTOR_WORDS as u32 || starts[n - 1] as usize != t.words.len() {
        return Err(format!("level starts {starts:?} do not frame {} words", t.words.len()));
    }
    if !t.bricks.len().is_multiple_of(BRICK_WORDS) {
        return Err(format!("{} brick words is not whole bricks", t.bricks.len()));
    }
    // `counts[l][i]`: voxels below entry i of level l; filled bottom-up.
    let mut below: Vec<u64> = t.bricks.chunks_exact(BRICK_WORDS).map(|b| u64::from(mask(b).count_ones())).collect();
    if let Some(i) = below.iter().position(|&c| c == 0) {
        return Err(format!("brick {i} is empty"));
    }
    for l in (0..n - 1).rev() {
        let (begin, end) = (starts[l] as usize, starts[l + 1] as usize);
        if !(end - begin).is_multiple_of(DESCRIPTOR_WORDS) {
            return Err(format!("level {l}: {} words is not whole descriptors", end - begin));
        }
        // The level below: its entries' words, base and stride.
        let (child_base, child_len, stride) = match l + 2 == n {
            true => (0, t.bricks.len(), BRICK_WORDS),
            false => (starts[l + 1] as usize, (starts[l + 2] - starts[l + 1]) as usize, DESCRIPTOR_WORDS),
        };
        let child_words = |p: usize, len: usize| match l + 2 == n {
            true => &t.bricks[p..p + len],
            false => &t.words[p..p + len],
        };
        let mut reached = vec![0u32; child_len / stride];
        let mut lists: HashSet<(usize, usize)> = HashSet::new();
        let mut counts = Vec::with_capacity((end - begin) / DESCRIPTOR_WORDS);
        for (k, d) in t.words[begin..end].chunks_exact(DESCRIPTOR_WORDS).enumerate() {
            let (m, ptr) = (mask(d), d[PTR] as usize);
            let at = begin + k * DESCRIPTOR_WORDS;
            let len = m.count_ones() as usize * stride;
            if m == 0 {
                return Err(format!("level {l}: the descriptor at word {at} has an empty mask"));
            }
            let rel = ptr.wrapping_sub(child_base);
            if ptr < child_base || rel + len > child_len || !rel.is_multiple_of(stride) {
                return Err(format!(
                    "level {l}: the descriptor at word {at} points at {ptr}, not a list of {} entries of level {}",
                    len / stride,
                    l + 1
                ));
            }
            if lists.insert((ptr, len)) {
                for r in &mut reached[rel / stride..(rel + len) / stride] {
                    *r += 1;
                }
            }
            counts.push(below[rel / stride..(rel + len) / stride].iter().sum::<u64>());
        }
        // Every stored entry is in a list, and lists do not overlap.
        if let Some(i) = reached.iter().position(|&r| r != 1) {
            let what = if reached[i] == 0 { "in no child list" } else { "in overlapping child lists" };
            return Err(format!("level {}: entry {i} is {what}", l + 1));
        }
        if t.params.dag {
            let mut seen: HashSet<&[u32]> = HashSet::new();
            for &(p, len) in &lists {
                if !seen.insert(child_words(p, len)) {
                    return Err(format!("level {}: the list at {p} is stored twice: the DAG is not minimal", l + 1));
                }
            }
        } else if lists.len() * DESCRIPTOR_WORDS != end - begin {
            return Err(format!("level {l}: two descriptors share a child list in a tree"));
        }
        below = counts;
    }
    if below[0] != t.voxels {
        return Err(format!("the root stands for {} voxels, the build met {}", below[0], t.voxels));
    }
    Ok(())
}

/// Every voxel's Morton code, increasing (depth first in slot order is Morton order).
pub fn expand(t: &Tree64) -> Vec<u64> {
    let mut out = Vec::with_capacity(t.voxels as usize);
    if !t.is_empty() {
        walk(t, 0, 0, 0, &mut out);
    }
    out
}

fn walk(t: &Tree64, level: usize, at: usize, code: u64, out: &mut Vec<u64>) {
    let n = t.shape().levels();
    let d = &t.words[at..at + DESCRIPTOR_WORDS];
    let m = mask(d);
    for slot in (0..64u64).filter(|s| m >> s & 1 == 1) {
        let i = child_index(m, slot as u32) as usize;
        let child = code << (3 * CHILD_BITS) | slot;
        if level + 2 == n {
            let p = d[PTR] as usize + i * BRICK_WORDS;
            let brick = mask(&t.bricks[p..p + BRICK_WORDS]);
            out.extend((0..64u64).filter(|v| brick >> v & 1 == 1).map(|v| child << (3 * CHILD_BITS) | v));
        } else {
            walk(t, level + 1, d[PTR] as usize + i * DESCRIPTOR_WORDS, child, out);
        }
    }
}

/// Whether the voxel at integer coordinates `c` is set, by descending from the root.
pub fn contains(t: &Tree64, c: [u32; 3]) -> bool {
    if t.is_empty() {
        return false;
    }
    let shifts = t.shape().dda_shifts();
    let n = shifts.len() - 1;
    let local = |k: usize| local_slot(c.map(|x| (x >> shifts[k]) & 3), CHILD_BITS);
    let mut at = 0usize;
    for level in 0..n - 1 {
        let d = &t.words[at..at + DESCRIPTOR_WORDS];
        let (m, slot) = (mask(d), local(level + 1));
        if m >> slot & 1 == 0 {
            return false;
        }
        let i = child_index(m, slot) as usize;
        if level + 2 == n {
            let p = d[PTR] as usize + i * BRICK_WORDS;
            return mask(&t.bricks[p..p + BRICK_WORDS]) >> local(n) & 1 == 1;
        }
        at = d[PTR] as usize + i * DESCRIPTOR_WORDS;
    }
    false
}
