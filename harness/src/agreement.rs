//! Agreement of a render's primary hits with a reference (docs/design.md §8 `agreement`).

use kernels::cpu::brute_force;
use kernels::cpu::render::{Frame, Sample};
use rayon::prelude::*;
use reports::Agreement;
use reports::images::Difference;
use scenes::{Camera, Triangle};

/// Triangle tests the brute-force check may spend per case; it samples that many / N pixels.
const BRUTE_FORCE_BUDGET: u64 = 300_000_000;
const MIN_SAMPLE: u64 = 256;
const MAX_SAMPLE: u64 = 16_384;
/// Hits on different triangles count as the same hit when their `t` agree this closely
/// (ties on shared edges and coplanar overlaps).
const TIE_REL_T: f64 = 1e-6;

#[derive(Default)]
struct Tally {
    pixels: u64,
    hit_mismatches: u64,
    prim_mismatches: u64,
    max_rel_t_error: f64,
}

/// How a pixel's hit compares with the reference's: the one classification the agreement counts
/// and the difference view draws.
fn classify(hit: Option<(f32, u64)>, reference: Option<(f32, u64)>) -> (Difference, Option<f64>) {
    match (hit, reference) {
        (Some((t, prim)), Some((rt, rprim))) => {
            let rel = f64::from((t - rt).abs()) / f64::from(rt.abs()).max(f64::MIN_POSITIVE);
            let d = if prim != rprim && rel > TIE_REL_T { Difference::Other(rel) } else { Difference::Same };
            (d, Some(rel))
        }
        (None, None) => (Difference::BothMiss, None),
        (Some(_), None) => (Difference::Extra, None),
        (None, Some(_)) => (Difference::Missing, None),
    }
}

/// A pixel of a frame against the same pixel of the reference's frame.
pub fn difference(sample: &Sample, reference: &Sample) -> Difference {
    classify(hit_of(sample), hit_of(reference)).0
}

impl Tally {
    fn add(&mut self, hit: Option<(f32, u64)>, reference: Option<(f32, u64)>) {
        self.pixels += 1;
        let (d, rel) = classify(hit, reference);
        if let Some(rel) = rel {
            self.max_rel_t_error = self.max_rel_t_error.max(rel);
        }
        match d {
            Difference::Other(_) => self.prim_mismatches += 1,
            Difference::Extra | Difference::Missing => self.hit_mismatches += 1,
            Difference::BothMiss | Difference::Same => {}
        }
    }

    fn merge(mut self, o: Tally) -> Tally {
        self.pixels += o.pixels;
        self.hit_mismatches += o.hit_mismatches;
        self.prim_mismatches += o.prim_mismatches;
        self.max_rel_t_error = self.max_rel_t_error.max(o.max_rel_t_error);
        self
    }

    fn finish(self, reference: &str) -> Agreement {
        Agreement {
            reference: reference.into(),
            pixels: self.pixels,
            hit_mismatches: self.hit_mismatches,
            prim_mismatches: self.prim_mismatches,
            max_rel_t_error: self.max_rel_t_error,
        }
    }
}

fn hit_of(s: &Sample) -> Option<(f32, u64)> {
    s.is_hit().then_some((s.t, s.prim))
}

/// Every pixel against the reference structure's frame.
pub fn against_frame(frame: &Frame, reference: &Frame, name: &str) -> Agreement {
    let mut tally = Tally::default();
    for (x, y, s) in frame.pixels() {
        tally.add(hit_of(s), hit_of(reference.at(x, y)));
    }
    tally.finish(name)
}

/// A deterministic sample of pixels against brute force (every triangle tested).
pub fn against_brute_force(frame: &Frame, camera: &Camera, triangles: &[Triangle]) -> Agreement {
    let total = u64::from(frame.width) * u64::from(frame.height);
    let n = (BRUTE_FORCE_BUDGET / (triangles.len() as u64).max(1)).clamp(MIN_SAMPLE, MAX_SAMPLE).min(total);
    // A multiplicative scramble spreads the sample over the whole image.
    let pixel = |k: u64| (k.wrapping_mul(2_654_435_761) % total) as u32;
    (0..n)
        .into_par_iter()
        .map(|k| {
            let p = pixel(k);
            let (x, y) = (p % frame.width, p / frame.width);
            let reference = brute_force::intersect(triangles, &camera.ray(x, y), 0.0, f32::INFINITY);
            let mut t = Tally::default();
            t.add(hit_of(frame.at(x, y)), reference.map(|h| (h.t, h.prim)));
            t
        })
        .reduce(Tally::default, Tally::merge)
        .finish("brute-force")
}
