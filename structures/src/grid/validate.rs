//! Structural checks of a built grid, for the builder's debug assertions and the tests.

use super::Grid;
use super::layout::{SUBGRID_BIT, occupancy};

impl Grid {
    /// Checks the layout's invariants: each grid's offsets are a prefix sum inside `refs`; every
    /// reference is a triangle or a sub-grid link alone in its cell; every sub-grid is linked
    /// exactly once, one level below its parent, over exactly its parent cell's box; every brick's
    /// occupancy bit is set exactly when one of its cells is non-empty; and every triangle is
    /// listed somewhere.
    #[allow(clippy::needless_range_loop)] // `a` indexes four arrays at once
    pub fn validate(&self) -> Result<(), String> {
        let mut linked = vec![0u32; self.headers.len()];
        let mut listed = vec![false; self.triangles.len()];
        for (g, h) in self.headers.iter().enumerate() {
            let m = h.cell_count() as usize;
            let first = h.first_cell as usize;
            let offsets = self.cells.get(first..first + m + 1).ok_or(format!("grid {g}: cells out of range"))?;
            if offsets.windows(2).any(|w| w[0] > w[1]) || offsets[m] as usize > self.refs.len() {
                return Err(format!("grid {g}: offsets are not a prefix sum inside refs"));
            }
            let words = self
                .bricks
                .get(h.first_brick as usize..(h.first_brick + h.brick_words()) as usize)
                .ok_or(format!("grid {g}: brick words out of range"))?;
            if words != occupancy(h, offsets) {
                return Err(format!("grid {g}: brick occupancy bits differ from its cells"));
            }
            for c in 0..m {
                let refs = &self.refs[offsets[c] as usize..offsets[c + 1] as usize];
                for &r in refs {
                    if r & SUBGRID_BIT == 0 {
                        *listed.get_mut(r as usize).ok_or(format!("grid {g} cell {c}: triangle {r} out of range"))? =
                            true;
                        continue;
                    }
                    let child = (r & !SUBGRID_BIT) as usize;
                    if refs.len() != 1 {
                        return Err(format!("grid {g} cell {c}: a sub-grid link shares its cell"));
                    }
                    let sub =
                        self.headers.get(child).ok_or(format!("grid {g} cell {c}: link to missing grid {child}"))?;
                    linked[child] += 1;
                    if sub.depth != h.depth + 1 {
                        return Err(format!("grid {child}: depth {} under a depth-{} parent", sub.depth, h.depth));
                    }
                    let (rx, ry) = (h.res[0], h.res[1]);
                    let idx = [c as u32 % rx, (c as u32 / rx) % ry, c as u32 / (rx * ry)];
                    for a in 0..3 {
                        if sub.min[a] != h.boundary(a, idx[a]) || sub.max[a] != h.boundary(a, idx[a] + 1) {
                            return Err(format!("grid {child}: box differs from parent cell {c} of grid {g}"));
                        }
                    }
                }
            }
        }
        if let Some(g) = (1..linked.len()).find(|&g| linked[g] != 1) {
            return Err(format!("grid {g} linked {} times", linked[g]));
        }
        match listed.iter().position(|&l| !l) {
            Some(t) => Err(format!("triangle {t} is in no cell")),
            None => Ok(()),
        }
    }
}
