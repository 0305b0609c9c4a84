/* build_large_rules.cl — the split rules of the large-node stage (Zhou et al. 2008, §4.1) that
 * both of its schedules apply, the level-by-level kernels (build_large.cl, build_large_groups.cl)
 * and the depth-first one (build_large_depth_first.cl): one copy, so that both build the same tree
 * node for node. It holds no kernel of its own; the binned SAH plane is build_large_sah.cl's. */
#ifndef KDRAY_BUILD_LARGE_RULES_CL
#define KDRAY_BUILD_LARGE_RULES_CL

#include "cl/builder/kernels/build_common.cl"

/* The chain of empty-space cuts of a node of box *box at `depth` whose references' bounds are
 * `tight` (within the box): while the widest empty slab on one side exceeds `ratio` of the box's
 * extent on its axis, cut it off (at most KDRAY_MAX_CUTS cuts, and none past the depth limit).
 * *box becomes the box of the chain's last node. Both large stages' rule (kd_split_large_nodes,
 * kd_build_large_depth_first). */
KDRAY_INLINE void kd_empty_space_cuts(KdBox* box, KdBox tight, uint depth, uint max_depth,
                                      float ratio, KdLargeCuts* chain) {
    for (uint g = 0; g < KDRAY_MAX_CUTS; ++g) chain->code[g] = 0, chain->pos[g] = 0.0f;
    chain->pad = 0;
    uint cuts = 0;
    while (cuts < KDRAY_MAX_CUTS && depth + cuts < max_depth) {
        const float3 extent = box->hi - box->lo;
        float best = ratio;
        uint axis = KDRAY_LEAF_AXIS, keep_above = 0;
        float pos = 0.0f;
        for (uint a = 0; a < 3; ++a) {
            const float e = kd_axis_of(extent, a);
            if (!(e > 0.0f)) continue;
            const float gap_lo = (kd_axis_of(tight.lo, a) - kd_axis_of(box->lo, a)) / e;
            const float gap_hi = (kd_axis_of(box->hi, a) - kd_axis_of(tight.hi, a)) / e;
            if (gap_lo > best)
                best = gap_lo, axis = a, pos = kd_axis_of(tight.lo, a), keep_above = 1;
            if (gap_hi > best)
                best = gap_hi, axis = a, pos = kd_axis_of(tight.hi, a), keep_above = 0;
        }
        if (axis == KDRAY_LEAF_AXIS) break;
        chain->code[cuts] = axis * 2 + keep_above;
        chain->pos[cuts] = pos;
        *box = kd_child_box(*box, axis, pos, keep_above);
        ++cuts;
    }
    chain->count = cuts;
}

/* The spatial median of the box's longest axis: the plane without bins, and the one the binned
 * SAH replaces when it finds one. */
KDRAY_INLINE void kd_median_plane(KdBox box, uint* axis, float* pos) {
    const float3 extent = box.hi - box.lo;
    *axis = extent.x >= extent.y && extent.x >= extent.z ? 0 : (extent.y >= extent.z ? 1 : 2);
    *pos = 0.5f * (kd_axis_of(box.lo, *axis) + kd_axis_of(box.hi, *axis));
}

/* The split axis, or KDRAY_LEAF_AXIS when the plane does not lie strictly inside the box (a box
 * flat in every axis cannot be split) or the children would pass the depth limit. */
KDRAY_INLINE uint kd_plane_or_leaf(KdBox box, uint axis, float pos, uint depth, uint max_depth) {
    const float lo = kd_axis_of(box.lo, axis), hi = kd_axis_of(box.hi, axis);
    return pos > lo && pos < hi && depth < max_depth ? axis : KDRAY_LEAF_AXIS;
}

/* A reference of box b (triangle tri) straddling the plane `split` of a node of box `node`: its
 * box in each child (*below, *above), the bounds of the triangle's part there (at worst b cut at
 * the plane); returns the children the triangle enters (KDRAY_BELOW | KDRAY_ABOVE), none when
 * clipping finds it in neither. Both large stages' clipping. The sides are written out, not
 * looped over an array of two boxes: the array stayed on the stack, and its 32-byte stores read
 * back in 16-byte halves stalled the depth-first partition's loop. */
KDRAY_HOT_INLINE uint kd_clip_side(KdBox b, __global const float* tri, const uint axis,
                                   float split, KdBox node, uint side, KdBox* out) {
    KdBox c = b, clipped;
    if (side == 0) c.hi = kd_with_axis(c.hi, axis, split);
    else c.lo = kd_with_axis(c.lo, axis, split);
    const int entered =
        kd_clip_triangle_bounds(tri, kd_child_box(node, axis, split, side), &clipped);
    if (entered) {
        c.lo = fmin(fmax(c.lo, clipped.lo), c.hi);
        c.hi = fmax(fmin(c.hi, clipped.hi), c.lo);
    }
    *out = c;
    return entered ? (side == 0 ? KDRAY_BELOW : KDRAY_ABOVE) : 0u;
}

KDRAY_HOT_INLINE uint kd_clip_straddler(KdBox b, __global const float* tri, const uint axis,
                                        float split, KdBox node, KdBox* below, KdBox* above) {
    return kd_clip_side(b, tri, axis, split, node, 0, below) |
           kd_clip_side(b, tri, axis, split, node, 1, above);
}

#endif /* KDRAY_BUILD_LARGE_RULES_CL */
