//! Structural checks of the wide BVH, used by the builder (debug) and the tests.

use super::WideBvh;
use super::layout::{EMPTY, NO_PRIM, WIDTH, WideNode, is_leaf, leaf_blocks};

impl<const W: usize> WideBvh<W> {
    /// Checks that every node is reachable once, children follow their parent (what bounds the
    /// traversal loop), unused slots hold the empty box, child boxes hold what they bound, every
    /// block lane is the soup's triangle bit for bit (or an empty lane after the used ones), and
    /// every triangle is in exactly one lane, and no path is deeper than `depth` (which sizes
    /// the traversal stack).
    pub fn validate(&self) -> Result<(), String> {
        let mut seen = vec![0u32; self.triangles.len()];
        let mut reached = vec![false; self.nodes.len()];
        let mut stack = vec![(0usize, 1usize)];
        while let Some((i, level)) = stack.pop() {
            if level > self.depth {
                return Err(format!("node {i} lies {level} deep, below the recorded depth {}", self.depth));
            }
            let node = self.nodes.get(i).ok_or_else(|| format!("node index {i} out of range"))?;
            if std::mem::replace(&mut reached[i], true) {
                return Err(format!("node {i} reached twice"));
            }
            for slot in 0..W {
                let word = node.child[slot];
                let (lo, hi) = node.bounds(slot);
                if word == EMPTY {
                    let empty = WideNode::<W>::EMPTY_NODE.bounds(0);
                    if (lo, hi) != empty {
                        return Err(format!("node {i} slot {slot}: unused slot without the empty box"));
                    }
                    continue;
                }
                let inside = |p: [f32; 3]| (0..3).all(|a| lo[a] <= p[a] && p[a] <= hi[a]);
                if is_leaf(word) {
                    let (first, count) = leaf_blocks(word);
                    let blocks = self
                        .blocks
                        .get(first..first + count)
                        .ok_or_else(|| format!("node {i} slot {slot}: blocks {first}+{count} out of range"))?;
                    for (b, block) in blocks.iter().enumerate() {
                        let used = block.len();
                        if used == 0 || (used < WIDTH && b + 1 < count) {
                            return Err(format!("node {i} slot {slot}: block {} holds {used} triangles", first + b));
                        }
                        for lane in 0..WIDTH {
                            let tri = block.triangle(lane);
                            let p = block.prim[lane];
                            if lane >= used {
                                if p != NO_PRIM || tri.iter().any(|c| !(c.x.is_nan() && c.y.is_nan() && c.z.is_nan())) {
                                    return Err(format!(
                                        "block {}: lane {lane} is neither a triangle nor empty",
                                        first + b
                                    ));
                                }
                                continue;
                            }
                            let want =
                                self.triangles.get(p as usize).ok_or_else(|| format!("prim {p} out of range"))?;
                            let same = tri
                                .iter()
                                .zip(want)
                                .all(|(a, b)| a.to_array().map(f32::to_bits) == b.to_array().map(f32::to_bits));
                            if !same {
                                return Err(format!("block {} lane {lane}: not triangle {p} of the soup", first + b));
                            }
                            if !tri.iter().all(|c| inside(c.to_array())) {
                                return Err(format!("node {i} slot {slot}: triangle {p} sticks out of its box"));
                            }
                            seen[p as usize] += 1;
                        }
                    }
                } else {
                    let c = word as usize;
                    if c <= i {
                        return Err(format!("node {i} slot {slot}: child {c} does not follow its parent"));
                    }
                    let child = self.nodes.get(c).ok_or_else(|| format!("node {i}: child {c} out of range"))?;
                    for s in 0..W {
                        if child.child[s] != EMPTY {
                            let (clo, chi) = child.bounds(s);
                            if !(inside(clo) && inside(chi)) {
                                return Err(format!("node {c} slot {s} sticks out of node {i} slot {slot}"));
                            }
                        }
                    }
                    stack.push((c, level + 1));
                }
            }
        }
        if let Some(i) = reached.iter().position(|&r| !r) {
            return Err(format!("node {i} is not reachable"));
        }
        match seen.iter().position(|&c| c != 1) {
            Some(t) => Err(format!("triangle {t} held in {} lanes", seen[t])),
            None => Ok(()),
        }
    }
}
