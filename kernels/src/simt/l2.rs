//! The shared L2 cache of the warp simulator: fully associative, least recently used, over 32-byte
//! sectors (the unit a GPU's L2 fills from memory). Real L2s are set-associative and hashed; a fully
//! associative LRU of the same size is the model's simplification, the same on every machine.

use std::collections::HashMap;

/// No entry (the list's end).
const NIL: u32 = u32::MAX;

#[derive(Clone, Copy, Debug)]
struct Entry {
    sector: u64,
    prev: u32,
    next: u32,
}

/// An LRU set of sectors: a hash map into a doubly linked list, most recent first.
#[derive(Debug)]
pub struct Lru {
    capacity: usize,
    map: HashMap<u64, u32, foldhash::fast::FixedState>,
    entries: Vec<Entry>,
    head: u32,
    tail: u32,
    pub accesses: u64,
    pub misses: u64,
}

impl Lru {
    /// A cache of `capacity` sectors (at least one).
    pub fn new(capacity: usize) -> Self {
        let capacity = capacity.max(1);
        Self {
            capacity,
            map: HashMap::with_capacity_and_hasher(capacity.min(1 << 20), foldhash::fast::FixedState::with_seed(0)),
            entries: Vec::with_capacity(capacity.min(1 << 20)),
            head: NIL,
            tail: NIL,
            accesses: 0,
            misses: 0,
        }
    }

    fn unlink(&mut self, i: u32) {
        let Entry { prev, next, .. } = self.entries[i as usize];
        match prev {
            NIL => self.head = next,
            p => self.entries[p as usize].next = next,
        }
        match next {
            NIL => self.tail = prev,
            n => self.entries[n as usize].prev = prev,
        }
    }

    fn push_front(&mut self, i: u32) {
        self.entries[i as usize].prev = NIL;
        self.entries[i as usize].next = self.head;
        if self.head != NIL {
            self.entries[self.head as usize].prev = i;
        }
        self.head = i;
        if self.tail == NIL {
            self.tail = i;
        }
    }

    /// Reads `sector`; whether it was cached. A miss evicts the least recently used sector when
    /// the cache is full.
    pub fn access(&mut self, sector: u64) -> bool {
        self.accesses += 1;
        if let Some(&i) = self.map.get(&sector) {
            self.unlink(i);
            self.push_front(i);
            return true;
        }
        self.misses += 1;
        let i = if self.entries.len() < self.capacity {
            self.entries.push(Entry { sector, prev: NIL, next: NIL });
            (self.entries.len() - 1) as u32
        } else {
            let victim = self.tail;
            self.unlink(victim);
            self.map.remove(&self.entries[victim as usize].sector);
            self.entries[victim as usize].sector = sector;
            victim
        };
        self.map.insert(sector, i);
        self.push_front(i);
        false
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use rand::{Rng, SeedableRng};

    /// The obvious LRU: a list, most recent first.
    fn brute_force(capacity: usize, stream: &[u64]) -> u64 {
        let mut list: Vec<u64> = Vec::new();
        let mut misses = 0;
        for &s in stream {
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
    fn misses_equal_a_brute_force_lru_on_random_streams() {
        let mut rng = rand_pcg::Pcg64::seed_from_u64(45);
        for (capacity, span) in [(1, 4), (3, 8), (16, 40), (64, 70), (100, 1000)] {
            let stream: Vec<u64> = (0..5000).map(|_| rng.random_range(0..span)).collect();
            let mut lru = Lru::new(capacity);
            for &s in &stream {
                lru.access(s);
            }
            assert_eq!(lru.misses, brute_force(capacity, &stream), "capacity {capacity}, span {span}");
            assert_eq!(lru.accesses, 5000);
        }
    }

    #[test]
    fn a_cycle_one_longer_than_the_cache_always_misses() {
        let mut lru = Lru::new(4);
        for round in 0..3 {
            for s in 0..5 {
                assert!(!lru.access(s), "round {round}, sector {s}");
            }
        }
        let mut lru = Lru::new(5);
        (0..5).for_each(|s| _ = lru.access(s));
        assert!((0..5).all(|s| lru.access(s)), "a cycle that fits hits after its first round");
    }
}
