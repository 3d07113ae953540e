//! The SIMD layer of the CPU kernels (issue 30): 4-lane `f32` vectors and masks over `std::arch`
//! SSE, and 8-lane ones over AVX, with exactly the IEEE semantics of the scalar code they stand in for.
//!
//! Bit-identical to the scalar kernels by construction (docs/design.md §5 "SIMD"):
//! - only `+ − × ÷` and comparisons, each correctly rounded in IEEE single precision as the
//!   scalar operations are; no fused multiply-add (Rust never contracts `a * b + c` either), no
//!   approximate reciprocal;
//! - [`F32x4::max_sel`] / [`F32x4::min_sel`] (and [`F32x8`]'s) are `maxps` / `minps`, which return their *second*
//!   operand when the first does not compare greater (less): `a.max_sel(b)` is the scalar
//!   `if a > b { a } else { b }` lane by lane, NaN and ±0 included (`f32::max` is not: it drops a
//!   NaN and may return either zero).
//!
//! SSE and SSE2 are part of every x86-64 CPU (the target's baseline features, checked at compile
//! time below), so these operations are sound anywhere on that target; a kernel enables SSE4.1
//! for its whole traversal with `#[target_feature]` only after run-time detection
//! (`structures::simd`). Other targets have no SIMD path: their kernels
//! run the scalar tests (`simd=scalar`, which `auto` picks there).

#[cfg(target_arch = "x86_64")]
pub use avx::{Avx, F32x8};
#[cfg(target_arch = "x86_64")]
pub use sse::{F32x4, M32x4};

#[cfg(target_arch = "x86_64")]
#[allow(unsafe_code)]
mod avx {
    //! Eight lanes, for the boxes of an 8-wide node. AVX is not part of the x86-64 baseline, so
    //! unlike SSE these operations are sound only on a CPU that has it: an [`F32x8`] can only be
    //! made through an [`Avx`] token ([`Avx::splat`], [`Avx::load`]), and the only way to get a
    //! token is the `unsafe` [`Avx::assume`], whose caller promises that this CPU has AVX.
    //!
    //! SAFETY (every other `unsafe` block of this module): each calls one AVX intrinsic, on
    //! values or on a reference to eight `f32`s (valid for the 32 bytes read or written). Those
    //! intrinsics need AVX at run time, which an `F32x8` or `Avx` in hand proves (above).
    //! Exercised by this module's tests and by tests/tests/simd.rs through `bvh4.width=8`.
    use std::arch::x86_64::*;
    use std::ops::{Add, Mul, Sub};

    /// Proof that this CPU has AVX: what every 8-lane value is made with.
    #[derive(Clone, Copy, Debug)]
    pub struct Avx(());

    impl Avx {
        /// The token.
        ///
        /// # Safety
        /// The CPU running the program must have AVX (`is_x86_feature_detected!("avx")`).
        #[inline(always)]
        pub unsafe fn assume() -> Self {
            Avx(())
        }

        #[inline(always)]
        pub fn splat(self, x: f32) -> F32x8 {
            F32x8(unsafe { _mm256_set1_ps(x) })
        }

        #[inline(always)]
        pub fn load(self, lanes: &[f32; 8]) -> F32x8 {
            F32x8(unsafe { _mm256_loadu_ps(lanes.as_ptr()) })
        }
    }

    /// Eight `f32` lanes.
    #[derive(Clone, Copy, Debug)]
    #[repr(transparent)]
    pub struct F32x8(__m256);

    impl F32x8 {
        #[inline(always)]
        pub fn to_array(self) -> [f32; 8] {
            let mut lanes = [0.0; 8];
            unsafe { _mm256_storeu_ps(lanes.as_mut_ptr(), self.0) };
            lanes
        }

        /// `if self > other { self } else { other }` per lane (`vmaxps`, `maxps`'s rule).
        #[inline(always)]
        pub fn max_sel(self, other: Self) -> Self {
            Self(unsafe { _mm256_max_ps(self.0, other.0) })
        }

        /// `if self < other { self } else { other }` per lane (`vminps`).
        #[inline(always)]
        pub fn min_sel(self, other: Self) -> Self {
            Self(unsafe { _mm256_min_ps(self.0, other.0) })
        }

        /// One bit per lane where `self <= other` (false where either is NaN, as the scalar
        /// `<=`), lane 0 lowest.
        #[inline(always)]
        pub fn le_bits(self, other: Self) -> u32 {
            unsafe { _mm256_movemask_ps(_mm256_cmp_ps::<_CMP_LE_OQ>(self.0, other.0)) as u32 }
        }
    }

    macro_rules! binary {
        ($trait:ident, $method:ident, $intrinsic:ident) => {
            impl $trait for F32x8 {
                type Output = F32x8;
                #[inline(always)]
                fn $method(self, other: F32x8) -> F32x8 {
                    F32x8(unsafe { $intrinsic(self.0, other.0) })
                }
            }
        };
    }

    binary!(Add, add, _mm256_add_ps);
    binary!(Sub, sub, _mm256_sub_ps);
    binary!(Mul, mul, _mm256_mul_ps);

    #[cfg(test)]
    mod tests {
        use super::*;

        /// Every lane operation against the scalar expression it stands for, bit for bit, on
        /// every lane (each lane holds a different pair), where this CPU has AVX.
        #[test]
        fn eight_lanes_are_the_scalar_operations_bit_for_bit() {
            if !std::arch::is_x86_feature_detected!("avx") {
                eprintln!("no AVX on this CPU: the 8-lane operations are never used here");
                return;
            }
            // SAFETY: detected just above.
            let avx = unsafe { Avx::assume() };
            let specials = [0.0, -0.0, 1.0, -1.5, f32::NAN, f32::INFINITY, f32::NEG_INFINITY, 1e-40, -3e38];
            for &a in &specials {
                let lanes: [f32; 8] = std::array::from_fn(|i| specials[i]);
                let (va, vb) = (avx.splat(a), avx.load(&lanes));
                let per_lane = |v: F32x8, f: &dyn Fn(f32) -> f32| {
                    v.to_array().iter().zip(&lanes).all(|(x, &b)| x.to_bits() == f(b).to_bits())
                };
                assert!(per_lane(va + vb, &|b| a + b) && per_lane(va - vb, &|b| a - b), "{a}");
                assert!(per_lane(va * vb, &|b| a * b), "{a}");
                assert!(per_lane(va.max_sel(vb), &|b| if a > b { a } else { b }), "max {a}");
                assert!(per_lane(va.min_sel(vb), &|b| if a < b { a } else { b }), "min {a}");
                let want = lanes.iter().enumerate().fold(0, |m, (i, &b)| m | (u32::from(a <= b) << i));
                assert_eq!(va.le_bits(vb), want, "le {a}");
            }
            assert_eq!(avx.load(&[1.0, 2.0, 3.0, 4.0, 5.0, 6.0, 7.0, 8.0]).to_array()[7], 8.0, "lane order kept");
        }
    }
}

#[cfg(target_arch = "x86_64")]
#[allow(unsafe_code)]
mod sse {
    //! SAFETY (every `unsafe` block of this module): each calls one SSE or SSE2 intrinsic on
    //! values (no pointers). Those intrinsics are unsafe to call only because they need their
    //! target feature, and SSE2 (which implies SSE) is enabled for every x86-64 target, as the
    //! assertion below checks at compile time. Exercised by this module's tests.
    use std::arch::x86_64::*;

    const _: () = assert!(cfg!(target_feature = "sse2"), "x86-64 always has SSE2");
    use std::ops::{Add, BitAnd, BitOr, Div, Mul, Not, Sub};

    /// Four `f32` lanes.
    #[derive(Clone, Copy, Debug)]
    #[repr(transparent)]
    pub struct F32x4(__m128);

    /// Four lane masks (all ones or all zeros per lane), the result of a comparison.
    #[derive(Clone, Copy, Debug)]
    #[repr(transparent)]
    pub struct M32x4(__m128);

    impl F32x4 {
        #[inline(always)]
        pub fn load(lanes: &[f32; 4]) -> Self {
            Self(bytemuck::cast(*lanes))
        }

        #[inline(always)]
        pub fn splat(x: f32) -> Self {
            Self(unsafe { _mm_set1_ps(x) })
        }

        #[inline(always)]
        pub fn to_array(self) -> [f32; 4] {
            bytemuck::cast(self.0)
        }

        /// The 4 × 4 transpose: lane `j` of result `i` is lane `i` of `rows[j]` (unpack and move
        /// shuffles only, no arithmetic), how four triangles read from the soup become lanes.
        #[inline(always)]
        pub fn transpose(rows: [Self; 4]) -> [Self; 4] {
            let [r0, r1, r2, r3] = rows.map(|r| r.0);
            unsafe {
                let (a, b) = (_mm_unpacklo_ps(r0, r1), _mm_unpacklo_ps(r2, r3));
                let (c, d) = (_mm_unpackhi_ps(r0, r1), _mm_unpackhi_ps(r2, r3));
                [
                    Self(_mm_movelh_ps(a, b)),
                    Self(_mm_movehl_ps(b, a)),
                    Self(_mm_movelh_ps(c, d)),
                    Self(_mm_movehl_ps(d, c)),
                ]
            }
        }

        /// `if self > other { self } else { other }` per lane (`maxps`).
        #[inline(always)]
        pub fn max_sel(self, other: Self) -> Self {
            Self(unsafe { _mm_max_ps(self.0, other.0) })
        }

        /// `if self < other { self } else { other }` per lane (`minps`).
        #[inline(always)]
        pub fn min_sel(self, other: Self) -> Self {
            Self(unsafe { _mm_min_ps(self.0, other.0) })
        }

        #[inline(always)]
        pub fn lt(self, other: Self) -> M32x4 {
            M32x4(unsafe { _mm_cmplt_ps(self.0, other.0) })
        }

        #[inline(always)]
        pub fn le(self, other: Self) -> M32x4 {
            M32x4(unsafe { _mm_cmple_ps(self.0, other.0) })
        }

        #[inline(always)]
        pub fn gt(self, other: Self) -> M32x4 {
            M32x4(unsafe { _mm_cmpgt_ps(self.0, other.0) })
        }

        #[inline(always)]
        pub fn eq(self, other: Self) -> M32x4 {
            M32x4(unsafe { _mm_cmpeq_ps(self.0, other.0) })
        }

        /// `if self != other` per lane; true where either is NaN, as the scalar `!=` is.
        #[inline(always)]
        pub fn ne(self, other: Self) -> M32x4 {
            M32x4(unsafe { _mm_cmpneq_ps(self.0, other.0) })
        }

        /// `if mask { yes } else { no }` per lane, bits unchanged.
        #[inline(always)]
        pub fn select(mask: M32x4, yes: Self, no: Self) -> Self {
            Self(unsafe { _mm_or_ps(_mm_and_ps(mask.0, yes.0), _mm_andnot_ps(mask.0, no.0)) })
        }
    }

    impl M32x4 {
        /// One bit per lane, lane 0 lowest.
        #[inline(always)]
        pub fn bits(self) -> u32 {
            unsafe { _mm_movemask_ps(self.0) as u32 }
        }
    }

    macro_rules! binary {
        ($ty:ident, $trait:ident, $method:ident, $intrinsic:ident) => {
            impl $trait for $ty {
                type Output = $ty;
                #[inline(always)]
                fn $method(self, other: $ty) -> $ty {
                    $ty(unsafe { $intrinsic(self.0, other.0) })
                }
            }
        };
    }

    binary!(F32x4, Add, add, _mm_add_ps);
    binary!(F32x4, Sub, sub, _mm_sub_ps);
    binary!(F32x4, Mul, mul, _mm_mul_ps);
    binary!(F32x4, Div, div, _mm_div_ps);
    binary!(M32x4, BitAnd, bitand, _mm_and_ps);
    binary!(M32x4, BitOr, bitor, _mm_or_ps);

    impl Not for M32x4 {
        type Output = M32x4;
        #[inline(always)]
        fn not(self) -> M32x4 {
            M32x4(unsafe { _mm_xor_ps(self.0, _mm_castsi128_ps(_mm_set1_epi32(-1))) })
        }
    }

    #[cfg(test)]
    mod tests {
        use super::*;

        /// Every lane operation against the scalar expression it stands for, over values that
        /// include NaN, ±0, ±∞ and denormals, bit for bit.
        #[test]
        fn lanes_are_the_scalar_operations_bit_for_bit() {
            let specials = [0.0, -0.0, 1.0, -1.5, f32::NAN, f32::INFINITY, f32::NEG_INFINITY, 1e-40, -3e38, 0.1];
            for &a in &specials {
                for &b in &specials {
                    let (va, vb) = (F32x4::splat(a), F32x4::splat(b));
                    let same = |v: F32x4, s: f32| v.to_array().iter().all(|x| x.to_bits() == s.to_bits());
                    assert!(same(va + vb, a + b) && same(va - vb, a - b), "{a} {b}");
                    assert!(same(va * vb, a * b) && same(va / vb, a / b), "{a} {b}");
                    assert!(same(va.max_sel(vb), if a > b { a } else { b }), "max {a} {b}");
                    assert!(same(va.min_sel(vb), if a < b { a } else { b }), "min {a} {b}");
                    let bit = |m: M32x4, s: bool| m.bits() == if s { 0b1111 } else { 0 };
                    assert!(bit(va.lt(vb), a < b) && bit(va.le(vb), a <= b) && bit(va.gt(vb), a > b), "{a} {b}");
                    assert!(bit(va.eq(vb), a == b) && bit(va.ne(vb), a != b) && bit(!va.eq(vb), a != b), "{a} {b}");
                    assert!(same(F32x4::select(va.lt(vb), va, vb), if a < b { a } else { b }), "select {a} {b}");
                }
            }
            let v = F32x4::load(&[1.0, 2.0, 3.0, 4.0]);
            assert_eq!(v.lt(F32x4::splat(2.5)).bits(), 0b0011, "lane 0 is the lowest bit");
            assert_eq!((v.gt(F32x4::splat(1.5)) & v.lt(F32x4::splat(3.5))).bits(), 0b0110);
            assert_eq!((v.lt(F32x4::splat(1.5)) | v.gt(F32x4::splat(3.5))).bits(), 0b1001);
            let picked = F32x4::select(v.gt(F32x4::splat(2.5)), v, F32x4::splat(-0.0)).to_array();
            assert_eq!(picked.map(f32::to_bits), [-0.0, -0.0, 3.0, 4.0].map(f32::to_bits), "select per lane");
        }

        #[test]
        fn transpose_swaps_rows_and_lanes() {
            let rows: [F32x4; 4] = std::array::from_fn(|j| F32x4::load(&std::array::from_fn(|i| (10 * j + i) as f32)));
            let cols = F32x4::transpose(rows);
            for (i, col) in cols.iter().enumerate() {
                assert_eq!(col.to_array(), std::array::from_fn(|j| (10 * j + i) as f32), "column {i}");
            }
        }
    }
}
