//! Structural checks of a triangle octree, used by the builder (debug) and the tests.

use std::collections::VecDeque;

use super::{MAX_DEPTH, TriOctree, layout};

impl TriOctree {
    /// Checks the breadth-first layout (the k-th record reached breadth first is record k, each
    /// interior node's children start where the previous node's end, leaves' references tile
    /// the list in order), that masks and counts are sane, that every referenced triangle's box
    /// meets its leaf's cell, that every triangle is referenced and the depth is bounded.
    pub fn validate(&self) -> Result<(), String> {
        let slack = self.root.size * 2f32.powi(-super::build::SLACK_LOG2);
        let mut referenced = vec![false; self.triangles.len()];
        let mut queue = VecDeque::from([(0usize, [0u32; 3], 0u32, self.root_is_leaf)]);
        let (mut next_index, mut next_child, mut next_ref) = (0usize, 1usize, 0usize);
        while let Some((i, cell, depth, leaf)) = queue.pop_front() {
            if i != next_index {
                return Err(format!("record {i} reached where record {next_index} should be (not breadth first)"));
            }
            next_index += 1;
            if depth > MAX_DEPTH {
                return Err(format!("record {i} at depth {depth}, past {MAX_DEPTH}"));
            }
            let r = self.records.get(i).ok_or_else(|| format!("record {i} out of range"))?;
            if !leaf {
                let (children, leaves) = (layout::child_mask(r), layout::leaf_mask(r));
                if children == 0 || leaves & !children != 0 {
                    return Err(format!("record {i}: child mask {children:#010b}, leaf mask {leaves:#010b}"));
                }
                if r[1] as usize != next_child {
                    return Err(format!("record {i}: first child {} where {next_child} was expected", r[1]));
                }
                next_child += children.count_ones() as usize;
                for slot in (0..8u32).filter(|s| children >> s & 1 == 1) {
                    let c = [0, 1, 2].map(|a| 2 * cell[a] + (slot >> a & 1));
                    queue.push_back((layout::child(r, slot), c, depth + 1, leaves >> slot & 1 == 1));
                }
                continue;
            }
            let (first, count) = (r[1] as usize, r[0] as usize);
            if first != next_ref || (count == 0 && i != 0) {
                return Err(format!(
                    "leaf {i}: references {first}+{count}, expected to start at {next_ref}, non-empty"
                ));
            }
            next_ref += count;
            let refs =
                self.refs.get(first..first + count).ok_or_else(|| format!("leaf {i}: references out of range"))?;
            let (lo, hi) = self.root.cell(depth, cell);
            let (lo, hi) = (lo - slack, hi + slack);
            for &t in refs {
                let tri =
                    self.triangles.get(t as usize).ok_or_else(|| format!("leaf {i}: triangle {t} out of range"))?;
                let (tlo, thi) = (tri[0].min(tri[1]).min(tri[2]), tri[0].max(tri[1]).max(tri[2]));
                if !(tlo.cmple(hi).all() && thi.cmpge(lo).all()) {
                    return Err(format!("leaf {i}: triangle {t} lies outside its cell"));
                }
                referenced[t as usize] = true;
            }
        }
        if next_index != self.records.len() || next_ref != self.refs.len() {
            return Err(format!(
                "{} records and {} references stored, {next_index} and {next_ref} reachable",
                self.records.len(),
                self.refs.len()
            ));
        }
        match referenced.iter().position(|&r| !r) {
            Some(t) => Err(format!("triangle {t} is in no leaf")),
            None => Ok(()),
        }
    }
}
