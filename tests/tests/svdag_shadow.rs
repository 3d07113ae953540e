//! The shadow SVDAG (issue 13, seed 001 §3) against what it encodes and what it stands for:
//!
//! - the double depth map against rays cast from the light through the reference BVH, texel by
//!   texel (entry depth, and exit depth of closed objects);
//! - the plain DAG answers exactly as the quantised shadow map for every voxel of the grid;
//! - the optimised DAG answers as the plain one for every voxel outside closed geometry;
//! - both DAGs are well formed and minimal below the root (every pointer on a node of the next
//!   level, no level holding two equal nodes);
//! - point queries for the light-facing surface points of a render agree with shadow rays through
//!   the BVH: from the point queried, except within one voxel of a shadow boundary (the DAG's
//!   quantisation); from the surface point itself (the renderer's rays), except within three (the
//!   query's normal offset of two voxels, and one), and on the room at 1024³ on ≥ 99.9 % of the
//!   points.

use std::collections::HashSet;

use glam::Vec3;
use kernels::cpu::render::{ShadeContext, Workload, render};
use kernels::cpu::svdag_shadow::{SurfacePoint, faces_away, query_point, shadow_queries, shadow_rays, surface_points};
use scenes::{Camera, Ray, Scene};
use structures::svdag::layout::{NodeKind, SHADOW_MIXED_BITS, node_words};
use structures::svdag::shadow::{self, ShadowDag, ShadowParams, ShadowSvdag, Variant, VoxelClass};
use structures::{BuildInput, Params};

fn load(name: &str) -> Scene {
    scenes::load_scene(name).unwrap_or_else(|e| panic!("{name}: {e}"))
}

fn build(scene: &Scene, level: u32) -> ShadowSvdag {
    shadow::build(scene, ShadowParams { level, variant: Variant::Optimised }).expect("shadow build")
}

fn bvh(scene: &Scene) -> Box<dyn kernels::Accel> {
    let params = Params::default();
    let input = BuildInput { scene, triangles: scene.triangles(), params: &params };
    kernels::build_structure("bvh", &input).expect("registered").expect("bvh builds")
}

/// The ray from the light through texel `(u, v)`'s centre, with `t` = linear depth.
fn texel_ray(s: &shadow::LightSpace, u: u32, v: u32) -> Ray {
    let n = s.resolution() as f64;
    let x = ((u as f64 + 0.5) / n * 2.0 - 1.0) * s.tan_half;
    let y = ((v as f64 + 0.5) / n * 2.0 - 1.0) * s.tan_half;
    Ray::new(s.light, s.axis + s.right * x as f32 + s.up * y as f32)
}

#[test]
fn depth_maps_match_rays_from_the_light() {
    for name in ["room", "city"] {
        let scene = load(name);
        let d = build(&scene, 8);
        let accel = bvh(&scene);
        let n = d.faces[0].resolution();
        let (mut first_bad, mut second_bad, mut closed) = (0, 0, 0);
        for space in &d.faces {
            let maps = shadow::depth_maps(&scene, space);
            for v in 0..n {
                for u in 0..n {
                    let i = (v * n + u) as usize;
                    let ray = texel_ray(space, u, v);
                    let hit = accel.intersect(&ray, space.near as f32, f32::INFINITY);
                    let want = hit.map_or(f32::INFINITY, |h| h.t);
                    // Depths agree to the rasteriser's 1/256-texel vertex snapping.
                    let close = |a: f32, b: f32| a == b || (a - b).abs() <= 1e-3 * b.abs();
                    first_bad += usize::from(!close(maps.d1[i], want));
                    if maps.d2[i] > maps.d1[i] && maps.d2[i].is_finite() {
                        closed += 1;
                        // The exit is a surface behind the entry: the ray meets geometry there.
                        // (past the BVH's own entry: the rasterised one is exact to the snapping only)
                        let behind = accel.intersect(&ray, want * (1.0 + 1e-5), f32::INFINITY);
                        second_bad += usize::from(!behind.is_some_and(|h| close(maps.d2[i], h.t)));
                    }
                }
            }
        }
        let texels = (n * n) as usize * d.faces.len();
        eprintln!(
            "{name}: {first_bad} of {texels} entry depths and {second_bad} of {closed} exits differ from the BVH"
        );
        assert!(first_bad * 1000 <= texels, "{name}: {first_bad} entry depths differ");
        assert!(closed > texels / 20, "{name}: {closed} texels enter a closed object");
        // Exits through a face another object touches (a city block's floor on the ground) may
        // meet that object first.
        assert!(second_bad * 200 <= closed.max(1000), "{name}: {second_bad} exit depths differ");
    }
}

/// Every voxel of every face: (lit, undefined) voxel counts.
fn voxel_answers(d: &ShadowSvdag) -> (u64, u64) {
    let n = d.faces[0].resolution();
    let level = d.level();
    let (mut undefined, mut lit) = (0u64, 0u64);
    for face in 0..d.faces.len() {
        for v in 0..n {
            for u in 0..n {
                let a = u32::from(d.lit_slices[face][(v * n + u) as usize]);
                for z in 0..n {
                    let c = [u, v, z];
                    let plain = d.plain.lit_voxel(face, c, level);
                    assert_eq!(plain, z < a, "plain DAG against the shadow map at face {face} {c:?}");
                    if (u * 7 + v * 3 + z) % 11 == 0 {
                        let (lit, nodes) = d.plain.descend(face, c, level);
                        assert_eq!(lit, plain);
                        let want = plain_nodes_read(&d.lit_slices[face], n, c, level);
                        assert_eq!(nodes, want, "nodes a plain query reads at face {face} {c:?}");
                    }
                    match d.voxel_class(face, c) {
                        VoxelClass::Undefined => undefined += 1,
                        class => {
                            lit += u64::from(class == VoxelClass::Lit);
                            let opt = d.optimised.lit_voxel(face, c, level);
                            assert_eq!(opt, plain, "optimised against plain at face {face} {c:?} ({class:?})");
                        }
                    }
                }
            }
        }
    }
    (lit, undefined)
}

/// The nodes a plain DAG's query of voxel `c` reads, from the shadow map alone: the root, and
/// one more for every block on the way down (side `2^(level − 1 − l)` below level `l`'s node)
/// that holds both lit and shadowed voxels. A voxel is lit where its slice lies before the
/// texel's first shadowed slice.
fn plain_nodes_read(lit_slices: &[u16], n: u32, c: [u32; 3], level: u32) -> u32 {
    let mut nodes = 1;
    for l in 0..level - 1 {
        let side = 1u32 << (level - 1 - l);
        let [u0, v0, z0] = c.map(|x| x / side * side);
        let (mut lo, mut hi) = (u32::MAX, 0);
        for v in v0..v0 + side {
            for u in u0..u0 + side {
                let a = u32::from(lit_slices[(v * n + u) as usize]);
                (lo, hi) = (lo.min(a), hi.max(a));
            }
        }
        let all_lit = lo >= z0 + side;
        let all_shadow = hi <= z0;
        if all_lit || all_shadow {
            break;
        }
        nodes += 1;
    }
    nodes
}

/// Parses a shadow DAG level by level: node sizes, pointers onto the next level's node starts,
/// every node reached, no two equal nodes in a level below the root.
fn check_words(dag: &ShadowDag, level: u32) {
    let w = &dag.words;
    let levels = dag.level_starts.len() - 1;
    assert_eq!(levels as u32, level, "levels 0…L − 1");
    let mut starts: Vec<Vec<u32>> = Vec::new();
    for l in 0..levels {
        let kind = if l + 1 == levels { NodeKind::Mask } else { NodeKind::Shadow };
        let (mut o, end) = (dag.level_starts[l] as usize, dag.level_starts[l + 1] as usize);
        let mut seen: HashSet<&[u32]> = HashSet::new();
        let mut nodes = Vec::new();
        while o < end {
            let size = node_words(kind, w[o]);
            let node = &w[o..o + size];
            assert!(w[o] >> 16 == 0, "level {l}: codes beyond 16 bits at {o}");
            assert!((0..8).all(|s| w[o] >> (2 * s) & 3 != 3), "level {l}: code 3 at {o}");
            if kind == NodeKind::Mask {
                assert_eq!(w[o] & SHADOW_MIXED_BITS, 0, "a voxel is never mixed");
            }
            assert!(seen.insert(node), "level {l}: node at {o} is a duplicate");
            nodes.push(o as u32);
            o += size;
        }
        assert_eq!(o, end);
        starts.push(nodes);
    }
    assert_eq!(starts[0], dag.roots, "the roots, one per face, make the root level");
    for l in 0..levels - 1 {
        let mut reached = vec![false; starts[l + 1].len()];
        for &o in &starts[l] {
            let k = (w[o as usize] & SHADOW_MIXED_BITS).count_ones();
            for p in &w[o as usize + 1..=o as usize + k as usize] {
                let at = starts[l + 1].binary_search(p).unwrap_or_else(|_| panic!("level {l}: pointer {p} is no node"));
                reached[at] = true;
            }
        }
        assert!(reached.iter().all(|&r| r), "level {}: an unreachable node", l + 1);
    }
}

#[test]
fn every_voxel_answers_as_the_shadow_map_and_closed_insides_only_change() {
    for (name, level) in [("room", 6), ("city", 7), ("terrain", 5), ("room", 7)] {
        let scene = load(name);
        let d = build(&scene, level);
        check_words(&d.plain, level);
        check_words(&d.optimised, level);
        let (lit, undefined) = voxel_answers(&d);
        eprintln!("{name} L={level}: {} faces, {lit} lit and {undefined} undefined voxels", d.faces.len());
        assert!(lit > 0, "{name}: no lit voxel");
        assert!(undefined > 0 || name == "terrain", "{name}: no undefined voxel proves little");
        assert!(d.optimised.bytes() <= d.plain.bytes(), "{name}: optimising added bytes");
        assert_eq!(d.stats.plain_bytes, d.plain.bytes());
    }
}

#[test]
fn point_queries_agree_with_shadow_rays() {
    for (name, level) in [("room", 10), ("city", 10)] {
        let scene = load(name);
        let d = build(&scene, level);
        let accel = bvh(&scene);
        let camera = Camera::new(scene.camera_spec(), 256, 256);
        let ctx = ShadeContext::for_scene(&scene, 0);
        let frame = render(accel.as_ref(), &camera, &ctx, Workload::Primary);
        // Points facing away from the light are unlit whatever answers (and are not asked).
        let points: Vec<SurfacePoint> =
            surface_points(&frame, &camera, &ctx).into_iter().filter(|s| !faces_away(s, ctx.light)).collect();
        // The renderer's shadow rays, from the surface; and rays from where the DAG is asked.
        let from_surface = shadow_rays(accel.as_ref(), &points, ctx.light);
        let asked: Vec<SurfacePoint> = points.iter().map(|s| SurfacePoint { p: query_point(&d, s), n: s.n }).collect();
        let from_query = shadow_rays(accel.as_ref(), &asked, ctx.light);
        let shadowed = from_surface.iter().filter(|&&r| r).count();
        assert!(shadowed * 100 > points.len(), "{name}: {shadowed} of {} points shadowed prove little", points.len());
        for variant in [Variant::Plain, Variant::Optimised] {
            let queries = shadow_queries(&d, variant, &points);
            for (rays, radius, what) in
                [(&from_query, 1, "rays from the query point"), (&from_surface, 3, "rays from the surface")]
            {
                let (mut outside, mut differ, mut off_boundary) = (0, 0, Vec::new());
                for ((s, &ray), q) in asked.iter().zip(rays).zip(&queries) {
                    let Some(q) = *q else {
                        outside += 1;
                        continue;
                    };
                    if q != ray {
                        differ += 1;
                        if !at_boundary(&d, s.p, radius) {
                            off_boundary.push(s.p);
                        }
                    }
                }
                let n = points.len() - outside;
                eprintln!(
                    "{name} L={level} {variant:?} against {what}: {n} points ({outside} outside the frustum), {differ} differ ({:.3} %), {} farther than {radius} voxels from a boundary",
                    100.0 * differ as f64 / n as f64,
                    off_boundary.len()
                );
                assert_eq!(outside, 0, "{name}: points outside the light's frustum");
                assert!(
                    off_boundary.is_empty(),
                    "{name} {variant:?} {what}: differences away from boundaries at {:?}",
                    &off_boundary[..off_boundary.len().min(5)]
                );
                if name == "room" && radius == 3 {
                    assert!(
                        differ * 1000 <= n,
                        "{name} {variant:?}: {differ} of {n} points differ from the renderer's shadow rays"
                    );
                }
            }
        }
    }
}

/// Whether a voxel within `radius` voxels of `q`'s is of the other class (the plain DAG's: lit
/// before `D1`, shadow from it on).
fn at_boundary(d: &ShadowSvdag, q: Vec3, radius: i64) -> bool {
    let Some((face, c)) = d.locate(q) else { return true };
    let n = d.faces[face].resolution() as i64;
    let lit = |c: [i64; 3]| {
        let t = (c[1] * n + c[0]) as usize;
        c[2] < i64::from(d.lit_slices[face][t])
    };
    let me = lit(c.map(i64::from));
    for dz in -radius..=radius {
        for dy in -radius..=radius {
            for dx in -radius..=radius {
                let o = [c[0] as i64 + dx, c[1] as i64 + dy, c[2] as i64 + dz];
                if o.iter().all(|&x| (0..n).contains(&x)) && lit(o) != me {
                    return true;
                }
            }
        }
    }
    false
}

#[test]
fn the_registry_builds_the_selected_variant() {
    let scene = load("room");
    for (variant, want) in [("plain", Variant::Plain), ("optimised", Variant::Optimised)] {
        let p = Params::parse(["voxel.levels=6", &format!("shadow.variant={variant}")]).expect("params");
        let d =
            ShadowSvdag::build(&BuildInput { scene: &scene, triangles: scene.triangles(), params: &p }).expect("build");
        assert_eq!(d.dag().variant, want);
    }
    let bad = Params::parse(["voxel.levels=16"]).expect("params");
    assert!(ShadowSvdag::build(&BuildInput { scene: &scene, triangles: scene.triangles(), params: &bad }).is_err());
}
