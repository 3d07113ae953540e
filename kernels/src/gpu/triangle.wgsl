// The watertight ray/triangle test of Woop, Benthin & Wald, "Watertight Ray/Triangle
// Intersection", JCGT 2(1), 2013 — the WGSL twin of kernels/src/cpu/triangle.rs, same arithmetic
// in the same order, so CPU and GPU hits agree (docs/design.md §3).
//
// Reads the triangle soup through the accessor `triangles(i)`: 9 words per triangle, the three
// vertices' x, y, z as f32 bits (structures' `Arc<[Triangle]>`, uploaded as it is).

struct ShearedRay {
    origin: vec3<f32>,
    // The axes (kx, ky, kz): kz where the direction is largest, kx and ky swapped when d[kz] < 0.
    k: vec3<u32>,
    // (sx, sy, sz) = (d[kx] / d[kz], d[ky] / d[kz], 1 / d[kz]).
    s: vec3<f32>,
}

fn sheared_ray(ray: Ray) -> ShearedRay {
    let d = ray.dir;
    let a = abs(d);
    var kz = 2u;
    if (a.x > a.y) {
        if (a.x > a.z) {
            kz = 0u;
        }
    } else if (a.y > a.z) {
        kz = 1u;
    }
    var kx = (kz + 1u) % 3u;
    var ky = (kx + 1u) % 3u;
    // Keep the winding of the projected triangle independent of the sign of d[kz].
    if (d[kz] < 0.0) {
        let swap = kx;
        kx = ky;
        ky = swap;
    }
    return ShearedRay(ray.origin, vec3<u32>(kx, ky, kz), vec3<f32>(d[kx] / d[kz], d[ky] / d[kz], 1.0 / d[kz]));
}

fn triangle_vertex(tri: u32, v: u32) -> vec3<f32> {
    let w = tri * 9u + v * 3u;
    return vec3<f32>(bitcast<f32>(triangles(w)), bitcast<f32>(triangles(w + 1u)), bitcast<f32>(triangles(w + 2u)));
}

// a·b − c·d as the CPU's f64 fallback gives it: both products exactly (the rounding error of each
// recovered with fma), their difference rounded once. Used only when an edge function is exactly
// zero, where its sign decides which of two triangles sharing the edge is hit.
fn exact_difference(a: f32, b: f32, c: f32, d: f32) -> f32 {
    let p = a * b;
    let q = c * d;
    return (p - q) + (fma(a, b, -p) - fma(c, d, -q));
}

// The hit distance t with t_min < t < t_max, two-sided; t_max itself when there is none.
fn intersect_triangle(r: ShearedRay, tri: u32, t_min: f32, t_max: f32) -> f32 {
    let kx = r.k.x;
    let ky = r.k.y;
    let kz = r.k.z;
    let a = triangle_vertex(tri, 0u) - r.origin;
    let b = triangle_vertex(tri, 1u) - r.origin;
    let c = triangle_vertex(tri, 2u) - r.origin;
    let ax = a[kx] - r.s.x * a[kz];
    let ay = a[ky] - r.s.y * a[kz];
    let bx = b[kx] - r.s.x * b[kz];
    let by = b[ky] - r.s.y * b[kz];
    let cx = c[kx] - r.s.x * c[kz];
    let cy = c[ky] - r.s.y * c[kz];
    var u = cx * by - cy * bx;
    var v = ax * cy - ay * cx;
    var w = bx * ay - by * ax;
    if (u == 0.0 || v == 0.0 || w == 0.0) {
        u = exact_difference(cx, by, cy, bx);
        v = exact_difference(ax, cy, ay, cx);
        w = exact_difference(bx, ay, by, ax);
    }
    if ((u < 0.0 || v < 0.0 || w < 0.0) && (u > 0.0 || v > 0.0 || w > 0.0)) {
        return t_max;
    }
    let det = u + v + w;
    if (det == 0.0) {
        return t_max; // degenerate, or the ray lies in the triangle's plane
    }
    let t = (u * (r.s.z * a[kz]) + v * (r.s.z * b[kz]) + w * (r.s.z * c[kz])) / det;
    if (t > t_min && t < t_max) {
        return t;
    }
    return t_max;
}

// The result of a triangle kernel: the nearest hit (best_t, triangle best_prim), or a miss when no
// triangle was hit (best_prim == NO_PRIM).
fn triangle_result(best_t: f32, best_prim: u32) -> TraceResult {
    if (best_prim == NO_PRIM) {
        return no_hit();
    }
    return TraceResult(true, best_t, best_prim, 0u);
}

// Tests triangle `prim` and takes its hit when nearer than the best so far, or as near with a
// smaller triangle index (the tie rule, cpu::bvh::tie_limit): past the first hit it tests up to one
// ulp beyond it, so the least (t, index) wins whatever order the triangles are tested in. A miss
// returns the limit itself, which neither condition accepts.
fn take_nearer(r: ShearedRay, prim: u32, t_min: f32, best_t: ptr<function, f32>, best_prim: ptr<function, u32>) -> bool {
    let limit = select(*best_t, bitcast<f32>(bitcast<u32>(*best_t) + 1u), *best_prim != NO_PRIM);
    let t = intersect_triangle(r, prim, t_min, limit);
    if (t < limit && (t < *best_t || prim < *best_prim)) {
        *best_t = t;
        *best_prim = prim;
        return true;
    }
    return false;
}
