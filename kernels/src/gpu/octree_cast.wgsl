// The Laine–Karras octree caster (seed 000 §6, Fig. 15), shared by the `svo` and `esvo` kernels
// exactly as kernels/src/cpu/octree_cast.rs is shared on the CPU. The node layout comes from
// functions the structure's own WGSL file defines (the WGSL twin of the `CastNodes` trait):
//
//   fn node_root() -> u32
//   fn node_fetch(node: u32, scale: u32) -> vec2<u32>      (the cached descriptor; children at scale)
//   fn node_valid(desc: vec2<u32>, slot: u32) -> bool
//   fn node_leaf(desc: vec2<u32>, slot: u32, scale: u32) -> bool
//   fn node_child(node: u32, desc: vec2<u32>, slot: u32, scale: u32) -> u32
//   fn node_contour(node: u32, desc: vec2<u32>, slot: u32) -> ContourRef
//
// Slots passed to them are world child slots (bit set = upper half, x in bit 0). The frame is
// octree_ray.wgsl's: the octree is [1, 2]³, mirrored so every direction component is negative.

struct ContourRef {
    present: bool,
    word: u32,
}

struct CastHit {
    hit: bool,
    t: f32,
    // The hit cube in the mirrored frame: minimum corner and scale.
    pos: vec3<f32>,
    scale: u32,
    // The ray's mirror mask (octree_ray.wgsl).
    mirror: u32,
}

// The t span in which the octree-space ray lies inside a contour's slab (cpu/esvo.rs
// `contour_span`, through structures::esvo::contour::Contour::slab).
fn contour_span(contour: u32, cube_min: vec3<f32>, size: f32, o: vec3<f32>, d: vec3<f32>) -> vec2<f32> {
    // 6-bit signed normal components at bits 12, 6, 0; 7-bit signed position at 18; thickness at 25.
    let n = vec3<f32>(
        f32(extractBits(bitcast<i32>(contour), 12u, 6u)),
        f32(extractBits(bitcast<i32>(contour), 6u, 6u)),
        f32(extractBits(bitcast<i32>(contour), 0u, 6u)),
    );
    let position = f32(extractBits(bitcast<i32>(contour), 18u, 7u));
    let thickness = f32(contour >> 25u);
    let plane_normal = n / size;
    let centre = cube_min + vec3<f32>(0.5 * size);
    let mid = dot(plane_normal, centre) + position * 0.75;
    let half_width = thickness * 0.375;
    let lo = mid - half_width;
    let hi = mid + half_width;
    let along = dot(plane_normal, d);
    let at_origin = dot(plane_normal, o);
    if (along == 0.0) {
        if (lo <= at_origin && at_origin <= hi) {
            return vec2<f32>(-BIG, BIG);
        }
        return vec2<f32>(1.0, 0.0);
    }
    let inv = 1.0 / along;
    let t0 = (lo - at_origin) * inv;
    let t1 = (hi - at_origin) * inv;
    return vec2<f32>(min(t0, t1), max(t0, t1));
}

// Casts the octree-space ray (o, d) over (t_min, t_max); `contours` intersects contours into the
// active span, `lod_k` > 0 stops at a voxel whose side is at most lod_k · t (octree units).
fn octree_cast(o: vec3<f32>, d: vec3<f32>, t_min_in: f32, t_max_in: f32, contours: bool, lod_k: f32) -> CastHit {
    let r = octree_ray(o, d);
    var miss: CastHit;
    miss.hit = false;
    let span = root_span(r, t_min_in, t_max_in);
    var t_min = span.x;
    var t_max = span.y;
    if (t_min > t_max) {
        return miss;
    }
    // Every span the stack restores ends by the ray's own end: past it nothing can be hit.
    let t_end = t_max;
    // (parent, t_max) per scale; scale S_MAX − 1 is the root's children.
    var stack_node: array<u32, 24>;
    var stack_t: array<f32, 24>;
    var h = t_max;
    var parent = node_root();
    var desc = vec2<u32>(0u);
    var have_desc = false;

    // The root's child the ray enters first: the upper half of an axis iff the ray has not yet
    // crossed its centre plane at t_min.
    var idx = 0u;
    var pos = vec3<f32>(1.0);
    var scale = S_MAX - 1u;
    var scale_exp2 = 0.5;
    let c0 = plane_t(r, vec3<f32>(1.5));
    for (var a = 0u; a < 3u; a++) {
        if (c0[a] > t_min) {
            idx ^= 1u << a;
            pos[a] = 1.5;
        }
    }

    // Every iteration PUSHes (at most S_MAX times in a row) or ADVANCEs, so bounding the advances
    // bounds the loop, as on the CPU (kernels/src/cpu/octree_cast.rs).
    var advances = 0u;
    loop {
        count_step();
        if (!have_desc) {
            desc = node_fetch(parent, scale);
            have_desc = true;
        }
        // Distances to the current cube's exit planes (its lower faces in the mirrored frame).
        let corner = plane_t(r, pos);
        let tc_max = min(min(corner.x, corner.y), corner.z);
        let slot = idx ^ r.mirror;

        if (node_valid(desc, slot) && t_min <= t_max) {
            // LOD: the voxel is small enough for the pixel it covers.
            if (lod_k > 0.0 && scale_exp2 <= tc_max * lod_k) {
                return CastHit(true, t_min, pos, scale, r.mirror);
            }
            // INTERSECT: the span inside this cube, narrowed by the voxel's contour.
            var tv_max = min(t_max, tc_max);
            let half_size = scale_exp2 * 0.5;
            let centre = plane_t(r, pos + vec3<f32>(half_size));
            if (contours) {
                let c = node_contour(parent, desc, slot);
                if (c.present) {
                    let cs = contour_span(c.word, world_cube_min(pos, scale_exp2, r.mirror), scale_exp2, o, d);
                    t_min = max(t_min, cs.x);
                    tv_max = min(tv_max, cs.y);
                }
            }
            if (t_min <= tv_max) {
                if (node_leaf(desc, slot, scale)) {
                    return CastHit(true, t_min, pos, scale, r.mirror);
                }
                // PUSH
                if (tc_max < h) {
                    stack_node[scale] = parent;
                    stack_t[scale] = t_max;
                }
                h = tc_max;
                parent = node_child(parent, desc, slot, scale);
                have_desc = false;
                idx = 0u;
                scale -= 1u;
                scale_exp2 = half_size;
                for (var a = 0u; a < 3u; a++) {
                    if (centre[a] > t_min) {
                        idx ^= 1u << a;
                        pos[a] += half_size;
                    }
                }
                t_max = tv_max;
                continue;
            }
        }

        // ADVANCE: step to the next cube of the same scale through the exit plane(s).
        let step_mask = advance_cube(&pos, corner, tc_max, scale_exp2);
        t_min = tc_max;
        idx ^= step_mask;
        advances += 1u;
        if (t_min > t_end || advances >= MAX_STEPS) {
            if (advances >= MAX_STEPS) {
                count_bound();
            }
            return miss;
        }

        // POP if a flipped bit went against the ray: the ray left the parent. The new scale is
        // the highest bit that differs between the float bits of the old and new positions.
        if ((idx & step_mask) != 0u) {
            var differing = 0u;
            for (var a = 0u; a < 3u; a++) {
                if (((step_mask >> a) & 1u) == 1u) {
                    differing |= bitcast<u32>(pos[a]) ^ bitcast<u32>(pos[a] + scale_exp2);
                }
            }
            scale = firstLeadingBit(differing);
            if (differing == 0u || scale >= S_MAX) {
                return miss;
            }
            scale_exp2 = bitcast<f32>((scale + 127u - S_MAX) << 23u);
            parent = stack_node[scale];
            t_max = stack_t[scale];
            idx = 0u;
            for (var a = 0u; a < 3u; a++) {
                let sh = bitcast<u32>(pos[a]) >> scale;
                pos[a] = bitcast<f32>(sh << scale);
                idx |= (sh & 1u) << a;
            }
            h = 0.0;
            have_desc = false;
        }
    }
    return miss;
}

// A cast's hit as the primitive every voxel kernel reports: t and the hit cube's Morton code,
// with how many levels above the leaves it lies (an LOD stop) in bits 58–63 (bits 26–31 of the
// high word; structures::voxel::morton::hit_id).
fn voxel_trace_result(h: CastHit) -> TraceResult {
    if (!h.hit) {
        return no_hit();
    }
    let code = cube_morton(h.pos, h.scale, h.mirror);
    let above = h.scale - (S_MAX - params(4u));
    return TraceResult(true, h.t, code.x, code.y | (above << 26u));
}
