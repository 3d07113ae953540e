//! Ropes for the stackless kd-tree walk (Popov, Günther, Seidel & Slusallek, "Stackless KD-Tree
//! Traversal for High Performance GPU Ray Tracing", Eurographics 2007, §3.1): each leaf gets its
//! box and, per face, a rope to the smallest node whose cell holds the whole face on its other
//! side. The ropes are carried down the tree (`build_ropes`): a node's children inherit its six,
//! each child's face on the split plane gets its sibling, and at every node each rope is pushed
//! down its target's subtree while one child still holds the node's whole face (`push_down`, the
//! paper's rope optimisation), so that a leaf's ropes are as tight as its own faces allow.
//!
//! `validate_ropes` checks every rope against a neighbour search that does not use the tree.

use std::collections::HashMap;

use glam::Vec3;

use super::build::split_box;
use super::layout::{KdNode, NO_ROPE, RopeLeaf, rope_slot};

type Cell = (Vec3, Vec3);

/// Pushes the rope `target` of the face (`axis`, `high`) of `cell` down the target's subtree
/// while one child of the target holds that whole face: the child beside the face where the
/// target splits on the face's axis, the child on the face's side where it splits across it.
fn push_down(nodes: &[KdNode], mut target: u32, axis: usize, high: bool, (lo, hi): Cell) -> u32 {
    while target != NO_ROPE {
        let n = &nodes[target as usize];
        if n.is_leaf() {
            break;
        }
        let (b, split, first) = (n.axis(), n.split(), n.first_child() as u32);
        target = if b == axis {
            // The neighbour lies beyond the face: its child nearest the face touches all of it.
            if high { first } else { first + 1 }
        } else if split >= hi[b] {
            first
        } else if split <= lo[b] {
            first + 1
        } else {
            break; // the split cuts the face: this node is the tightest
        };
    }
    target
}

/// Gives every leaf its [`RopeLeaf`] (its box, reference start and six ropes), in depth-first
/// order, and points the leaf's node at it.
pub(super) fn build_ropes(nodes: &mut [KdNode], bounds: Cell) -> Vec<RopeLeaf> {
    let mut leaves = Vec::new();
    let mut pending = vec![(0usize, bounds, [NO_ROPE; 6])];
    while let Some((i, cell, mut ropes)) = pending.pop() {
        for axis in 0..3 {
            for high in [false, true] {
                let slot = rope_slot(axis, high);
                ropes[slot] = push_down(nodes, ropes[slot], axis, high, cell);
            }
        }
        let n = nodes[i];
        if n.is_leaf() {
            let (min, max) = (cell.0.to_array(), cell.1.to_array());
            nodes[i] = KdNode::leaf(leaves.len() as u32, n.count() as u32);
            leaves.push(RopeLeaf { min, first_ref: n.first_ref() as u32, max, ropes });
            continue;
        }
        let (axis, first) = (n.axis(), n.first_child());
        let (below, above) = split_box(cell, axis, n.split());
        let (mut below_ropes, mut above_ropes) = (ropes, ropes);
        below_ropes[rope_slot(axis, true)] = first as u32 + 1;
        above_ropes[rope_slot(axis, false)] = first as u32;
        pending.push((first + 1, above, above_ropes));
        pending.push((first, below, below_ropes));
    }
    leaves
}

/// Every node's cell and its span in depth-first order (`[enter, exit)`: a node's subtree is the
/// nodes entered within its span), walked from the root.
fn cells_and_spans(nodes: &[KdNode], bounds: Cell) -> (Vec<Cell>, Vec<(u32, u32)>) {
    let mut cells = vec![bounds; nodes.len()];
    let mut spans = vec![(0u32, 0u32); nodes.len()];
    let mut clock = 0u32;
    // (node, children done): a node's exit is stamped after its subtree.
    let mut pending = vec![(0usize, false)];
    while let Some((i, done)) = pending.pop() {
        if done {
            spans[i].1 = clock;
            continue;
        }
        spans[i].0 = clock;
        clock += 1;
        pending.push((i, true));
        let n = &nodes[i];
        if !n.is_leaf() {
            let (below, above) = split_box(cells[i], n.axis(), n.split());
            let first = n.first_child();
            cells[first] = below;
            cells[first + 1] = above;
            pending.push((first + 1, false));
            pending.push((first, false));
        }
    }
    (cells, spans)
}

/// Checks each leaf's record (its box is its cell) and each of its ropes against a search that
/// does not use the tree: the leaves across a face are those whose cell starts (or ends) on the
/// face's plane and overlaps the face with positive area (where the root cell is flat on an axis,
/// with positive length), found among all leaves grouped by
/// their faces' planes. A rope must be [`NO_ROPE`] exactly where there are none (the face lies
/// on the root cell's boundary); otherwise it must name a node whose cell holds the whole face,
/// whose subtree holds every such leaf, and, if it is an inner node, neither of whose children
/// holds them all (the tightest such node).
pub(super) fn validate_ropes(nodes: &[KdNode], leaves: &[RopeLeaf], bounds: Cell) -> Result<(), String> {
    let (cells, spans) = cells_and_spans(nodes, bounds);
    let leaf_nodes: Vec<usize> = (0..nodes.len()).filter(|&i| nodes[i].is_leaf()).collect();
    if leaf_nodes.len() != leaves.len() {
        return Err(format!("{} leaves, {} rope records", leaf_nodes.len(), leaves.len()));
    }
    // Leaves by the plane of each face: (axis, high face?, plane bits) → leaf nodes.
    let mut by_face: HashMap<(usize, bool, u32), Vec<usize>> = HashMap::new();
    for &i in &leaf_nodes {
        let (lo, hi) = cells[i];
        for axis in 0..3 {
            by_face.entry((axis, false, lo[axis].to_bits())).or_default().push(i);
            by_face.entry((axis, true, hi[axis].to_bits())).or_default().push(i);
        }
    }
    let within = |r: usize, m: usize| spans[r].0 <= spans[m].0 && spans[m].0 < spans[r].1;
    let mut seen = vec![false; leaves.len()];
    for &i in &leaf_nodes {
        let k = nodes[i].first_ref();
        let record = leaves.get(k).ok_or_else(|| format!("leaf {i}: record {k} out of range"))?;
        if std::mem::replace(&mut seen[k], true) {
            return Err(format!("leaf {i}: record {k} shared"));
        }
        let (lo, hi) = cells[i];
        if record.min != lo.to_array() || record.max != hi.to_array() {
            return Err(format!("leaf {i}: stored box {:?}…{:?}, cell {lo}…{hi}", record.min, record.max));
        }
        for axis in 0..3 {
            for high in [false, true] {
                let plane = if high { hi[axis] } else { lo[axis] };
                let rope = record.ropes[rope_slot(axis, high)];
                let face = || format!("leaf {i}'s {} face on axis {axis}", if high { "high" } else { "low" });
                if bounds.0[axis] == bounds.1[axis] {
                    // The root cell is flat on this axis: every face on it is the boundary.
                    if rope != NO_ROPE {
                        return Err(format!("{}: rope {rope} across the flat root cell", face()));
                    }
                    continue;
                }
                let overlaps = |m: &usize| {
                    let (mlo, mhi) = cells[*m];
                    // Positive area; on an axis where the cell is flat, the same zero extent.
                    (0..3).filter(|&b| b != axis).all(|b| match lo[b] < hi[b] {
                        true => mlo[b] < hi[b] && mhi[b] > lo[b],
                        false => mlo[b] <= lo[b] && mhi[b] >= hi[b],
                    })
                };
                let across: Vec<usize> = by_face
                    .get(&(axis, !high, plane.to_bits()))
                    .map(|v| v.iter().copied().filter(|m| overlaps(m)).collect())
                    .unwrap_or_default();
                if across.is_empty() {
                    let boundary = if high { bounds.1[axis] } else { bounds.0[axis] };
                    if rope != NO_ROPE || plane != boundary {
                        return Err(format!("{}: no leaf across it, rope {rope}, plane {plane}", face()));
                    }
                    continue;
                }
                let r = rope as usize;
                let (rlo, rhi) = *cells.get(r).ok_or_else(|| format!("{}: rope {rope} out of range", face()))?;
                let holds_face = (if high { rlo[axis] } else { rhi[axis] }) == plane
                    && (0..3).filter(|&b| b != axis).all(|b| rlo[b] <= lo[b] && rhi[b] >= hi[b]);
                if !holds_face {
                    return Err(format!("{}: rope {r}'s cell {rlo}…{rhi} does not hold the face", face()));
                }
                if let Some(m) = across.iter().find(|&&m| !within(r, m)) {
                    return Err(format!("{}: neighbour leaf {m} is outside rope {r}'s subtree", face()));
                }
                let n = &nodes[r];
                if !n.is_leaf() {
                    let first = n.first_child();
                    for child in [first, first + 1] {
                        if across.iter().all(|&m| within(child, m)) {
                            return Err(format!(
                                "{}: rope {r} is not the tightest: its child {child} holds every neighbour",
                                face()
                            ));
                        }
                    }
                }
            }
        }
    }
    Ok(())
}
