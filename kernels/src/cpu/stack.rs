//! The traversal stack of the SIMD kernels (issue 30): a fixed array that is *not* initialised
//! when a ray starts. A zeroed `[T; N]` cost a memset per ray — 42 of bvh4's 1,150 instructions
//! per primary ray on the dragon, 41 of ORG's 3,220 (callgrind, `trace_rays dragon 256`) — for
//! entries most rays never reach.
//!
//! Safe to use: entries below `len` are the only ones read, and every one of them was written by
//! [`Stack::push`]; pushing past `N` panics (a corrupt structure, never a sound one: each kernel
//! sizes `N` by the depth its builder guarantees) instead of writing past the array.

use std::mem::MaybeUninit;

pub(crate) struct Stack<T: Copy, const N: usize> {
    slots: [MaybeUninit<T>; N],
    len: usize,
}

impl<T: Copy, const N: usize> Stack<T, N> {
    #[inline(always)]
    pub fn new() -> Self {
        Self { slots: [MaybeUninit::uninit(); N], len: 0 }
    }

    /// Pushes `value`; `false` (and nothing written) when all `N` entries are taken.
    #[inline(always)]
    #[must_use]
    pub fn try_push(&mut self, value: T) -> bool {
        match self.slots.get_mut(self.len) {
            Some(slot) => {
                slot.write(value);
                self.len += 1;
                true
            }
            None => false,
        }
    }

    /// Pushes `value`; panics when all `N` entries are taken.
    #[inline(always)]
    #[track_caller]
    pub fn push(&mut self, value: T) {
        if !self.try_push(value) {
            panic!("traversal stack of {N} entries overflowed");
        }
    }

    /// The entry pushed last, removed; `None` when empty.
    #[inline(always)]
    #[allow(unsafe_code)]
    pub fn pop(&mut self) -> Option<T> {
        if self.len == 0 {
            return None;
        }
        self.len -= 1;
        // SAFETY: `len` ≤ `N` always (`try_push` grows it only after writing a slot below `N`),
        // so the new `len` is below `N` and in bounds; every entry below the length before this
        // pop was written by `try_push`, so this one is initialised.
        Some(unsafe { self.slots.get_unchecked(self.len).assume_init() })
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn pops_in_reverse_and_refuses_past_its_size() {
        let mut s = Stack::<u32, 3>::new();
        assert_eq!(s.pop(), None);
        for v in [7, 8, 9] {
            assert!(s.try_push(v));
        }
        assert!(!s.try_push(10), "a fourth entry in a stack of three");
        assert_eq!([s.pop(), s.pop()], [Some(9), Some(8)]);
        s.push(5);
        assert_eq!([s.pop(), s.pop(), s.pop()], [Some(5), Some(7), None]);
    }

    #[test]
    #[should_panic(expected = "traversal stack of 1 entries overflowed")]
    fn push_past_its_size_panics() {
        let mut s = Stack::<u8, 1>::new();
        s.push(1);
        s.push(2);
    }
}
