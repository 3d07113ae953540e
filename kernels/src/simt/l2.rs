//! The shared L2 cache of the warp simulator: set-associative with least-recently-used
//! replacement in each set, over 32-byte sectors (the unit a GPU's L2 fills from memory). A
//! sector's set is picked by a multiplicative hash of its address, as GPUs hash addresses over
//! their L2 slices so that strided reads spread. The real hash functions are unpublished; this
//! one is the model's, the same on every machine.

/// Ways per set: 16, as in NVIDIA's L2s.
pub const WAYS: usize = 16;

/// No sector (an empty way).
const EMPTY: u64 = u64::MAX;

/// An LRU cache of sectors in sets of [`WAYS`] ways, each set most recent first.
#[derive(Debug)]
pub struct Lru {
    ways: usize,
    sets: u64,
    tags: Vec<u64>,
    pub accesses: u64,
    pub misses: u64,
}

impl Lru {
    /// A cache of `capacity` sectors (at least one) in sets of [`WAYS`] ways (one set of
    /// `capacity` ways when it holds fewer).
    pub fn new(capacity: usize) -> Self {
        Self::with_ways(capacity, WAYS)
    }

    /// A cache of `capacity` sectors in sets of `ways` ways; `ways = capacity` is fully
    /// associative.
    pub fn with_ways(capacity: usize, ways: usize) -> Self {
        let capacity = capacity.max(1);
        let ways = ways.clamp(1, capacity);
        let sets = (capacity / ways) as u64;
        Self { ways, sets, tags: vec![EMPTY; sets as usize * ways], accesses: 0, misses: 0 }
    }

    /// The set sector `sector` maps to.
    pub fn set_of(&self, sector: u64) -> u64 {
        // Fibonacci hashing: the high bits of the product, spread over the sets.
        ((u128::from(sector.wrapping_mul(0x9E37_79B9_7F4A_7C15)) * u128::from(self.sets)) >> 64) as u64
    }

    /// Reads `sector`; whether it was cached. A miss evicts its set's least recently used
    /// sector when the set is full.
    pub fn access(&mut self, sector: u64) -> bool {
        self.accesses += 1;
        let start = self.set_of(sector) as usize * self.ways;
        let set = &mut self.tags[start..start + self.ways];
        match set.iter().position(|&t| t == sector) {
            Some(p) => {
                set[..=p].rotate_right(1);
                true
            }
            None => {
                self.misses += 1;
                set.rotate_right(1);
                set[0] = sector;
                false
            }
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use rand::{Rng, SeedableRng};

    /// The obvious LRU: a list, most recent first; its misses over `stream`.
    fn brute_force(capacity: usize, stream: impl Iterator<Item = u64>) -> u64 {
        let mut list: Vec<u64> = Vec::new();
        let mut misses = 0;
        for s in stream {
            if let Some(p) = list.iter().position(|&x| x == s) {
                list.remove(p);
            } else {
                misses += 1;
                if list.len() == capacity {
                    list.pop();
                }
            }
            list.insert(0, s);
        }
        misses
    }

    #[test]
    fn fully_associative_misses_equal_a_brute_force_lru_on_random_streams() {
        let mut rng = rand_pcg::Pcg64::seed_from_u64(45);
        for (capacity, span) in [(1, 4), (3, 8), (16, 40), (64, 70), (100, 1000)] {
            let stream: Vec<u64> = (0..5000).map(|_| rng.random_range(0..span)).collect();
            let mut lru = Lru::with_ways(capacity, capacity);
            for &s in &stream {
                lru.access(s);
            }
            assert_eq!(lru.misses, brute_force(capacity, stream.iter().copied()), "capacity {capacity}, span {span}");
            assert_eq!(lru.accesses, 5000);
        }
    }

    #[test]
    fn each_set_is_a_brute_force_lru_of_its_own_sectors() {
        let mut rng = rand_pcg::Pcg64::seed_from_u64(46);
        let stream: Vec<u64> = (0..20000).map(|_| rng.random_range(0..4000)).collect();
        let mut lru = Lru::new(64 * WAYS);
        for &s in &stream {
            lru.access(s);
        }
        let expected: u64 =
            (0..64).map(|set| brute_force(WAYS, stream.iter().copied().filter(|&s| lru.set_of(s) == set))).sum();
        assert_eq!(lru.misses, expected);
        // The hash spreads consecutive sectors over every set.
        let used: std::collections::HashSet<u64> = (0..4000).map(|s| lru.set_of(s)).collect();
        assert_eq!(used.len(), 64);
    }

    #[test]
    fn a_cycle_one_longer_than_the_cache_always_misses() {
        let mut lru = Lru::with_ways(4, 4);
        for round in 0..3 {
            for s in 0..5 {
                assert!(!lru.access(s), "round {round}, sector {s}");
            }
        }
        let mut lru = Lru::with_ways(5, 5);
        (0..5).for_each(|s| _ = lru.access(s));
        assert!((0..5).all(|s| lru.access(s)), "a cycle that fits hits after its first round");
    }
}
