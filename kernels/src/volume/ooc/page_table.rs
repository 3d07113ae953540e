//! Address translation for out-of-core volumes (issue 42; seed 003's virtual-texturing section):
//! a virtual brick — its index in the store's brick grid — to the slot of the brick cache that
//! holds it, or none. The schemes the seed and the literature weigh, one [`PageTable`] each:
//!
//! - [`Flat`]: one entry per virtual brick, a single read to translate; its size grows with the
//!   virtual volume, not with what is resident (seed 003: "fastest to translate").
//! - [`MultiLevel`]: a directory over blocks of [`PAGE`]³ virtual bricks, each block's page of
//!   entries allocated while any of its bricks is resident (Hadwiger, Beyer, Jeong & Pfister,
//!   "Interactive volume exploration of petascale microscopy data streams using a
//!   visualization-driven virtual memory approach", 2012): two reads, size with the resident set.
//! - [`Tree64`]: a 64-tree over the virtual bricks (`tree64`'s shape), a dense node of 64 entries
//!   a level: a hierarchy as its own page table, one read a level, its size with the resident set.
//! - [`Hashed`]: a hash map from virtual brick to slot (seed 003's "simple" choice; hashbrown with
//!   foldhash), its size with the resident set, a probe sequence per translation.
//!
//! Each counts the memory it holds ([`PageTable::bytes`]) and the reads a translation makes
//! ([`PageTable::reads_per_lookup`]), the figures the report compares.

use hashbrown::HashMap;

/// A cache slot.
pub type Slot = u32;

/// No slot: the brick is not resident.
const ABSENT: u32 = u32::MAX;

/// Virtual bricks per axis of a [`MultiLevel`] page.
pub const PAGE: u32 = 8;

/// The schemes by the names the harness and the report use.
pub const SCHEMES: [&str; 4] = ["flat", "multi-level", "64-tree", "hash"];

/// Work to do with a page table, whatever its scheme ([`with_scheme`] builds the scheme named).
pub trait WithTable {
    type Output;
    fn with<T: PageTable + Sync>(self, table: T) -> Self::Output;
}

/// `work` done with an empty table of the scheme `name` (one of [`SCHEMES`]) over a grid of
/// `bricks` virtual bricks per axis; `None` for a name that is no scheme.
pub fn with_scheme<W: WithTable>(name: &str, bricks: [u32; 3], work: W) -> Option<W::Output> {
    let count = bricks.iter().map(|&b| b as usize).product();
    Some(match name {
        "flat" => work.with(Flat::new(count)),
        "multi-level" => work.with(MultiLevel::new(bricks)),
        "64-tree" => work.with(Tree64::new(bricks)),
        "hash" => work.with(Hashed::new()),
        _ => return None,
    })
}

/// Virtual brick → cache slot.
pub trait PageTable {
    /// The scheme's name, as the report shows it.
    fn name(&self) -> &'static str;
    /// The slot holding virtual brick `brick`, `None` if it is not resident.
    fn lookup(&self, brick: u32) -> Option<Slot>;
    /// Records that `brick` is now held by `slot`.
    fn map(&mut self, brick: u32, slot: Slot);
    /// Records that `brick` is no longer resident.
    fn unmap(&mut self, brick: u32);
    /// Bytes the table holds now.
    fn bytes(&self) -> u64;
    /// Heap bytes the table has allocated: [`PageTable::bytes`] and pages kept for reuse.
    fn held_bytes(&self) -> u64 {
        self.bytes()
    }
    /// Memory reads a lookup makes (for a hash table, the expected probes of a hit).
    fn reads_per_lookup(&self) -> f64;
}

/// One entry per virtual brick.
#[derive(Clone, Debug)]
pub struct Flat {
    entries: Vec<u32>,
}

impl Flat {
    /// A table over `bricks` virtual bricks, all absent.
    pub fn new(bricks: usize) -> Self {
        Self { entries: vec![ABSENT; bricks] }
    }
}

impl PageTable for Flat {
    fn name(&self) -> &'static str {
        "flat"
    }
    #[inline]
    fn lookup(&self, brick: u32) -> Option<Slot> {
        let s = self.entries[brick as usize];
        (s != ABSENT).then_some(s)
    }
    fn map(&mut self, brick: u32, slot: Slot) {
        self.entries[brick as usize] = slot;
    }
    fn unmap(&mut self, brick: u32) {
        self.entries[brick as usize] = ABSENT;
    }
    fn bytes(&self) -> u64 {
        (self.entries.len() * size_of::<u32>()) as u64
    }
    fn reads_per_lookup(&self) -> f64 {
        1.0
    }
}

/// A directory over blocks of [`PAGE`]³ virtual bricks; a block's page exists while it holds a
/// resident brick.
#[derive(Clone, Debug)]
pub struct MultiLevel {
    /// Virtual bricks per axis.
    bricks: [u32; 3],
    /// Blocks per axis.
    blocks: [u32; 3],
    /// Per block, its page's index in `pages` (or [`ABSENT`]).
    directory: Vec<u32>,
    /// Pages of `PAGE³` entries, with the count of resident bricks in each.
    pages: Vec<(Box<[u32]>, u32)>,
    /// Pages no block uses, for reuse.
    free: Vec<u32>,
}

impl MultiLevel {
    /// A table over a grid of `bricks` virtual bricks per axis, all absent.
    pub fn new(bricks: [u32; 3]) -> Self {
        let blocks = bricks.map(|b| b.div_ceil(PAGE));
        let n = blocks.iter().map(|&b| b as usize).product();
        Self { bricks, blocks, directory: vec![ABSENT; n], pages: Vec::new(), free: Vec::new() }
    }

    /// Block and entry within its page of virtual brick `brick` (x fastest in both).
    #[inline]
    fn split(&self, brick: u32) -> (usize, usize) {
        let [nx, ny, _] = self.bricks;
        let c = [brick % nx, brick / nx % ny, brick / (nx * ny)];
        let block = std::array::from_fn::<u32, 3, _>(|a| c[a] / PAGE);
        let within = std::array::from_fn::<u32, 3, _>(|a| c[a] % PAGE);
        let [bx, by, _] = self.blocks;
        let b = block[0] + bx * (block[1] + by * block[2]);
        (b as usize, (within[0] + PAGE * (within[1] + PAGE * within[2])) as usize)
    }
}

impl PageTable for MultiLevel {
    fn name(&self) -> &'static str {
        "multi-level"
    }
    #[inline]
    fn lookup(&self, brick: u32) -> Option<Slot> {
        let (block, entry) = self.split(brick);
        let page = self.directory[block];
        if page == ABSENT {
            return None;
        }
        let s = self.pages[page as usize].0[entry];
        (s != ABSENT).then_some(s)
    }
    fn map(&mut self, brick: u32, slot: Slot) {
        let (block, entry) = self.split(brick);
        if self.directory[block] == ABSENT {
            let page = match self.free.pop() {
                Some(p) => p,
                None => {
                    self.pages.push((vec![ABSENT; (PAGE * PAGE * PAGE) as usize].into_boxed_slice(), 0));
                    self.pages.len() as u32 - 1
                }
            };
            self.directory[block] = page;
        }
        let (entries, resident) = &mut self.pages[self.directory[block] as usize];
        if entries[entry] == ABSENT {
            *resident += 1;
        }
        entries[entry] = slot;
    }
    fn unmap(&mut self, brick: u32) {
        let (block, entry) = self.split(brick);
        let page = self.directory[block];
        if page == ABSENT {
            return;
        }
        let (entries, resident) = &mut self.pages[page as usize];
        if entries[entry] != ABSENT {
            entries[entry] = ABSENT;
            *resident -= 1;
            if *resident == 0 {
                self.directory[block] = ABSENT;
                self.free.push(page);
            }
        }
    }
    /// The directory and the pages in use (a freed page is kept for reuse but counted out).
    fn bytes(&self) -> u64 {
        let page = u64::from(PAGE * PAGE * PAGE) * size_of::<u32>() as u64;
        (self.directory.len() * size_of::<u32>()) as u64 + (self.pages.len() - self.free.len()) as u64 * page
    }
    fn held_bytes(&self) -> u64 {
        let page = u64::from(PAGE * PAGE * PAGE) * size_of::<u32>() as u64;
        let records = self.pages.capacity() * size_of::<(Box<[u32]>, u32)>() + self.free.capacity() * 4;
        (self.directory.capacity() * size_of::<u32>() + records) as u64 + self.pages.len() as u64 * page
    }
    fn reads_per_lookup(&self) -> f64 {
        2.0
    }
}

/// A 64-tree over the virtual bricks (fan-out 4³ a level, as `tree64`), each node a dense table
/// of 64 entries — a child node's index, or at the last level a slot — allocated while a brick
/// below it is resident and given back when none is: a hierarchy as its own page table, one read
/// a level.
#[derive(Clone, Debug)]
pub struct Tree64 {
    bricks: [u32; 3],
    /// Levels of 4³ below the root (the root's level included): 4^levels ≥ every axis.
    levels: u32,
    /// Nodes of 64 entries, with the count of non-absent entries in each; node 0 is the root.
    nodes: Vec<([u32; 64], u32)>,
    free: Vec<u32>,
}

impl Tree64 {
    pub fn new(bricks: [u32; 3]) -> Self {
        let mut levels = 1;
        while bricks.iter().any(|&b| b > 1 << (2 * levels)) {
            levels += 1;
        }
        Self { bricks, levels, nodes: vec![([ABSENT; 64], 0)], free: Vec::new() }
    }

    /// The brick's coordinates.
    #[inline]
    fn coords(&self, brick: u32) -> [u32; 3] {
        let [nx, ny, _] = self.bricks;
        [brick % nx, brick / nx % ny, brick / (nx * ny)]
    }

    /// The entry of level `l` (0 the root) on the path to `c`: 2 bits of each axis, x lowest.
    #[inline]
    fn entry(&self, c: [u32; 3], l: u32) -> usize {
        let shift = 2 * (self.levels - 1 - l);
        ((c[0] >> shift & 3) | (c[1] >> shift & 3) << 2 | (c[2] >> shift & 3) << 4) as usize
    }
}

impl PageTable for Tree64 {
    fn name(&self) -> &'static str {
        "64-tree"
    }
    #[inline]
    fn lookup(&self, brick: u32) -> Option<Slot> {
        let c = self.coords(brick);
        let mut node = 0usize;
        for l in 0..self.levels {
            let e = self.nodes[node].0[self.entry(c, l)];
            if e == ABSENT {
                return None;
            }
            if l + 1 == self.levels {
                return Some(e);
            }
            node = e as usize;
        }
        None
    }
    fn map(&mut self, brick: u32, slot: Slot) {
        let c = self.coords(brick);
        let mut node = 0usize;
        for l in 0..self.levels - 1 {
            let e = self.entry(c, l);
            if self.nodes[node].0[e] == ABSENT {
                let child = match self.free.pop() {
                    Some(f) => f,
                    None => {
                        self.nodes.push(([ABSENT; 64], 0));
                        self.nodes.len() as u32 - 1
                    }
                };
                self.nodes[node].0[e] = child;
                self.nodes[node].1 += 1;
            }
            node = self.nodes[node].0[e] as usize;
        }
        let e = self.entry(c, self.levels - 1);
        if self.nodes[node].0[e] == ABSENT {
            self.nodes[node].1 += 1;
        }
        self.nodes[node].0[e] = slot;
    }
    fn unmap(&mut self, brick: u32) {
        let c = self.coords(brick);
        let mut path = Vec::with_capacity(self.levels as usize);
        let mut node = 0usize;
        for l in 0..self.levels {
            let e = self.entry(c, l);
            let next = self.nodes[node].0[e];
            if next == ABSENT {
                return;
            }
            path.push((node, e));
            node = next as usize;
        }
        // Clear the slot, then every node the clearing left empty, from the bottom (the root stays).
        for &(node, e) in path.iter().rev() {
            let child = self.nodes[node].0[e];
            self.nodes[node].0[e] = ABSENT;
            self.nodes[node].1 -= 1;
            if (node, e) != *path.last().expect("a path") {
                self.free.push(child);
            }
            if self.nodes[node].1 > 0 || node == 0 {
                break;
            }
        }
    }
    /// The nodes in use, 64 entries each.
    fn bytes(&self) -> u64 {
        ((self.nodes.len() - self.free.len()) * 64 * size_of::<u32>()) as u64
    }
    fn held_bytes(&self) -> u64 {
        (self.nodes.capacity() * size_of::<([u32; 64], u32)>() + self.free.capacity() * size_of::<u32>()) as u64
    }
    fn reads_per_lookup(&self) -> f64 {
        f64::from(self.levels)
    }
}

/// A hash map from virtual brick to slot.
#[derive(Clone, Debug, Default)]
pub struct Hashed {
    map: HashMap<u32, u32, foldhash::fast::FixedState>,
}

impl Hashed {
    pub fn new() -> Self {
        Self::default()
    }
}

impl PageTable for Hashed {
    fn name(&self) -> &'static str {
        "hash"
    }
    #[inline]
    fn lookup(&self, brick: u32) -> Option<Slot> {
        self.map.get(&brick).copied()
    }
    fn map(&mut self, brick: u32, slot: Slot) {
        self.map.insert(brick, slot);
    }
    fn unmap(&mut self, brick: u32) {
        self.map.remove(&brick);
    }
    /// The table's buckets (key and slot) and their control bytes, as hashbrown allocates them.
    fn bytes(&self) -> u64 {
        let capacity = self.map.capacity();
        if capacity == 0 {
            return 0;
        }
        // A SwissTable holds up to 7/8 of its power-of-two buckets, and a control byte per bucket
        // plus one group's worth.
        let buckets = (capacity * 8).div_ceil(7).next_power_of_two() as u64;
        buckets * (2 * size_of::<u32>() as u64 + 1) + 16
    }
    /// A hit in a SwissTable reads its control group and, almost always, one bucket.
    fn reads_per_lookup(&self) -> f64 {
        2.0
    }
}

#[cfg(test)]
mod tests {
    use rand::{Rng, SeedableRng};

    use super::*;

    /// Every scheme against a plain map over a random sequence of maps, remaps and unmaps on an
    /// uneven grid (blocks cut by its faces), every brick looked up after each change.
    /// Each name of [`SCHEMES`] builds its own scheme; another builds none.
    #[test]
    fn every_scheme_is_built_by_its_name() {
        struct Name;
        impl WithTable for Name {
            type Output = &'static str;
            fn with<T: PageTable + Sync>(self, table: T) -> &'static str {
                table.name()
            }
        }
        for scheme in SCHEMES {
            assert_eq!(with_scheme(scheme, [5, 6, 7], Name), Some(scheme));
        }
        assert_eq!(with_scheme("octree", [5, 6, 7], Name), None);
    }

    #[test]
    fn every_scheme_maps_every_brick_as_a_plain_map_does() {
        let bricks = [13u32, 9, 17];
        let n = bricks.iter().product::<u32>();
        let mut tables: Vec<Box<dyn PageTable>> = vec![
            Box::new(Flat::new(n as usize)),
            Box::new(MultiLevel::new(bricks)),
            Box::new(Hashed::new()),
            Box::new(Tree64::new(bricks)),
        ];
        let mut plain = std::collections::HashMap::new();
        let mut rng = rand_pcg::Pcg64::seed_from_u64(42);
        for step in 0..4000 {
            let brick = rng.random_range(0..n);
            if rng.random_bool(0.6) {
                let slot = rng.random_range(0..1000);
                plain.insert(brick, slot);
                tables.iter_mut().for_each(|t| t.map(brick, slot));
            } else {
                plain.remove(&brick);
                tables.iter_mut().for_each(|t| t.unmap(brick));
            }
            if step % 97 == 0 || step > 3990 {
                for b in 0..n {
                    for t in &tables {
                        assert_eq!(t.lookup(b), plain.get(&b).copied(), "{} at step {step}, brick {b}", t.name());
                    }
                }
            }
        }
        // Everything unmapped: the multi-level table gives its pages back.
        for b in 0..n {
            tables.iter_mut().for_each(|t| t.unmap(b));
        }
        let multi = MultiLevel::new(bricks);
        assert_eq!(tables[1].bytes(), multi.bytes(), "only the directory is left");
        assert_eq!(tables[3].bytes(), 64 * 4, "only the 64-tree's root is left");
        assert!(tables.iter().all(|t| (0..n).all(|b| t.lookup(b).is_none())));
    }

    #[test]
    fn sizes_grow_with_the_virtual_volume_or_with_the_resident_set() {
        let bricks = [256u32; 3];
        let n = 256 * 256 * 256;
        let (mut flat, mut multi, mut hashed) = (Flat::new(n), MultiLevel::new(bricks), Hashed::new());
        assert_eq!(flat.bytes(), 64 << 20, "4 bytes per virtual brick, resident or not");
        assert_eq!(multi.bytes(), 32 * 32 * 32 * 4, "a directory entry per block of 8³");
        // 1000 resident bricks in one corner: two pages (of 8³ bricks) per 10 along x, and so on.
        for z in 0..10 {
            for y in 0..10 {
                for x in 0..10 {
                    let b = x + 256 * (y + 256 * z);
                    flat.map(b, b);
                    multi.map(b, b);
                    hashed.map(b, b);
                }
            }
        }
        assert_eq!(flat.bytes(), 64 << 20);
        assert_eq!(multi.bytes(), 32 * 32 * 32 * 4 + 8 * 512 * 4, "eight pages touched");
        assert!(hashed.bytes() < 64 << 10, "a thousand entries: {}", hashed.bytes());
    }
}
