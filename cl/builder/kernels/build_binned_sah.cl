/* build_binned_sah.cl — the binned SAH plane of a node, the one rule of the large-node stage
 * (build_large_sah.cl, KDRAY_LARGE_BINS bins fixed per program) and of the small stage's binned
 * search (build_small_bins.cl, the batch's small_bins at run time). It holds no kernel.
 *
 * A node's bins divide its tight box (its references' bounds within the node's box) into `bins`
 * equal slabs per axis; counts[(2 axis + side) bins + bin] counts the references whose lo
 * (side 0) or hi (side 1) falls in the bin. The candidate planes are the bins + 1 slab
 * boundaries, the tight box's faces included (they cut off empty space). */
#ifndef KDRAY_BUILD_BINNED_SAH_CL
#define KDRAY_BUILD_BINNED_SAH_CL

#include "cl/builder/kernels/build_common.cl"

/* bins / extent per axis of a tight box (0 on an axis without extent; lane 3 unused). */
KDRAY_INLINE float4 kd_bin_scale(KdBox tight, uint bins) {
    const float4 extent = (float4)(tight.hi - tight.lo, 0.0f);
    return select((float4)(0.0f), (float)bins / extent, extent > (float4)(0.0f));
}

/* Bins of a reference's lo and hi on the three axes (lane 3 unused) of a tight box starting at
 * lo, with kd_bin_scale's scale. A value exactly on a bin boundary b lies on the plane between
 * bins b - 1 and b, which it must not cross: a lo there goes to bin b (not below the plane), a hi
 * to bin b - 1 (not above it), the bin of the float just before it. Conversions saturate, so
 * values before the box fall in bin 0; vector conversions, not floor and ceil, which PoCL left
 * as branchy scalar code (the large stage's kernel then took 40% of a Kitchen build). */
KDRAY_INLINE void kd_bins_of(KdBox b, float4 lo, float4 scale, uint bins, uint4* lo_bin,
                             uint4* hi_bin) {
    const uint4 last = (uint4)(bins - 1u);
    const float4 f_lo = ((float4)(b.lo, 0.0f) - lo) * scale;
    const float4 f_hi = ((float4)(b.hi, 0.0f) - lo) * scale;
    const float4 before_hi = select((float4)(0.0f), as_float4(as_int4(f_hi) - 1), f_hi > 0.0f);
    *lo_bin = min(convert_uint4_sat_rtz(f_lo), last);
    *hi_bin = min(convert_uint4_sat_rtz(before_hi), last);
}

/* Binned plane b (0 .. bins) of `axis`: the boundary between bins b - 1 and b of the tight box,
 * its faces at b = 0 and b = bins (they cut off empty space). */
KDRAY_INLINE float kd_binned_plane_pos(KdBox tight, uint axis, uint b, uint bins) {
    const float t_lo = kd_axis_of(tight.lo, axis), t_hi = kd_axis_of(tight.hi, axis);
    return b == 0 ? t_lo : b == bins ? t_hi : t_lo + (t_hi - t_lo) * ((float)b / (float)bins);
}

/* What the SAH of a node's planes on one axis shares: the box's extent on the axis, the cross
 * section and ring of the other two, and C_i / SA. */
typedef struct KdPlaneFrame {
    float lo, hi, cross, ring, cost_scale;
} KdPlaneFrame;

KDRAY_INLINE KdPlaneFrame kd_plane_frame(KdBox box, uint axis, float cost_intersection) {
    const float3 e = box.hi - box.lo;
    const float e1 = kd_axis_of(e, (axis + 1) % 3), e2 = kd_axis_of(e, (axis + 2) % 3);
    KdPlaneFrame f;
    f.lo = kd_axis_of(box.lo, axis);
    f.hi = kd_axis_of(box.hi, axis);
    f.cross = e1 * e2;
    f.ring = e1 + e2;
    f.cost_scale = cost_intersection / kd_box_area(box);
    return f;
}

/* Whether a plane at p may split the node: strictly inside its box. */
KDRAY_INLINE int kd_plane_inside(KdPlaneFrame f, float p) {
    return p > f.lo && p < f.hi;
}

/* SAH = C_t + C_i (N_L SA_L + N_R SA_R) / SA of the plane at p inside the box (child area
 * 2 (cross + d ring)), scaled by (1 - empty_bonus) when a side is empty. One expression for every
 * caller, so that a group pricing planes in parallel gets the costs, and so the pick, of a
 * work-item pricing them in turn. */
KDRAY_INLINE float kd_binned_plane_cost(KdPlaneFrame f, float p, uint below, uint above,
                                        float cost_traversal, float empty_bonus) {
    const float cost = cost_traversal + f.cost_scale * 2.0f *
                                            ((float)below * (f.cross + (p - f.lo) * f.ring) +
                                             (float)above * (f.cross + (f.hi - p) * f.ring));
    return below == 0 || above == 0 ? cost * (1.0f - empty_bonus) : cost;
}

/* The cheapest binned plane of a node of `count` references inside `box`, as *axis and *pos, and
 * its cost (kd_binned_plane_cost); INFINITY (and *axis, *pos unchanged) when no plane lies
 * strictly inside the box. A plane's counts are those of the bins: below, the references whose
 * lo bin lies before it; above, those whose hi bin lies at or after it (a reference lying in the
 * plane is in neither count; the exact classification that follows the choice puts it on one
 * side). The first cheapest in (axis, plane) order wins. */
KDRAY_INLINE float kd_cheapest_binned_plane(KdBox box, KdBox tight, const uint* counts, uint bins,
                                            uint count, float cost_traversal,
                                            float cost_intersection, float empty_bonus, uint* axis,
                                            float* pos) {
    float best = INFINITY;
    for (uint a = 0; a < 3; ++a) {
        const KdPlaneFrame f = kd_plane_frame(box, a, cost_intersection);
        uint below = 0, above = count;
        for (uint b = 0; b <= bins; ++b) {
            /* The plane between bins b - 1 and b: below gains bin b - 1's starts, above has lost
             * the ends before bin b. */
            if (b > 0) {
                below += counts[(2 * a) * bins + b - 1];
                above -= counts[(2 * a + 1) * bins + b - 1];
            }
            const float p = kd_binned_plane_pos(tight, a, b, bins);
            if (!kd_plane_inside(f, p)) continue;
            const float cost =
                kd_binned_plane_cost(f, p, below, above, cost_traversal, empty_bonus);
            if (cost < best) best = cost, *axis = a, *pos = p;
        }
    }
    return best;
}

#endif /* KDRAY_BUILD_BINNED_SAH_CL */
