//! The chessboard (Chebyshev, L∞) distance transform of a dense grid of cells, in linear time:
//! Rosenfeld & Pfaltz's two raster passes ("Sequential operations in digital picture processing",
//! JACM 1966) with the 26-neighbourhood at unit weight, in 3-D (Borgefors, "Distance
//! transformations in arbitrary dimensions", CVGIP 1984).
//!
//! Why two passes are exact: a cell's chessboard distance to an occupied cell is the length of a
//! shortest path of unit steps to any of the 26 neighbours, and with no obstacles the steps of a
//! path may be taken in any order. Every step is either *forward* (to a cell later in raster
//! order: `dz = +1`, or `dz = 0, dy = +1`, or `(+1, 0, 0)`) or the negation of one, so every
//! shortest path can be reordered into its forward steps, then its backward ones. The forward
//! pass (raster order, each cell from its 13 neighbours before it) finds the shortest
//! forward-only paths; the backward pass (reverse order, the other 13) extends them by
//! backward-only paths.
//!
//! Distances are capped (`cap` is also the value of "no occupied cell within `cap`"), which the
//! passes keep exactly: each is a min over `+1`s, both monotone, so the capped passes give the
//! capped distance. Per row the 12 neighbours in earlier rows are one vectorisable min of four
//! rows and a horizontal min of three; only the neighbour in the same row is a serial scan.

/// The capped chessboard distance of every cell of a grid of `dims` cells (x fastest) to the
/// nearest cell where `occupied` holds: 0 on occupied cells, at most `cap` (≥ 1) elsewhere, `cap`
/// where no occupied cell lies within `cap − 1`. Cells outside the grid count as empty.
pub fn chebyshev(dims: [usize; 3], cap: u8, occupied: impl Fn(usize) -> bool) -> Vec<u8> {
    assert!(cap >= 1, "a distance cap below 1 leaves no room for an empty cell");
    let [nx, ny, nz] = dims;
    let mut d: Vec<u8> = (0..nx * ny * nz).map(|i| if occupied(i) { 0 } else { cap }).collect();
    if d.is_empty() {
        return d;
    }
    let mut near = vec![0u8; nx];
    // Forward: rows in raster order, each from the three rows below it in the previous plane, the
    // previous row of its plane, and its left neighbour.
    for z in 0..nz {
        for y in 0..ny {
            let before = [
                (z > 0 && y > 0).then(|| (z - 1, y - 1)),
                (z > 0).then(|| (z - 1, y)),
                (z > 0 && y + 1 < ny).then(|| (z - 1, y + 1)),
                (y > 0).then(|| (z, y - 1)),
            ];
            relax_row(&mut d, [nx, ny], (z, y), &before, &mut near, cap, false);
        }
    }
    // Backward: the mirror image, from the other 13.
    for z in (0..nz).rev() {
        for y in (0..ny).rev() {
            let after = [
                (z + 1 < nz && y > 0).then(|| (z + 1, y - 1)),
                (z + 1 < nz).then(|| (z + 1, y)),
                (z + 1 < nz && y + 1 < ny).then(|| (z + 1, y + 1)),
                (y + 1 < ny).then(|| (z, y + 1)),
            ];
            relax_row(&mut d, [nx, ny], (z, y), &after, &mut near, cap, true);
        }
    }
    d
}

/// One row of a pass: each cell becomes at most one more than its nearest already-relaxed
/// neighbour — the x−1..x+1 cells of the `rows` given, then (serially) the previous cell of the
/// row itself in the pass's direction.
fn relax_row(
    d: &mut [u8],
    [n, ny]: [usize; 2],
    (z, y): (usize, usize),
    rows: &[Option<(usize, usize)>; 4],
    near: &mut [u8],
    cap: u8,
    backward: bool,
) {
    near.fill(u8::MAX);
    for &(rz, ry) in rows.iter().flatten() {
        let row = &d[(rz * ny + ry) * n..][..n];
        for (m, &v) in near.iter_mut().zip(row) {
            *m = (*m).min(v);
        }
    }
    let row = &mut d[(z * ny + y) * n..][..n];
    // The horizontal min of three, then one step on, into the row.
    let mut left = u8::MAX;
    for x in 0..n {
        let right = if x + 1 < n { near[x + 1] } else { u8::MAX };
        let m = left.min(near[x]).min(right);
        left = near[x];
        row[x] = row[x].min(m.saturating_add(1).min(cap));
    }
    let step = |prev: u8, cur: &mut u8| *cur = (*cur).min(prev.saturating_add(1).min(cap));
    if backward {
        for x in (0..n - 1).rev() {
            let prev = row[x + 1];
            step(prev, &mut row[x]);
        }
    } else {
        for x in 1..n {
            let prev = row[x - 1];
            step(prev, &mut row[x]);
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    /// The capped distance by brute force: every occupied cell against every cell.
    fn brute(dims: [usize; 3], cap: u8, occ: &[bool]) -> Vec<u8> {
        let [nx, ny] = [dims[0] as i64, dims[1] as i64];
        let at = |i: usize| [i as i64 % nx, i as i64 / nx % ny, i as i64 / (nx * ny)];
        let occupied: Vec<[i64; 3]> = (0..occ.len()).filter(|&i| occ[i]).map(at).collect();
        (0..occ.len())
            .map(|i| {
                let c = at(i);
                let near = occupied.iter().map(|o| (0..3).map(|a| (c[a] - o[a]).abs()).max().unwrap_or(0)).min();
                near.map_or(cap, |d| d.min(i64::from(cap)) as u8)
            })
            .collect()
    }

    /// A small deterministic generator (the test needs no crate's).
    fn next(state: &mut u64) -> u64 {
        *state ^= *state << 13;
        *state ^= *state >> 7;
        *state ^= *state << 17;
        *state
    }

    #[test]
    fn equals_brute_force_on_random_grids_of_every_density() {
        let mut state = 0x43;
        for dims in [
            [1usize, 1, 1],
            [2, 2, 2],
            [3, 3, 3],
            [5, 5, 5],
            [8, 8, 8],
            [13, 13, 13],
            [16, 16, 16],
            [1, 7, 3],
            [9, 2, 5],
            [4, 11, 1],
        ] {
            for per_mille in [0u64, 1, 5, 30, 200, 700, 1000] {
                for cap in [1u8, 2, 3, 7, 255] {
                    let occ: Vec<bool> =
                        (0..dims.iter().product()).map(|_| next(&mut state) % 1000 < per_mille).collect();
                    let got = chebyshev(dims, cap, |i| occ[i]);
                    assert_eq!(got, brute(dims, cap, &occ), "{dims:?}, {per_mille}‰ occupied, cap {cap}");
                }
            }
        }
    }

    #[test]
    fn a_single_cell_gives_chessboard_shells() {
        let side = 11usize;
        let mut occ = vec![false; side.pow(3)];
        occ[(2 * side + 9) * side + 4] = true; // (4, 9, 2): shells reach every face at a different distance
        let got = chebyshev([side; 3], 255, |i| occ[i]);
        for (i, &d) in got.iter().enumerate() {
            let c = [i % side, i / side % side, i / (side * side)];
            let want = [c[0].abs_diff(4), c[1].abs_diff(9), c[2].abs_diff(2)].into_iter().max().unwrap();
            assert_eq!(usize::from(d), want, "cell {c:?}");
        }
    }
}
