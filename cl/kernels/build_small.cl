/* build_small.cl — the small-node stage of Zhou et al. (2008), §4.2: every small root (a node of
 * at most T <= 64 triangles) is split by the full surface area heuristic, with the triangle sets
 * of a node and of each split candidate held as 64-bit masks over the root's triangle list.
 *
 *   kd_compute_split_masks     preprocessing: per candidate plane, the masks of the root's
 *                              triangles below and above it
 *   kd_build_small_subtrees    per small root: its whole subtree, depth first, in preorder
 *
 * The paper splits the small nodes of one level at a time, with a launch per level. Here one
 * work-item builds a root's whole subtree in one launch: the root's masks (at most 64 references
 * of 128 bytes) stay in its cache across the subtree's levels instead of being read again by a new
 * launch per level, and the ~20 launches, scans and read-backs of the levels are gone. The trees
 * are the same: each node gets the same SAH decision from the same inputs. One departure from the
 * paper: a node of at most KDRAY_RECLIP_REFS triangles re-clips them to its box and prices its
 * subtree with masks of its own (re-clipping, below).
 *
 * Candidates are the boundaries of the root's (clipped) triangle boxes, or of a re-clipped node's
 * (KdClippedTable): candidate 6*ref + 2*axis
 * + side lies at the box's lo (side 0) or hi (side 1) on that axis. side_masks holds 16 masks per
 * reference, [16 ref + k] the triangles below its candidate k and [16 ref + 8 + k] those above
 * (k < 6; two lanes of padding each), so that the kernels read a reference's masks as two ulong8.
 *
 * Both kernels run over one batch of small roots at a time: roots root_begin.., whose references
 * are ref_begin.. (contiguous, as the large stage lays them out). side_masks and the node records
 * hold the batch's alone, indexed from those starts, so that neither need outgrow the device's
 * largest allocation (a scene of ten million triangles wants 4 GB of masks).
 *
 * Triangles lying in a candidate plane go to the cheaper side, as in the reference builder (Wald &
 * Havran 2006, "p_side"): a triangle that is flat on an axis has its lo and hi candidates at the
 * same plane, so the two lanes carry the two choices, lo with the plane's flat triangles below
 * and hi with them above, and the SAH search prices both without a lane more. The same two lanes
 * let a node cut its flat triangles off at its own face (a flat child, e.g. a wall): the lo lane
 * at the node's lo face, the hi lane at its hi face. Planar triangles below only cost the BART
 * Robots 13% of SAH (reference builder forced to that choice: 553.8 -> 623.8). */
#include "cl/kernels/build_common.cl"

/* The six split candidates of a reference's box (6 floats, lo.xyz hi.xyz) in the lanes of one
 * float8: lane k = 2 * axis + side is the box's lo (side 0) or hi (side 1) on that axis; lanes 6
 * and 7 are 0. */
inline float8 kd_candidate_lanes(__global const float* b) {
    return (float8)(b[0], b[3], b[1], b[4], b[2], b[5], 0.0f, 0.0f);
}

/* A box's bounds beside those lanes: *lo and *hi hold, in lane 2 * axis + side, its lo and hi on
 * that axis (lanes 6 and 7: 0). */
inline void kd_box_lanes(KdBox box, float8* lo, float8* hi) {
    *lo = (float8)(box.lo.x, box.lo.x, box.lo.y, box.lo.y, box.lo.z, box.lo.z, 0.0f, 0.0f);
    *hi = (float8)(box.hi.x, box.hi.x, box.hi.y, box.hi.y, box.hi.z, box.hi.z, 0.0f, 0.0f);
}

/* The lanes (of a reference's six candidates, lane 2 * axis + side at pos) whose planar triangles
 * go above: the hi lanes of the axes on which the reference is flat (lo and hi at one plane). */
inline int8 kd_planar_above_lanes(float8 pos) {
    const int8 odd = (int8)(0, -1, 0, -1, 0, -1, 0, 0);
    return odd & (pos == pos.s00224466);
}

/* The sides of one candidate plane per lane (at pos) that a box (lo, hi lanes) lies on, -1 where
 * true; planar_above: the lanes whose planar triangles go above (kd_compute_split_masks). */
inline void kd_candidate_sides(float8 pos, int8 planar_above, float8 lo, float8 hi, int8* below,
                               int8* above) {
    const int8 crosses_up = hi > pos;
    *above = crosses_up | (planar_above & (lo >= pos));
    *below = (lo < pos) | (~planar_above & ~crosses_up);
}

/* Split candidates (§4.2, "small node preprocessing"): for each candidate plane the set of the
 * root's triangles below it and the set above it, by the same rule as every split (kd_classify
 * with the planar side below: below when lo < plane or when not hi > plane, above when
 * hi > plane), except in the hi lane of an axis on which the reference is flat, where triangles
 * lying in the plane go above (below when lo < plane, above when hi > plane or lo >= plane).
 * One work-item per reference computes its six candidates together in the lanes of
 * one float8 (two lanes unused), so each box of the root is loaded once for six planes; the
 * work-items of one root run the same loop, which keeps GPU lanes converged. Per plane, one
 * scalar loop over the root took 86 ms of CPU per kitchen build (perf); this one 24 ms. */
__kernel void kd_compute_split_masks(uint ref_begin, uint refs, __global const float* ref_box,
                                     __global const uint* ref_root,
                                     __global const uint* root_ref_start,
                                     __global const uint* root_ref_count,
                                     __global ulong* side_masks) {
    if (get_global_id(0) >= refs) return;
    const uint ref = ref_begin + (uint)get_global_id(0);
    const float8 pos = kd_candidate_lanes(ref_box + (size_t)ref * 6);
    const int8 planar_above = kd_planar_above_lanes(pos);
    const uint root = ref_root[ref];
    const uint start = root_ref_start[root], count = root_ref_count[root];
    /* The masks' low and high 32 bits, each in 32-bit lanes (half the vector width of 64-bit
     * lanes), in registers: one loop per half. */
    uint8 below_half[2], above_half[2];
    for (uint part = 0; part < 2; ++part) {
        uint8 below_bits = (uint8)(0), above_bits = (uint8)(0);
        const uint end = min(count, 32u * (part + 1));
        for (uint j = 32u * part; j < end; ++j) {
            float8 lo, hi;
            kd_box_lanes(kd_load_box(ref_box, start + j), &lo, &hi);
            int8 is_below, is_above;
            kd_candidate_sides(pos, planar_above, lo, hi, &is_below, &is_above);
            const uint bit = 1u << (j & 31u);
            below_bits |= as_uint8(is_below) & bit;
            above_bits |= as_uint8(is_above) & bit;
        }
        below_half[part] = below_bits;
        above_half[part] = above_bits;
    }
    const ulong8 below = convert_ulong8(below_half[0]) | (convert_ulong8(below_half[1]) << 32);
    const ulong8 above = convert_ulong8(above_half[0]) | (convert_ulong8(above_half[1]) << 32);
    vstore8(below, 0, side_masks + (size_t)(ref - ref_begin) * 16);
    vstore8(above, 1, side_masks + (size_t)(ref - ref_begin) * 16);
}

/* The children of a node (its triangles `node`) for the six candidates of one reference, at pos
 * (lanes as in kd_compute_split_masks), given the candidates' masks: inside the node's box (lo,
 * hi per lane) the masks themselves; at the node's lo face, the lo lanes make a flat child below
 * of the triangles lying in the face (below and not above) and leave the rest above; at its hi
 * face, the hi lanes make a flat child above of those lying there (above and not below). The
 * masks are over boxes clipped to the small root (or to a re-clipping ancestor), not to the node,
 * so on a face they would also count the triangles that only extend past it. Lanes that split
 * nothing (other candidates on a face, lanes 6 and 7) get no child at all: *valid is 0 there. */
inline void kd_candidate_children(ulong8 node, ulong8 below, ulong8 above, float8 pos, float8 lo,
                                  float8 hi, ulong8* below_out, ulong8* above_out, long8* valid) {
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

/* The SAH split of one small node (§4.2): for every candidate of the node's triangles inside the
 * node's box, or on its faces as kd_candidate_children allows, SAH(x) = C_t + C_i (N_L SA_L +
 * N_R SA_R) / SA, the counts by popcount of the children's masks, scaled by (1 - empty_bonus)
 * when a side with some width is empty, as in the reference builder. The search returns the
 * cheapest candidate (6 * reference + lane), or KDRAY_NO_CANDIDATE when C_i N is no more than
 * the best: the node becomes a leaf.
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

inline void kd_start_split_search(KdSplitSearch* s, KdBox box, ulong mask, float cost_traversal,
                                  float cost_intersection, float empty_bonus) {
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
inline ulong8 kd_popcount8(ulong8 x) {
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
inline void kd_price_candidates(KdSplitSearch* s, float8 pos, ulong8 below, ulong8 above,
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

/* The first cheapest candidate of all, in candidate order (reference, then lane), as one loop
 * over every candidate would pick: the least cost, then the least index among the lanes at that
 * cost, by two horizontal minimums (comparing candidate by candidate made a chain of dependent
 * selects through one best cost, half of the search's time; a scalar loop over the lanes
 * branched on every lane, 13%). Lanes 6 and 7, and lanes that found nothing cheaper than the
 * leaf, hold the leaf's cost and NO_CANDIDATE, so they change neither. */
inline uint kd_cheapest_candidate(const KdSplitSearch* s) {
    const float4 cost4 = fmin(s->lane_cost.lo, s->lane_cost.hi);
    const float2 cost2 = fmin(cost4.lo, cost4.hi);
    const float best_cost = fmin(cost2.lo, cost2.hi);
    const uint8 at_best =
        select((uint8)(KDRAY_NO_CANDIDATE), s->lane_candidate, as_uint8(s->lane_cost == best_cost));
    const uint4 index4 = min(at_best.lo, at_best.hi);
    const uint2 index2 = min(index4.lo, index4.hi);
    return min(index2.lo, index2.hi);
}

/* The lowest set bit's index. */
inline uint kd_lowest_bit(ulong bits) {
    return (uint)popcount((bits & (0ul - bits)) - 1ul);
}

/* The split of a node whose mask is over the small root's references (start..), by their masks
 * in root_masks. */
inline uint kd_best_small_split(KdBox box, ulong mask, uint start, __global const float* ref_box,
                                __global const ulong* root_masks, float cost_traversal,
                                float cost_intersection, float empty_bonus) {
    KdSplitSearch s;
    kd_start_split_search(&s, box, mask, cost_traversal, cost_intersection, empty_bonus);
    for (ulong rest = mask; rest != 0; rest &= rest - 1) {
        const uint j = kd_lowest_bit(rest), ref = start + j;
        kd_price_candidates(&s, kd_candidate_lanes(ref_box + (size_t)ref * 6),
                            vload8(0, root_masks + (size_t)j * 16),
                            vload8(1, root_masks + (size_t)j * 16), ref * 6);
    }
    return kd_cheapest_candidate(&s);
}

/* Whether the plane of triangle tri (9 floats) misses the box: its corners all lie on one side
 * of it (the normal's test of Akenine-Moller's triangle-box overlap), by more than the rounding
 * of the normal, which a sliver or a collapsed triangle makes as large as the normal itself. */
inline int kd_plane_misses_box(__global const float* tri, KdBox box) {
    const float3 a = (float3)(tri[0], tri[1], tri[2]);
    const float3 e1 = (float3)(tri[3], tri[4], tri[5]) - a;
    const float3 e2 = (float3)(tri[6], tri[7], tri[8]) - a;
    const float3 n = cross(e1, e2);
    const float3 centre = 0.5f * (box.lo + box.hi), half_extent = 0.5f * (box.hi - box.lo);
    const float3 to_centre = centre - a;
    const float distance = dot(n, to_centre), radius = dot(fabs(n), half_extent);
    /* The normal is off by a few ulps of |e1| |e2| per component; the distances by that times
     * the lever arm. */
    const float reach = fabs(to_centre.x) + fabs(to_centre.y) + fabs(to_centre.z) + half_extent.x +
                        half_extent.y + half_extent.z;
    const float slack = 1e-5f * (fabs(distance) + radius) + 1e-4f * length(e1) * length(e2) * reach;
    return fabs(distance) > radius + slack;
}

/* The masks carry boxes clipped to the small root (or to a re-clipping ancestor), not to the node,
 * so a triangle whose box straddles a split may still miss one child inside this node (a long
 * diagonal triangle past the corner of a deep node). A straddling triangle whose plane misses a
 * child's box leaves that child. */
inline void kd_drop_missed_triangles(ulong* below, ulong* above, KdBox box, uint axis, float split,
                                     uint start, const uchar* table_ref,
                                     __global const uint* ref_tri,
                                     __global const float* triangles) {
    for (ulong rest = *below & *above; rest != 0; rest &= rest - 1) {
        const ulong bit = rest & (0ul - rest);
        const uint j = kd_lowest_bit(rest);
        const uint ref = start + (table_ref ? table_ref[j] : j);
        __global const float* tri = triangles + (size_t)ref_tri[ref] * KDRAY_FLOATS_PER_TRIANGLE;
        const int miss_below = kd_plane_misses_box(tri, kd_child_box(box, axis, split, 0));
        const int miss_above = kd_plane_misses_box(tri, kd_child_box(box, axis, split, 1));
        if (miss_above && !miss_below) *above &= ~bit;
        if (miss_below && !miss_above) *below &= ~bit;
    }
}

/* Re-clipping (not in Zhou et al.): the masks hold the small root's boxes, which no split inside
 * its subtree clips, so a long diagonal triangle that a few splits have cut keeps the root's box:
 * the SAH counts it on both sides of planes it does not reach inside the node, and its own
 * candidates are not its bounds there. A node of at most KDRAY_RECLIP_REFS references of which
 * some extend past its box gets a table of its own: those references' triangles clipped to the
 * node's box (the large stage's clipping), the candidates and masks of them over the node's
 * references alone, in private memory; its subtree is split with that table. Only the first such
 * node on a path does this (its descendants use its table), so one table per work-item is live:
 * the walk is depth first, and the nodes pending on the stack above a clipped node are all its
 * descendants. */
#define KDRAY_RECLIP_REFS 32u

typedef struct KdClippedTable {
    float candidates[KDRAY_RECLIP_REFS * 8]; /* per reference: its clipped box's candidate lanes */
    uint masks[KDRAY_RECLIP_REFS * 16]; /* per reference: 8 lanes below, 8 above (side_masks) */
    uchar ref[KDRAY_RECLIP_REFS];       /* its index in the small root's list */
} KdClippedTable;

/* The table of the node (box, its references `mask` over the small root's list from start), or 0
 * when none of them extends past the box (clipping changes nothing). *mask becomes the node's
 * references over the table; a triangle that misses the box leaves the node. */
inline int kd_clip_node_table(KdBox box, ulong* mask, uint start, __global const float* ref_box,
                              __global const uint* ref_tri, __global const float* triangles,
                              KdClippedTable* t) {
    int any_cut = 0;
    for (ulong rest = *mask; rest != 0 && !any_cut; rest &= rest - 1) {
        const KdBox b = kd_load_box(ref_box, start + kd_lowest_bit(rest));
        any_cut = any(b.lo < box.lo) || any(b.hi > box.hi);
    }
    if (!any_cut) return 0;
    uint n = 0;
    for (ulong rest = *mask; rest != 0; rest &= rest - 1) {
        const uint j = kd_lowest_bit(rest);
        KdBox b = kd_load_box(ref_box, start + j);
        if (any(b.lo < box.lo) || any(b.hi > box.hi)) {
            b.lo = fmax(b.lo, box.lo);
            b.hi = fmax(fmin(b.hi, box.hi), b.lo);
            KdBox clipped;
            __global const float* tri =
                triangles + (size_t)ref_tri[start + j] * KDRAY_FLOATS_PER_TRIANGLE;
            if (!kd_clip_triangle_bounds(tri, box, &clipped)) continue;
            b.lo = fmin(fmax(b.lo, clipped.lo), b.hi);
            b.hi = fmax(fmin(b.hi, clipped.hi), b.lo);
        }
        t->ref[n] = (uchar)j;
        vstore8((float8)(b.lo.x, b.hi.x, b.lo.y, b.hi.y, b.lo.z, b.hi.z, 0.0f, 0.0f), n,
                t->candidates);
        ++n;
    }
    for (uint l = 0; l < n; ++l) {
        const float8 pos = vload8(l, t->candidates);
        const int8 planar_above = kd_planar_above_lanes(pos);
        uint8 below_bits = (uint8)(0), above_bits = (uint8)(0);
        for (uint m = 0; m < n; ++m) {
            const float8 other = vload8(m, t->candidates);
            int8 is_below, is_above;
            kd_candidate_sides(pos, planar_above, other.s00224466, other.s11335577, &is_below,
                               &is_above);
            below_bits |= as_uint8(is_below) & (1u << m);
            above_bits |= as_uint8(is_above) & (1u << m);
        }
        vstore8(below_bits, 0, t->masks + l * 16);
        vstore8(above_bits, 1, t->masks + l * 16);
    }
    *mask = (1ul << n) - 1ul;
    return 1;
}

/* kd_best_small_split over a clipped table. */
inline uint kd_best_clipped_split(KdBox box, ulong mask, const KdClippedTable* t,
                                  float cost_traversal, float cost_intersection,
                                  float empty_bonus) {
    KdSplitSearch s;
    kd_start_split_search(&s, box, mask, cost_traversal, cost_intersection, empty_bonus);
    for (ulong rest = mask; rest != 0; rest &= rest - 1) {
        const uint l = kd_lowest_bit(rest);
        kd_price_candidates(&s, vload8(l, t->candidates),
                            convert_ulong8(vload8(0, t->masks + l * 16)),
                            convert_ulong8(vload8(1, t->masks + l * 16)), l * 6);
    }
    return kd_cheapest_candidate(&s);
}

/* A mask over a clipped table as a mask over the small root's references. */
inline ulong kd_root_mask(const KdClippedTable* t, ulong mask) {
    ulong root = 0;
    for (ulong rest = mask; rest != 0; rest &= rest - 1) root |= 1ul << t->ref[kd_lowest_bit(rest)];
    return root;
}

/* A node waiting on the subtree builder's stack: the above child of the split node `parent`. */
typedef struct KdPendingNode {
    KdBox box;
    ulong mask;
    uint depth;
    uint parent;
    uint parent_axis;
    uint on_table; /* its mask is over the work-item's KdClippedTable, not the small root's list */
} KdPendingNode;

/* Small-node stage (§4.2), one work-item per small root: split the root's subtree depth first,
 * writing its nodes in preorder (below child right after its parent, above child after the below
 * subtree, as the output layout wants) to the root's run of subtree_nodes (the record layout is
 * in build_common.cl; leaf offsets count from the subtree's first leaf reference). A node becomes
 * a leaf when no split beats C_i N, at the depth limit, or when its box has no area.
 *
 * The first pass gives a root of count references first_scale * (count + 1) records, from
 * first_scale * (the batch's references and roots before it) on. Outputs per root: its node and
 * leaf reference counts; a subtree that outgrows its run is still counted, only not written.
 * totals (zeroed by the host): [0] the stage's node count, [1] the smallest scale that holds
 * every subtree, [2] the most levels of one subtree. The second pass (second_pass != 0) builds
 * again only the subtrees that outgrew the first, each into exactly its counted records from
 * second_offset[root - root_begin] on (kd_second_pass_records). */
__kernel void kd_build_small_subtrees(
    uint root_begin, uint roots, uint ref_begin, __global const float* root_box,
    __global const uint* root_depth, __global const uint* root_ref_start,
    __global const uint* root_ref_count, __global const float* ref_box,
    __global const ulong* side_masks, __global const uint* ref_tri, __global const float* triangles,
    float cost_traversal, float cost_intersection, float empty_bonus, uint max_depth,
    uint first_scale, uint second_pass, __global const uint* second_offset,
    __global uint4* subtree_nodes, __global uint* subtree_node_count,
    __global uint* subtree_leaf_refs, __global uint* totals) {
    if (get_global_id(0) >= roots) return;
    const uint q = root_begin + (uint)get_global_id(0);
    const uint start = root_ref_start[q], count = root_ref_count[q];
    const uint first_budget = first_scale * (count + 1);
    if (second_pass && subtree_node_count[q] <= first_budget) return;
    const uint budget = second_pass ? subtree_node_count[q] : first_budget;
    __global uint4* out =
        second_pass
            ? subtree_nodes + second_offset[q - root_begin]
            : subtree_nodes + (size_t)first_scale * ((start - ref_begin) + (q - root_begin));
    __global const ulong* root_masks = side_masks + (size_t)(start - ref_begin) * 16;
    KdPendingNode stack[KDRAY_MAX_DEPTH];
    uint top = 0;
    KdPendingNode node;
    node.box = kd_load_box(root_box, q);
    node.mask = count >= 64 ? ~0ul : ((1ul << count) - 1ul);
    node.depth = root_depth[q];
    node.parent = KDRAY_NO_CANDIDATE;
    node.on_table = 0;
    KdClippedTable table;
    uint written = 0, leaf_refs = 0, deepest = node.depth;
    for (;;) {
        /* The next node in preorder; an above child completes its parent's record. */
        const uint at = written++;
        deepest = max(deepest, node.depth);
        if (node.parent != KDRAY_NO_CANDIDATE && node.parent < budget)
            out[node.parent].x = node.parent_axis | (at << 2);
        uint best = KDRAY_NO_CANDIDATE;
        if (node.mask != 0 && node.depth < max_depth && kd_box_area(node.box) > 0.0f) {
            if (!node.on_table && popcount(node.mask) <= KDRAY_RECLIP_REFS)
                node.on_table = kd_clip_node_table(node.box, &node.mask, start, ref_box, ref_tri,
                                                   triangles, &table);
            if (node.on_table)
                best = kd_best_clipped_split(node.box, node.mask, &table, cost_traversal,
                                             cost_intersection, empty_bonus);
            else
                best = kd_best_small_split(node.box, node.mask, start, ref_box, root_masks,
                                           cost_traversal, cost_intersection, empty_bonus);
        }
        if (best == KDRAY_NO_CANDIDATE) {
            /* Leaf: its triangles are the mask's, its references the next in preorder. */
            const ulong leaf_mask = node.on_table ? kd_root_mask(&table, node.mask) : node.mask;
            const uint n = popcount(leaf_mask);
            if (at < budget)
                out[at] = (uint4)(KDRAY_LEAF_AXIS | (leaf_refs << 2), n, (uint)leaf_mask,
                                  (uint)(leaf_mask >> 32));
            leaf_refs += n;
            if (top == 0) break;
            node = stack[--top];
            continue;
        }
        /* Inner node: go on with the below child, keep the above child for later. */
        const uint ref = best / 6, k = best % 6, axis = k / 2;
        float8 pos;
        ulong8 below, above;
        const uchar* table_ref = 0;
        if (node.on_table) {
            pos = vload8(ref, table.candidates);
            below = convert_ulong8(vload8(0, table.masks + ref * 16));
            above = convert_ulong8(vload8(1, table.masks + ref * 16));
            table_ref = table.ref;
        } else {
            __global const ulong* masks = root_masks + (size_t)(ref - start) * 16;
            pos = kd_candidate_lanes(ref_box + (size_t)ref * 6);
            below = vload8(0, masks);
            above = vload8(1, masks);
        }
        float candidate_pos[8];
        vstore8(pos, 0, candidate_pos);
        const float split = candidate_pos[k];
        ulong children[2][8];
        {
            float8 lo, hi;
            kd_box_lanes(node.box, &lo, &hi);
            long8 valid;
            kd_candidate_children((ulong8)(node.mask), below, above, pos, lo, hi, &below, &above,
                                  &valid);
            vstore8(below, 0, children[0]);
            vstore8(above, 0, children[1]);
        }
        kd_drop_missed_triangles(&children[0][k], &children[1][k], node.box, axis, split, start,
                                 table_ref, ref_tri, triangles);
        if (at < budget) out[at] = (uint4)(axis, as_uint(split), 0, 0);
        KdPendingNode pending;
        pending.box = kd_child_box(node.box, axis, split, 1);
        pending.mask = children[1][k];
        pending.depth = node.depth + 1;
        pending.parent = at;
        pending.parent_axis = axis;
        pending.on_table = node.on_table;
        stack[top++] = pending;
        node.box = kd_child_box(node.box, axis, split, 0);
        node.mask = children[0][k];
        node.depth += 1;
        node.parent = KDRAY_NO_CANDIDATE;
    }
    subtree_node_count[q] = written;
    subtree_leaf_refs[q] = leaf_refs;
    atomic_add(&totals[0], written);
    atomic_max(&totals[1], (written + count) / (count + 1));
    atomic_max(&totals[2], deepest - root_depth[q] + 1);
}

/* The second pass's records of a batch's roots (roots root_begin..): records[g] the node count of
 * root root_begin + g when its subtree outgrew the first pass's first_scale * (count + 1), else
 * 0; their exclusive scan places each subtree (kd_build_small_subtrees). */
__kernel void kd_second_pass_records(uint root_begin, uint roots, uint first_scale,
                                     __global const uint* root_ref_count,
                                     __global const uint* subtree_node_count,
                                     __global uint* records) {
    const uint g = get_global_id(0);
    if (g >= roots) return;
    const uint q = root_begin + g, nodes = subtree_node_count[q];
    records[g] = nodes > first_scale * (root_ref_count[q] + 1) ? nodes : 0u;
}
