//! Grid resolutions: Eq. 1 and Algorithms 1–2 of seed 002 §1.

use glam::Vec3;

/// Largest cell count any single (sub-)grid may have; a request beyond it is scaled down to it
/// (Eq. 1 on a box with a near-zero side asks for absurd counts — the paper's §1.1 point).
pub const MAX_CELLS_PER_GRID: f64 = (1u64 << 27) as f64;

/// Eq. 1: `M_i = L_i · ∛(target / V)`, rounded half up and at least 1.
///
/// Eq. 1 is undefined for a box of zero volume (a zero-length side); there it falls back to
/// Algorithm 1's zero-length cases, which is what any implementation must do. The total is capped
/// at [`MAX_CELLS_PER_GRID`].
pub fn eq1(extent: Vec3, target_cells: f64) -> [u32; 3] {
    let v = f64::from(extent.x) * f64::from(extent.y) * f64::from(extent.z);
    if v <= 0.0 {
        return algorithm1(extent, target_cells);
    }
    let s = (target_cells / v).cbrt();
    cap([0, 1, 2].map(|i| round_at_least_one(f64::from(extent[i]) * s)))
}

/// Algorithm 1: the resolution for about `target_cells` (= λN) cells, with the sides sorted
/// `L_i ≥ L_j ≥ L_k` and the zero-length cases:
/// (1) all zero → 1×1×1; (2) only `L_i > 0` → `M_i = λN`;
/// (3) `L_k = 0` → `M_i = ⌊√(λN·L_i/L_j) + 0.5⌋`, `M_j = ⌊√(λN·L_j/L_i) + 0.5⌋`, falling back to (2)
/// when `M_j < 1`; (4) all positive → Eq. 1 rounded with +0.5, falling back to (3) when `M_k < 1`.
pub fn algorithm1(extent: Vec3, target_cells: f64) -> [u32; 3] {
    let mut axes = [0usize, 1, 2];
    axes.sort_by(|&a, &b| extent[b].total_cmp(&extent[a])); // stable: ties keep x, y, z order
    let [i, j, k] = axes;
    let l = |a: usize| f64::from(extent[a]);
    let n = target_cells.max(1.0);
    let mut m = [1u32; 3];
    let case2 = |m: &mut [u32; 3]| m[i] = round_at_least_one(n);
    let case3 = |m: &mut [u32; 3]| {
        let mj = (n * l(j) / l(i)).sqrt() + 0.5;
        if mj < 1.0 {
            case2(m);
        } else {
            m[i] = round_at_least_one((n * l(i) / l(j)).sqrt());
            m[j] = mj.floor() as u32;
        }
    };
    if l(i) == 0.0 {
        // case (1)
    } else if l(j) == 0.0 {
        case2(&mut m);
    } else if l(k) == 0.0 {
        case3(&mut m);
    } else {
        let s = (n / (l(i) * l(j) * l(k))).cbrt();
        let mk = l(k) * s + 0.5;
        if mk < 1.0 {
            case3(&mut m);
        } else {
            m[i] = round_at_least_one(l(i) * s);
            m[j] = round_at_least_one(l(j) * s);
            m[k] = mk.floor() as u32;
        }
    }
    cap(m)
}

/// Algorithm 2: Algorithm 1, then `M_i ≤ α · L_i / LF_avg_i`, where `LF_avg_i` is the mean
/// extent of the triangles' bounding boxes on axis `i`. An axis on which every triangle is flat
/// (`LF_avg_i = 0`) has no cap.
pub fn algorithm2(extent: Vec3, target_cells: f64, alpha: f32, mean_triangle_extent: Vec3) -> [u32; 3] {
    let mut m = algorithm1(extent, target_cells);
    for a in 0..3 {
        if mean_triangle_extent[a] > 0.0 {
            let max = f64::from(alpha) * f64::from(extent[a]) / f64::from(mean_triangle_extent[a]);
            m[a] = m[a].min(round_at_least_one(max));
        }
    }
    m
}

/// The cell count of a resolution.
pub fn cells(m: [u32; 3]) -> u64 {
    m.iter().map(|&v| u64::from(v)).product()
}

fn round_at_least_one(x: f64) -> u32 {
    (x + 0.5).floor().clamp(1.0, f64::from(u32::MAX >> 1)) as u32
}

/// Scales a resolution down uniformly until it has at most [`MAX_CELLS_PER_GRID`] cells.
fn cap(m: [u32; 3]) -> [u32; 3] {
    let total = cells(m) as f64;
    if total <= MAX_CELLS_PER_GRID {
        return m;
    }
    let s = (MAX_CELLS_PER_GRID / total).cbrt();
    let mut out = m.map(|v| ((f64::from(v) * s).floor() as u32).max(1));
    while cells(out) as f64 > MAX_CELLS_PER_GRID {
        let big = (0..3).max_by_key(|&a| out[a]).unwrap_or(0);
        out[big] = (out[big] - 1).max(1);
    }
    out
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn paper_example_of_section_1_1() {
        // N = 1000, λ = 1, box 1000 × 1000 × 1: Eq. 1 gives 100 × 100 × 0.1 → 1, i.e. 10 000 cells,
        // ten times λN; Algorithm 1 keeps about λN = 1000 (case 3: √(1000) ≈ 31.6 → 32 per side).
        let e = Vec3::new(1000.0, 1000.0, 1.0);
        assert_eq!(eq1(e, 1000.0), [100, 100, 1]);
        assert_eq!(algorithm1(e, 1000.0), [32, 32, 1]);
    }

    #[test]
    fn algorithm1_zero_length_cases() {
        assert_eq!(algorithm1(Vec3::ZERO, 500.0), [1, 1, 1], "case 1");
        assert_eq!(algorithm1(Vec3::new(0.0, 7.0, 0.0), 500.0), [1, 500, 1], "case 2");
        assert_eq!(algorithm1(Vec3::new(4.0, 0.0, 1.0), 100.0), [20, 1, 5], "case 3: √(100·4) = 20, √(100/4) = 5");
        // Case 3 falling back to case 2: √(λN·L_j/L_i) + 0.5 < 1.
        assert_eq!(algorithm1(Vec3::new(1000.0, 0.0, 0.001), 10.0), [10, 1, 1]);
        // Case 4 falling back to case 3 (then 2): a thin slab.
        assert_eq!(algorithm1(Vec3::new(10.0, 10.0, 1e-6), 100.0), [10, 10, 1]);
        assert_eq!(algorithm1(Vec3::new(2.0, 2.0, 2.0), 64.0), [4, 4, 4], "case 4");
    }

    #[test]
    fn algorithm2_caps_by_mean_triangle_size() {
        // Unit cube, 1000 cells → 10 per axis; triangles 0.5 wide on x with α = 2 allow only 4.
        let m = algorithm2(Vec3::ONE, 1000.0, 2.0, Vec3::new(0.5, 0.0, 0.01));
        assert_eq!(m, [4, 10, 10]);
    }

    #[test]
    fn huge_requests_are_capped() {
        let m = eq1(Vec3::new(1.0, 1.0, 1e-30), 1e9);
        assert!(cells(m) as f64 <= MAX_CELLS_PER_GRID && m.iter().all(|&v| v >= 1), "{m:?}");
    }
}
