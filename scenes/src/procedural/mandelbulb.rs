//! "Mandelbulb": a surface mesh of the power-8 Mandelbulb (seed 004's fractal test scenes).
//!
//! A detailed, self-similar surface with deep crevices: many small triangles packed unevenly,
//! where voxel DAGs find repeated subtrees and grids find wildly varying cell occupancy.
//!
//! The escape-time distance estimate `0.5·ln r·r / dr` (White–Nylander power-8 formula) is sampled
//! on a `resolution`³ grid over [`HALF_EXTENT`]; the surface is its level set at half a cell
//! width, extracted with naive surface nets: one vertex per grid cell the level set crosses (the
//! mean of the crossing points on the cell's edges), one quad per grid edge that crosses it,
//! joining the four cells around that edge. The mesh is indexed (vertices shared), watertight, but
//! not guaranteed two-manifold (a cell face crossed on all four edges gives an edge of four
//! triangles), so the object is not marked closed.

use glam::{DVec3, UVec3, Vec3};
use rayon::prelude::*;

use super::shapes::{SceneBuilder, push_quad};
use crate::mesh::Mesh;
use crate::scene::Scene;

/// The sampled cube is `[-HALF_EXTENT, HALF_EXTENT]³`; the power-8 bulb lies within about ±1.15.
const HALF_EXTENT: f64 = 1.25;
const POWER: i32 = 8;
const MAX_ITERATIONS: u32 = 12;
const BAILOUT: f64 = 2.0;

/// The distance estimate at `c`: positive outside, about zero or negative inside.
fn distance_estimate(c: DVec3) -> f64 {
    let (mut z, mut dr, mut r) = (c, 1.0, c.length());
    for _ in 0..MAX_ITERATIONS {
        if r > BAILOUT {
            break;
        }
        dr = r.powi(POWER - 1) * f64::from(POWER) * dr + 1.0;
        if r > 0.0 {
            let theta = (z.z / r).clamp(-1.0, 1.0).acos() * f64::from(POWER);
            let phi = z.y.atan2(z.x) * f64::from(POWER);
            z = r.powi(POWER) * DVec3::new(theta.sin() * phi.cos(), theta.sin() * phi.sin(), theta.cos()) + c;
        } else {
            z = c;
        }
        r = z.length();
    }
    if r > 0.0 { 0.5 * r.ln() * r / dr } else { -1.0 }
}

pub(super) fn generate(resolution: u32) -> Scene {
    let grid = Grid::new(resolution);
    let field = sample_field(&grid);
    let mut builder = SceneBuilder::new();
    builder.object("mandelbulb", false, |mesh| {
        let vertex_of = place_vertices(&grid, &field, mesh);
        connect_quads(&grid, &field, &vertex_of, mesh);
    });
    let n = grid.n;
    let provenance = format!(
        "accel-bench procedural::mandelbulb resolution={n}: power-{POWER} Mandelbulb, distance estimate \
         ({MAX_ITERATIONS} iterations, bailout {BAILOUT}) on a {n}^3 grid over [-{HALF_EXTENT},{HALF_EXTENT}]^3, \
         level set at half a cell, naive surface nets"
    );
    builder.finish("mandelbulb", provenance, None, None)
}

/// The sample grid: `n`³ points `cell` apart from `-HALF_EXTENT`, so `(n − 1)`³ cells.
struct Grid {
    n: usize,
    cell: f64,
}

impl Grid {
    fn new(resolution: u32) -> Self {
        let n = resolution.max(2) as usize;
        Self { n, cell: 2.0 * HALF_EXTENT / (n - 1) as f64 }
    }

    fn cells(&self) -> usize {
        self.n - 1
    }

    fn sample(&self, field: &[f32], p: UVec3) -> f32 {
        field[(p.z as usize * self.n + p.y as usize) * self.n + p.x as usize]
    }
}

/// The distance estimate minus the iso level at every grid point, x fastest. Computed in z slabs
/// on rayon; each value is a pure function of its index, so the thread count does not matter.
fn sample_field(grid: &Grid) -> Vec<f32> {
    let (n, iso) = (grid.n, 0.5 * grid.cell);
    let point = |i: usize| -HALF_EXTENT + i as f64 * grid.cell;
    let mut field = vec![0.0f32; n * n * n];
    field.par_chunks_mut(n * n).enumerate().for_each(|(z, slab)| {
        for (i, value) in slab.iter_mut().enumerate() {
            // World y is the bulb's polar axis (its z), so the canonical camera sees it upright.
            let (x, y) = (point(i % n), point(i / n));
            *value = (distance_estimate(DVec3::new(x, point(z), y)) - iso) as f32;
        }
    });
    field
}

/// The edge directions of the grid: `axis` and the two others, with e_u × e_v = e_axis.
fn frame(axis: usize) -> [UVec3; 3] {
    [UVec3::AXES[axis], UVec3::AXES[(axis + 1) % 3], UVec3::AXES[(axis + 2) % 3]]
}

/// Adds one vertex per cell the level set crosses, at the mean of the crossing points on the
/// cell's 12 edges; returns each cell's vertex index (`u32::MAX` where none).
fn place_vertices(grid: &Grid, field: &[f32], mesh: &mut Mesh) -> Vec<u32> {
    let cells = grid.cells();
    let mut vertex_of = vec![u32::MAX; cells * cells * cells];
    for (index, slot) in vertex_of.iter_mut().enumerate() {
        let (x, y, z) = (index % cells, index / cells % cells, index / (cells * cells));
        let c = UVec3::new(x as u32, y as u32, z as u32);
        let (mut sum, mut crossings) = (Vec3::ZERO, 0u32);
        for axis in 0..3 {
            let [step, u, v] = frame(axis);
            for k in 0..4u32 {
                let a = c + u * (k & 1) + v * (k >> 1);
                let (fa, fb) = (grid.sample(field, a), grid.sample(field, a + step));
                if (fa < 0.0) != (fb < 0.0) {
                    sum += (a - c).as_vec3() + step.as_vec3() * (fa / (fa - fb));
                    crossings += 1;
                }
            }
        }
        if crossings > 0 {
            let local = c.as_vec3() + sum / crossings as f32;
            *slot = mesh.push_vertex(local * grid.cell as f32 - HALF_EXTENT as f32);
        }
    }
    vertex_of
}

/// Adds one quad per grid edge the level set crosses, joining the vertices of the four cells
/// around the edge and facing the outside (the end where the field is ≥ 0).
fn connect_quads(grid: &Grid, field: &[f32], vertex_of: &[u32], mesh: &mut Mesh) {
    let (n, cells) = (grid.n as u32, grid.cells() as u32);
    let vertex = |p: UVec3| vertex_of[((p.z * cells + p.y) * cells + p.x) as usize];
    for index in 0..n * n * n {
        let p = UVec3::new(index % n, index / n % n, index / (n * n));
        for axis in 0..3 {
            let [step, u, v] = frame(axis);
            let q = p + step;
            // All four cells around the edge, p − u − v … p, must lie in the grid.
            let (pu, pv) = (p[(axis + 1) % 3], p[(axis + 2) % 3]);
            if q[axis] >= n || pu == 0 || pv == 0 || pu >= cells || pv >= cells {
                continue;
            }
            let inside_p = grid.sample(field, p) < 0.0;
            if inside_p == (grid.sample(field, q) < 0.0) {
                continue;
            }
            // Counter-clockwise about +axis; reversed when the outside lies towards −axis.
            let [a, b, c, d] = [p - u - v, p - v, p, p - u].map(vertex);
            push_quad(mesh, if inside_p { [a, b, c, d] } else { [a, d, c, b] });
        }
    }
}
