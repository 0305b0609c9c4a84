/* build_small.cl — the small-node stage of Zhou et al. (2008), §4.2: every small root (a node of
 * at most T <= 64 triangles) is split by the full surface area heuristic, with the triangle sets
 * of a node and of each split candidate held as 64-bit masks over the root's triangle list.
 *
 *   kd_compute_split_masks   preprocessing: per candidate plane, the masks of the root's triangles
 *                            below and above it
 *   kd_split_small_nodes     per small node of a level: the cheapest candidate, or a leaf
 *   kd_emit_small_children   node records and the next level's small nodes
 *
 * Candidates are the boundaries of the root's (clipped) triangle boxes: candidate 6*ref + 2*axis
 * + side lies at the box's lo (side 0) or hi (side 1) on that axis. side_masks holds 16 masks per
 * reference, [16 ref + k] the triangles below its candidate k and [16 ref + 8 + k] those above
 * (k < 6; two lanes of padding each), so that the kernels read a reference's masks as two ulong8. */
#include "cl/kernels/build_common.cl"

/* Split candidates (§4.2, "small node preprocessing"): for each candidate plane the set of the
 * root's triangles below it and the set above it, by the same rule as every split (kd_classify
 * with the planar side below: below when lo < plane or when not hi > plane, above when
 * hi > plane). One work-item per reference computes its six candidates together in the lanes of
 * one float8 (two lanes unused), so each box of the root is loaded once for six planes; the
 * work-items of one root run the same loop, which keeps GPU lanes converged. Per plane, one
 * scalar loop over the root took 86 ms of CPU per kitchen build (perf); this one 24 ms. */
__kernel void kd_compute_split_masks(uint refs, __global const float* ref_box,
                                     __global const uint* ref_root,
                                     __global const uint* root_ref_start,
                                     __global const uint* root_ref_count,
                                     __global ulong* side_masks) {
    const uint ref = get_global_id(0);
    if (ref >= refs) return;
    __global const float* own = ref_box + (size_t)ref * 6;
    /* Lane k = 2 * axis + side: candidate k, at lo (side 0) or hi (side 1) on the axis. */
    const float8 pos = (float8)(own[0], own[3], own[1], own[4], own[2], own[5], 0.0f, 0.0f);
    const uint root = ref_root[ref];
    const uint start = root_ref_start[root], count = root_ref_count[root];
    ulong8 below = (ulong8)(0), above = (ulong8)(0);
    for (uint j = 0; j < count; ++j) {
        __global const float* b = ref_box + (size_t)(start + j) * 6;
        const float8 lo = (float8)(b[0], b[0], b[1], b[1], b[2], b[2], 0.0f, 0.0f);
        const float8 hi = (float8)(b[3], b[3], b[4], b[4], b[5], b[5], 0.0f, 0.0f);
        const int8 is_above = hi > pos; /* -1 where true */
        const int8 is_below = (lo < pos) | ~is_above;
        below |= convert_ulong8(is_below & 1) << (ulong)j;
        above |= convert_ulong8(is_above & 1) << (ulong)j;
    }
    vstore8(below, 0, side_masks + (size_t)ref * 16);
    vstore8(above, 1, side_masks + (size_t)ref * 16);
}

/* SAH split of small nodes (§4.2): for every candidate of the node's triangles that lies strictly
 * inside the node's box, SAH(x) = C_t + C_i (N_L SA_L + N_R SA_R) / SA, the counts by popcount of
 * the node's mask and the candidate's masks, scaled by (1 - empty_bonus) when a side is empty as
 * in the reference builder. The node becomes a leaf when C_i N is no more than the best, at the
 * depth limit, or when its box has no area. split_flag (0/1) is scanned into child positions.
 *
 * Only the candidates of the node's own triangles (the set bits of its mask) are evaluated: the
 * SAH is piecewise linear between those boundaries, so its minimum lies on one of them. */
__kernel void kd_split_small_nodes(uint nodes, __global const float* node_box,
                                   __global const ulong* node_mask,
                                   __global const uint* node_root, __global const uint* node_depth,
                                   __global const float* ref_box,
                                   __global const uint* root_ref_start,
                                   __global const ulong* side_masks, float cost_traversal,
                                   float cost_intersection, float empty_bonus, uint max_depth,
                                   __global uint* split_axis, __global float* split_pos,
                                   __global ulong* child_mask, __global uint* split_flag) {
    const uint i = get_global_id(0);
    if (i >= nodes) return;
    const ulong mask = node_mask[i];
    const uint n = popcount(mask);
    const KdBox box = kd_load_box(node_box, i);
    const float area = kd_box_area(box);
    split_flag[i] = 0;
    split_axis[i] = KDRAY_LEAF_AXIS;
    if (n == 0 || node_depth[i] >= max_depth || !(area > 0.0f)) return;

    /* Child area = 2 (cross + d * ring); the 2 and 1/area fold into one scale of the counts.
     * The six candidates of a triangle are the lanes of one float8 (lane k = 2 * axis + side, as
     * in kd_compute_split_masks; lanes 6 and 7 unused): a scalar loop per candidate took 131 ms
     * of CPU per kitchen build (perf), this one 115 ms. */
    const float cost_scale = cost_intersection * 2.0f / area;
    const float3 e = box.hi - box.lo;
    const float8 lo = (float8)(box.lo.x, box.lo.x, box.lo.y, box.lo.y, box.lo.z, box.lo.z, 0, 0);
    const float8 hi = (float8)(box.hi.x, box.hi.x, box.hi.y, box.hi.y, box.hi.z, box.hi.z, 0, 0);
    const float8 cross =
        (float8)(e.y * e.z, e.y * e.z, e.z * e.x, e.z * e.x, e.x * e.y, e.x * e.y, 0, 0);
    const float8 ring = (float8)(e.y + e.z, e.y + e.z, e.z + e.x, e.z + e.x, e.x + e.y, e.x + e.y,
                                 0, 0);
    const ulong8 node = (ulong8)(mask);
    const uint start = root_ref_start[node_root[i]];
    float best_cost = cost_intersection * (float)n;
    uint best_candidate = 0xFFFFFFFFu;
    for (ulong rest = mask; rest != 0; rest &= rest - 1) {
        const uint ref = start + (uint)popcount((rest & (0ul - rest)) - 1ul); /* lowest set bit */
        __global const float* b = ref_box + (size_t)ref * 6;
        const float8 pos = (float8)(b[0], b[3], b[1], b[4], b[2], b[5], 0, 0);
        const ulong8 below = node & vload8(0, side_masks + (size_t)ref * 16);
        const ulong8 above = node & vload8(1, side_masks + (size_t)ref * 16);
        const float8 n_below = convert_float8(popcount(below));
        const float8 n_above = convert_float8(popcount(above));
        float8 cost = cost_traversal + cost_scale * (n_below * (cross + (pos - lo) * ring) +
                                                     n_above * (cross + (hi - pos) * ring));
        cost = select(cost, cost * (1.0f - empty_bonus), convert_int8((below == 0) | (above == 0)));
        /* Only planes strictly inside the node split it (lanes 6 and 7: 0 < 0 is false). */
        cost = select((float8)(INFINITY), cost, convert_int8((pos > lo) & (pos < hi)));
        /* The first cheapest candidate wins, in candidate order, as a scalar loop would pick. */
        const float lane[6] = {cost.s0, cost.s1, cost.s2, cost.s3, cost.s4, cost.s5};
        for (uint k = 0; k < 6; ++k) {
            const int better = lane[k] < best_cost;
            best_cost = better ? lane[k] : best_cost;
            best_candidate = better ? ref * 6 + k : best_candidate;
        }
    }
    if (best_candidate == 0xFFFFFFFFu) return;
    const uint ref = best_candidate / 6, k = best_candidate % 6;
    split_flag[i] = 1;
    split_axis[i] = k / 2;
    split_pos[i] = ref_box[(size_t)ref * 6 + (k % 2) * 3 + k / 2];
    child_mask[2 * i] = mask & side_masks[(size_t)ref * 16 + k];
    child_mask[2 * i + 1] = mask & side_masks[(size_t)ref * 16 + 8 + k];
}

/* Node records of a small level and its children, the next level's nodes: split node i's
 * children are next-level nodes 2*rank(i) and 2*rank(i)+1 and get node ids from node_base. */
__kernel void kd_emit_small_children(uint nodes, __global const float* node_box,
                                     __global const ulong* node_mask,
                                     __global const uint* node_root,
                                     __global const uint* node_depth,
                                     __global const uint* node_id, __global const uint* split_axis,
                                     __global const float* split_pos,
                                     __global const ulong* child_mask,
                                     __global const uint* split_rank, uint node_base,
                                     __global KdBuildNode* records, __global float* next_box,
                                     __global ulong* next_mask, __global uint* next_root,
                                     __global uint* next_depth, __global uint* next_node_id) {
    const uint i = get_global_id(0);
    if (i >= nodes) return;
    const ulong mask = node_mask[i];
    const uint axis = split_axis[i];
    if (axis == KDRAY_LEAF_AXIS) {
        records[node_id[i]] = kd_build_leaf(popcount(mask), node_root[i], mask);
        return;
    }
    const KdBox box = kd_load_box(node_box, i);
    const float split = split_pos[i];
    const uint first = 2 * split_rank[i];
    for (uint side = 0; side < 2; ++side) {
        const uint j = first + side;
        kd_store_box(next_box, j, kd_child_box(box, axis, split, side));
        next_mask[j] = child_mask[2 * i + side];
        next_root[j] = node_root[i];
        next_depth[j] = node_depth[i] + 1;
        next_node_id[j] = node_base + j;
    }
    records[node_id[i]] = kd_build_inner(axis, split, node_base + first, node_base + first + 1);
}
