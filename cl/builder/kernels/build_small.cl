/* build_small.cl — the small-node stage of Zhou et al. (2008), §4.2: every small root (a node of
 * at most T <= 64 triangles) is split by the full surface area heuristic, with the triangle sets
 * of a node and of each split candidate held as 64-bit masks over the root's triangle list.
 *
 *   kd_compute_split_masks     preprocessing: per candidate plane, the masks of the root's
 *                              triangles below and above it (and _grouped, its CPU shape)
 *   kd_build_small_subtrees    per small root: its whole subtree, depth first, in preorder
 *
 * The paper splits the small nodes of one level at a time, with a launch per level. Here one
 * work-item builds a root's whole subtree in one launch: the root's masks (at most 64 references
 * of 128 bytes) stay in its cache across the subtree's levels instead of being read again by a new
 * launch per level, and the ~20 launches, scans and read-backs of the levels are gone. The trees
 * are the same: each node gets the same SAH decision from the same inputs. One departure from the
 * paper: a node of at most KDRAY_RECLIP_REFS triangles re-clips them to its box and prices its
 * subtree with masks of its own (build_small_reclip.cl). The SAH search of one node is in
 * build_small_search.cl.
 *
 * Candidates are the boundaries of the root's (clipped) triangle boxes, or of a re-clipped node's
 * (KdClippedTable): candidate 6*ref + 2*axis + side lies at the box's lo (side 0) or hi (side 1)
 * on that axis. side_masks holds KDRAY_MASK_WORDS_PER_REF (16) masks per reference, [16 ref + k]
 * the triangles below its candidate k and [16 ref + 8 + k] those above (k < 6; two lanes of
 * padding each), so that the kernels read a reference's masks as two ulong8.
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
#include "cl/builder/kernels/build_common.cl"
#include "cl/builder/kernels/build_small_bins.cl"
#include "cl/builder/kernels/build_small_reclip.cl"
#include "cl/builder/kernels/build_small_search.cl"
/* The same stage in the paper's level-parallel shape, in this program (one compile for both). */
#include "cl/builder/kernels/build_small_level.cl"

/* Split candidates (§4.2, "small node preprocessing"): for each candidate plane the set of the
 * root's triangles below it and the set above it, by the same rule as every split (kd_classify
 * with the planar side below: below when lo < plane or when not hi > plane, above when
 * hi > plane), except in the hi lane of an axis on which the reference is flat, where triangles
 * lying in the plane go above (below when lo < plane, above when hi > plane or lo >= plane).
 * A reference's six candidates are computed together in the lanes of one float8 (two lanes
 * unused), so each box of the root is loaded once for six planes. Per plane, one scalar loop over
 * the root took 86 ms of CPU per kitchen build (perf); the per-reference shape below 24 ms.
 *
 * Two shapes, the same masks bit for bit: kd_compute_split_masks, one work-item per reference,
 * whose work-items of one root run the same loop (GPU lanes stay converged; the per-level small
 * stage's); and kd_compute_split_masks_grouped, a work-item per KDRAY_MASK_GROUP references
 * (CPU devices; the per-root stage's), which loads each box of the root once for all of them. */

/* The masks of reference `ref` (of the batch from ref_begin on) alone. */
KDRAY_INLINE void kd_split_masks_of(uint ref, uint ref_begin, __global const float* ref_box,
                                    __global const uint* ref_root,
                                    __global const KdSmallRoot* small_roots,
                                    __global ulong* side_masks) {
    const float8 pos = kd_candidate_lanes(ref_box + (size_t)ref * KDRAY_BOX_FLOATS);
    const int8 planar_above = kd_planar_above_lanes(pos);
    const uint root = ref_root[ref];
    const uint start = small_roots[root].ref_start, count = small_roots[root].ref_count;
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
    vstore8(below, 0, side_masks + (size_t)(ref - ref_begin) * KDRAY_MASK_WORDS_PER_REF);
    vstore8(above, 1, side_masks + (size_t)(ref - ref_begin) * KDRAY_MASK_WORDS_PER_REF);
}

/* Work-item r: the masks of the batch's reference ref_begin + r (of refs). */
__kernel void kd_compute_split_masks(uint ref_begin, uint refs, __global const float* ref_box,
                                     __global const uint* ref_root,
                                     __global const KdSmallRoot* small_roots,
                                     __global ulong* side_masks) {
    if (get_global_id(0) >= refs) return;
    kd_split_masks_of(ref_begin + (uint)get_global_id(0), ref_begin, ref_box, ref_root, small_roots,
                      side_masks);
}

/* Work-item g: the masks of the batch's references KDRAY_MASK_GROUP g .. (of refs), four. Those
 * of the group's first root are priced together, the candidates of two references per float16,
 * against each box of the root loaded once; any of another root (a root ends inside the group)
 * alone. A quarter of the box loads and shuffles: at low, the masks took about 12.3 -> 8.8 ms of
 * CPU per Kitchen build and 20.3 -> 13.6 ms per dragon res2 build (perf at 4 kHz over 21 builds),
 * the Kitchen build 30.7 -> 27.9 ms on 2 PoCL threads (interleaved). */
#if KDRAY_MASK_GROUP != 4u
#error "kd_compute_split_masks_grouped holds the candidates of four references in two float16"
#endif
__kernel void kd_compute_split_masks_grouped(uint ref_begin, uint refs,
                                             __global const float* ref_box,
                                             __global const uint* ref_root,
                                             __global const KdSmallRoot* small_roots,
                                             __global ulong* side_masks) {
    const uint first = KDRAY_MASK_GROUP * (uint)get_global_id(0);
    if (first >= refs) return;
    const uint ref = ref_begin + first, root = ref_root[ref];
    const uint in_batch = min(KDRAY_MASK_GROUP, refs - first);
    uint together = 1;
    while (together < in_batch && ref_root[ref + together] == root) ++together;
    /* Lanes 8 (k % 2).. of pos[k / 2]: reference k's candidates; past `together`, the last one's
     * again. */
    float8 candidates[KDRAY_MASK_GROUP];
    for (uint k = 0; k < KDRAY_MASK_GROUP; ++k)
        candidates[k] =
            kd_candidate_lanes(ref_box + (size_t)(ref + min(k, together - 1u)) * KDRAY_BOX_FLOATS);
    float16 pos[2];
    int16 planar_above[2];
    for (uint h = 0; h < 2; ++h) {
        pos[h] = (float16)(candidates[2 * h], candidates[2 * h + 1]);
        planar_above[h] = (int16)(kd_planar_above_lanes(candidates[2 * h]),
                                  kd_planar_above_lanes(candidates[2 * h + 1]));
    }
    const uint start = small_roots[root].ref_start, count = small_roots[root].ref_count;
    /* [h][part]: the masks of pos[h]'s lanes, bits 32 part.. of the root's references. */
    uint16 below_bits[2][2], above_bits[2][2];
    for (uint part = 0; part < 2; ++part) {
        uint16 below0 = (uint16)(0), above0 = (uint16)(0), below1 = (uint16)(0),
               above1 = (uint16)(0);
        const uint end = min(count, 32u * (part + 1));
        for (uint j = 32u * part; j < end; ++j) {
            float8 lo8, hi8;
            kd_box_lanes(kd_load_box(ref_box, start + j), &lo8, &hi8);
            const float16 lo = (float16)(lo8, lo8), hi = (float16)(hi8, hi8);
            const uint bit = 1u << (j & 31u);
            int16 is_below, is_above;
            KDRAY_CANDIDATE_SIDES(int16, pos[0], planar_above[0], lo, hi, is_below, is_above);
            below0 |= as_uint16(is_below) & bit;
            above0 |= as_uint16(is_above) & bit;
            KDRAY_CANDIDATE_SIDES(int16, pos[1], planar_above[1], lo, hi, is_below, is_above);
            below1 |= as_uint16(is_below) & bit;
            above1 |= as_uint16(is_above) & bit;
        }
        below_bits[0][part] = below0;
        above_bits[0][part] = above0;
        below_bits[1][part] = below1;
        above_bits[1][part] = above1;
    }
    __global ulong* out = side_masks + (size_t)first * KDRAY_MASK_WORDS_PER_REF;
    for (uint k = 0; k < together; ++k) {
        const uint h = k / 2;
        const uint8 below_lo = (k & 1u) ? below_bits[h][0].hi : below_bits[h][0].lo;
        const uint8 below_hi = (k & 1u) ? below_bits[h][1].hi : below_bits[h][1].lo;
        const uint8 above_lo = (k & 1u) ? above_bits[h][0].hi : above_bits[h][0].lo;
        const uint8 above_hi = (k & 1u) ? above_bits[h][1].hi : above_bits[h][1].lo;
        vstore8(convert_ulong8(below_lo) | (convert_ulong8(below_hi) << 32), 2 * k, out);
        vstore8(convert_ulong8(above_lo) | (convert_ulong8(above_hi) << 32), 2 * k + 1, out);
    }
    for (uint k = together; k < in_batch; ++k)
        kd_split_masks_of(ref + k, ref_begin, ref_box, ref_root, small_roots, side_masks);
}

/* The masks carry boxes clipped to the small root (or to a re-clipping ancestor), not to the node,
 * so a triangle whose box straddles a split may still miss one child inside this node (a long
 * diagonal triangle past the corner of a deep node). A straddling triangle whose plane misses a
 * child's box leaves that child; only those that reach past the node on another axis are tested
 * (kd_straddler_may_miss). */
KDRAY_INLINE void kd_drop_missed_triangles(ulong* below, ulong* above, KdBox box, uint axis,
                                           float split, uint start, __global const float* ref_box,
                                           const KdClippedTable* table,
                                           __global const uint* ref_tri,
                                           __global const float* triangles) {
    for (ulong rest = *below & *above; rest != 0; rest &= rest - 1) {
        const ulong bit = rest & (0ul - rest);
        const uint j = kd_lowest_bit(rest);
        const KdBox ref_bounds =
            table ? kd_lanes_box(vload8(j, table->candidates)) : kd_load_box(ref_box, start + j);
        if (!kd_straddler_may_miss(ref_bounds, box, axis)) continue;
        /* A re-clipped node's table holds its triangles' planes: no fetch from the triangles. */
        const KdTrianglePlane plane =
            table ? table->planes[j]
                  : kd_triangle_plane(triangles +
                                      (size_t)ref_tri[start + j] * KDRAY_FLOATS_PER_TRIANGLE);
        const int miss_below = kd_plane_misses_box(&plane, kd_child_box(box, axis, split, 0));
        const int miss_above = kd_plane_misses_box(&plane, kd_child_box(box, axis, split, 1));
        if (miss_above && !miss_below) *above &= ~bit;
        if (miss_below && !miss_above) *below &= ~bit;
    }
}

/* The exact split of a node (Zhou et al.'s search, build_small_search.cl): over its table when it
 * has one, else over the small root's masks. 1 with the plane (*axis, *split) and the children's
 * masks when a candidate costs less than the leaf's C_i N, else 0. */
KDRAY_INLINE int kd_exact_small_split(KdBox box, ulong mask, const KdClippedTable* table,
                                      uint start, __global const float* ref_box,
                                      __global const ulong* root_masks, float cost_traversal,
                                      float cost_intersection, float empty_bonus, uint* axis,
                                      float* split, ulong* below_child, ulong* above_child) {
    const uint best = table ? kd_best_clipped_split(box, mask, table, cost_traversal,
                                                    cost_intersection, empty_bonus)
                            : kd_best_small_split(box, mask, start, ref_box, root_masks,
                                                  cost_traversal, cost_intersection, empty_bonus);
    if (best == KDRAY_NO_CANDIDATE) return 0;
    const uint ref = best >> KDRAY_CANDIDATE_STRIDE_SHIFT, k = best & (KDRAY_CANDIDATE_STRIDE - 1u);
    *axis = k / 2;
    float8 pos;
    ulong8 below, above;
    if (table) {
        pos = vload8(ref, table->candidates);
        below = convert_ulong8(vload8(0, table->masks + ref * KDRAY_MASK_WORDS_PER_REF));
        above = convert_ulong8(vload8(1, table->masks + ref * KDRAY_MASK_WORDS_PER_REF));
    } else {
        __global const ulong* masks = root_masks + (size_t)(ref - start) * KDRAY_MASK_WORDS_PER_REF;
        pos = kd_candidate_lanes(ref_box + (size_t)ref * KDRAY_BOX_FLOATS);
        below = vload8(0, masks);
        above = vload8(1, masks);
    }
    *split = kd_split_at_candidate(pos, below, above, mask, box, k, below_child, above_child);
    return 1;
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
 * subtree, as the output layout wants) to the root's run of subtree_nodes (KdSmallNode records,
 * core/device/kd_build_shared.h; leaf offsets count from the subtree's first leaf reference). A
 * node becomes a leaf when no split beats C_i N, at the depth limit, when its box has no area, or
 * when it holds at most a.leaf_size triangles (the cheaper build qualities: no search at all). A
 * node not on a re-clipped table is split by a.small_bins bins (build_small_bins.cl) when that is
 * set; side_masks is then unused (the host makes no masks).
 *
 * The first pass gives a root of count references first_scale * (count + 1) records, from
 * first_scale * (the batch's references and roots before it) on. Outputs per root: its node and
 * leaf reference counts; a subtree that outgrows its run is still counted, only not written.
 * totals (zeroed by the host): [0] the stage's node count, [1] the smallest scale that holds
 * every subtree, [2] the most levels of one subtree. The second pass (second_pass != 0) builds
 * again only the subtrees that outgrew the first, each into exactly its counted records from
 * second_offset[root - root_begin] on (kd_second_pass_records). The batch and the SAH costs come
 * in `a`. */
__kernel void kd_build_small_subtrees(
    KdSmallBatchArgs a, __global const KdSmallRoot* small_roots, __global const float* ref_box,
    __global const ulong* side_masks, __global const uint* ref_tri, __global const float* triangles,
    __global const uint* second_offset, __global KdSmallNode* subtree_nodes,
    __global uint* subtree_node_count, __global uint* subtree_leaf_refs, __global uint* totals) {
    const uint root_begin = a.root_begin, ref_begin = a.ref_begin, first_scale = a.first_scale;
    const uint second_pass = a.second_pass, max_depth = a.max_depth;
    const float cost_traversal = a.cost_traversal, cost_intersection = a.cost_intersection;
    const float empty_bonus = a.empty_bonus;
    const uint reclip_refs = min(a.reclip_refs, KDRAY_RECLIP_REFS), leaf_size = a.leaf_size;
    const uint small_bins = min(a.small_bins, KDRAY_SMALL_MAX_BINS);
    if (get_global_id(0) >= a.roots) return;
    const uint q = root_begin + (uint)get_global_id(0);
    const KdSmallRoot root = small_roots[q];
    const uint start = root.ref_start, count = root.ref_count;
    const uint first_budget = first_scale * (count + 1);
    if (second_pass && subtree_node_count[q] <= first_budget) return;
    const uint budget = second_pass ? subtree_node_count[q] : first_budget;
    __global KdSmallNode* out =
        second_pass
            ? subtree_nodes + second_offset[q - root_begin]
            : subtree_nodes + (size_t)first_scale * ((start - ref_begin) + (q - root_begin));
    __global const ulong* root_masks =
        side_masks + (size_t)(start - ref_begin) * KDRAY_MASK_WORDS_PER_REF;
    KdPendingNode stack[KDRAY_MAX_DEPTH];
    uint top = 0;
    KdPendingNode node;
    node.box = kd_box_of(root.box);
    node.mask = count >= 64 ? ~0ul : ((1ul << count) - 1ul);
    node.depth = root.depth;
    node.parent = KDRAY_NO_CANDIDATE;
    node.on_table = 0;
    KdClippedTable table;
    uint written = 0, leaf_refs = 0, deepest = node.depth;
    for (;;) {
        /* The next node in preorder; an above child completes its parent's record. */
        const uint at = written++;
        deepest = max(deepest, node.depth);
        if (node.parent != KDRAY_NO_CANDIDATE && node.parent < budget)
            out[node.parent].axis_and_offset = node.parent_axis | (at << 2);
        /* The split (axis, plane) and its children's masks, by the exact search over masks or
         * over the node's table, or by bins (build_small_bins.cl). */
        int split_found = 0;
        uint axis = 0;
        float split = 0.0f;
        ulong children[2] = {0, 0};
        const KdClippedTable* node_table = 0;
        const uint node_refs = popcount(node.mask);
        if (node_refs > leaf_size && node.depth < max_depth && kd_box_area(node.box) > 0.0f) {
            if (!node.on_table && node_refs <= reclip_refs)
                node.on_table = kd_clip_node_table(node.box, &node.mask, start, ref_box, ref_tri,
                                                   triangles, &table);
            if (!node.on_table && small_bins > 0) {
                split_found = kd_binned_small_split(node.box, node.mask, start, ref_box, small_bins,
                                                    cost_traversal, cost_intersection, empty_bonus,
                                                    &axis, &split, &children[0], &children[1]);
            } else {
                split_found =
                    kd_exact_small_split(node.box, node.mask, node.on_table ? &table : 0, start,
                                         ref_box, root_masks, cost_traversal, cost_intersection,
                                         empty_bonus, &axis, &split, &children[0], &children[1]);
            }
            if (node.on_table) node_table = &table;
        }
        if (!split_found) {
            /* Leaf: its triangles are the mask's, its references the next in preorder. */
            const ulong leaf_mask = node.on_table ? kd_root_mask(&table, node.mask) : node.mask;
            const uint n = popcount(leaf_mask);
            if (at < budget) out[at] = kd_small_leaf(leaf_refs, n, leaf_mask);
            leaf_refs += n;
            if (top == 0) break;
            node = stack[--top];
            continue;
        }
        /* Inner node: go on with the below child, keep the above child for later. */
        kd_drop_missed_triangles(&children[0], &children[1], node.box, axis, split, start, ref_box,
                                 node_table, ref_tri, triangles);
        if (at < budget) out[at] = kd_small_inner(axis, split);
        KdPendingNode pending;
        pending.box = kd_child_box(node.box, axis, split, 1);
        pending.mask = children[1];
        pending.depth = node.depth + 1;
        pending.parent = at;
        pending.parent_axis = axis;
        pending.on_table = node.on_table;
        stack[top++] = pending;
        node.box = kd_child_box(node.box, axis, split, 0);
        node.mask = children[0];
        node.depth += 1;
        node.parent = KDRAY_NO_CANDIDATE;
    }
    subtree_node_count[q] = written;
    subtree_leaf_refs[q] = leaf_refs;
    atomic_add(&totals[0], written);
    atomic_max(&totals[1], (written + count) / (count + 1));
    atomic_max(&totals[2], deepest - root.depth + 1);
}

/* The second pass's records of a batch's roots (roots a.root_begin..): records[g] the node count
 * of root a.root_begin + g when its subtree outgrew the first pass's a.first_scale * (count + 1),
 * else 0; their exclusive scan places each subtree (kd_build_small_subtrees). */
__kernel void kd_second_pass_records(KdSmallBatchArgs a, __global const KdSmallRoot* small_roots,
                                     __global const uint* subtree_node_count,
                                     __global uint* records) {
    const uint g = get_global_id(0);
    if (g >= a.roots) return;
    const uint q = a.root_begin + g, nodes = subtree_node_count[q];
    records[g] = nodes > a.first_scale * (small_roots[q].ref_count + 1) ? nodes : 0u;
}
