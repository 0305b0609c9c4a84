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
 * side 1 those whose hi does. The bins and the plane's price are build_binned_sah.cl's, which the
 * small stage's binned search (build_small_bins.cl) shares. */
#ifndef KDRAY_BUILD_LARGE_SAH_CL
#define KDRAY_BUILD_LARGE_SAH_CL

#include "cl/builder/kernels/build_binned_sah.cl"

#define KDRAY_BIN_VALUES (KDRAY_BIN_COUNTS * KDRAY_LARGE_BINS)

/* kd_bins_of at the program's KDRAY_LARGE_BINS. */
KDRAY_INLINE void kd_large_bins(KdBox b, float4 lo, float4 scale, uint4* lo_bin, uint4* hi_bin) {
    kd_bins_of(b, lo, scale, KDRAY_LARGE_BINS, lo_bin, hi_bin);
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
    const float4 scale = kd_bin_scale(tight, KDRAY_LARGE_BINS);
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

KDRAY_INLINE int kd_best_large_split(KdBox box, KdBox tight, __global const uint* bins, uint first,
                                     uint end, uint count, float cost_traversal,
                                     float cost_intersection, float empty_bonus, uint* axis,
                                     float* pos) {
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
    return kd_cheapest_binned_plane(box, tight, counts, KDRAY_LARGE_BINS, count, cost_traversal,
                                    cost_intersection, empty_bonus, axis, pos) < INFINITY;
}
#endif /* KDRAY_BUILD_LARGE_SAH_CL */
