//! CPU kernel of the shadow SVDAG (`structures::svdag::shadow`, seed 001 §3): "is this surface
//! point lit?" as a point query — project into the light's voxel grid, descend to the first
//! uniform child — beside the shadow workload's other answers for the same points: shadow rays
//! through any structure, and a lookup in the quantised shadow map.
//!
//! The points are the shadow workload's own ([`surface_points`]): each primary hit lifted off its
//! surface by the renderer's epsilon along the normal facing the viewer. A point query is asked a
//! little further out, two voxels along that normal ([`query_point`]): a voxel of the light's grid
//! (side `s`, diagonal `√3·s`) around a point `2s` off a plane cannot cross the plane, so a lit
//! surface is not shadowed by its own voxels (the shadow map's "acne"), as a shadow ray
//! is not shadowed by its own triangle.

use glam::Vec3;
use rayon::prelude::*;
use scenes::{Camera, Ray};
use structures::svdag::shadow::{ShadowSvdag, Variant};

use super::render::{Frame, ShadeContext};
use crate::Traverse;

/// A visible surface point of a primary render: lifted off the surface, with the normal facing
/// the viewer.
#[derive(Clone, Copy, Debug)]
pub struct SurfacePoint {
    pub p: Vec3,
    pub n: Vec3,
}

/// The shadow workload's points: every primary hit of `frame` (row-major), lifted as
/// `render::shade_hit` lifts them.
pub fn surface_points(frame: &Frame, camera: &Camera, ctx: &ShadeContext) -> Vec<SurfacePoint> {
    frame
        .pixels()
        .filter(|(_, _, s)| s.is_hit())
        .map(|(x, y, s)| {
            let ray = camera.ray(x, y);
            let n = if s.normal.dot(ray.dir) > 0.0 { -s.normal } else { s.normal };
            SurfacePoint { p: ray.at(s.t) + n * ctx.epsilon, n }
        })
        .collect()
}

/// Whether each point is occluded from `light`: one shadow ray each through `accel`, as the
/// renderer's shadow workload casts it.
pub fn shadow_rays(accel: &dyn Traverse, points: &[SurfacePoint], light: Vec3) -> Vec<bool> {
    points.par_iter().with_min_len(256).map(|s| accel.occluded(&Ray::new(s.p, light - s.p), 0.0, 1.0 - 1e-4)).collect()
}

/// Where a point query for surface point `s` is asked: two voxels of the light's grid out along
/// the normal.
#[inline]
pub fn query_point(dag: &ShadowSvdag, s: &SurfacePoint) -> Vec3 {
    s.p + s.n * (2.0 * dag.voxel_size_at(s.p)) as f32
}

/// Whether a surface point faces away from the light: its own surface shadows it (as a shadow
/// ray from a closed surface finds), and no query is asked — a normal offset away from the light
/// would leave the surface's own shadow.
#[inline]
pub fn faces_away(s: &SurfacePoint, light: Vec3) -> bool {
    s.n.dot(light - s.p) <= 0.0
}

/// Whether each point is occluded by the `variant` DAG's answer (`None` outside the light's
/// frustum); a point facing away from the light is occluded without a query.
pub fn shadow_queries(dag: &ShadowSvdag, variant: Variant, points: &[SurfacePoint]) -> Vec<Option<bool>> {
    let light = dag.faces[0].light;
    points
        .par_iter()
        .with_min_len(1024)
        .map(
            |s| {
                if faces_away(s, light) { Some(true) } else { dag.lit_in(variant, query_point(dag, s)).map(|lit| !lit) }
            },
        )
        .collect()
}

/// The mean number of nodes a `variant` DAG's query reads, over the points asked (facing the
/// light, inside its frustum): what a query's cost grows with. Untimed; 0 where none is asked.
pub fn query_nodes_mean(dag: &ShadowSvdag, variant: Variant, points: &[SurfacePoint]) -> f64 {
    let light = dag.faces[0].light;
    let (sum, n) = points
        .par_iter()
        .with_min_len(1024)
        .filter(|s| !faces_away(s, light))
        .filter_map(|s| dag.query_nodes(variant, query_point(dag, s)))
        .map(|nodes| (u64::from(nodes), 1u64))
        .reduce(|| (0, 0), |a, b| (a.0 + b.0, a.1 + b.1));
    if n == 0 { 0.0 } else { sum as f64 / n as f64 }
}

/// The same queries answered by the quantised shadow map the plain DAG encodes.
pub fn shadow_map_lookups(dag: &ShadowSvdag, points: &[SurfacePoint]) -> Vec<Option<bool>> {
    let light = dag.faces[0].light;
    points
        .par_iter()
        .with_min_len(1024)
        .map(|s| if faces_away(s, light) { Some(true) } else { dag.lit_by_map(query_point(dag, s)).map(|lit| !lit) })
        .collect()
}
