//! Checks of a built [`Svdag`] that do not trust the builder: the words parse level by level,
//! every pointer lands on a node of the next level, every node but the root is reachable, and no
//! level holds two identical nodes (with unique children, identical words are identical subtrees,
//! so this is minimality); plus the voxels the DAG stands for, by full expansion or point query.

use std::collections::HashSet;

use super::Svdag;
use super::layout::{CHILD_MASK, Leaves, NodeKind, brick_byte, brick_mask, node_words, pointer_index};
use crate::voxel::morton;

/// The structural checks above; `Err` says what is wrong and where.
pub fn validate(dag: &Svdag) -> Result<(), String> {
    validate_with_roots(dag, &[0])
}

/// [`validate`] for a DAG whose root level holds `roots` (word indices, in order): a temporal
/// SVDAG's frames, which may repeat a root (roots are never merged).
pub fn validate_with_roots(dag: &Svdag, roots: &[u32]) -> Result<(), String> {
    let w = &dag.words;
    let levels = dag.level_starts.len() - 1;
    if w.is_empty() {
        return if dag.voxels == 0 { Ok(()) } else { Err(format!("no words for {} voxels", dag.voxels)) };
    }
    if dag.level_starts[levels] as usize != w.len() || levels != dag.bottom_level() as usize + 1 {
        return Err(format!("level starts {:?} do not cover {} words", dag.level_starts, w.len()));
    }
    // Node starts per level, in order.
    let mut starts: Vec<Vec<u32>> = Vec::with_capacity(levels);
    for l in 0..levels {
        let kind = NodeKind::of_level(dag.leaves, l as u32, dag.bottom_level());
        let (begin, end) = (dag.level_starts[l] as usize, dag.level_starts[l + 1] as usize);
        let mut nodes = Vec::new();
        let mut seen: HashSet<&[u32]> = HashSet::new();
        let mut o = begin;
        while o < end {
            let n = node_words(kind, w[o]);
            if o + n > end {
                return Err(format!("level {l}: node at word {o} runs past the level's end {end}"));
            }
            let node = &w[o..o + n];
            let empty = match kind {
                NodeKind::Brick => node[0] == 0 && node[1] == 0,
                _ => node[0] & CHILD_MASK == 0 || node[0] & !CHILD_MASK != 0,
            };
            if empty {
                return Err(format!("level {l}: node at word {o} has an empty or malformed mask {:#x}", node[0]));
            }
            if !seen.insert(node) && l > 0 {
                return Err(format!("level {l}: node at word {o} duplicates another node: the DAG is not minimal"));
            }
            nodes.push(o as u32);
            o += n;
        }
        if dag.stats.nodes_per_level.get(l) != Some(&(nodes.len() as u64)) {
            return Err(format!("level {l}: {} nodes, stats say {:?}", nodes.len(), dag.stats.nodes_per_level.get(l)));
        }
        starts.push(nodes);
    }
    if starts[0] != roots {
        return Err(format!("level 0 holds the nodes at {:?}, not the roots {roots:?}", starts[0]));
    }
    // Pointers: onto node starts of the next level, and every such node pointed at.
    for l in 0..levels - 1 {
        let mut reached = vec![false; starts[l + 1].len()];
        for &o in &starts[l] {
            let mask = w[o as usize];
            for slot in (0..8).filter(|s| mask >> s & 1 == 1) {
                let p = w[pointer_index(o, mask, slot) as usize];
                match starts[l + 1].binary_search(&p) {
                    Ok(k) => reached[k] = true,
                    Err(_) => {
                        return Err(format!(
                            "level {l}: node {o} child {slot} points at {p}, not a node of level {}",
                            l + 1
                        ));
                    }
                }
            }
        }
        if let Some(k) = reached.iter().position(|r| !r) {
            return Err(format!("level {}: node at word {} is unreachable", l + 1, starts[l + 1][k]));
        }
    }
    Ok(())
}

/// Every voxel the DAG stands for, as Morton codes at level `L`, in increasing order (a
/// depth-first walk in slot order is Morton order).
pub fn expand(dag: &Svdag) -> Vec<u64> {
    expand_from(dag, dag.root.word)
}

/// [`expand`] from the root at word `root` (a temporal SVDAG's frame).
pub fn expand_from(dag: &Svdag, root: u32) -> Vec<u64> {
    let mut out = Vec::new();
    if !dag.is_empty() {
        expand_node(dag, root, 0, 0, &mut out);
    }
    out
}

fn expand_node(dag: &Svdag, node: u32, level: u32, code: u64, out: &mut Vec<u64>) {
    let w = &dag.words;
    let bottom = dag.bottom_level();
    if level == bottom {
        match dag.leaves {
            Leaves::Bits => out.extend((0..8).filter(|s| w[node as usize] >> s & 1 == 1).map(|s| code << 3 | s)),
            Leaves::Bricks => {
                let brick = brick_mask(w, node as usize);
                out.extend((0..64).filter(|b| brick >> b & 1 == 1).map(|b| code << 6 | b));
            }
        }
        return;
    }
    let mask = w[node as usize];
    for slot in (0..8).filter(|s| mask >> s & 1 == 1) {
        let child = w[pointer_index(node, mask, slot) as usize];
        expand_node(dag, child, level + 1, code << 3 | slot as u64, out);
    }
}

/// Whether the voxel at integer coordinates `c` (level `L`) is set: a descent by the path's
/// child slots, as the caster finds a node's position (seed 001 §2.3).
pub fn contains(dag: &Svdag, c: [u32; 3]) -> bool {
    if dag.is_empty() {
        return false;
    }
    let level = dag.grid.level;
    let code = morton::encode(c);
    let slot_at = |l: u32| (code >> (3 * (level - 1 - l))) as u32 & 7;
    let w = &dag.words;
    let mut node = dag.root.word;
    for l in 0..dag.bottom_level() {
        let mask = w[node as usize];
        let slot = slot_at(l);
        if mask >> slot & 1 == 0 {
            return false;
        }
        node = w[pointer_index(node, mask, slot) as usize];
    }
    match dag.leaves {
        Leaves::Bits => w[node as usize] >> slot_at(level - 1) & 1 == 1,
        Leaves::Bricks => brick_byte(brick_mask(w, node as usize), slot_at(level - 2)) >> slot_at(level - 1) & 1 == 1,
    }
}
