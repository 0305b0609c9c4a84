/* build_small_search.cl — the SAH search of one small node (Zhou et al. 2008, §4.2) over a table
 * of split-candidate masks: the small root's (side_masks, build_small.cl) or a re-clipped node's
 * (build_small_reclip.cl). A reference's six candidates are the lanes of one float8; the search
 * prices all of them at once per reference of the node. It holds no kernel of its own. */
#ifndef KDRAY_BUILD_SMALL_SEARCH_CL
#define KDRAY_BUILD_SMALL_SEARCH_CL

#include "cl/builder/kernels/build_common.cl"

/* The six split candidates of a reference's box (6 floats, lo.xyz hi.xyz) in the lanes of one
 * float8: lane k = 2 * axis + side is the box's lo (side 0) or hi (side 1) on that axis; lanes 6
 * and 7 are 0. */
KDRAY_INLINE float8 kd_candidate_lanes(__global const float* b) {
    return (float8)(b[0], b[3], b[1], b[4], b[2], b[5], 0.0f, 0.0f);
}

/* A box's bounds beside those lanes: *lo and *hi hold, in lane 2 * axis + side, its lo and hi on
 * that axis (lanes 6 and 7: 0). */
KDRAY_INLINE void kd_box_lanes(KdBox box, float8* lo, float8* hi) {
    *lo = (float8)(box.lo.x, box.lo.x, box.lo.y, box.lo.y, box.lo.z, box.lo.z, 0.0f, 0.0f);
    *hi = (float8)(box.hi.x, box.hi.x, box.hi.y, box.hi.y, box.hi.z, box.hi.z, 0.0f, 0.0f);
}

/* The lanes (of a reference's six candidates, lane 2 * axis + side at pos) whose planar triangles
 * go above: the hi lanes of the axes on which the reference is flat (lo and hi at one plane). */
KDRAY_INLINE int8 kd_planar_above_lanes(float8 pos) {
    const int8 odd = (int8)(0, -1, 0, -1, 0, -1, 0, 0);
    return odd & (pos == pos.s00224466);
}

/* The box whose candidate lanes (kd_candidate_lanes' order) are c. */
KDRAY_INLINE KdBox kd_lanes_box(float8 c) {
    KdBox b;
    b.lo = c.s024;
    b.hi = c.s135;
    return b;
}

/* Whether a triangle that straddles a node's split (in both children's masks) is worth the plane
 * test that may drop it from one child (kd_drop_missed_triangles): only when its box b (clipped to
 * the small root or to a re-clipping ancestor, not to the node) reaches past the node's box on an
 * axis other than the split's. A split that makes straddlers lies strictly inside the node (one on
 * its face makes none, kd_candidate_children). Were b the exact bounds of the triangle's clipped
 * part, inside the node's slab on both of those axes that convex part would have points on both
 * sides of the split inside the node, meeting both children, so the test could drop nothing.
 * Clipped boxes are intersections of such bounds, a little larger at times, so the rule keeps a
 * few triangles the test would have dropped (Kitchen at high: 2 nodes of 690,461 more; no tree at
 * low changed on the Kitchen, Robots, dragon res2 or Sponza); a kept triangle costs a ray a wasted
 * test, never a missed hit. Testing every straddler, its triangle fetched, took over a quarter of
 * the small stage at low (dragon res2: 31 ms; 27 ms with this rule, 22 ms with no test at all). */
KDRAY_INLINE int kd_straddler_may_miss(KdBox b, KdBox node, uint axis) {
    const int3 past = (b.lo < node.lo) | (b.hi > node.hi);
    return (axis != 0 && past.x) || (axis != 1 && past.y) || (axis != 2 && past.z);
}

/* The sides of one candidate plane per lane (at pos) that a box (lo, hi lanes) lies on, -1 where
 * true; planar_above: the lanes whose planar triangles go above (kd_compute_split_masks). A macro
 * over the vector width, for the float16 lanes of kd_compute_split_masks_grouped. */
#define KDRAY_CANDIDATE_SIDES(mask_type, pos, planar_above, lo, hi, below, above) \
    do {                                                                             \
        const mask_type crosses_up_ = (hi) > (pos);                            \
        (above) = crosses_up_ | ((planar_above) & ((lo) >= (pos)));                  \
        (below) = ((lo) < (pos)) | (~(planar_above) & ~crosses_up_);                 \
    } while (0)
KDRAY_INLINE void kd_candidate_sides(float8 pos, int8 planar_above, float8 lo, float8 hi,
                                     int8* below, int8* above) {
    KDRAY_CANDIDATE_SIDES(int8, pos, planar_above, lo, hi, *below, *above);
}

/* The children of a node (its triangles `node`) for the six candidates of one reference, at pos
 * (lanes as in kd_compute_split_masks), given the candidates' masks: inside the node's box (lo,
 * hi per lane) the masks themselves; at the node's lo face, the lo lanes make a flat child below
 * of the triangles lying in the face (below and not above) and leave the rest above; at its hi
 * face, the hi lanes make a flat child above of those lying there (above and not below). The
 * masks are over boxes clipped to the small root (or to a re-clipping ancestor), not to the node,
 * so on a face they would also count the triangles that only extend past it. Lanes that split
 * nothing (other candidates on a face, lanes 6 and 7) get no child at all: *valid is 0 there. */
KDRAY_INLINE void kd_candidate_children(ulong8 node, ulong8 below, ulong8 above, float8 pos,
                                        float8 lo, float8 hi, ulong8* below_out, ulong8* above_out,
                                        long8* valid) {
    const int8 lo_lane = (int8)(-1, 0, -1, 0, -1, 0, 0, 0);
    const int8 hi_lane = (int8)(0, -1, 0, -1, 0, -1, 0, 0);
    below &= node;
    above &= node;
    const long8 at_lo = convert_long8(lo_lane & (pos == lo));
    const long8 at_hi = convert_long8(hi_lane & (pos == hi));
    const ulong8 flat_below = below & ~above, flat_above = above & ~below;
    *below_out = select(select(below, node & ~flat_above, at_hi), flat_below, at_lo);
    *above_out = select(select(above, flat_above, at_hi), node & ~flat_below, at_lo);
    *valid = convert_long8((lo_lane | hi_lane) & (pos > lo) & (pos < hi)) | at_lo | at_hi;
}

/* The children (their triangle masks) of a node (triangles `mask`, box) split at candidate k of a
 * reference whose candidate lanes are pos and masks below and above (kd_candidate_children), and
 * the split plane's position. The one split of both small-stage shapes, so that their trees are
 * the same. */
KDRAY_INLINE float kd_split_at_candidate(float8 pos, ulong8 below, ulong8 above, ulong mask,
                                         KdBox box, uint k, ulong* below_child,
                                         ulong* above_child) {
    float candidate_pos[8];
    vstore8(pos, 0, candidate_pos);
    ulong children[2][8];
    float8 lo, hi;
    kd_box_lanes(box, &lo, &hi);
    long8 valid;
    kd_candidate_children((ulong8)(mask), below, above, pos, lo, hi, &below, &above, &valid);
    vstore8(below, 0, children[0]);
    vstore8(above, 0, children[1]);
    *below_child = children[0][k];
    *above_child = children[1][k];
    return candidate_pos[k];
}

/* The SAH split of one small node (§4.2): for every candidate of the node's triangles inside the
 * node's box, or on its faces as kd_candidate_children allows, SAH(x) = C_t + C_i (N_L SA_L +
 * N_R SA_R) / SA, the counts by popcount of the children's masks, scaled by (1 - empty_bonus)
 * when a side with some width is empty, as in the reference builder. The search returns the
 * cheapest candidate (KDRAY_CANDIDATE_STRIDE * reference + lane), or KDRAY_NO_CANDIDATE when
 * C_i N is no more than the best: the node becomes a leaf.
 *
 * Only the candidates of the node's own triangles (the set bits of its mask) are evaluated: the
 * SAH is piecewise linear between those boundaries, so its minimum lies on one of them. The six
 * candidates of a triangle are the lanes of one float8 (lane k = 2 * axis + side, as in
 * kd_compute_split_masks; lanes 6 and 7 unused): a scalar loop per candidate took 131 ms of CPU
 * per kitchen build (perf), this one 115 ms. The search is split in three (start, price each
 * reference, pick) because the references and their masks come from global memory for the small
 * root's table and from private memory for a re-clipped node's (KdClippedTable). */
#define KDRAY_NO_CANDIDATE 0xFFFFFFFFu

typedef struct KdSplitSearch {
    ulong8 node;
    float8 lo, hi, cross, ring;
    float cost_scale, cost_traversal, empty_bonus;
    /* Per lane, the first cheapest candidate so far and its cost. */
    float8 lane_cost;
    uint8 lane_candidate;
} KdSplitSearch;

KDRAY_INLINE void kd_start_split_search(KdSplitSearch* s, KdBox box, ulong mask,
                                        float cost_traversal, float cost_intersection,
                                        float empty_bonus) {
    /* Child area = 2 (cross + d * ring); the 2 and 1/area fold into one scale of the counts. */
    s->cost_scale = cost_intersection * 2.0f / kd_box_area(box);
    s->cost_traversal = cost_traversal;
    s->empty_bonus = empty_bonus;
    const float3 e = box.hi - box.lo;
    kd_box_lanes(box, &s->lo, &s->hi);
    s->cross = (float8)(e.y * e.z, e.y * e.z, e.z * e.x, e.z * e.x, e.x * e.y, e.x * e.y, 0, 0);
    s->ring = (float8)(e.y + e.z, e.y + e.z, e.z + e.x, e.z + e.x, e.x + e.y, e.x + e.y, 0, 0);
    s->node = (ulong8)(mask);
    /* A candidate must beat the leaf, C_i N; NO_CANDIDATE is the largest index. */
    s->lane_cost = (float8)(cost_intersection * (float)popcount(mask));
    s->lane_candidate = (uint8)(KDRAY_NO_CANDIDATE);
}

/* popcount of each lane. On CPU devices (KDRAY_SWAR_POPCOUNT, set by the host) by the
 * bit-parallel sum, the byte counts added by a multiply: PoCL's LLVM lowered popcount(ulong8) for
 * skylake-avx512, which has no vector popcount, to byte-table lookups a 128-bit quarter at a time,
 * about 60 instructions for the two counts of a search step (Kitchen build 67.9 -> 61.9 ms, the
 * median of 5 interleaved rounds of 7 builds). GPUs count bits in one instruction. */
KDRAY_INLINE ulong8 kd_popcount8(ulong8 x) {
#if KDRAY_SWAR_POPCOUNT
    x = x - ((x >> 1) & 0x5555555555555555ul);
    x = (x & 0x3333333333333333ul) + ((x >> 2) & 0x3333333333333333ul);
    x = (x + (x >> 4)) & 0x0F0F0F0F0F0F0F0Ful;
    return (x * 0x0101010101010101ul) >> 56;
#else
    return popcount(x);
#endif
}

/* The six candidates of one reference (at pos, numbered first_candidate + lane), given their
 * masks below and above. */
KDRAY_INLINE void kd_price_candidates(KdSplitSearch* s, float8 pos, ulong8 below, ulong8 above,
                                      uint first_candidate) {
    const uint8 lane_index = (uint8)(0, 1, 2, 3, 4, 5, 6, 7);
    long8 valid;
    kd_candidate_children(s->node, below, above, pos, s->lo, s->hi, &below, &above, &valid);
    const float8 n_below = convert_float8(kd_popcount8(below));
    const float8 n_above = convert_float8(kd_popcount8(above));
    float8 cost =
        s->cost_traversal + s->cost_scale * (n_below * (s->cross + (pos - s->lo) * s->ring) +
                                             n_above * (s->cross + (s->hi - pos) * s->ring));
    const int8 empty = ((n_below == 0.0f) & (pos > s->lo)) | ((n_above == 0.0f) & (pos < s->hi));
    cost = select(cost, cost * (1.0f - s->empty_bonus), empty);
    cost = select((float8)(INFINITY), cost, convert_int8(valid));
    /* Strictly cheaper replaces: the lane keeps its first cheapest. */
    const int8 better = cost < s->lane_cost;
    s->lane_cost = select(s->lane_cost, cost, better);
    s->lane_candidate =
        select(s->lane_candidate, (uint8)(first_candidate) + lane_index, as_uint8(better));
}

/* The cheapest cost found (C_i N, the leaf's, when no candidate beat it): the cost of
 * kd_cheapest_candidate's pick, which the per-level stage's work-groups reduce
 * (build_small_level.cl). */
KDRAY_INLINE float kd_cheapest_cost(const KdSplitSearch* s) {
    const float4 cost4 = fmin(s->lane_cost.lo, s->lane_cost.hi);
    const float2 cost2 = fmin(cost4.lo, cost4.hi);
    return fmin(cost2.lo, cost2.hi);
}

/* The first cheapest candidate of all, in candidate order (reference, then lane), as one loop
 * over every candidate would pick: the least cost, then the least index among the lanes at that
 * cost, by two horizontal minimums (comparing candidate by candidate made a chain of dependent
 * selects through one best cost, half of the search's time; a scalar loop over the lanes
 * branched on every lane, 13%). Lanes 6 and 7, and lanes that found nothing cheaper than the
 * leaf, hold the leaf's cost and NO_CANDIDATE, so they change neither. */
KDRAY_INLINE uint kd_cheapest_candidate(const KdSplitSearch* s) {
    const float best_cost = kd_cheapest_cost(s);
    const uint8 at_best =
        select((uint8)(KDRAY_NO_CANDIDATE), s->lane_candidate, as_uint8(s->lane_cost == best_cost));
    const uint4 index4 = min(at_best.lo, at_best.hi);
    const uint2 index2 = min(index4.lo, index4.hi);
    return min(index2.lo, index2.hi);
}

/* The split of a node whose mask is over the small root's references (start..), by their masks
 * in root_masks. */
KDRAY_INLINE uint kd_best_small_split(KdBox box, ulong mask, uint start,
                                      __global const float* ref_box,
                                      __global const ulong* root_masks, float cost_traversal,
                                      float cost_intersection, float empty_bonus) {
    KdSplitSearch s;
    kd_start_split_search(&s, box, mask, cost_traversal, cost_intersection, empty_bonus);
    for (ulong rest = mask; rest != 0; rest &= rest - 1) {
        const uint j = kd_lowest_bit(rest), ref = start + j;
        kd_price_candidates(&s, kd_candidate_lanes(ref_box + (size_t)ref * KDRAY_BOX_FLOATS),
                            vload8(0, root_masks + (size_t)j * KDRAY_MASK_WORDS_PER_REF),
                            vload8(1, root_masks + (size_t)j * KDRAY_MASK_WORDS_PER_REF),
                            ref * KDRAY_CANDIDATE_STRIDE);
    }
    return kd_cheapest_candidate(&s);
}

#endif /* KDRAY_BUILD_SMALL_SEARCH_CL */
