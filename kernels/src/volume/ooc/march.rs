//! Ray-guided marching of an out-of-core volume (issue 42): the frame's rays march the lattice
//! samples of the dense marcher, in rounds. In a round every unfinished ray marches until it ends
//! or needs a brick that is not resident — then it records the brick and waits. The round's
//! requests are de-duplicated, given cache slots ([`SlotCache`]: a brick used in the round is not
//! evicted) and read from the store in parallel; the waiting rays go on in the next round. A frame
//! is done when no ray waits. A sample whose brick the transfer function makes wholly transparent
//! (by the store's per-brick value range) needs no brick: it leaves the ray as it was.
//!
//! **The dense marcher's image, bit for bit, whatever the cache size.** A sample is the same
//! lattice point, its cell the same ([`super::super::cell_at`]), and its eight corners, read from
//! its cell's brick (whose apron holds the high-side corners, clamped as the sampler clamps), the
//! same values interpolated in the same order ([`super::super::interpolate`]); the compositing is
//! the same ([`super::super::blend`]). The cache changes how many rounds a frame takes, never a
//! pixel.

use glam::Vec3;
use rayon::prelude::*;
use scenes::volume::store::{BrickGrid, BrickSource};
use scenes::{Camera, Samples, SceneError};

use super::cache::{Allocation, Eviction, SlotCache};
use super::page_table::{PageTable, Slot};
use crate::volume::{TransferFunction, VolumeImage, blend, cell_at, interpolate, samples_in};

/// Heap bytes a cache slot's records take ([`SlotCache`]: owner, last use, clock bit, free-list entry).
const SLOT_RECORD_BYTES: usize = 4 + 8 + 1 + 4;

/// A bound on a frame's heap per pixel: its colour (16 bytes), its ray's state between rounds
/// (`Pending`), its round's outcome and the slots it read (up to 32 distinct runs of bricks in a
/// round before the list is reallocated past 128 bytes), its request, and the order of finished rays.
pub const FRAME_BYTES_PER_PIXEL: u64 = 16 + size_of::<Pending>() as u64 + 2 * (8 + 24 + 128) + 4 + 8;

/// One frame's work.
#[derive(Clone, Debug, Default, PartialEq)]
pub struct FrameStats {
    /// March-and-load rounds until no ray waited.
    pub rounds: u32,
    /// Bricks loaded (constant bricks are filled, not read), and the bytes read or generated.
    pub loads: u64,
    pub bytes_read: u64,
    /// Translations that found the brick resident, and that did not (a ray then waited).
    pub hits: u64,
    pub misses: u64,
    pub evictions: u64,
    /// Distinct bricks the frame's samples read.
    pub working_set: u64,
    /// Leaps over empty bricks (with their neighbours).
    pub leaps: u64,
}

/// A volume from a brick source (a store on disk, a generated field), cast through a fixed-size
/// brick cache.
pub struct OocVolume<S: BrickSource, T: PageTable> {
    source: S,
    grid: BrickGrid,
    table: T,
    cache: SlotCache,
    /// The resident bricks' samples, slot after slot.
    pool: Samples,
    /// Per virtual brick, whether the transfer function makes every value of its range transparent.
    empty: Vec<bool>,
    /// Per virtual brick, whether it and its 26 neighbours are empty: a ray may leap over it
    /// (a sample inside it, its position rounded across a face, still reads an empty brick).
    leap: Vec<bool>,
    /// Per block of [`SUPER`]³ bricks, whether every brick of it may be leapt: a ray crosses the
    /// block in one leap (a sparse field at 8192³ is 256 bricks across, most of them leapt).
    leap_super: Vec<bool>,
    /// Blocks of [`SUPER`]³ bricks per axis.
    supers: [u32; 3],
    inv_spacing: [f32; 3],
    last: [u32; 3],
}

/// Bricks per axis of a block a ray may leap whole.
pub const SUPER: u32 = 8;

/// A ray's state between rounds.
struct Pending {
    pixel: usize,
    origin: Vec3,
    dir: Vec3,
    /// The next lattice sample, and the end of the ray's samples.
    k: i64,
    end: i64,
    rgb: [f32; 3],
    transmittance: f32,
    samples: u64,
    /// Leaps over empty bricks.
    skipped: u64,
}

/// The distinct bricks of `requests` (one per waiting ray), the most requested first; of equals,
/// the lowest index first.
fn most_wanted(mut requests: Vec<u32>) -> Vec<u32> {
    requests.sort_unstable();
    let mut counted: Vec<(u32, u32)> = Vec::new();
    for b in requests {
        match counted.last_mut() {
            Some((last, n)) if *last == b => *n += 1,
            _ => counted.push((b, 1)),
        }
    }
    counted.sort_by_key(|&(b, n)| (std::cmp::Reverse(n), b));
    counted.into_iter().map(|(b, _)| b).collect()
}

/// What one round did to one ray.
enum Outcome {
    Done,
    /// Waits for this virtual brick.
    Waits(u32),
}

impl<S: BrickSource, T: PageTable + Sync> OocVolume<S, T> {
    /// The source's volume through `table` and a cache of `slots` bricks evicted by `policy`.
    pub fn new(source: S, table: T, slots: usize, policy: Eviction) -> Self {
        let cache = SlotCache::new(slots, policy);
        let g = source.grid();
        let pool = source.kind().zeros(cache.slots() * g.samples());
        let supers = g.bricks.map(|b| b.div_ceil(SUPER));
        Self {
            inv_spacing: source.spacing().map(|s| 1.0 / s),
            last: g.dims.map(|d| d - 1),
            empty: vec![false; g.count()],
            leap: vec![false; g.count()],
            leap_super: vec![false; supers.iter().map(|&s| s as usize).product()],
            supers,
            grid: g,
            source,
            table,
            cache,
            pool,
        }
    }

    /// Bricks that `tf` makes wholly transparent are skipped without being read.
    pub fn set_transfer_function(&mut self, tf: &TransferFunction) {
        for (i, e) in self.empty.iter_mut().enumerate() {
            let (min, max) = self.source.range(i);
            *e = !min.is_nan() && tf.is_empty_over(min, max);
        }
        // The occupied bricks dilated by one brick, axis by axis: what is left may be leapt.
        let mut occupied: Vec<bool> = self.empty.iter().map(|e| !e).collect();
        let n = self.grid.bricks.map(|b| b as usize);
        let stride = [1, n[0], n[0] * n[1]];
        for a in 0..3 {
            let before = occupied.clone();
            for (i, o) in occupied.iter_mut().enumerate() {
                let c = i / stride[a] % n[a];
                *o |= (c > 0 && before[i - stride[a]]) || (c + 1 < n[a] && before[i + stride[a]]);
            }
        }
        for (l, o) in self.leap.iter_mut().zip(&occupied) {
            *l = !o;
        }
        // A block may be leapt whole where each of its bricks may.
        self.leap_super.fill(true);
        for (i, &l) in self.leap.iter().enumerate() {
            if !l {
                let block = self.super_index(self.grid.brick(i));
                self.leap_super[block] = false;
            }
        }
    }

    /// The index of the block of brick `b`.
    #[inline]
    fn super_index(&self, b: [u32; 3]) -> usize {
        let [sx, sy, _] = self.supers.map(|s| s as usize);
        let c = b.map(|c| (c / SUPER) as usize);
        c[0] + sx * (c[1] + sy * c[2])
    }

    pub fn table(&self) -> &T {
        &self.table
    }

    /// Bytes of the cache's samples (its slots × a brick's samples).
    pub fn pool_bytes(&self) -> u64 {
        (self.pool.len() * self.source.kind().bytes()) as u64
    }

    /// Heap bytes the volume holds beside the cache's samples: per-brick emptiness, the slots'
    /// records and the page table (its pages kept for reuse included). The source's own state
    /// (a store's index, a field's blob lists) is the source's.
    pub fn state_bytes(&self) -> u64 {
        let per_brick = self.empty.capacity() + self.leap.capacity() + self.leap_super.capacity();
        (per_brick + self.cache.slots() * SLOT_RECORD_BYTES) as u64 + self.table.held_bytes()
    }

    /// A bound on the heap a frame of `pixels` rays holds while it runs, on `threads` worker
    /// threads: per pixel its colour, its ray's state between rounds and the round's outcome
    /// with the slots the ray read ([`FRAME_BYTES_PER_PIXEL`] in all); per virtual brick whether
    /// the frame read it, and the two masks a change of transfer function dilates through; per
    /// thread two bricks' buffers for loading (a brick and its bytes read).
    pub fn frame_bytes(&self, pixels: u64, threads: usize) -> u64 {
        let brick = (self.grid.samples() * self.source.kind().bytes()) as u64;
        pixels * FRAME_BYTES_PER_PIXEL + 3 * self.empty.len() as u64 + 2 * brick * threads as u64
    }

    /// Renders `camera`'s rays through the volume under `tf` every `step`, as
    /// `volume::render(&Dense, …)` does.
    pub fn render(
        &mut self,
        camera: &Camera,
        tf: &TransferFunction,
        step: f32,
    ) -> Result<(VolumeImage, FrameStats), SceneError> {
        let (w, h) = (camera.width, camera.height);
        let spacing = self.source.spacing();
        let hi = Vec3::from_array(std::array::from_fn(|a| self.last[a] as f32 * spacing[a]));
        let mut rgba = vec![[0.0, 0.0, 0.0, 0.0]; (w * h) as usize];
        let mut rays: Vec<Pending> = (0..w * h)
            .filter_map(|i| {
                let ray = camera.ray(i % w, i / w);
                let inv = crate::cpu::slab::reciprocal(ray.dir);
                let (t0, t1) = crate::cpu::slab::interval(
                    &ray.origin.to_array(),
                    &inv,
                    &[0.0; 3],
                    &hi.to_array(),
                    0.0,
                    f32::INFINITY,
                )?;
                let ks = samples_in(t0, t1, step);
                Some(Pending {
                    pixel: i as usize,
                    origin: ray.origin,
                    dir: ray.dir,
                    k: ks.start,
                    end: ks.end,
                    rgb: [0.0; 3],
                    transmittance: 1.0,
                    samples: 0,
                    skipped: 0,
                })
            })
            .collect();
        let mut stats = FrameStats::default();
        let mut samples = 0;
        let mut touched = vec![false; self.empty.len()];
        let (hits0, misses0, evictions0) = (self.cache.hits, self.cache.misses, self.cache.evictions);
        while !rays.is_empty() {
            stats.rounds += 1;
            self.cache.next_round();
            // MARCH: every waiting ray as far as the resident bricks take it.
            let this = &*self;
            let outcomes: Vec<(Outcome, Vec<Slot>)> = rays.par_iter_mut().map(|r| this.march(r, tf, step)).collect();
            let mut requests = Vec::new();
            let mut finished = Vec::new();
            for (i, (outcome, used)) in outcomes.into_iter().enumerate() {
                for s in used {
                    self.cache.touch(s);
                    touched[self.cache.owner(s).expect("a slot a ray read holds a brick") as usize] = true;
                }
                match outcome {
                    Outcome::Done => finished.push(i),
                    Outcome::Waits(b) => {
                        self.cache.misses += 1;
                        requests.push(b);
                    }
                }
            }
            for &i in finished.iter().rev() {
                let r = rays.swap_remove(i);
                rgba[r.pixel] = [r.rgb[0], r.rgb[1], r.rgb[2], 1.0 - r.transmittance];
                samples += r.samples;
                stats.leaps += r.skipped;
            }
            // LOAD: each requested brick once, as long as a slot is not pinned by this round — the
            // bricks most rays wait for first, so that a cache too small for the round's requests
            // lets the most rays go on.
            let wanted = most_wanted(requests);
            let mut loads: Vec<(Slot, u32)> = Vec::new();
            for &b in &wanted {
                match self.cache.allocate(&mut self.table, b) {
                    Allocation::Free(s) | Allocation::Evicted(s, _) => loads.push((s, b)),
                    Allocation::Full => break,
                }
            }
            loads.sort_unstable();
            stats.loads += loads.len() as u64;
            stats.bytes_read += loads.iter().map(|&(_, b)| self.source.cost(b as usize)).sum::<u64>();
            self.load(&loads)?;
        }
        stats.hits = self.cache.hits - hits0;
        stats.misses = self.cache.misses - misses0;
        stats.evictions = self.cache.evictions - evictions0;
        stats.working_set = touched.iter().filter(|&&t| t).count() as u64;
        Ok((VolumeImage { width: w, height: h, rgba, samples, visits: 0 }, stats))
    }

    /// Marches `r` from its next sample until it ends or needs a missing brick; the slots it
    /// read from (each run of samples in one brick once), for the cache to pin.
    fn march(&self, r: &mut Pending, tf: &TransferFunction, step: f32) -> (Outcome, Vec<Slot>) {
        let g = self.grid;
        let n = g.samples();
        let side = g.side() as u32;
        // The brick side is a power of two: a cell's brick and place in it by shift and mask
        // (a division by a side known only at run time costs tens of cycles, three a step).
        let (shift, mask) = (g.brick.trailing_zeros(), g.brick - 1);
        let mut used = Vec::new();
        while r.k < r.end {
            let t = r.k as f32 * step;
            let (cell, f) = cell_at(r.origin + r.dir * t, self.inv_spacing, self.last);
            let brick = cell.map(|c| c >> shift);
            let b = g.index(brick) as u32;
            // The block first: its flags are few enough to stay in cache, the bricks' are not.
            let whole = self.leap_super[self.super_index(brick)];
            if whole || self.leap[b as usize] {
                // To the first sample at or past where the ray leaves the brick's cells, or its
                // block's where the whole block may be leapt: every sample skipped lies in it.
                let span = match whole {
                    true => brick.map(|c| c / SUPER * SUPER..(c / SUPER + 1) * SUPER),
                    false => brick.map(|c| c..c + 1),
                };
                r.k = (r.k + 1).max(samples_in(self.exit(r, span), f32::INFINITY, step).start);
                r.skipped += 1;
                continue;
            }
            if self.empty[b as usize] {
                // Past the brick's samples in one move: they read nothing. Per axis a sample's cell
                // never decreases (or never increases) along the ray, so the samples in the brick
                // are a run of `k`s. Its end is estimated from where the ray leaves the brick's
                // box, then settled by the cells themselves (the estimate may round either way).
                let in_brick = |k: i64| {
                    let (c, _) = cell_at(r.origin + r.dir * (k as f32 * step), self.inv_spacing, self.last);
                    c.map(|c| c >> shift) == brick
                };
                let mut next =
                    (r.k + 1).max(samples_in(self.exit(r, brick.map(|c| c..c + 1)), f32::INFINITY, step).start);
                while next - 1 > r.k && !in_brick(next - 1) {
                    next -= 1;
                }
                while next < r.end && in_brick(next) {
                    next += 1;
                }
                r.k = next;
                continue;
            }
            {
                let Some(slot) = self.table.lookup(b) else { return (Outcome::Waits(b), used) };
                if used.last() != Some(&slot) {
                    used.push(slot);
                }
                let base = slot as usize * n;
                let l = cell.map(|c| c & mask);
                let v = interpolate(f, |dx, dy, dz| {
                    self.pool.get(base + (l[0] + dx + side * (l[1] + dy + side * (l[2] + dz))) as usize)
                });
                r.samples += 1;
                if !blend(&mut r.rgb, &mut r.transmittance, tf.eval(v)) {
                    return (Outcome::Done, used);
                }
            }
            r.k += 1;
        }
        (Outcome::Done, used)
    }

    /// Where `r` leaves the box of the cells of bricks `span` (per axis a range of bricks; its far
    /// faces at the domain's): the nearest exit face.
    fn exit(&self, r: &Pending, span: [std::ops::Range<u32>; 3]) -> f32 {
        let spacing = self.source.spacing();
        let mut t = f32::INFINITY;
        for a in 0..3 {
            let d = r.dir[a];
            if d != 0.0 {
                let brick = self.grid.brick;
                let cell = if d > 0.0 { (span[a].end * brick).min(self.last[a]) } else { span[a].start * brick };
                t = t.min((cell as f32 * spacing[a] - r.origin[a]) / d);
            }
        }
        t
    }

    /// Reads `loads` (slot, virtual brick; by slot) into their slots of the pool, in parallel.
    fn load(&mut self, loads: &[(Slot, u32)]) -> Result<(), SceneError> {
        let n = self.grid.samples();
        let source = &self.source;
        let read = |b: u32, out: &mut Samples| source.read_brick(b as usize, out);
        macro_rules! fill {
            ($pool:expr, $variant:ident) => {{
                let mut slots: Vec<(usize, &mut [_])> = $pool.chunks_mut(n).enumerate().collect();
                slots.retain(|(s, _)| loads.binary_search_by_key(&(*s as Slot), |l| l.0).is_ok());
                slots.into_par_iter().try_for_each_init(
                    || Samples::$variant(Vec::new()),
                    |brick, (s, dst)| {
                        let b = loads[loads.binary_search_by_key(&(s as Slot), |l| l.0).expect("listed")].1;
                        read(b, brick)?;
                        let Samples::$variant(src) = brick else { unreachable!("the store's type") };
                        dst.copy_from_slice(src);
                        Ok(())
                    },
                )
            }};
        }
        match &mut self.pool {
            Samples::U8(pool) => fill!(pool, U8),
            Samples::U16(pool) => fill!(pool, U16),
            Samples::F32(pool) => fill!(pool, F32),
        }
    }
}

#[cfg(test)]
mod tests {
    use super::super::page_table::{Flat, Hashed, MultiLevel, Tree64};
    use scenes::volume::store::BrickStore;

    use super::*;
    use crate::volume::{dense::Dense, render};

    fn temp(name: &str) -> std::path::PathBuf {
        let dir = std::env::temp_dir().join(format!("accel-bench-ooc-{}-{name}", std::process::id()));
        std::fs::create_dir_all(&dir).expect("temp dir");
        dir.join("v.bricks")
    }

    #[test]
    fn the_bricks_most_rays_wait_for_are_loaded_first() {
        assert_eq!(most_wanted(vec![7, 3, 9, 3, 7, 3, 1]), vec![3, 7, 1, 9]);
        assert_eq!(most_wanted(Vec::new()), Vec::<u32>::new());
    }

    /// The dense marcher's image bit for bit, with every page table and eviction policy, from a
    /// cache of one brick (every round loads one) to one that holds the whole volume.
    #[test]
    fn images_equal_the_dense_marchers_whatever_the_cache() {
        for (name, brick) in [("marschner-lobb@33", 8), ("particles@40:30", 4)] {
            let volume = scenes::load_volume(name, 1 << 30).expect("volume");
            let path = temp(&name.replace(['@', ':'], "-"));
            let grid = scenes::volume::store::write_volume(&path, &volume, brick).expect("written");
            let (lo, hi) = super::super::super::Sampler::new(&volume).domain();
            let (v_lo, v_hi) = volume.value_range();
            let tf = TransferFunction::ramp_above(v_lo + 0.4 * (v_hi - v_lo), v_hi, 0.3);
            let spec = scenes::CameraSpec::canonical(scenes::Aabb { min: lo, max: hi });
            let camera = Camera::new(spec, 24, 20);
            let step = 0.7;
            let oracle = render(&Dense, &volume, &tf, &camera, step);
            let bits = |img: &VolumeImage| img.rgba.iter().flat_map(|p| p.map(f32::to_bits)).collect::<Vec<_>>();
            assert!(oracle.rgba.iter().any(|p| p[3] > 0.0), "{name}: the view sees something");
            for slots in [1, 3, grid.count()] {
                for policy in [Eviction::Lru, Eviction::Clock] {
                    let tables = [
                        run(&path, Flat::new(grid.count()), slots, policy, &camera, &tf, step),
                        run(&path, MultiLevel::new(grid.bricks), slots, policy, &camera, &tf, step),
                        run(&path, Hashed::new(), slots, policy, &camera, &tf, step),
                        run(&path, Tree64::new(grid.bricks), slots, policy, &camera, &tf, step),
                    ];
                    for (t, (rgba, stats)) in tables.into_iter().enumerate() {
                        let img = VolumeImage { rgba, ..oracle.clone() };
                        assert!(
                            bits(&img) == bits(&oracle),
                            "{name}: {slots} slots, {policy:?}, table {t}: pixels differ"
                        );
                        assert!(
                            stats.loads >= stats.working_set,
                            "{name}: a cold cache loads each brick used: {stats:?}"
                        );
                        if slots == 1 {
                            assert!(
                                stats.loads <= u64::from(stats.rounds),
                                "{name}: one slot, one load a round: {stats:?}"
                            );
                        }
                        if slots == grid.count() {
                            assert_eq!(stats.evictions, 0, "{name}: a cache of the whole volume evicts nothing");
                            assert_eq!(stats.loads, stats.working_set, "{name}: each brick loaded once");
                        }
                    }
                }
            }
            std::fs::remove_dir_all(path.parent().expect("dir")).ok();
        }
    }

    /// A sparse field of many bricks, where rays leap whole blocks of [`SUPER`]³ bricks, and
    /// single bricks beside occupied ones: the dense marcher's image bit for bit, from several
    /// views (axis-parallel ones among them), with fewer leaps than bricks crossed.
    #[test]
    fn leaping_whole_blocks_skips_no_visible_sample() {
        let (n, count, brick) = (130, 3, 2);
        let volume = scenes::volume::procedural::particles(n, count, 1 << 30).expect("field");
        let (lo, hi) = super::super::super::Sampler::new(&volume).domain();
        let tf = TransferFunction::ramp_above(20.0, 255.0, 0.4);
        let source = scenes::volume::store::ParticleBricks::new(n, count, brick).expect("layout");
        let g = source.grid();
        let mut v = OocVolume::new(source, Flat::new(g.count()), g.count(), Eviction::Clock);
        v.set_transfer_function(&tf);
        let whole = v.leap_super.iter().filter(|&&l| l).count();
        assert!(whole > 0 && whole < v.leap_super.len(), "some blocks leapt whole, not all: {whole}");
        let centre = (lo + hi) * 0.5;
        for eye in [
            lo + (hi - lo) * glam::Vec3::new(1.6, 1.3, 1.9),
            centre + glam::Vec3::new(0.0, 0.0, 2.0 * n as f32),
            centre - glam::Vec3::new(2.0 * n as f32, 0.0, 0.0),
        ] {
            let spec = scenes::CameraSpec { eye, target: centre, up: glam::Vec3::Y, vfov_deg: 40.0 };
            let camera = Camera::new(spec, 40, 32);
            let oracle = render(&Dense, &volume, &tf, &camera, 0.5);
            assert!(oracle.rgba.iter().any(|p| p[3] > 0.0), "the view sees a blob");
            let (image, stats) = v.render(&camera, &tf, 0.5).expect("rendered");
            let bits = |img: &VolumeImage| img.rgba.iter().flat_map(|p| p.map(f32::to_bits)).collect::<Vec<_>>();
            assert!(bits(&image) == bits(&oracle), "{eye}: pixels differ");
            // Brick by brick, the same image with several times the leaps.
            let blocks = v.leap_super.clone();
            v.leap_super.fill(false);
            let (single, by_brick) = v.render(&camera, &tf, 0.5).expect("rendered");
            v.leap_super = blocks;
            assert!(bits(&single) == bits(&oracle), "{eye}: pixels differ, brick by brick");
            assert!(
                stats.leaps * 3 < by_brick.leaps,
                "{eye}: {} leaps, {} brick by brick",
                stats.leaps,
                by_brick.leaps
            );
        }
    }

    /// A field generated brick by brick on demand renders as the whole field does.
    #[test]
    fn a_generated_field_renders_as_the_whole_field() {
        let (n, count) = (64, 6);
        let volume = scenes::volume::procedural::particles(n, count, 1 << 30).expect("field");
        let (lo, hi) = super::super::super::Sampler::new(&volume).domain();
        let tf = TransferFunction::ramp_above(20.0, 255.0, 0.4);
        let camera = Camera::new(scenes::CameraSpec::canonical(scenes::Aabb { min: lo, max: hi }), 20, 16);
        let oracle = render(&Dense, &volume, &tf, &camera, 0.6);
        assert!(oracle.rgba.iter().any(|p| p[3] > 0.0), "the view sees a blob");
        let source = scenes::volume::store::ParticleBricks::new(n, count, 8).expect("layout");
        let bricks = source.grid().count();
        let mut v = OocVolume::new(source, Hashed::new(), 4, Eviction::Clock);
        v.set_transfer_function(&tf);
        let (img, stats) = v.render(&camera, &tf, 0.6).expect("rendered");
        let bits = |rgba: &[[f32; 4]]| rgba.iter().flat_map(|p| p.map(f32::to_bits)).collect::<Vec<_>>();
        assert!(bits(&img.rgba) == bits(&oracle.rgba), "pixels differ");
        assert!(stats.working_set < bricks as u64, "empty bricks are skipped: {stats:?} of {bricks}");
        assert!(stats.leaps > 0 && img.samples < oracle.samples, "rays leap over empty space: {stats:?}");
    }

    fn run<T: PageTable + Sync>(
        path: &std::path::Path,
        table: T,
        slots: usize,
        policy: Eviction,
        camera: &Camera,
        tf: &TransferFunction,
        step: f32,
    ) -> (Vec<[f32; 4]>, FrameStats) {
        let mut v = OocVolume::new(BrickStore::open(path).expect("store"), table, slots, policy);
        v.set_transfer_function(tf);
        let (img, stats) = v.render(camera, tf, step).expect("rendered");
        (img.rgba, stats)
    }
}
