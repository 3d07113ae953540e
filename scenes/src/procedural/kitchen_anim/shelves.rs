//! The wall shelves over the counter and the pantry rack beside the fridge, and the rows of things
//! on them: jars, cans, stacked bowls, cups, bottles, runs of books (some leaning), stacked plates
//! and spice jars.
//!
//! Every item's kind, size, turn about the vertical and place along its shelf come from the seed,
//! so no two are the same voxels (seed 001 §4: a voxel DAG merges only identical, grid-aligned
//! subtrees; a real kitchen's clutter has none).

use glam::{Mat4, Vec2, Vec3};
use rand::Rng;
use rand_pcg::Pcg64Mcg;

use super::fridge::FRIDGE_X;
use super::parts::{
    any_yaw, bottle_profile, bowl_outline, frame, jar_profile, plate_profile, push_beam, push_cup, push_rod,
};
use super::{BACK, HALF_Z, SLICES};
use crate::mesh::Mesh;
use crate::procedural::shapes::{box_between, push_box, push_lathe, vessel_profile};

/// The wall shelves over the left of the counter: boards with their tops at `SHELF_Y`.
pub(super) const SHELF_Y: [f32; 2] = [1.45, 1.85];
pub(super) const SHELF_X: (f32, f32) = (-3.4, -0.6);
pub(super) const SHELF_DEPTH: f32 = 0.28;
const SHELF_BOARD: f32 = 0.03;

/// The open pantry rack right of the fridge: x and z ranges, and its boards' tops.
pub(super) const PANTRY_X: (f32, f32) = (FRIDGE_X.1 + 0.1, FRIDGE_X.1 + 0.7);
pub(super) const PANTRY_Z: (f32, f32) = (-HALF_Z + 0.02, -HALF_Z + 0.38);
pub(super) const PANTRY_Y: [f32; 5] = [0.06, 0.48, 0.9, 1.32, 1.74];
pub(super) const PANTRY_TOP: f32 = 2.0;
/// The pantry's side panels' and boards' thickness.
pub(super) const PANEL: f32 = 0.02;

/// The wall shelves: boards on three brackets each.
pub(super) fn shelves(mesh: &mut Mesh) {
    for y in SHELF_Y {
        let board =
            box_between(Vec3::new(SHELF_X.0, y - SHELF_BOARD, BACK), Vec3::new(SHELF_X.1, y, -HALF_Z + SHELF_DEPTH));
        push_box(mesh, board, false);
        for k in 0..3 {
            let x = SHELF_X.0 + 0.15 + k as f32 * 0.5 * (SHELF_X.1 - SHELF_X.0 - 0.3);
            let bracket = box_between(
                Vec3::new(x - 0.015, y - SHELF_BOARD - 0.15, BACK),
                Vec3::new(x + 0.015, y - SHELF_BOARD, -HALF_Z + 0.2),
            );
            push_box(mesh, bracket, false);
            // The bracket's diagonal strut.
            let (wall, tip) = (
                Vec3::new(x, y - SHELF_BOARD - 0.14, -HALF_Z + 0.01),
                Vec3::new(x, y - SHELF_BOARD - 0.01, -HALF_Z + 0.19),
            );
            push_beam(mesh, wall, tip, Vec3::X, 0.02, 0.012);
        }
    }
}

/// The pantry rack: two side panels, the boards and a top, braced by two crossed rods at the back.
pub(super) fn pantry(mesh: &mut Mesh) {
    let (x0, x1) = PANTRY_X;
    let (z0, z1) = PANTRY_Z;
    for x in [x0, x1 - PANEL] {
        push_box(mesh, box_between(Vec3::new(x, 0.0, z0), Vec3::new(x + PANEL, PANTRY_TOP, z1)), false);
    }
    for y in PANTRY_Y.into_iter().chain([PANTRY_TOP]) {
        push_box(mesh, box_between(Vec3::new(x0 + PANEL, y - PANEL, z0), Vec3::new(x1 - PANEL, y, z1)), false);
    }
    let back = z0 + 0.015;
    let (lo, hi) = (PANTRY_Y[0] + 0.03, PANTRY_TOP - 0.05);
    push_rod(mesh, Vec3::new(x0 + PANEL, lo, back), Vec3::new(x1 - PANEL, hi, back), 0.006, 8);
    push_rod(mesh, Vec3::new(x1 - PANEL, lo, back), Vec3::new(x0 + PANEL, hi, back), 0.006, 8);
}

/// One thing on a shelf, its sizes drawn before it is placed.
enum ShelfItem {
    Jar {
        radius: f32,
        height: f32,
    },
    Can {
        radius: f32,
        height: f32,
    },
    Bowls {
        radius: f32,
        height: f32,
        count: u32,
    },
    Cup {
        radius: f32,
        height: f32,
    },
    Bottle {
        radius: f32,
        height: f32,
    },
    /// A row of books (thickness, height, depth), the last one leaning back onto the others by
    /// `lean` radians.
    Books {
        books: Vec<Vec3>,
        lean: f32,
    },
    Plates {
        radius: f32,
        count: u32,
    },
    Spices {
        count: u32,
    },
}

impl ShelfItem {
    fn draw(rng: &mut Pcg64Mcg, headroom: f32, depth: f32) -> Self {
        let tallest = |most: f32| most.min(headroom - 0.02);
        match rng.random_range(0..9u32) {
            0 => Self::Jar { radius: rng.random_range(0.035..0.06), height: rng.random_range(0.08..tallest(0.22)) },
            1 => Self::Can { radius: rng.random_range(0.03..0.045), height: rng.random_range(0.07..tallest(0.15)) },
            2 => Self::Bowls {
                radius: rng.random_range(0.06..0.1),
                height: rng.random_range(0.05..0.08),
                count: rng.random_range(1..5),
            },
            3 => Self::Cup { radius: rng.random_range(0.032..0.042), height: rng.random_range(0.075..0.1) },
            4 => Self::Bottle { radius: rng.random_range(0.03..0.045), height: rng.random_range(0.16..tallest(0.32)) },
            5 | 6 => {
                let count = rng.random_range(3..9);
                let books = (0..count)
                    .map(|_| {
                        Vec3::new(
                            rng.random_range(0.015..0.045),
                            rng.random_range(0.14..tallest(0.28)),
                            rng.random_range(0.12..(depth - 0.04).min(0.22)),
                        )
                    })
                    .collect();
                let lean = if rng.random_bool(0.5) { rng.random_range(0.12..0.4) } else { 0.0 };
                Self::Books { books, lean }
            }
            7 => Self::Plates {
                radius: rng.random_range(0.085..(0.5 * depth - 0.015).min(0.125)),
                count: rng.random_range(2..8),
            },
            _ => Self::Spices { count: rng.random_range(2..6) },
        }
    }

    /// Width along the shelf and depth across it.
    fn footprint(&self) -> Vec2 {
        match self {
            Self::Jar { radius, .. } | Self::Can { radius, .. } | Self::Bottle { radius, .. } => {
                Vec2::splat(2.0 * radius)
            }
            Self::Bowls { radius, .. } | Self::Plates { radius, .. } => Vec2::splat(2.0 * radius),
            // The handle may point any way.
            Self::Cup { radius, height } => Vec2::splat(2.0 * (radius + 0.52 * height + 0.005)),
            Self::Books { books, lean } => {
                let last = books[books.len() - 1];
                let upright: f32 = books[..books.len() - 1].iter().map(|b| b.x + 0.002).sum();
                let leaning = if *lean > 0.0 { last.y * lean.sin() + last.x * lean.cos() } else { last.x };
                Vec2::new(upright + leaning, books.iter().map(|b| b.z).fold(0.0, f32::max))
            }
            Self::Spices { count } => Vec2::new(0.05 * *count as f32, 0.05),
        }
    }

    /// Places the item with its footprint's centre at `at` (on the shelf's top).
    fn push(&self, mesh: &mut Mesh, rng: &mut Pcg64Mcg, at: Vec3) {
        match *self {
            Self::Jar { radius, height } => {
                push_lathe(mesh, &jar_profile(radius, height), SLICES, false, frame(any_yaw(rng), at))
            }
            Self::Can { radius, height } => {
                let can = [
                    Vec2::new(0.0, height - 0.003),
                    Vec2::new(0.9 * radius, height - 0.003),
                    Vec2::new(0.93 * radius, height),
                    Vec2::new(radius, height - 0.008),
                    Vec2::new(radius, 0.006),
                    Vec2::new(0.92 * radius, 0.0),
                    Vec2::new(0.0, 0.0),
                ];
                push_lathe(mesh, &can, 24, false, frame(any_yaw(rng), at));
            }
            Self::Bowls { radius, height, count } => {
                let bowl = vessel_profile(&bowl_outline(radius, height), 0.005);
                for k in 0..count {
                    push_lathe(
                        mesh,
                        &bowl,
                        SLICES,
                        false,
                        frame(any_yaw(rng), at + Vec3::Y * (k as f32 * 0.4 * height)),
                    );
                }
            }
            Self::Cup { radius, height } => push_cup(mesh, frame(any_yaw(rng), at), radius, height),
            Self::Bottle { radius, height } => {
                push_lathe(mesh, &bottle_profile(radius, height), 24, false, frame(any_yaw(rng), at))
            }
            Self::Books { ref books, lean } => {
                let mut x = at.x - 0.5 * self.footprint().x;
                for (k, book) in books.iter().enumerate() {
                    let leaning = lean > 0.0 && k == books.len() - 1;
                    // A leaning book stands on its near bottom edge, its top resting on the book before.
                    let (pivot, tilt) =
                        if leaning { (x + book.y * lean.sin(), lean) } else { (x, rng.random_range(-0.03..0.03f32)) };
                    let z = at.z + rng.random_range(-0.01..0.01);
                    let place = Mat4::from_translation(Vec3::new(pivot, at.y, z))
                        * Mat4::from_rotation_z(if leaning { tilt } else { 0.0 });
                    let turn = if leaning { Mat4::IDENTITY } else { Mat4::from_rotation_y(tilt) };
                    let centre = Vec3::new(0.5 * book.x, 0.5 * book.y, 0.0);
                    push_box(mesh, place * Mat4::from_translation(centre) * turn * Mat4::from_scale(*book), false);
                    x += book.x + 0.002;
                }
            }
            Self::Plates { radius, count } => {
                let plate = plate_profile(radius);
                for k in 0..count {
                    push_lathe(mesh, &plate, SLICES, false, frame(any_yaw(rng), at + Vec3::Y * (k as f32 * 0.011)));
                }
            }
            Self::Spices { count } => {
                for k in 0..count {
                    let (radius, height) = (rng.random_range(0.016..0.022), rng.random_range(0.06..0.1));
                    let spot = at
                        + Vec3::new(0.05 * (k as f32 - 0.5 * (count - 1) as f32), 0.0, rng.random_range(-0.004..0.004));
                    push_lathe(mesh, &jar_profile(radius, height), 12, false, frame(any_yaw(rng), spot));
                }
            }
        }
    }
}

/// Fills the shelf whose top is at `y`, from `x.0` to `x.1` along x, centred on `z` and `depth`
/// deep, with a row of things no taller than `headroom`, left to right, until it is full.
fn fill_shelf(mesh: &mut Mesh, rng: &mut Pcg64Mcg, x: (f32, f32), y: f32, z: f32, depth: f32, headroom: f32) {
    let mut cursor = x.0 + rng.random_range(0.0..0.04);
    loop {
        let item = ShelfItem::draw(rng, headroom, depth);
        let size = item.footprint();
        if cursor + size.x > x.1 {
            break;
        }
        let slack = (0.5 * (depth - size.y) - 0.01).max(0.0);
        let at = Vec3::new(cursor + 0.5 * size.x, y, z + slack * rng.random_range(-1.0..1.0f32));
        item.push(mesh, rng, at);
        cursor += size.x + rng.random_range(0.01..0.06);
    }
}

/// The two wall shelves' rows.
pub(super) fn shelf_items(mesh: &mut Mesh, rng: &mut Pcg64Mcg) {
    let z = -HALF_Z + 0.5 * SHELF_DEPTH;
    for (y, headroom) in [(SHELF_Y[0], SHELF_Y[1] - SHELF_Y[0] - 0.04), (SHELF_Y[1], 0.4)] {
        fill_shelf(mesh, rng, (SHELF_X.0 + 0.02, SHELF_X.1 - 0.02), y, z, SHELF_DEPTH, headroom);
    }
}

/// The pantry rack's rows, all five boards and the top.
pub(super) fn pantry_items(mesh: &mut Mesh, rng: &mut Pcg64Mcg) {
    let (z, depth) = (0.5 * (PANTRY_Z.0 + PANTRY_Z.1), PANTRY_Z.1 - PANTRY_Z.0);
    for (k, y) in PANTRY_Y.into_iter().enumerate() {
        // Up to the underside of the board above (or the top), less a centimetre.
        let above = PANTRY_Y.get(k + 1).copied().unwrap_or(PANTRY_TOP);
        fill_shelf(mesh, rng, (PANTRY_X.0 + 0.03, PANTRY_X.1 - 0.03), y, z, depth, above - PANEL - y - 0.01);
    }
}
