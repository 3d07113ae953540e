//! Structural checks of a kd-tree, used by the builder (debug) and the tests.

use super::{KdTraversal, KdTree, MAX_DEPTH, ropes};

impl KdTree {
    /// Checks that every inner node's children follow it and its plane lies strictly inside its
    /// cell, that every reference is in range and its triangle's box meets its leaf's cell, that
    /// every triangle is referenced somewhere, every node is reachable and the depth is bounded;
    /// with ropes, that every leaf's record holds its cell and every rope its neighbours
    /// (`ropes::validate_ropes`).
    pub fn validate(&self) -> Result<(), String> {
        let mut referenced = vec![false; self.triangles.len()];
        let mut visited = 0usize;
        let mut pending = vec![(0usize, self.bounds, 1usize)];
        while let Some((i, (lo, hi), depth)) = pending.pop() {
            visited += 1;
            if depth > MAX_DEPTH as usize + 1 {
                return Err(format!("node {i} at depth {depth}, past {MAX_DEPTH}"));
            }
            let n = self.nodes.get(i).ok_or_else(|| format!("node index {i} out of range"))?;
            if n.is_leaf() {
                if self.params.traversal == KdTraversal::Ropes && n.first_ref() >= self.leaves.len() {
                    return Err(format!("leaf {i}: rope record {} out of range", n.first_ref()));
                }
                let range = self.leaf_refs(n);
                let refs = self.refs.get(range).ok_or_else(|| format!("leaf {i}: references out of range"))?;
                for &r in refs {
                    let tri =
                        self.triangles.get(r as usize).ok_or_else(|| format!("leaf {i}: triangle {r} out of range"))?;
                    let (tlo, thi) = (tri[0].min(tri[1]).min(tri[2]), tri[0].max(tri[1]).max(tri[2]));
                    if !(tlo.cmple(hi).all() && thi.cmpge(lo).all()) {
                        return Err(format!("leaf {i}: triangle {r} lies outside its cell"));
                    }
                    referenced[r as usize] = true;
                }
                continue;
            }
            let (axis, split, first) = (n.axis(), n.split(), n.first_child());
            if first <= i || first + 1 >= self.nodes.len() {
                return Err(format!("node {i}: children at {first} do not follow it or are out of range"));
            }
            if !(split > lo[axis] && split < hi[axis]) {
                return Err(format!(
                    "node {i}: plane {split} on axis {axis} outside its cell {}…{}",
                    lo[axis], hi[axis]
                ));
            }
            let (below, above) = super::build::split_box((lo, hi), axis, split);
            pending.push((first, below, depth + 1));
            pending.push((first + 1, above, depth + 1));
        }
        if visited != self.nodes.len() {
            return Err(format!("{} nodes stored, {visited} reachable", self.nodes.len()));
        }
        if let Some(t) = referenced.iter().position(|&r| !r) {
            return Err(format!("triangle {t} is in no leaf"));
        }
        match self.params.traversal {
            KdTraversal::Ropes => ropes::validate_ropes(&self.nodes, &self.leaves, self.bounds),
            KdTraversal::Stack | KdTraversal::Restart if !self.leaves.is_empty() => {
                Err(format!("{} rope records without ropes", self.leaves.len()))
            }
            KdTraversal::Stack | KdTraversal::Restart => Ok(()),
        }
    }
}
