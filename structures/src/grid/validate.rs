//! Structural checks of a built grid, for the builder's debug assertions and the tests.

use super::layout::{SUBGRID_BIT, occupancy};
use super::{CellLayout, Grid};
use crate::bvh4::layout::{Tri4, WIDTH};

impl Grid {
    /// Checks the layout's invariants: each grid's offsets are a prefix sum inside `refs`; every
    /// reference is a triangle or a sub-grid link alone in its cell; every sub-grid is linked
    /// exactly once, one level below its parent, over exactly its parent cell's box; every brick's
    /// occupancy bit is set exactly when one of its cells is non-empty; and every triangle is
    /// listed somewhere; with [`CellLayout::Blocks`], every cell's blocks are exactly its
    /// triangles copied four at a time in reference order, and a link's cell has none.
    #[allow(clippy::needless_range_loop)] // `a` indexes four arrays at once
    pub fn validate(&self) -> Result<(), String> {
        let mut linked = vec![0u32; self.headers.len()];
        let mut listed = vec![false; self.triangles.len()];
        for (g, h) in self.headers.iter().enumerate() {
            let m = h.table_len() as usize;
            let first = h.first_cell as usize;
            let offsets = self.cells.get(first..first + m + 1).ok_or(format!("grid {g}: cells out of range"))?;
            match (h.order, &self.morton) {
                (super::ORDER_ROW_MAJOR, _) if g > 0 || self.morton.is_none() => {}
                (super::ORDER_MORTON, Some(mc)) if g == 0 && mc.interleave.len() == m as u64 => {}
                _ => return Err(format!("grid {g}: order {} without its interleave", h.order)),
            }
            if offsets.windows(2).any(|w| w[0] > w[1]) || offsets[m] as usize > self.refs.len() {
                return Err(format!("grid {g}: offsets are not a prefix sum inside refs"));
            }
            let words = self
                .bricks
                .get(h.first_brick as usize..(h.first_brick + h.brick_words()) as usize)
                .ok_or(format!("grid {g}: brick words out of range"))?;
            if words != occupancy(h, offsets, |c| self.cell_index(h, c)) {
                return Err(format!("grid {g}: brick occupancy bits differ from its cells"));
            }
            for c in 0..m {
                let refs = &self.refs[offsets[c] as usize..offsets[c + 1] as usize];
                let Some(idx) = self.cell_at(h, c as u32) else {
                    if !refs.is_empty() {
                        return Err(format!("grid {g}: padding entry {c} holds references"));
                    }
                    continue;
                };
                self.check_blocks(first + c, refs).map_err(|e| format!("grid {g} cell {c}: {e}"))?;
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

    /// The blocks of the cell whose offsets start at `cells[at]`, against its references `refs`.
    fn check_blocks(&self, at: usize, refs: &[u32]) -> Result<(), String> {
        match self.layout {
            CellLayout::Refs if self.blocks.is_empty() && self.cell_blocks.is_empty() => return Ok(()),
            CellLayout::Refs => return Err("blocks stored for layout=refs".into()),
            CellLayout::Blocks if self.cell_blocks.len() != self.cells.len() => {
                return Err(format!("{} block offsets for {} cell offsets", self.cell_blocks.len(), self.cells.len()));
            }
            CellLayout::Blocks => {}
        }
        let (from, to) = (self.cell_blocks[at] as usize, self.cell_blocks[at + 1] as usize);
        let blocks = self.blocks.get(from..to).ok_or(format!("blocks {from}..{to} out of range"))?;
        let triangles: &[u32] = match refs {
            [link] if link & SUBGRID_BIT != 0 => &[],
            _ => refs,
        };
        let chunks = triangles.chunks(WIDTH);
        if chunks.len() != blocks.len() {
            return Err(format!("{} blocks for {} triangles", blocks.len(), triangles.len()));
        }
        for (block, quad) in blocks.iter().zip(chunks) {
            if bytemuck::bytes_of(block) != bytemuck::bytes_of(&Tri4::gather(quad, &self.triangles)) {
                return Err(format!("a block differs from its triangles {quad:?}"));
            }
        }
        Ok(())
    }
}
