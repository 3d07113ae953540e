//! The wide BVH's words, exactly as its kernels read them (`kernels::cpu::bvh4`): nodes with
//! their 4 or 8 children's boxes side by side, and leaves of triangles copied into 4-lane blocks.

use bytemuck::{Pod, Zeroable};

/// Triangles per leaf block: the lanes of one SSE register. Both node widths keep 4-triangle
/// blocks, as Embree's BVH8 does (its triangle leaves are `Triangle4`s under 8-wide nodes too).
pub const WIDTH: usize = 4;

/// One node of a `W`-wide tree: the children's boxes as structure-of-arrays, so one `W`-lane
/// slab test reads each bound of all of them with one load (`lo[axis][slot]`), and their child
/// words. An unused slot holds [`EMPTY`] and the empty box (`lo` = +∞, `hi` = −∞), which no ray
/// enters, so the kernels test every slot without looking at the count.
///
/// Cache-line aligned, as Embree's nodes are: 128 bytes for 4 children (16 of them padding) and
/// 256 for 8, so a node spans exactly two or four lines and no 8-lane load of a bound splits a
/// line (at 16-byte alignment half of them would, and a 4-wide node would touch three lines in two).
#[repr(C, align(64))]
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct WideNode<const W: usize> {
    pub lo: [[f32; W]; 3],
    pub hi: [[f32; W]; 3],
    /// Per slot: an inner child's node index, a leaf ([`leaf`]), or [`EMPTY`].
    pub child: [u32; W],
}

/// A node of the 4-wide tree (SSE).
pub type Bvh4Node = WideNode<4>;
/// A node of the 8-wide tree (AVX2).
pub type Bvh8Node = WideNode<8>;

const _: () = assert!(size_of::<Bvh4Node>() == 128 && size_of::<Bvh8Node>() == 256);

/// Up to four triangles of one leaf, vertices as structure-of-arrays (`v[vertex][axis][lane]`),
/// copied in leaf order from the scene's soup (no reference array to read through), 160 bytes.
/// A lane without a triangle has NaN corners, which the watertight test rejects on every path
/// (every comparison with NaN is false, so its `t` never passes `t > t_min`), and `prim` [`NO_PRIM`].
#[repr(C, align(16))]
#[derive(Clone, Copy, Debug, Pod, Zeroable)]
pub struct Tri4 {
    pub v: [[[f32; WIDTH]; 3]; 3],
    /// The triangle's index in the scene's soup, per lane.
    pub prim: [u32; WIDTH],
}

const _: () = assert!(size_of::<Tri4>() == 160);

/// A child word of an unused slot.
pub const EMPTY: u32 = u32::MAX;
/// Set in a child word that names a leaf.
pub const LEAF_BIT: u32 = 1 << 31;
/// Bits of a leaf word holding its block count less one (leaves of 1–8 blocks, 32 triangles).
pub const BLOCK_COUNT_BITS: u32 = 3;
/// Most blocks one leaf holds.
pub const MAX_LEAF_BLOCKS: usize = 1 << BLOCK_COUNT_BITS;
/// Blocks a tree may hold: a leaf's first block index has 28 bits, and the all-ones word is [`EMPTY`].
pub const MAX_BLOCKS: usize = (1 << (31 - BLOCK_COUNT_BITS)) - 1;
/// A lane of a block without a triangle.
pub const NO_PRIM: u32 = u32::MAX;

/// The child word of a leaf of `count` (1..=8) blocks starting at block `first`.
pub const fn leaf(first: u32, count: u32) -> u32 {
    LEAF_BIT | (first << BLOCK_COUNT_BITS) | (count - 1)
}

/// `(first block, block count)` of a leaf word.
#[inline(always)]
pub const fn leaf_blocks(word: u32) -> (usize, usize) {
    let body = word & !LEAF_BIT;
    ((body >> BLOCK_COUNT_BITS) as usize, (body & ((1 << BLOCK_COUNT_BITS) - 1)) as usize + 1)
}

#[inline(always)]
pub const fn is_leaf(word: u32) -> bool {
    word & LEAF_BIT != 0
}

impl<const W: usize> WideNode<W> {
    /// A node with every slot unused.
    pub const EMPTY_NODE: Self =
        Self { lo: [[f32::INFINITY; W]; 3], hi: [[f32::NEG_INFINITY; W]; 3], child: [EMPTY; W] };

    /// Puts a child with box `[lo, hi]` in `slot`.
    pub fn set(&mut self, slot: usize, lo: [f32; 3], hi: [f32; 3], child: u32) {
        for a in 0..3 {
            self.lo[a][slot] = lo[a];
            self.hi[a][slot] = hi[a];
        }
        self.child[slot] = child;
    }

    /// The box of `slot` as `(lo, hi)`.
    pub fn bounds(&self, slot: usize) -> ([f32; 3], [f32; 3]) {
        (std::array::from_fn(|a| self.lo[a][slot]), std::array::from_fn(|a| self.hi[a][slot]))
    }
}

impl Tri4 {
    /// A block with no triangle in any lane.
    pub const EMPTY_BLOCK: Tri4 = Tri4 { v: [[[f32::NAN; WIDTH]; 3]; 3], prim: [NO_PRIM; WIDTH] };

    /// Triangles `prims` (at most [`WIDTH`]) of the soup copied into one block, in order; the
    /// lanes after them stay empty.
    pub fn gather(prims: &[u32], triangles: &[scenes::Triangle]) -> Tri4 {
        debug_assert!(prims.len() <= WIDTH);
        let mut b = Tri4::EMPTY_BLOCK;
        for (lane, &p) in prims.iter().enumerate() {
            for (k, corner) in triangles[p as usize].iter().enumerate() {
                for (a, &x) in corner.to_array().iter().enumerate() {
                    b.v[k][a][lane] = x;
                }
            }
            b.prim[lane] = p;
        }
        b
    }

    /// The triangle of `lane`, as the soup stores it.
    #[inline(always)]
    pub fn triangle(&self, lane: usize) -> scenes::Triangle {
        std::array::from_fn(|k| glam::Vec3::new(self.v[k][0][lane], self.v[k][1][lane], self.v[k][2][lane]))
    }

    /// Lanes holding a triangle (they come first).
    pub fn len(&self) -> usize {
        self.prim.iter().take_while(|&&p| p != NO_PRIM).count()
    }

    pub fn is_empty(&self) -> bool {
        self.len() == 0
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn leaf_words_round_trip_and_never_read_as_empty() {
        for (first, count) in [(0, 1), (5, 8), (MAX_BLOCKS as u32 - 8, 8), (123_456, 3)] {
            let w = leaf(first, count);
            assert!(is_leaf(w));
            assert_ne!(w, EMPTY);
            assert_eq!(leaf_blocks(w), (first as usize, count as usize));
        }
    }
}
