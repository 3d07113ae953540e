//! Builds ESVO's layout ([`super::layout`]) from the canonical voxel octree: contours fitted per
//! voxel, descriptors emitted depth-first with far pointers where a 15-bit offset does not reach,
//! page headers at every 8 KiB, the info section, contour data and one attribute attachment.

use std::time::Instant;

use glam::Vec3;
use rayon::prelude::*;
use scenes::Scene;

use super::attributes::{CompressedBlock, compress_block, encode_abgr, encode_normal};
use super::contour::{FitParams, FitScratch, fit_with};
use super::layout::*;
use super::{Attributes, Esvo, EsvoParams, EsvoStats};
use crate::voxel::{self, Octree};

/// Offsets predicted above this many slots get a far pointer. The prediction leaves out page
/// headers and the padding before a run that would straddle a page (at most 17 slots per page
/// crossed), so the margin keeps every near pointer within [`CHILD_PTR_MAX`].
const FAR_THRESHOLD: u64 = CHILD_PTR_MAX as u64 - 600;

pub fn build(scene: &Scene, params: EsvoParams) -> Esvo {
    let (tree, voxelize) = voxel::build_octree(scene, params.level);
    let t0 = Instant::now();
    let contours = if params.contours { fit_contours(scene, &tree, &params) } else { Vec::new() };
    let contour_ms = t0.elapsed().as_secs_f64() * 1e3;
    let t1 = Instant::now();
    let mut esvo = Emitter::new(&tree, &contours, params.attributes).emit();
    esvo.params = params;
    esvo.voxelize = voxelize;
    esvo.stats.contour_ms = contour_ms;
    esvo.stats.layout_ms = t1.elapsed().as_secs_f64() * 1e3 - esvo.stats.attributes_ms;
    esvo
}

/// Per level (index = level, 1..=L; level 0 is empty), per voxel: its contour word, 0 = none.
///
/// Top-down, so each voxel knows the slab its ancestors already impose (cooperating contours,
/// §5.3), and each voxel's candidate triangles are those of its parent whose bounding box meets
/// its cube (`fit` clips exactly). The top [`SPLIT_LEVEL`] levels go level by level, in parallel
/// over a level's voxels; below, one rayon task per voxel of that level descends depth-first: in
/// Morton order a voxel's descendants are contiguous at every level, so each task fills its own
/// ranges and the ranges concatenate in task order.
fn fit_contours(scene: &Scene, tree: &Octree, esvo: &EsvoParams) -> Vec<Vec<u32>> {
    let grid = tree.grid;
    let levels = grid.level as usize;
    if tree.is_empty() {
        return vec![Vec::new(); levels + 1];
    }
    let to_octree = |p: Vec3| (p - grid.origin) / grid.size + Vec3::ONE;
    let triangles: Vec<[Vec3; 3]> = scene.triangles().par_iter().map(|t| t.map(to_octree)).collect();
    let bounds: Vec<[Vec3; 2]> =
        triangles.par_iter().map(|p| [p[0].min(p[1]).min(p[2]), p[0].max(p[1]).max(p[2])]).collect();
    let params = FitParams { max_ratio: esvo.contour_max_ratio, ..FitParams::default() };
    let fitter = ContourFitter {
        tree,
        triangles: &triangles,
        bounds: &bounds,
        params,
        inherited_enough: esvo.contour_inherited,
    };

    let split = levels.min(SPLIT_LEVEL);
    let mut contours: Vec<Vec<u32>> = vec![Vec::new(); levels + 1];
    let all = (0..triangles.len() as u32).collect();
    let mut frontier = vec![Voxel { index: 0, coords: [0; 3], triangles: all, inherited: f32::INFINITY }];
    for (level, out) in contours.iter_mut().enumerate().take(split) {
        // Per voxel of the level: its contour word and its children with their candidates.
        let expanded: Vec<(u32, Vec<Voxel<Vec<u32>>>)> = frontier
            .par_iter()
            .map(|v| {
                let (word, inherited) = fitter.fit_voxel(level, v, &mut FitBuffers::default());
                let mut children = Vec::new();
                fitter.for_each_child(level, v, inherited, &mut ChildLists::default(), |child, list| {
                    children.push(child.with(list.to_vec()))
                });
                (word, children)
            })
            .collect();
        if level > 0 {
            *out = vec![0; tree.levels[level].len()];
            for (v, (word, _)) in frontier.iter().zip(&expanded) {
                out[v.index] = *word;
            }
        }
        frontier = expanded.into_iter().flat_map(|(_, children)| children).collect();
    }
    let subtrees: Vec<Fill> = frontier
        .into_par_iter()
        .map(|voxel| {
            let mut fill = Fill::subtree(tree, split, voxel.index);
            fitter.visit(split, &voxel, &mut fill);
            fill
        })
        .collect();
    for (level, out) in contours.iter_mut().enumerate().skip(split) {
        *out = subtrees.iter().flat_map(|f| f.words[level].iter().copied()).collect();
        assert_eq!(out.len(), tree.levels[level].len(), "subtree ranges tile level {level}");
    }
    contours
}

/// Levels fitted level by level before the tree is split into one task per voxel (≤ 8³ tasks).
const SPLIT_LEVEL: usize = 3;

/// What contour fitting reads: the octree and the triangles in octree space with their boxes.
struct ContourFitter<'a> {
    tree: &'a Octree,
    triangles: &'a [[Vec3; 3]],
    bounds: &'a [[Vec3; 2]],
    params: FitParams,
    /// [`EsvoParams::contour_inherited`].
    inherited_enough: f32,
}

/// A voxel to fit: its index and integer coordinates at its level, its candidate triangles, and
/// the thickness (octree units) of its ancestors' nearest contour.
struct Voxel<T> {
    index: usize,
    coords: [u32; 3],
    triangles: T,
    inherited: f32,
}

impl Voxel<()> {
    fn with<T>(self, triangles: T) -> Voxel<T> {
        Voxel { index: self.index, coords: self.coords, triangles, inherited: self.inherited }
    }
}

/// The candidate triangles of a voxel's eight children, by child slot.
type ChildLists = [Vec<u32>; 8];

/// Contour words of one subtree: per level, a range of voxels, with scratch buffers per level.
struct Fill {
    /// Per level: the index of the first voxel `words` holds.
    first: Vec<usize>,
    words: Vec<Vec<u32>>,
    /// Per level: the children's candidate triangles, reused.
    lists: Vec<ChildLists>,
    scratch: FitBuffers,
}

/// What fitting one voxel reuses: its triangles' corners and `fit`'s own buffers.
#[derive(Default)]
struct FitBuffers {
    corners: Vec<[Vec3; 3]>,
    fit: FitScratch,
}

impl Fill {
    /// The descendants of voxel `index` at level `split`, from that level down.
    fn subtree(tree: &Octree, split: usize, index: usize) -> Self {
        let levels = tree.levels.len();
        let mut first = vec![0; levels];
        let mut words = vec![Vec::new(); levels];
        let mut range = index..index + 1;
        for level in split..levels {
            first[level] = range.start;
            words[level] = vec![0; range.len()];
            if level + 1 < levels {
                let node = &tree.levels[level];
                let last = range.end - 1;
                range = node.first_child[range.start] as usize
                    ..node.first_child[last] as usize + node.masks[last].count_ones() as usize;
            }
        }
        Fill { first, words, lists: vec![ChildLists::default(); levels], scratch: FitBuffers::default() }
    }
}

impl ContourFitter<'_> {
    /// The contour word of voxel `v` at `level` (0: none) and the inherited thickness its
    /// children see. No contour where its ancestors' slab already pins the surface to a
    /// fraction of the voxel ("store one only where it tightens the bound meaningfully").
    fn fit_voxel<T: AsRef<[u32]>>(&self, level: usize, v: &Voxel<T>, buffers: &mut FitBuffers) -> (u32, f32) {
        if !self.worth_fitting(level, v.inherited) {
            return (0, v.inherited);
        }
        let side = voxel_side(level);
        let c = v.coords;
        let lo = Vec3::ONE + Vec3::new(c[0] as f32, c[1] as f32, c[2] as f32) * side;
        let FitBuffers { corners, fit } = buffers;
        corners.clear();
        corners.extend(v.triangles.as_ref().iter().map(|&t| self.triangles[t as usize]));
        match fit_with(corners, lo, side, &self.params, fit) {
            Some(f) => (f.contour.0, v.inherited.min(slab_thickness(f.contour, side))),
            None => (0, v.inherited),
        }
    }

    /// Whether a voxel at `level` whose ancestors' slab is `inherited` thick gets a contour fitted:
    /// not the root, nor a voxel that slab already pins to [`EsvoParams::contour_inherited`] of
    /// its side.
    fn worth_fitting(&self, level: usize, inherited: f32) -> bool {
        level > 0 && inherited > self.inherited_enough * voxel_side(level)
    }

    /// Calls `f` for each child of interior voxel `v` at `level` with its candidate triangles
    /// (those of `v` whose boxes meet the child's cube), built in `lists` in one pass over `v`'s
    /// triangles: per axis, a box meets the lower children, the upper ones or both.
    fn for_each_child<T: AsRef<[u32]>>(
        &self,
        level: usize,
        v: &Voxel<T>,
        inherited: f32,
        lists: &mut ChildLists,
        mut f: impl FnMut(Voxel<()>, &[u32]),
    ) {
        /// Child slots in the upper half of axis x, y, z (bit `a` of the slot set).
        const UPPER: [u8; 3] = [0b1010_1010, 0b1100_1100, 0b1111_0000];
        let node = &self.tree.levels[level];
        let mask = node.masks[v.index];
        let side = voxel_side(level + 1);
        let c = v.coords;
        let parent_lo = Vec3::ONE + Vec3::new(c[0] as f32, c[1] as f32, c[2] as f32) * (2.0 * side);
        let (centre, parent_hi) = (parent_lo + Vec3::splat(side), parent_lo + Vec3::splat(2.0 * side));
        for list in lists.iter_mut() {
            list.clear();
        }
        // Leaves that will not be fitted need no candidates.
        let leaves = level + 2 == self.tree.levels.len();
        if !leaves || self.worth_fitting(level + 1, inherited) {
            for &t in v.triangles.as_ref() {
                let [lo, hi] = self.bounds[t as usize];
                // Exactly the test `cube_lo ≤ hi && cube_hi ≥ lo` of each child's cube.
                let lower = (lo.cmple(centre) & hi.cmpge(parent_lo)).bitmask();
                let upper = (hi.cmpge(centre) & lo.cmple(parent_hi)).bitmask();
                let mut children = mask;
                for (a, &up) in UPPER.iter().enumerate() {
                    let half = |bits: u32, slots: u8| if bits >> a & 1 == 1 { slots } else { 0 };
                    children &= half(lower, !up) | half(upper, up);
                }
                while children != 0 {
                    lists[children.trailing_zeros() as usize].push(t);
                    children &= children - 1;
                }
            }
        }
        let mut child = node.first_child[v.index] as usize;
        for slot in 0..8u32 {
            if mask >> slot & 1 == 0 {
                continue;
            }
            let coords = [c[0] * 2 + (slot & 1), c[1] * 2 + (slot >> 1 & 1), c[2] * 2 + (slot >> 2 & 1)];
            f(Voxel { index: child, coords, triangles: (), inherited }, &lists[slot as usize]);
            child += 1;
        }
    }

    /// Fits `v` at `level` and, depth-first, its whole subtree into `fill`.
    fn visit<T: AsRef<[u32]>>(&self, level: usize, v: &Voxel<T>, fill: &mut Fill) {
        let (word, inherited) = self.fit_voxel(level, v, &mut fill.scratch);
        fill.words[level][v.index - fill.first[level]] = word;
        if level + 1 == self.tree.levels.len() {
            return;
        }
        let mut lists = std::mem::take(&mut fill.lists[level]);
        self.for_each_child(level, v, inherited, &mut lists, |child, triangles| {
            self.visit(level + 1, &child.with(triangles), fill)
        });
        fill.lists[level] = lists;
    }
}

/// The side of a voxel at `level` in octree units, 2^−level (exact; `exp2` is a libm call).
fn voxel_side(level: usize) -> f32 {
    1.0 / (1u64 << level) as f32
}

/// Thickness in octree units of a contour of a voxel of side `side`: `0.75·T / |n|` voxel sides.
fn slab_thickness(c: super::contour::Contour, side: f32) -> f32 {
    let n = c.normal();
    let len = Vec3::new(n[0] as f32, n[1] as f32, n[2] as f32).length();
    c.thickness() as f32 * 2.0 * super::contour::CHALF / len * side
}

/// What a slot of the descriptor array holds (for the memory breakdown).
#[derive(Clone, Copy, PartialEq)]
enum Slot {
    Header,
    Descriptor { level: u8, voxel: u32 },
    Far,
    Pad,
}

struct Emitter<'a> {
    tree: &'a Octree,
    contours: &'a [Vec<u32>],
    attributes: Attributes,
    /// Predicted slots emitted below each interior voxel (levels 0..L−1), excluding itself.
    sub: Vec<Vec<u64>>,
    slots: Vec<[u32; 2]>,
    kinds: Vec<Slot>,
    contour_data: Vec<u32>,
    /// Raw attachment: lookup entry per slot, values (ABGR, normal) per voxel.
    lookups: Vec<u32>,
    values: Vec<u32>,
    stats: EsvoStats,
}

impl<'a> Emitter<'a> {
    fn new(tree: &'a Octree, contours: &'a [Vec<u32>], attributes: Attributes) -> Self {
        let levels = tree.grid.level as usize;
        let mut sub: Vec<Vec<u64>> = vec![Vec::new(); levels];
        // Bottom-up: level L−1 voxels emit nothing below themselves (their children are leaves).
        if levels > 0 {
            sub[levels - 1] = vec![0; tree.levels[levels - 1].len()];
        }
        for l in (0..levels.saturating_sub(1)).rev() {
            let level = &tree.levels[l];
            sub[l] = (0..level.len())
                .map(|i| {
                    let first = level.first_child[i] as usize;
                    let m = level.masks[i].count_ones() as usize;
                    let subs = &sub[l + 1][first..first + m];
                    let far = far_flags(subs).count_ones() as u64;
                    m as u64 + far + subs.iter().sum::<u64>() + 1
                })
                .collect();
        }
        // Room for every predicted slot plus the page headers and padding (≤ 12 % at L = 11),
        // so that the arrays do not grow (and copy) millions of slots at a time.
        let predicted = sub.first().and_then(|s| s.first()).map_or(0, |&n| n as usize + 1);
        let capacity = predicted + predicted / 8 + PAGE_SLOTS;
        Self {
            tree,
            contours,
            attributes,
            sub,
            slots: Vec::with_capacity(capacity),
            kinds: Vec::with_capacity(capacity),
            contour_data: Vec::with_capacity(contours.iter().map(|c| c.iter().filter(|&&w| w != 0).count()).sum()),
            lookups: Vec::new(),
            values: Vec::new(),
            stats: EsvoStats::default(),
        }
    }

    /// Appends `n` contiguous slots, first inserting the page header where a page starts and
    /// padding so the run neither straddles a page nor (compressed attributes) starts odd.
    fn alloc(&mut self, n: usize) -> usize {
        debug_assert!(n < PAGE_SLOTS / 2);
        let even = self.attributes == Attributes::Compressed;
        loop {
            let s = self.slots.len();
            if s.is_multiple_of(PAGE_SLOTS) {
                self.push(Slot::Header);
            } else if (even && s % 2 == 1) || s / PAGE_SLOTS != (s + n - 1) / PAGE_SLOTS {
                self.push(Slot::Pad);
            } else {
                for _ in 0..n {
                    self.push(Slot::Pad);
                }
                return s;
            }
        }
    }

    fn push(&mut self, kind: Slot) {
        self.slots.push([0, 0]);
        self.kinds.push(kind);
    }

    fn emit(mut self) -> Esvo {
        let mut root_slot = 0;
        if !self.tree.is_empty() {
            root_slot = self.alloc(1);
            self.visit(0, 0, root_slot, None);
        }
        self.finish(root_slot)
    }

    /// Writes the descriptor of voxel `i` at `level` into `slot`, then lays out its children's.
    /// `far` is the far-pointer slot the parent reserved for it, if its offset may not fit.
    fn visit(&mut self, level: usize, i: usize, slot: usize, far: Option<usize>) {
        let leaf_parent = level + 1 == self.tree.levels.len() - 1;
        let node = &self.tree.levels[level];
        let mask = node.masks[i] as u32;
        let first = node.first_child[i] as usize;
        let m = mask.count_ones() as usize;
        self.kinds[slot] = Slot::Descriptor { level: level as u8, voxel: i as u32 };
        self.stats.descriptors += 1;

        // Second word: this voxel's children's contours, consecutive.
        let mut contour_mask = 0;
        let contour_ptr = self.contour_data.len() as u32;
        if let Some(level_contours) = self.contours.get(level + 1).filter(|c| !c.is_empty()) {
            for (k, s) in (0..8).filter(|s| mask >> s & 1 == 1).enumerate() {
                let c = level_contours[first + k];
                if c != 0 && contour_ptr <= CONTOUR_PTR_MAX {
                    contour_mask |= 1 << s;
                    self.contour_data.push(c);
                }
            }
        }
        self.slots[slot][1] = if contour_mask != 0 { (contour_ptr << CONTOUR_PTR_SHIFT) | contour_mask } else { 0 };

        // Raw attachment: one value per valid child.
        if self.attributes == Attributes::Raw {
            let value_ptr = (self.values.len() / 2) as u32;
            self.lookups.resize(self.slots.len().max(slot + 1), 0);
            self.lookups[slot] = (value_ptr.min(VALUE_PTR_MAX) << VALUE_PTR_SHIFT) | mask;
            for k in 0..m {
                let a = self.tree.levels[level + 1].attrs[first + k];
                self.values.push(encode_abgr(a.color));
                self.values.push(encode_normal(a.normal));
            }
        }

        if leaf_parent {
            self.slots[slot][0] = descriptor_w0(0, false, mask, mask);
            return;
        }
        let subs = &self.sub[level + 1][first..first + m];
        let flags = far_flags(subs);
        let f = flags.count_ones() as usize;
        let group = self.alloc(m + f);
        let offset = (group - slot) as u32;
        self.slots[slot][0] = match far {
            Some(far_slot) => {
                self.slots[far_slot][0] = offset;
                descriptor_w0((far_slot - slot) as u32, true, mask, 0)
            }
            None => {
                assert!(offset <= CHILD_PTR_MAX, "near child pointer {offset} overflows: far prediction is wrong");
                descriptor_w0(offset, false, mask, 0)
            }
        };
        let mut far_slots = [None; 8];
        let mut next_far = group + m;
        for (k, far_slot) in far_slots.iter_mut().enumerate().take(m) {
            if flags >> k & 1 == 1 {
                self.kinds[next_far] = Slot::Far;
                self.stats.far_pointers += 1;
                *far_slot = Some(next_far);
                next_far += 1;
            }
        }
        for (k, far_slot) in far_slots.into_iter().enumerate().take(m) {
            self.visit(level + 1, first + k, group + k, far_slot);
        }
    }

    fn finish(mut self, root_slot: usize) -> Esvo {
        let desc_words = self.slots.len() * 2;
        let info = desc_words;
        let mut words: Vec<u32> = Vec::with_capacity(desc_words + 8 + self.contour_data.len());
        for (s, (slot, kind)) in self.slots.iter().zip(&self.kinds).enumerate() {
            match kind {
                Slot::Header => {
                    self.stats.page_headers += 1;
                    words.extend([(info - s * 2) as u32, 0]);
                }
                Slot::Pad => {
                    self.stats.padding_slots += 1;
                    words.extend(slot);
                }
                _ => words.extend(slot),
            }
        }
        // Info section: block pointer (signed, words from the info section to the descriptors),
        // contour pointer, attachment count, then (type, pointer) per attachment.
        let attach_count = 1u32;
        let info_words = INFO_HEADER_WORDS + 2 * attach_count as usize;
        let contour_word = info + info_words;
        let attach_word = contour_word + self.contour_data.len();
        words.push((-(info as i64)) as i32 as u32);
        words.push((contour_word - info) as u32);
        words.push(attach_count);
        let attach_type = match self.attributes {
            Attributes::Raw => ATTACH_RAW,
            Attributes::Compressed => ATTACH_COMPRESSED,
        };
        words.extend([attach_type, (attach_word - info) as u32]);
        self.stats.contours = self.contour_data.len() as u64;
        words.extend(&self.contour_data);
        let (colour_bytes, normal_bytes, lookup_bytes) = match self.attributes {
            Attributes::Raw => {
                self.lookups.resize(self.slots.len(), 0);
                words.extend(&self.lookups);
                words.extend(&self.values);
                (self.values.len() as u64 * 2, self.values.len() as u64 * 2, self.lookups.len() as u64 * 4)
            }
            Attributes::Compressed => {
                let t0 = Instant::now();
                let blocks = self.compressed_blocks();
                self.stats.attributes_ms = t0.elapsed().as_secs_f64() * 1e3;
                for b in &blocks {
                    words.extend(b.0);
                }
                (blocks.len() as u64 * 8, blocks.len() as u64 * 16, 0)
            }
        };
        let tree = self.tree;
        self.stats.leaf_voxels = tree.voxel_count();
        self.stats.voxels = tree.voxel_count() + tree.interior_count();
        self.stats.colour_bytes = colour_bytes;
        self.stats.normal_bytes = normal_bytes;
        self.stats.lookup_bytes = lookup_bytes;
        self.stats.desc_slots = self.slots.len() as u64;
        Esvo {
            occupied: occupied_box(tree),
            grid: tree.grid,
            words,
            root_slot: root_slot as u32,
            info_word: info as u32,
            contour_word: contour_word as u32,
            attach_word: attach_word as u32,
            attributes: self.attributes,
            stats: self.stats,
            params: EsvoParams::default(),
            voxelize: Default::default(),
        }
    }

    /// One compressed block per pair of slots `(2j, 2j + 1)`: the 16 child values of the two
    /// descriptors (siblings, or a descriptor and a non-descriptor slot), slot `8·(s & 1) + i`.
    fn compressed_blocks(&self) -> Vec<CompressedBlock> {
        let n = self.slots.len().div_ceil(2);
        (0..n)
            .into_par_iter()
            .map(|j| {
                let mut values = [None; 16];
                for half in 0..2 {
                    let Some(Slot::Descriptor { level, voxel }) = self.kinds.get(2 * j + half).copied() else {
                        continue;
                    };
                    let node = &self.tree.levels[level as usize];
                    let mask = node.masks[voxel as usize] as u32;
                    let first = node.first_child[voxel as usize] as usize;
                    let children = &self.tree.levels[level as usize + 1].attrs;
                    for (k, s) in (0..8).filter(|s| mask >> s & 1 == 1).enumerate() {
                        let a = children[first + k];
                        values[half * 8 + s] = Some((a.color, a.normal));
                    }
                }
                compress_block(&values)
            })
            .collect()
    }
}

/// The octree-space box of the leaves' parents (see [`Esvo::occupied`]); the root cube when
/// there are no parents with codes to bound (an empty tree, or L = 0).
fn occupied_box(tree: &Octree) -> [Vec3; 2] {
    let root = [Vec3::ONE, Vec3::splat(2.0)];
    let Some(level) = tree.levels.len().checked_sub(2).filter(|&l| l > 0) else { return root };
    let mut bounds = voxel::CodeBounds::default();
    tree.levels[level].codes.iter().for_each(|&code| bounds.add(code));
    bounds.octree_box(level as u32)
}

/// Which of the children (with predicted subtree sizes `subs`, laid out in this order right after
/// their group and its far slots) need a far pointer: child `k`'s own group lands
/// `(m − k) + far + Σ_{j<k} subs[j]` slots after it. Iterated to a fixed point, since each far
/// slot moves every later group by one.
fn far_flags(subs: &[u64]) -> u8 {
    let m = subs.len() as u64;
    let mut flags = 0u8;
    loop {
        let far = flags.count_ones() as u64;
        let mut next = 0u8;
        let mut before = 0u64;
        for (k, &s) in subs.iter().enumerate() {
            // A child whose children are leaves has no group of its own to point at.
            if s > 0 && (m - k as u64) + far + before > FAR_THRESHOLD {
                next |= 1 << k;
            }
            before += s;
        }
        if next == flags {
            return flags;
        }
        flags = next;
    }
}
