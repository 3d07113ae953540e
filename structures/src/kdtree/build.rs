//! The SAH kd-tree build of Wald & Havran, "On building fast kd-trees for ray tracing, and on
//! doing that in O(N log N)", IEEE RT 2006: split candidates are the events where a triangle's
//! (clipped) box starts, ends or lies in a plane, sorted once; each node finds its best plane in
//! one sweep over its sorted events (§4.3, Algorithm 4), classifies its triangles as left, right or
//! both from the events of that axis (§4.4), and hands each child its events already sorted: the
//! one-sided triangles' by filtering, the straddling ones' freshly made and sorted, then merged
//! (§4.5) — O(N log N) in all. Subtrees are built in parallel (rayon).

use glam::Vec3;
use rayon::prelude::*;
use scenes::Triangle;

use super::clip::clipped_bounds;
use super::{KdParams, Tmp};

/// Event kinds, in the order the sweep needs them at one position: ends, planar, starts.
const END: u8 = 0;
const PLANAR: u8 = 1;
const START: u8 = 2;

/// One end of a triangle's box on one axis, in 8 bytes (the build streams hundreds of millions):
/// the position, and a key holding the axis (bits 30–31), the kind (bits 28–29) and the
/// triangle's index into the node's triangle list (bits 0–27), so that ordering the keys orders
/// by axis, then kind.
#[derive(Clone, Copy, Debug)]
struct Event {
    pos: f32,
    key: u32,
}

/// The most triangles a node's local indices can number.
pub(super) const MAX_TRIANGLES: usize = 1 << 28;
const TRI_BITS: u32 = (1 << 28) - 1;

impl Event {
    fn new(pos: f32, tri: u32, axis: u8, kind: u8) -> Self {
        debug_assert!(tri <= TRI_BITS && axis < 3 && kind <= START);
        Self { pos, key: u32::from(axis) << 30 | u32::from(kind) << 28 | tri }
    }

    fn tri(&self) -> u32 {
        self.key & TRI_BITS
    }

    fn axis(&self) -> u8 {
        (self.key >> 30) as u8
    }

    fn kind(&self) -> u8 {
        (self.key >> 28 & 3) as u8
    }

    fn with_tri(self, tri: u32) -> Self {
        Self { key: self.key & !TRI_BITS | tri, ..self }
    }
}

fn event_order(a: &Event, b: &Event) -> std::cmp::Ordering {
    a.pos.total_cmp(&b.pos).then((a.key >> 28).cmp(&(b.key >> 28)))
}

/// A node's triangles (global ids) and its events (over local indices into `tris`), sorted.
struct NodeInput {
    tris: Vec<u32>,
    events: Vec<Event>,
}

/// The best plane of a node: axis, position, which side its planar triangles go to, and cost.
#[derive(Clone, Copy, Debug)]
struct Plane {
    axis: usize,
    pos: f32,
    planar_left: bool,
    cost: f32,
}

/// Nodes holding more triangles than this build their children in parallel.
const PARALLEL_TRIANGLES: usize = 4096;

/// Builds the tree over `triangles` inside `bounds` (the scene box). Returns the temporary tree.
pub(super) fn build_tree(triangles: &[Triangle], bounds: (Vec3, Vec3), params: &KdParams, max_depth: u32) -> Tmp {
    let tris: Vec<u32> = (0..triangles.len() as u32).collect();
    let mut events: Vec<Event> = tris
        .par_iter()
        .flat_map_iter(|&t| {
            let [a, b, c] = triangles[t as usize];
            box_events((a.min(b).min(c), a.max(b).max(c)), t)
        })
        .collect();
    events.par_sort_unstable_by(event_order);
    let ctx = Ctx { triangles, params, max_depth };
    ctx.node(NodeInput { tris, events }, bounds, 0)
}

/// The events of a box (`lo..hi`) on the three axes: planar where it is flat, else start and end.
fn box_events((lo, hi): (Vec3, Vec3), tri: u32) -> impl Iterator<Item = Event> {
    (0..3u8).flat_map(move |axis| {
        let (a, b) = (lo[axis as usize], hi[axis as usize]);
        let planar = a == b;
        let first = Event::new(a, tri, axis, if planar { PLANAR } else { START });
        let second = (!planar).then_some(Event::new(b, tri, axis, END));
        std::iter::once(first).chain(second)
    })
}

fn area((lo, hi): (Vec3, Vec3)) -> f32 {
    let d = (hi - lo).max(Vec3::ZERO);
    2.0 * (d.x * d.y + d.y * d.z + d.z * d.x)
}

struct Ctx<'a> {
    triangles: &'a [Triangle],
    params: &'a KdParams,
    max_depth: u32,
}

impl Ctx<'_> {
    fn node(&self, input: NodeInput, bounds: (Vec3, Vec3), depth: u32) -> Tmp {
        let n = input.tris.len();
        let leaf_cost = self.params.ci * n as f32;
        let plane = match depth < self.max_depth && n > self.params.leaf_size as usize {
            true => self.find_plane(&input, bounds).filter(|p| p.cost < leaf_cost),
            false => None,
        };
        let Some(plane) = plane else {
            return Tmp::Leaf(input.tris);
        };
        let (below, above) = split_box(bounds, plane.axis, plane.pos);
        let (left, right) = self.distribute(input, plane, below, above);
        let (l, r) = if n > PARALLEL_TRIANGLES {
            rayon::join(|| self.node(left, below, depth + 1), || self.node(right, above, depth + 1))
        } else {
            (self.node(left, below, depth + 1), self.node(right, above, depth + 1))
        };
        Tmp::Inner { axis: plane.axis as u8, pos: plane.pos, children: Box::new([l, r]) }
    }

    /// The sweep of Algorithm 4: one pass over the node's sorted events, all three axes at once,
    /// with per-axis counts of triangles left of, in and right of the candidate plane.
    fn find_plane(&self, input: &NodeInput, bounds: (Vec3, Vec3)) -> Option<Plane> {
        let n = input.tris.len() as u32;
        let total = area(bounds);
        if total <= 0.0 {
            return None;
        }
        let (mut nl, mut np, mut nr) = ([0u32; 3], [0u32; 3], [n; 3]);
        let mut best: Option<Plane> = None;
        let events = &input.events;
        let mut i = 0;
        while i < events.len() {
            let (axis, pos) = (events[i].axis(), events[i].pos);
            let mut counts = [0u32; 3];
            while i < events.len() && events[i].axis() == axis && events[i].pos == pos {
                counts[events[i].kind() as usize] += 1;
                i += 1;
            }
            let [ends, planar, starts] = counts;
            let k = axis as usize;
            np[k] = planar;
            nr[k] -= planar + ends;
            // A plane on the node's boundary cuts off nothing: never a split (with the
            // empty-space bonus it would otherwise win over and over).
            if pos > bounds.0[k] && pos < bounds.1[k] {
                let (below, above) = split_box(bounds, k, pos);
                let (pl, pr) = (area(below) / total, area(above) / total);
                for planar_left in [true, false] {
                    let (l, r) = if planar_left { (nl[k] + np[k], nr[k]) } else { (nl[k], nr[k] + np[k]) };
                    let cost = self.cost(pl, pr, l, r);
                    if best.is_none_or(|b| cost < b.cost) {
                        best = Some(Plane { axis: k, pos, planar_left, cost });
                    }
                }
            }
            nl[k] += starts + planar;
            np[k] = 0;
        }
        best
    }

    /// SAH cost of a split with probabilities `pl`, `pr` and counts `l`, `r` (§3, with the
    /// empty-space bonus: a split that cuts off an empty child is cheaper).
    fn cost(&self, pl: f32, pr: f32, l: u32, r: u32) -> f32 {
        let p = self.params;
        let bonus = if l == 0 || r == 0 { 1.0 - p.empty_bonus } else { 1.0 };
        bonus * (p.ct + p.ci * (pl * l as f32 + pr * r as f32))
    }

    /// Classifies the triangles against the plane (§4.4) and builds both children's inputs.
    fn distribute(
        &self,
        input: NodeInput,
        plane: Plane,
        below: (Vec3, Vec3),
        above: (Vec3, Vec3),
    ) -> (NodeInput, NodeInput) {
        // One word per triangle: its side in the top two bits, its index in its child (the left
        // one for a straddler) below: one random read per event in the filtering pass.
        const BOTH: u32 = 0;
        const LEFT: u32 = 1 << 30;
        const RIGHT: u32 = 2 << 30;
        const INDEX: u32 = (1 << 30) - 1;
        let NodeInput { tris, events } = input;
        let mut word = vec![BOTH; tris.len()];
        for e in events.iter().filter(|e| e.axis() as usize == plane.axis) {
            let t = e.tri() as usize;
            match e.kind() {
                END if e.pos <= plane.pos => word[t] = LEFT,
                START if e.pos >= plane.pos => word[t] = RIGHT,
                PLANAR if e.pos < plane.pos || (e.pos == plane.pos && plane.planar_left) => word[t] = LEFT,
                PLANAR => word[t] = RIGHT,
                _ => {}
            }
        }
        // Local indices in each child, in the node's order (one-sided and straddling mixed).
        let mut child_tris = [Vec::new(), Vec::new()];
        let mut straddlers: Vec<(u32, [u32; 2])> = Vec::new();
        for (t, w) in word.iter_mut().enumerate() {
            let (l, r) = (child_tris[0].len() as u32, child_tris[1].len() as u32);
            match *w {
                LEFT => {
                    *w |= l;
                    child_tris[0].push(tris[t]);
                }
                RIGHT => {
                    *w |= r;
                    child_tris[1].push(tris[t]);
                }
                _ => {
                    straddlers.push((tris[t], [l, r]));
                    child_tris[0].push(tris[t]);
                    child_tris[1].push(tris[t]);
                }
            }
        }
        drop(tris);
        // The one-sided triangles' events, filtered: still sorted. At most six per triangle.
        let mut only = child_tris.each_ref().map(|c| Vec::with_capacity(6 * c.len()));
        for e in &events {
            let w = word[e.tri() as usize];
            if w & !INDEX != BOTH {
                only[usize::from(w & RIGHT != 0)].push(e.with_tri(w & INDEX));
            }
        }
        drop(events);
        drop(word);
        // The straddling triangles' events in each child: their boxes clipped to it.
        let mut children = [(below, 0usize), (above, 1usize)].map(|(cell, c)| {
            let mut fresh: Vec<Event> = Vec::with_capacity(6 * straddlers.len());
            let mut dropped: Vec<u32> = Vec::new();
            for &(tri, local) in &straddlers {
                match self.straddler_box(tri, cell) {
                    Some(b) => fresh.extend(box_events(b, local[c])),
                    // Perfect splits: the triangle only touches the cell (clipped away).
                    None => dropped.push(local[c]),
                }
            }
            fresh.sort_unstable_by(event_order);
            let events = merge(std::mem::take(&mut only[c]), fresh);
            compact(NodeInput { tris: std::mem::take(&mut child_tris[c]), events }, &dropped)
        });
        let right = children[1].take();
        let left = children[0].take();
        (left, right)
    }

    /// A straddling triangle's box within `cell`: the triangle clipped to the cell ("perfect
    /// splits", §4.5) or its box cut to the cell; `None` where clipping leaves nothing.
    fn straddler_box(&self, tri: u32, cell: (Vec3, Vec3)) -> Option<(Vec3, Vec3)> {
        let t = &self.triangles[tri as usize];
        if self.params.perfect_splits {
            return clipped_bounds(t, cell);
        }
        let (lo, hi) = (t[0].min(t[1]).min(t[2]).max(cell.0), t[0].max(t[1]).max(t[2]).min(cell.1));
        (lo.cmple(hi).all()).then_some((lo, hi))
    }
}

impl NodeInput {
    fn take(&mut self) -> NodeInput {
        NodeInput { tris: std::mem::take(&mut self.tris), events: std::mem::take(&mut self.events) }
    }
}

/// Drops the triangles `dropped` (local indices, increasing: clipped away) and renumbers the
/// events' local indices.
fn compact(input: NodeInput, dropped: &[u32]) -> NodeInput {
    if dropped.is_empty() {
        return input;
    }
    let mut renumber = vec![u32::MAX; input.tris.len()];
    let mut tris = Vec::with_capacity(input.tris.len() - dropped.len());
    let mut gone = dropped.iter().peekable();
    for (t, &tri) in input.tris.iter().enumerate() {
        if gone.peek() == Some(&&(t as u32)) {
            gone.next();
            continue;
        }
        renumber[t] = tris.len() as u32;
        tris.push(tri);
    }
    let events = input
        .events
        .into_iter()
        .filter(|e| renumber[e.tri() as usize] != u32::MAX)
        .map(|e| e.with_tri(renumber[e.tri() as usize]))
        .collect();
    NodeInput { tris, events }
}

/// Merges two event lists sorted by [`event_order`].
fn merge(a: Vec<Event>, b: Vec<Event>) -> Vec<Event> {
    if b.is_empty() {
        return a;
    }
    let mut out = Vec::with_capacity(a.len() + b.len());
    let (mut i, mut j) = (0, 0);
    while i < a.len() && j < b.len() {
        if event_order(&b[j], &a[i]).is_lt() {
            out.push(b[j]);
            j += 1;
        } else {
            out.push(a[i]);
            i += 1;
        }
    }
    out.extend_from_slice(&a[i..]);
    out.extend_from_slice(&b[j..]);
    out
}

/// The two halves of `bounds` at `pos` on `axis`.
pub(super) fn split_box((lo, hi): (Vec3, Vec3), axis: usize, pos: f32) -> ((Vec3, Vec3), (Vec3, Vec3)) {
    let (mut below_hi, mut above_lo) = (hi, lo);
    below_hi[axis] = pos;
    above_lo[axis] = pos;
    ((lo, below_hi), (above_lo, hi))
}
