/* build_large_sah.cl — the binned SAH split of the large-node stage (build_large.cl), for
 * KDRAY_LARGE_BINS > 0; it holds no kernel of its own.
 *
 * Zhou et al. split a large node at the spatial median of its longest axis (§4.1); with
 * KDRAY_LARGE_BINS > 0 the plane is instead the cheapest by the SAH among the KDRAY_LARGE_BINS + 1
 * equally spaced planes of each axis of the node's tight box, as the GPU builders after it do
 * (Danilewski, Popov & Slusallek 2010, "Binned SAH kd-tree construction on a GPU"; Wu, Zhang &
 * Liu 2011). The median costs the shared scenes up to 21% of SAH (Sponza, against the reference
 * builder); bins of the tight box, not of the node's box, because the top levels' boxes are
 * mostly empty space (the horse: 8 bins of the tight box gave 1.02 times the full SAH, 32 of the
 * node's box 1.09, in a CPU experiment on the reference builder).
 *
 * Counts come per reduction chunk (at most KDRAY_REDUCE_CHUNK references of one node), in
 * chunk_bins[chunk][axis][side][bin]: side 0 counts the references whose lo falls in the bin,
 * side 1 those whose hi does. */
#ifndef KDRAY_BUILD_LARGE_SAH_CL
#define KDRAY_BUILD_LARGE_SAH_CL

#include "cl/builder/kernels/build_common.cl"

#define KDRAY_BIN_VALUES (KDRAY_BIN_COUNTS * KDRAY_LARGE_BINS)

/* Bins of a reference's lo and hi on the three axes (lane 3 unused) of a tight box starting at
 * lo, with bins / extent in scale. A value exactly on a bin boundary b lies on the plane between
 * bins b - 1 and b, which it must not cross: a lo there goes to bin b (not below the plane), a hi
 * to bin b - 1 (not above it), the bin of the float just before it. Conversions saturate, so
 * values before the box fall in bin 0; vector conversions, not floor and ceil, which PoCL left
 * as branchy scalar code (the kernel then took 40% of a Kitchen build). */
KDRAY_INLINE void kd_large_bins(KdBox b, float4 lo, float4 scale, uint4* lo_bin, uint4* hi_bin) {
    const uint4 last = (uint4)(KDRAY_LARGE_BINS - 1);
    const float4 f_lo = ((float4)(b.lo, 0.0f) - lo) * scale;
    const float4 f_hi = ((float4)(b.hi, 0.0f) - lo) * scale;
    const float4 before_hi = select((float4)(0.0f), as_float4(as_int4(f_hi) - 1), f_hi > 0.0f);
    *lo_bin = min(convert_uint4_sat_rtz(f_lo), last);
    *hi_bin = min(convert_uint4_sat_rtz(before_hi), last);
}

/* counts[KDRAY_BIN_VALUES]: the bins of boxes[begin .. end) over `tight` (both large stages: a
 * reduction chunk's, a depth-first node's). With low's 8 bins the six histograms are int8
 * registers, a bin's count raised in the lane whose index is the bin (a true comparison is -1),
 * instead of six increments in memory per reference, each after a move of its bin out of a vector
 * register. The counts are the same integers. Kitchen low, perf over 3 interleaved pairs of 30
 * builds: kd_bin_large_chunks 25% fewer samples (about 1.7% of the build), the depth-first
 * kernel's no fewer (its time is elsewhere). */
KDRAY_INLINE void kd_bin_references(__global const float* boxes, uint begin, uint end, KdBox tight,
                                    uint* counts) {
    const float4 extent = (float4)(tight.hi - tight.lo, 0.0f);
    const float4 scale =
        select((float4)(0.0f), (float)KDRAY_LARGE_BINS / extent, extent > (float4)(0.0f));
    const float4 lo = (float4)(tight.lo, 0.0f);
#if KDRAY_LARGE_BINS == 8
    const int8 lane = (int8)(0, 1, 2, 3, 4, 5, 6, 7);
    int8 histogram[6] = {(int8)(0), (int8)(0), (int8)(0), (int8)(0), (int8)(0), (int8)(0)};
    for (uint r = begin; r < end; ++r) {
        uint4 lo_bin, hi_bin;
        kd_large_bins(kd_load_box(boxes, r), lo, scale, &lo_bin, &hi_bin);
        histogram[0] -= lane == (int8)((int)lo_bin.x);
        histogram[1] -= lane == (int8)((int)hi_bin.x);
        histogram[2] -= lane == (int8)((int)lo_bin.y);
        histogram[3] -= lane == (int8)((int)hi_bin.y);
        histogram[4] -= lane == (int8)((int)lo_bin.z);
        histogram[5] -= lane == (int8)((int)hi_bin.z);
    }
    for (uint k = 0; k < 6; ++k) vstore8(as_uint8(histogram[k]), k, counts);
#else
    for (uint k = 0; k < KDRAY_BIN_VALUES; ++k) counts[k] = 0;
    for (uint r = begin; r < end; ++r) {
        uint4 lo_bin, hi_bin;
        kd_large_bins(kd_load_box(boxes, r), lo, scale, &lo_bin, &hi_bin);
        ++counts[lo_bin.x];
        ++counts[KDRAY_LARGE_BINS + hi_bin.x];
        ++counts[2 * KDRAY_LARGE_BINS + lo_bin.y];
        ++counts[3 * KDRAY_LARGE_BINS + hi_bin.y];
        ++counts[4 * KDRAY_LARGE_BINS + lo_bin.z];
        ++counts[5 * KDRAY_LARGE_BINS + hi_bin.z];
    }
#endif
}

/* The tight box a node's bins divide: its references' bounds within the node's box. */
KDRAY_INLINE KdBox kd_bin_box(KdBox box, __global const float* tight_box, uint i) {
    KdBox tight = kd_load_box(tight_box, i);
    tight.lo = fmax(tight.lo, box.lo);
    tight.hi = fmin(tight.hi, box.hi);
    return tight;
}

/* The cheapest binned plane of a node inside `box` (its box after the empty-space cuts), as
 * *axis and *pos; 0 when no plane lies strictly inside the box. The node's counts are the sum of
 * bins[first .. end): its chunks' bins, or (the element-parallel stage, build_large_groups.cl)
 * the one entry kd_sum_node_bins made of them. A plane's counts are those of
 * the bins: below, the references whose lo bin lies before it; above, those whose hi bin lies at
 * or after it. The exact classification follows the choice. */
KDRAY_INLINE int kd_best_binned_plane(KdBox box, KdBox tight, const uint* counts, uint count,
                                      float cost_traversal, float cost_intersection,
                                      float empty_bonus, uint* axis, float* pos);

KDRAY_INLINE int kd_best_large_split(KdBox box, KdBox tight, __global const uint* bins,
                                     uint first, uint end, uint count,
                                     float cost_traversal, float cost_intersection,
                                     float empty_bonus, uint* axis, float* pos) {
    uint counts[KDRAY_BIN_VALUES];
    for (uint k = 0; k < KDRAY_BIN_VALUES; ++k) counts[k] = 0;
    for (uint c = first; c < end; ++c) {
        __global const uint* in = bins + (size_t)c * KDRAY_BIN_VALUES;
        for (uint k = 0; k < KDRAY_BIN_VALUES; ++k) counts[k] += in[k];
    }
    return kd_best_binned_plane(box, tight, counts, count, cost_traversal, cost_intersection,
                                empty_bonus, axis, pos);
}

/* kd_best_large_split's choice from a node's summed bins (`counts`, KDRAY_BIN_VALUES of them):
 * also the depth-first stage's, which bins a node's references itself. */
KDRAY_INLINE int kd_best_binned_plane(KdBox box, KdBox tight, const uint* counts, uint count,
                                      float cost_traversal, float cost_intersection,
                                      float empty_bonus, uint* axis, float* pos) {
    const float3 e = box.hi - box.lo;
    const float cost_scale = cost_intersection / kd_box_area(box);
    float best = INFINITY;
    for (uint a = 0; a < 3; ++a) {
        const float lo = kd_axis_of(box.lo, a), hi = kd_axis_of(box.hi, a);
        const float t_lo = kd_axis_of(tight.lo, a), t_hi = kd_axis_of(tight.hi, a);
        const float e1 = kd_axis_of(e, (a + 1) % 3), e2 = kd_axis_of(e, (a + 2) % 3);
        const float cross = e1 * e2, ring = e1 + e2;
        uint below = 0, above = count;
        for (uint b = 0; b <= KDRAY_LARGE_BINS; ++b) {
            /* The plane between bins b - 1 and b: below gains bin b - 1's starts, above has lost
             * the ends before bin b. */
            if (b > 0) {
                below += counts[(2 * a) * KDRAY_LARGE_BINS + b - 1];
                above -= counts[(2 * a + 1) * KDRAY_LARGE_BINS + b - 1];
            }
            const float p = b == 0 ? t_lo
                            : b == KDRAY_LARGE_BINS
                                ? t_hi
                                : t_lo + (t_hi - t_lo) * ((float)b / (float)KDRAY_LARGE_BINS);
            if (!(p > lo && p < hi)) continue;
            float cost = cost_traversal +
                         cost_scale * 2.0f *
                             ((float)below * (cross + (p - lo) * ring) +
                              (float)above * (cross + (hi - p) * ring));
            if (below == 0 || above == 0) cost *= 1.0f - empty_bonus;
            if (cost < best) best = cost, *axis = a, *pos = p;
        }
    }
    return best < INFINITY;
}
#endif /* KDRAY_BUILD_LARGE_SAH_CL */
