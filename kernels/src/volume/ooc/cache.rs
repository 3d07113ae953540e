//! The brick cache's slots and their replacement (issue 42): a fixed number of slots, each holding
//! one resident brick, and which slot a newly loaded brick takes — a free one, or the one the
//! policy evicts: least recently used ([`Eviction::Lru`]) or the clock's second chance
//! ([`Eviction::Clock`]). Ray-guided loading works in rounds: the rays march until each has
//! finished or waits for a missing brick, the missing bricks load, the waiting rays go on. A
//! brick used in the current round is pinned — a waiting ray needs it — and is never evicted in
//! that round; when every slot is pinned, [`SlotCache::allocate`] says so and the round's
//! remaining loads wait for the next round.
//!
//! The samples live elsewhere (a pool indexed by slot); this is the bookkeeping, with the page
//! table it keeps in step.

use super::page_table::{PageTable, Slot};

/// Which resident brick makes room.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum Eviction {
    /// The one used longest ago.
    Lru,
    /// The first the clock hand finds unreferenced since it last passed (it clears references as
    /// it passes): an approximation of LRU without a timestamp per use.
    Clock,
}

/// What [`SlotCache::allocate`] found.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum Allocation {
    /// A free slot.
    Free(Slot),
    /// A slot whose brick (virtual index) was evicted and unmapped.
    Evicted(Slot, u32),
    /// Every slot holds a brick used in this round.
    Full,
}

/// Per slot: the brick held, when it was last used and whether the clock saw it used.
#[derive(Clone, Debug)]
pub struct SlotCache {
    policy: Eviction,
    owner: Vec<u32>,
    last_used: Vec<u64>,
    referenced: Vec<bool>,
    free: Vec<Slot>,
    hand: usize,
    /// LRU's candidates in this round: the slots not pinned when the round's first victim was
    /// sought, least recently used last (ties: the lowest slot last), so that a round's victims
    /// cost one sort instead of a scan of every slot each.
    lru_queue: Vec<Slot>,
    /// The round `lru_queue` was sorted in (0: never).
    queue_round: u64,
    /// The current round (starts at 1: a slot last used in round 0 was never used).
    round: u64,
    pub hits: u64,
    pub misses: u64,
    pub evictions: u64,
}

const NONE: u32 = u32::MAX;

impl SlotCache {
    /// A cache of `slots` slots (at least one), all free.
    pub fn new(slots: usize, policy: Eviction) -> Self {
        let slots = slots.max(1);
        Self {
            policy,
            owner: vec![NONE; slots],
            last_used: vec![0; slots],
            referenced: vec![false; slots],
            free: (0..slots as Slot).rev().collect(),
            hand: 0,
            lru_queue: Vec::new(),
            queue_round: 0,
            round: 1,
            hits: 0,
            misses: 0,
            evictions: 0,
        }
    }

    pub fn slots(&self) -> usize {
        self.owner.len()
    }

    /// Starts the next round: what was used so far is no longer pinned.
    pub fn next_round(&mut self) {
        self.round += 1;
    }

    /// The slot of `brick` through `table`, marked used in this round (pinned); `None`, counted
    /// as a miss, where it is not resident.
    #[inline]
    pub fn use_brick(&mut self, table: &impl PageTable, brick: u32) -> Option<Slot> {
        let found = table.lookup(brick);
        match found {
            Some(s) => self.touch(s),
            None => self.misses += 1,
        }
        found
    }

    /// Slot `s`, found resident by a translation made elsewhere, marked used in this round
    /// (pinned) and counted as a hit.
    #[inline]
    pub fn touch(&mut self, s: Slot) {
        self.hits += 1;
        self.mark(s);
    }

    #[inline]
    fn mark(&mut self, s: Slot) {
        self.last_used[s as usize] = self.round;
        self.referenced[s as usize] = true;
    }

    fn pinned(&self, s: usize) -> bool {
        self.last_used[s] == self.round
    }

    /// A slot for `brick` (not resident): free, or evicted by the policy among the slots not used
    /// in this round; mapped in `table` and pinned. [`Allocation::Full`] where every slot is pinned.
    pub fn allocate(&mut self, table: &mut impl PageTable, brick: u32) -> Allocation {
        let found = match self.free.pop() {
            Some(s) => Allocation::Free(s),
            None => match self.victim() {
                Some(s) => {
                    let old = self.owner[s as usize];
                    table.unmap(old);
                    self.evictions += 1;
                    Allocation::Evicted(s, old)
                }
                None => return Allocation::Full,
            },
        };
        let (Allocation::Free(s) | Allocation::Evicted(s, _)) = found else { unreachable!() };
        self.owner[s as usize] = brick;
        table.map(brick, s);
        self.mark(s);
        found
    }

    fn victim(&mut self) -> Option<Slot> {
        let n = self.owner.len();
        match self.policy {
            Eviction::Lru => {
                // A slot's last use changes in a round only by being pinned, so the order sorted
                // at the round's first eviction holds for the round; pinned ones are passed over.
                if self.queue_round != self.round {
                    let (last_used, round) = (&self.last_used, self.round);
                    self.lru_queue.clear();
                    self.lru_queue.extend((0..n as Slot).filter(|&s| last_used[s as usize] != round));
                    self.lru_queue.sort_unstable_by_key(|&s| std::cmp::Reverse((last_used[s as usize], s)));
                    self.queue_round = self.round;
                }
                while let Some(s) = self.lru_queue.pop() {
                    if !self.pinned(s as usize) {
                        return Some(s);
                    }
                }
                None
            }
            Eviction::Clock => {
                // Two sweeps at most: the first clears the references it passes.
                for _ in 0..2 * n {
                    let s = self.hand;
                    self.hand = (self.hand + 1) % n;
                    if self.pinned(s) {
                        continue;
                    }
                    if self.referenced[s] {
                        self.referenced[s] = false;
                        continue;
                    }
                    return Some(s as Slot);
                }
                None
            }
        }
    }

    /// The brick slot `s` holds, if any.
    pub fn owner(&self, s: Slot) -> Option<u32> {
        let b = self.owner[s as usize];
        (b != NONE).then_some(b)
    }
}

#[cfg(test)]
mod tests {
    use super::super::page_table::{Flat, Hashed};
    use super::*;

    #[test]
    fn a_brick_used_in_this_round_is_never_evicted() {
        for policy in [Eviction::Lru, Eviction::Clock] {
            // A cache just large enough for one ray's three bricks.
            let mut table = Flat::new(100);
            let mut cache = SlotCache::new(3, policy);
            for b in [10, 20, 30] {
                assert!(matches!(cache.allocate(&mut table, b), Allocation::Free(_)), "{policy:?}");
            }
            // The ray's fourth brick cannot come in this round: all three are pinned.
            assert_eq!(cache.allocate(&mut table, 40), Allocation::Full, "{policy:?}");
            assert!([10, 20, 30].iter().all(|&b| table.lookup(b).is_some()), "{policy:?}: still resident");
            // Next round the ray uses 20 and 30 again; 10 goes.
            cache.next_round();
            assert!(cache.use_brick(&table, 20).is_some() && cache.use_brick(&table, 30).is_some());
            let Allocation::Evicted(s, old) = cache.allocate(&mut table, 40) else { panic!("{policy:?}: evicts") };
            assert_eq!(old, 10, "{policy:?}");
            assert_eq!((table.lookup(10), table.lookup(40)), (None, Some(s)), "{policy:?}");
            assert_eq!(cache.owner(s), Some(40));
        }
    }

    /// LRU's victims, sorted once a round, are the linear scan's: the least recently used slot
    /// not pinned, the lowest of equals — over rounds of random uses and allocations.
    #[test]
    fn lru_victims_equal_a_scan_of_every_slot() {
        use rand::{Rng, SeedableRng};
        let mut rng = rand_pcg::Pcg64Mcg::seed_from_u64(42);
        let mut table = Flat::new(400);
        let mut cache = SlotCache::new(37, Eviction::Lru);
        let mut evicted = 0;
        for _ in 0..300 {
            cache.next_round();
            for _ in 0..rng.random_range(0..20) {
                cache.use_brick(&table, rng.random_range(0..400));
            }
            for _ in 0..rng.random_range(0..30) {
                let b = rng.random_range(0..400);
                if table.lookup(b).is_some() {
                    continue;
                }
                let n = cache.slots();
                let expected = match cache.free.last() {
                    Some(_) => None,
                    None => (0..n).filter(|&s| !cache.pinned(s)).min_by_key(|&s| cache.last_used[s]).map(|s| s as Slot),
                };
                match cache.allocate(&mut table, b) {
                    Allocation::Evicted(s, _) => {
                        assert_eq!(Some(s), expected);
                        evicted += 1;
                    }
                    Allocation::Full => assert_eq!(expected, None),
                    Allocation::Free(_) => {}
                }
            }
        }
        assert!(evicted > 1000, "the test evicts: {evicted}");
    }

    #[test]
    fn lru_evicts_the_least_recently_used_and_clock_gives_a_second_chance() {
        let mut table = Hashed::new();
        let mut lru = SlotCache::new(4, Eviction::Lru);
        for b in 0..4 {
            lru.allocate(&mut table, b);
            lru.next_round();
        }
        // Used since, in this order: 2, 0, 3; brick 1 is the least recently used.
        for b in [2, 0, 3] {
            lru.use_brick(&table, b);
            lru.next_round();
        }
        assert_eq!(lru.allocate(&mut table, 9), Allocation::Evicted(1, 1));
        assert_eq!((lru.hits, lru.misses, lru.evictions), (3, 0, 1));

        let mut table = Hashed::new();
        let mut clock = SlotCache::new(3, Eviction::Clock);
        for b in 0..3 {
            clock.allocate(&mut table, b);
        }
        clock.next_round();
        // Every slot referenced: the hand clears them all once and takes slot 0 on its second pass.
        assert_eq!(clock.allocate(&mut table, 7), Allocation::Evicted(0, 0));
        clock.next_round();
        // Brick 1 used again: the hand (at slot 1) gives it a second chance and takes slot 2.
        clock.use_brick(&table, 1);
        clock.next_round();
        assert_eq!(clock.allocate(&mut table, 8), Allocation::Evicted(2, 2));
        assert_eq!(table.lookup(1), Some(1));
    }
}
