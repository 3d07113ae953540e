//! Structural checks of a flattened BVH, used by the builder (debug) and the tests.

use glam::Vec3;

use super::Bvh;

impl Bvh {
    /// Checks that every triangle is referenced exactly once, every child lies inside its
    /// parent's box, every referenced triangle inside its leaf's box, and indices are in range.
    pub fn validate(&self) -> Result<(), String> {
        let mut seen = vec![0u32; self.triangles.len()];
        let mut stack = vec![0usize];
        let mut visited = 0usize;
        while let Some(i) = stack.pop() {
            visited += 1;
            let n = self.nodes.get(i).ok_or_else(|| format!("node index {i} out of range"))?;
            let (lo, hi) = (n.min(), n.max());
            if n.is_leaf() {
                let range = n.first as usize..(n.first + n.count) as usize;
                let refs = self.refs.get(range).ok_or_else(|| format!("node {i}: ref range out of bounds"))?;
                for &r in refs {
                    let tri = self.triangles.get(r as usize).ok_or_else(|| format!("ref {r} out of range"))?;
                    if !tri.iter().all(|&p| inside(p, lo, hi)) {
                        return Err(format!("node {i}: triangle {r} sticks out of its leaf box"));
                    }
                    seen[r as usize] += 1;
                }
            } else if !self.triangles.is_empty() {
                // Children after their parent: what bounds the CPU traversal loop (kernels/src/cpu/bvh.rs).
                if (n.first as usize) <= i {
                    return Err(format!("node {i}: children at {} do not follow their parent", n.first));
                }
                for c in [n.first as usize, n.first as usize + 1] {
                    let child = self.nodes.get(c).ok_or_else(|| format!("node {i}: child {c} out of range"))?;
                    if !(inside(child.min(), lo, hi) && inside(child.max(), lo, hi)) {
                        return Err(format!("node {i}: child {c} sticks out of its parent"));
                    }
                    stack.push(c);
                }
            }
        }
        if visited != self.nodes.len() {
            return Err(format!("{} nodes stored, {visited} reachable", self.nodes.len()));
        }
        match seen.iter().position(|&c| c != 1) {
            Some(t) => Err(format!("triangle {t} referenced {} times", seen[t])),
            None => Ok(()),
        }
    }
}

fn inside(p: Vec3, lo: Vec3, hi: Vec3) -> bool {
    p.cmpge(lo).all() && p.cmple(hi).all()
}
