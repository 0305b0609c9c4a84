/* build_small_bins.cl — the small stage's binned search: a small node split at the cheapest of the
 * binned planes of its tight box (build_binned_sah.cl, the large stage's rule), with no
 * split-candidate masks. It holds no kernel of its own.
 *
 * Zhou et al. price every candidate of a small node exactly, by popcounts of the candidates' masks
 * (build_small_search.cl), which a pass over every pair of a small root's references computes
 * first: 64 x 64 box tests for a root of 64, the largest share of the small stage at `low`
 * (15% of a Kitchen build against 9% for the searches it feeds). Binned, a node of n references
 * costs two passes over them (its tight box, its bins) and a third for its children, O(n) and in
 * cache, and no mask is made at all. The batch's small_bins chooses it
 * (BuildParams::small_split_bins): a node on a re-clipped table keeps the exact search over the
 * table's own masks, and the leaf rule is the exact search's: a split only where it costs less than
 * C_i N.
 *
 * A node's children follow the chosen plane by kd_classify with planar references below; a
 * straddler whose plane misses a child leaves it (kd_drop_missed_triangles), as after an exact
 * split. Both small-stage shapes make the same counts, box and pick (the per-level stage's group
 * reduces the box and counts the bins in local memory, then its work-item 0 prices the planes by
 * this file's function), so their trees are the same. */
#ifndef KDRAY_BUILD_SMALL_BINS_CL
#define KDRAY_BUILD_SMALL_BINS_CL

#include "cl/builder/kernels/build_binned_sah.cl"

#define KDRAY_SMALL_BIN_VALUES (KDRAY_BIN_COUNTS * KDRAY_SMALL_MAX_BINS)

/* Whether a reference box lies below and above a small node's binned plane (axis, pos). */
KDRAY_INLINE uint kd_small_bin_sides(KdBox b, uint axis, float pos) {
    return kd_classify(kd_axis_of(b.lo, axis), kd_axis_of(b.hi, axis), pos, KDRAY_BELOW);
}

/* The binned split of a node (box; references `mask` over the small root's list from start, their
 * boxes in ref_box): 1 with the plane (*axis, *pos) and the children's masks when a plane costs
 * less than the leaf's C_i N, else 0. */
KDRAY_INLINE int kd_binned_small_split(KdBox box, ulong mask, uint start,
                                       __global const float* ref_box, uint bins,
                                       float cost_traversal, float cost_intersection,
                                       float empty_bonus, uint* axis, float* pos, ulong* below,
                                       ulong* above) {
    KdBox tight;
    tight.lo = (float3)(INFINITY);
    tight.hi = (float3)(-INFINITY);
    for (ulong rest = mask; rest != 0; rest &= rest - 1) {
        const KdBox b = kd_load_box(ref_box, start + kd_lowest_bit(rest));
        tight.lo = fmin(tight.lo, b.lo);
        tight.hi = fmax(tight.hi, b.hi);
    }
    tight.lo = fmax(tight.lo, box.lo);
    tight.hi = fmin(tight.hi, box.hi);
    uint counts[KDRAY_SMALL_BIN_VALUES];
    for (uint k = 0; k < KDRAY_BIN_COUNTS * bins; ++k) counts[k] = 0;
    const float4 scale = kd_bin_scale(tight, bins), lo = (float4)(tight.lo, 0.0f);
    for (ulong rest = mask; rest != 0; rest &= rest - 1) {
        uint4 lo_bin, hi_bin;
        kd_bins_of(kd_load_box(ref_box, start + kd_lowest_bit(rest)), lo, scale, bins, &lo_bin,
                   &hi_bin);
        ++counts[lo_bin.x];
        ++counts[bins + hi_bin.x];
        ++counts[2 * bins + lo_bin.y];
        ++counts[3 * bins + hi_bin.y];
        ++counts[4 * bins + lo_bin.z];
        ++counts[5 * bins + hi_bin.z];
    }
    const uint n = popcount(mask);
    const float cost = kd_cheapest_binned_plane(box, tight, counts, bins, n, cost_traversal,
                                                cost_intersection, empty_bonus, axis, pos);
    if (!(cost < cost_intersection * (float)n)) return 0;
    *below = *above = 0;
    for (ulong rest = mask; rest != 0; rest &= rest - 1) {
        const ulong bit = rest & (0ul - rest);
        const uint sides =
            kd_small_bin_sides(kd_load_box(ref_box, start + kd_lowest_bit(rest)), *axis, *pos);
        if (sides & KDRAY_BELOW) *below |= bit;
        if (sides & KDRAY_ABOVE) *above |= bit;
    }
    return 1;
}

#endif /* KDRAY_BUILD_SMALL_BINS_CL */
