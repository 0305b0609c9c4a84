/* build_small_level.cl — the small-node stage in the paper's shape (Zhou et al. 2008, §4.2): the
 * small nodes of one level at a time across the device, one work-group of KDRAY_LAUNCH_GROUP
 * work-items (most launches' group size, launch.h) per node. Work-item j prices the six candidates
 * of the node's j-th reference (the popcounts of its masks and the candidates' side masks,
 * build_small_search.cl) and the group reduces the costs in local memory to the cheapest
 * candidate, so no work-item holds a table of its own. build_small.cl's per-root kernel builds
 * each root's subtree in one work-item instead, with 4.6 KB of private tables: a CPU's shape,
 * which on a GPU spills and starves occupancy.
 *
 * Both shapes make the same decisions from the same inputs, so the trees are the same node for
 * node: the same candidates and SAH (kd_price_candidates), the same pick (least cost, then least
 * candidate index: kd_cheapest_candidate over one reference's lanes, then the group's reduction
 * over references in the same order), the same leaf criteria, and the same re-clipping
 * (kd_reclip_box). A node that re-clips keeps its table in local memory only while its group
 * runs; its descendants rebuild it at their own level from the re-clipping node's box and
 * references (KdSmallLevelNode.table_box, table_mask), which gives the same table again.
 *
 *   kd_start_small_level    the batch's small roots as the first level's nodes
 *   kd_split_small_level    one level: each node a leaf or split, its children the next level's
 *   kd_size_small_level     bottom up, one launch per level: nodes and leaf references per subtree
 *   kd_place_small_level    top down, one launch per level: preorder positions in the subtree
 *   kd_count_small_level    per root: its subtree's node and leaf reference counts
 *   kd_write_small_level    every node's KdSmallNode record, where the per-root kernel puts it
 *
 * The records land where kd_build_small_subtrees puts them (the first pass's records, or the
 * second's for a subtree that outgrew those), so the output stage (build_output.cl) reads either
 * shape's alike. */
#include "cl/builder/kernels/build_common.cl"
#include "cl/builder/kernels/build_small_bins.cl"
#include "cl/builder/kernels/build_small_reclip.cl"
#include "cl/builder/kernels/build_small_search.cl"

KDRAY_INLINE ulong kd_join_mask(uint lo, uint hi) {
    return ((ulong)hi << 32) | (ulong)lo;
}

KDRAY_INLINE KdBox kd_level_box(const float* b) {
    KdBox box;
    box.lo = (float3)(b[0], b[1], b[2]);
    box.hi = (float3)(b[3], b[4], b[5]);
    return box;
}

KDRAY_INLINE void kd_store_level_box(KdBox box, float* b) {
    b[0] = box.lo.x;
    b[1] = box.lo.y;
    b[2] = box.lo.z;
    b[3] = box.hi.x;
    b[4] = box.hi.y;
    b[5] = box.hi.z;
}

/* The batch's roots (a.root_begin.., a.roots of them) as nodes 0.. of the first level. */
__kernel void kd_start_small_level(KdSmallBatchArgs a, __global const KdSmallRoot* small_roots,
                                   __global KdSmallLevelNode* nodes) {
    const uint g = get_global_id(0);
    if (g >= a.roots) return;
    const uint q = a.root_begin + g;
    const KdSmallRoot root = small_roots[q];
    const ulong mask = root.ref_count >= 64 ? ~0ul : ((1ul << root.ref_count) - 1ul);
    KdSmallLevelNode n;
    for (uint i = 0; i < 3; ++i) {
        n.box[i] = root.box.lo[i];
        n.box[3 + i] = root.box.hi[i];
    }
    n.mask_lo = n.root_mask_lo = (uint)mask;
    n.mask_hi = n.root_mask_hi = (uint)(mask >> 32);
    for (uint i = 0; i < 6; ++i) n.table_box[i] = 0.0f;
    n.table_mask_lo = n.table_mask_hi = 0;
    n.root = q;
    n.depth = root.depth;
    n.table_on = 0;
    n.axis = KDRAY_LEAF_AXIS;
    n.split = 0.0f;
    n.child = 0;
    nodes[g] = n;
}

/* The re-clipped table of a node (kd_clip_node_table's, built by the group in local memory): the
 * references `mask` (over the small root's list from start) clipped to `box`, the misses dropped,
 * with their candidates, masks and planes. Work-item lid clips reference lid, then computes the
 * masks of table entry lid. keep_bits: two words of local scratch. Returns the table's size.
 * Every work-item of the group must call it (barriers). */
KDRAY_INLINE uint kd_group_clip_table(KdBox box, ulong mask, uint start,
                                      __global const float* ref_box, __global const uint* ref_tri,
                                      __global const float* triangles, __local KdClippedTable* t,
                                      __local uint* keep_bits, uint lid) {
    if (lid < 2) keep_bits[lid] = 0;
    barrier(CLK_LOCAL_MEM_FENCE);
    int keep = 0;
    KdBox b;
    __global const float* tri = triangles;
    if ((mask >> lid) & 1ul) {
        b = kd_load_box(ref_box, start + lid);
        tri = triangles + (size_t)ref_tri[start + lid] * KDRAY_FLOATS_PER_TRIANGLE;
        keep = kd_reclip_box(box, tri, &b);
        if (keep) atomic_or(&keep_bits[lid >> 5], 1u << (lid & 31u));
    }
    barrier(CLK_LOCAL_MEM_FENCE);
    const ulong kept = kd_join_mask(keep_bits[0], keep_bits[1]);
    const uint n = popcount(kept);
    if (keep) {
        /* Table entries in the order of the root's references, as kd_clip_node_table's loop. */
        const uint l = popcount(kept & ((1ul << lid) - 1ul));
        t->ref[l] = (uchar)lid;
        t->planes[l] = kd_triangle_plane(tri);
        vstore8((float8)(b.lo.x, b.hi.x, b.lo.y, b.hi.y, b.lo.z, b.hi.z, 0.0f, 0.0f), l,
                t->candidates);
    }
    barrier(CLK_LOCAL_MEM_FENCE);
    if (lid < n) KD_TABLE_ENTRY_MASKS(t, lid, n); /* one entry a work-item, local memory */
    barrier(CLK_LOCAL_MEM_FENCE);
    return n;
}

/* A mask over a local table as a mask over the small root's references (kd_root_mask). */
KDRAY_INLINE ulong kd_group_root_mask(__local const KdClippedTable* t, ulong mask) {
    ulong root = 0;
    for (ulong rest = mask; rest != 0; rest &= rest - 1) root |= 1ul << t->ref[kd_lowest_bit(rest)];
    return root;
}

/* The group's candidate of least cost (each work-item's in group_cost / group_candidate), the
 * least index among equal costs: the per-root search's pick. Every work-item calls it after a
 * barrier and gets the same index. */
KDRAY_INLINE uint kd_group_least_candidate(__local float* group_cost, __local uint* group_candidate,
                                           uint lid) {
    for (uint stride = KDRAY_LAUNCH_GROUP / 2; stride > 0; stride >>= 1) {
        if (lid < stride) {
            const float c = group_cost[lid + stride];
            const uint k = group_candidate[lid + stride];
            if (c < group_cost[lid] || (c == group_cost[lid] && k < group_candidate[lid])) {
                group_cost[lid] = c;
                group_candidate[lid] = k;
            }
        }
        barrier(CLK_LOCAL_MEM_FENCE);
    }
    return group_candidate[0];
}

/* The exact split of a group's node (mask over its table when on_table, else over the small root's
 * references from start, whose masks are root_masks): work-item lid prices the candidates of the
 * node's lid-th reference (table entry), and the group reduces the costs in local memory to the
 * per-root search's pick (kd_exact_small_split). 1 with the plane and the children's masks in
 * every work-item when a candidate beats C_i N, else 0. Every work-item of the group calls it. */
KDRAY_INLINE int kd_group_exact_split(KdBox box, ulong mask, uint on_table, uint start,
                                      __global const float* ref_box,
                                      __global const ulong* root_masks,
                                      __local const KdClippedTable* table, KdSmallBatchArgs a,
                                      uint lid, __local float* group_cost,
                                      __local uint* group_candidate, uint* axis, float* split,
                                      ulong* children) {
    KdSplitSearch s;
    kd_start_split_search(&s, box, mask, a.cost_traversal, a.cost_intersection, a.empty_bonus);
    if ((mask >> lid) & 1ul) {
        if (on_table)
            kd_price_candidates(
                &s, vload8(lid, table->candidates),
                convert_ulong8(vload8(0, table->masks + lid * KDRAY_MASK_WORDS_PER_REF)),
                convert_ulong8(vload8(1, table->masks + lid * KDRAY_MASK_WORDS_PER_REF)),
                lid * KDRAY_CANDIDATE_STRIDE);
        else
            kd_price_candidates(
                &s, kd_candidate_lanes(ref_box + (size_t)(start + lid) * KDRAY_BOX_FLOATS),
                vload8(0, root_masks + (size_t)lid * KDRAY_MASK_WORDS_PER_REF),
                vload8(1, root_masks + (size_t)lid * KDRAY_MASK_WORDS_PER_REF),
                (start + lid) * KDRAY_CANDIDATE_STRIDE);
    }
    group_candidate[lid] = kd_cheapest_candidate(&s);
    group_cost[lid] = kd_cheapest_cost(&s);
    barrier(CLK_LOCAL_MEM_FENCE);
    const uint best = kd_group_least_candidate(group_cost, group_candidate, lid);
    if (best == KDRAY_NO_CANDIDATE) return 0;
    /* The children of the best candidate, as kd_exact_small_split makes them. */
    const uint ref = best >> KDRAY_CANDIDATE_STRIDE_SHIFT, k = best & (KDRAY_CANDIDATE_STRIDE - 1u);
    *axis = k / 2;
    float8 pos;
    ulong8 below, above;
    if (on_table) {
        pos = vload8(ref, table->candidates);
        below = convert_ulong8(vload8(0, table->masks + ref * KDRAY_MASK_WORDS_PER_REF));
        above = convert_ulong8(vload8(1, table->masks + ref * KDRAY_MASK_WORDS_PER_REF));
    } else {
        __global const ulong* masks = root_masks + (size_t)(ref - start) * KDRAY_MASK_WORDS_PER_REF;
        pos = kd_candidate_lanes(ref_box + (size_t)ref * KDRAY_BOX_FLOATS);
        below = vload8(0, masks);
        above = vload8(1, masks);
    }
    *split = kd_split_at_candidate(pos, below, above, mask, box, k, &children[0], &children[1]);
    return 1;
}

/* A work-item per binned plane; the binned search's local words inside the re-clip table's. */
#if 3 * (KDRAY_SMALL_MAX_BINS + 1) > KDRAY_LAUNCH_GROUP || \
    KDRAY_RECLIP_REFS * 8 < 2 * KDRAY_LAUNCH_GROUP ||      \
    KDRAY_RECLIP_REFS * KDRAY_MASK_WORDS_PER_REF < KDRAY_SMALL_BIN_VALUES + 4
#error "kd_group_binned_split: too many bins for a group, or its words exceed the table's"
#endif

/* The binned split of a group's node (references `mask` over the small root's list from start),
 * kd_binned_small_split's in the group's shape: work-item lid loads the node's lid-th reference,
 * the group reduces the tight box and counts the bins in local memory, work-item k < 3
 * (bins + 1) prices plane k (axis k / (bins + 1)) by kd_binned_plane_cost, the group reduces the
 * costs (group_cost, group_candidate) to the least, then the least index: the first cheapest in
 * (axis, plane) order, as the per-root stage's loop picks. Every work-item then classifies its
 * reference. 1 with the plane and the children's masks in every work-item when a plane beats
 * C_i N, else 0. Every work-item of the group calls it. */
KDRAY_INLINE int kd_group_binned_split(KdBox box, ulong mask, uint start,
                                       __global const float* ref_box, uint small_bins,
                                       KdSmallBatchArgs a, uint lid, __local KdClippedTable* table,
                                       __local float* group_cost, __local uint* group_candidate,
                                       uint* axis, float* split, ulong* children) {
    /* A binned node has no table: the tight box's reduction (a bound per work-item, an axis at a
     * time) takes the table's candidate words, the bin counts and the children's masks its mask
     * words, so the binned search adds nothing to the kernel's local memory. */
    __local float* lo = table->candidates;
    __local float* hi = table->candidates + KDRAY_LAUNCH_GROUP;
    __local uint* counts = table->masks;
    __local uint* child_words = table->masks + KDRAY_SMALL_BIN_VALUES;
    const int mine = (mask >> lid) & 1ul;
    KdBox b;
    b.lo = (float3)(INFINITY);
    b.hi = (float3)(-INFINITY);
    if (mine) b = kd_load_box(ref_box, start + lid);
    for (uint k = lid; k < KDRAY_BIN_COUNTS * small_bins; k += KDRAY_LAUNCH_GROUP) counts[k] = 0;
    if (lid < 4) child_words[lid] = 0;
    float3 reduced_lo, reduced_hi;
    for (uint i = 0; i < 3; ++i) {
        lo[lid] = kd_axis_of(b.lo, i);
        hi[lid] = kd_axis_of(b.hi, i);
        barrier(CLK_LOCAL_MEM_FENCE);
        for (uint stride = KDRAY_LAUNCH_GROUP / 2; stride > 0; stride >>= 1) {
            if (lid < stride) {
                lo[lid] = fmin(lo[lid], lo[lid + stride]);
                hi[lid] = fmax(hi[lid], hi[lid + stride]);
            }
            barrier(CLK_LOCAL_MEM_FENCE);
        }
        if (i == 0) reduced_lo.x = lo[0], reduced_hi.x = hi[0];
        if (i == 1) reduced_lo.y = lo[0], reduced_hi.y = hi[0];
        if (i == 2) reduced_lo.z = lo[0], reduced_hi.z = hi[0];
        /* Every work-item has read the bounds before the next axis overwrites them. */
        barrier(CLK_LOCAL_MEM_FENCE);
    }
    KdBox tight;
    tight.lo = fmax(reduced_lo, box.lo);
    tight.hi = fmin(reduced_hi, box.hi);
    if (mine) {
        uint4 lo_bin, hi_bin;
        kd_bins_of(b, (float4)(tight.lo, 0.0f), kd_bin_scale(tight, small_bins), small_bins,
                   &lo_bin, &hi_bin);
        atomic_inc(&counts[lo_bin.x]);
        atomic_inc(&counts[small_bins + hi_bin.x]);
        atomic_inc(&counts[2 * small_bins + lo_bin.y]);
        atomic_inc(&counts[3 * small_bins + hi_bin.y]);
        atomic_inc(&counts[4 * small_bins + lo_bin.z]);
        atomic_inc(&counts[5 * small_bins + hi_bin.z]);
    }
    barrier(CLK_LOCAL_MEM_FENCE);
    /* Plane lid, against the leaf: a plane must cost less than C_i N, and NO_CANDIDATE (the
     * largest index) keeps the leaf's cost. */
    const uint n = popcount(mask), planes = small_bins + 1;
    const float leaf_cost = a.cost_intersection * (float)n;
    float cost = leaf_cost;
    uint candidate = KDRAY_NO_CANDIDATE;
    if (lid < 3 * planes) {
        const uint plane_axis = lid / planes, plane = lid % planes;
        uint below = 0, above = n;
        for (uint k = 0; k < plane; ++k) {
            below += counts[(2 * plane_axis) * small_bins + k];
            above -= counts[(2 * plane_axis + 1) * small_bins + k];
        }
        const KdPlaneFrame f = kd_plane_frame(box, plane_axis, a.cost_intersection);
        const float p = kd_binned_plane_pos(tight, plane_axis, plane, small_bins);
        if (kd_plane_inside(f, p)) {
            const float c =
                kd_binned_plane_cost(f, p, below, above, a.cost_traversal, a.empty_bonus);
            if (c < leaf_cost) cost = c, candidate = lid;
        }
    }
    group_cost[lid] = cost;
    group_candidate[lid] = candidate;
    barrier(CLK_LOCAL_MEM_FENCE);
    const uint best = kd_group_least_candidate(group_cost, group_candidate, lid);
    if (best == KDRAY_NO_CANDIDATE) return 0;
    *axis = best / planes;
    *split = kd_binned_plane_pos(tight, *axis, best % planes, small_bins);
    if (mine) {
        const uint sides = kd_small_bin_sides(b, *axis, *split);
        const uint word = lid >> 5, bit = 1u << (lid & 31u);
        if (sides & KDRAY_BELOW) atomic_or(&child_words[word], bit);
        if (sides & KDRAY_ABOVE) atomic_or(&child_words[2 + word], bit);
    }
    barrier(CLK_LOCAL_MEM_FENCE);
    children[0] = kd_join_mask(child_words[0], child_words[1]);
    children[1] = kd_join_mask(child_words[2], child_words[3]);
    return 1;
}

/* One level of the small stage (§4.2), one work-group per node (nodes level_begin.., level_nodes
 * of them): the node becomes a leaf or splits at its cheapest candidate, by the rules of
 * kd_build_small_subtrees. A split node's two children are appended to the next level at
 * *next_free (the host made room for two per node). The group's work-items share the node's
 * table when it re-clips and reduce the candidates' costs in local memory. */
__kernel __attribute__((reqd_work_group_size(KDRAY_LAUNCH_GROUP, 1, 1))) void kd_split_small_level(
    KdSmallBatchArgs a, uint level_begin, uint level_nodes, __global const KdSmallRoot* small_roots,
    __global const float* ref_box, __global const ulong* side_masks, __global const uint* ref_tri,
    __global const float* triangles, __global KdSmallLevelNode* nodes, __global uint* next_free) {
    __local KdClippedTable table;
    __local float group_cost[KDRAY_LAUNCH_GROUP];
    __local uint group_candidate[KDRAY_LAUNCH_GROUP];
    __local uint scratch[7]; /* [0] a reference reaches past the box; [1, 2] kept; [3, 6] dropped */
    const uint small_bins = min(a.small_bins, KDRAY_SMALL_MAX_BINS);
    const uint g = get_group_id(0), lid = get_local_id(0);
    /* Every work-item of a group takes the same branches up to the end: the barriers need it. */
    if (g >= level_nodes) return;
    const uint id = level_begin + g;
    const KdSmallLevelNode n = nodes[id];
    /* Work-item 0 rewrites nodes[id] below; the group's other work-items must have read it first
     * (Oclgrind --data-races reported the race). */
    barrier(CLK_GLOBAL_MEM_FENCE);
    const uint reclip_refs = min(a.reclip_refs, KDRAY_RECLIP_REFS);
    const KdSmallRoot root = small_roots[n.root];
    const uint start = root.ref_start;
    __global const ulong* root_masks =
        side_masks + (size_t)(start - a.ref_begin) * KDRAY_MASK_WORDS_PER_REF;
    const KdBox box = kd_level_box(n.box);
    ulong mask = kd_join_mask(n.mask_lo, n.mask_hi);
    uint on_table = n.table_on;
    KdBox table_box = kd_level_box(n.table_box);
    ulong table_mask = kd_join_mask(n.table_mask_lo, n.table_mask_hi);
    int have_table = 0; /* the table is in local memory */
    int split_found = 0;
    uint axis = 0;
    float split = 0.0f;
    ulong children[2] = {0, 0};

    /* Search when the node is no leaf by size, depth or a box without area. */
    if (popcount(mask) > a.leaf_size && n.depth < a.max_depth && kd_box_area(box) > 0.0f) {
        /* Re-clip when the node is small enough and some of its references reach past its box
         * (kd_clip_node_table); on a table already, rebuild its ancestor's. */
        int fresh_table = 0;
        if (!on_table && popcount(mask) <= reclip_refs) {
            if (lid == 0) scratch[0] = 0;
            barrier(CLK_LOCAL_MEM_FENCE);
            if ((mask >> lid) & 1ul) {
                const KdBox b = kd_load_box(ref_box, start + lid);
                if (any(b.lo < box.lo) || any(b.hi > box.hi)) atomic_or(&scratch[0], 1u);
            }
            barrier(CLK_LOCAL_MEM_FENCE);
            if (scratch[0]) {
                on_table = 1;
                table_box = box;
                table_mask = mask;
                fresh_table = 1;
            }
        }
        /* One call site for the group clip: PoCL 3.1's work-group compiler (LLVM 15) crashed in
         * its inliner on this kernel while it had two, each with barriers (a cold kernel cache
         * segfaulted every per-level build). */
        if (on_table) {
            const uint size = kd_group_clip_table(table_box, table_mask, start, ref_box, ref_tri,
                                                  triangles, &table, scratch + 1, lid);
            if (fresh_table) mask = size >= 64 ? ~0ul : (1ul << size) - 1ul;
            have_table = 1;
        }

        if (!on_table && small_bins > 0)
            split_found =
                kd_group_binned_split(box, mask, start, ref_box, small_bins, a, lid, &table,
                                      group_cost, group_candidate, &axis, &split, children);
        else
            split_found =
                kd_group_exact_split(box, mask, on_table, start, ref_box, root_masks, &table, a,
                                     lid, group_cost, group_candidate, &axis, &split, children);
    }

    if (!split_found) {
        /* Leaf: its triangles over the root's references. */
        if (lid == 0) {
            const ulong leaf_mask = have_table ? kd_group_root_mask(&table, mask)
                                               : kd_join_mask(n.root_mask_lo, n.root_mask_hi);
            nodes[id].axis = KDRAY_LEAF_AXIS;
            nodes[id].split = 0.0f;
            nodes[id].child = 0;
            nodes[id].root_mask_lo = (uint)leaf_mask;
            nodes[id].root_mask_hi = (uint)(leaf_mask >> 32);
        }
        return;
    }

    /* kd_drop_missed_triangles, a straddling triangle per work-item (those kd_straddler_may_miss
     * picks): one whose plane misses a child's box leaves that child. */
    if (lid < 4) scratch[3 + lid] = 0;
    barrier(CLK_LOCAL_MEM_FENCE);
    const ulong straddle = children[0] & children[1];
    if (((straddle >> lid) & 1ul) &&
        kd_straddler_may_miss(on_table ? kd_lanes_box(vload8(lid, table.candidates))
                                       : kd_load_box(ref_box, start + lid),
                              box, axis)) {
        const KdTrianglePlane plane =
            on_table ? table.planes[lid]
                     : kd_triangle_plane(triangles +
                                         (size_t)ref_tri[start + lid] * KDRAY_FLOATS_PER_TRIANGLE);
        const int miss_below = kd_plane_misses_box(&plane, kd_child_box(box, axis, split, 0));
        const int miss_above = kd_plane_misses_box(&plane, kd_child_box(box, axis, split, 1));
        const uint word = lid >> 5, bit = 1u << (lid & 31u);
        if (miss_below && !miss_above) atomic_or(&scratch[3 + word], bit);
        if (miss_above && !miss_below) atomic_or(&scratch[5 + word], bit);
    }
    barrier(CLK_LOCAL_MEM_FENCE);
    if (lid != 0) return;
    const ulong child_mask[2] = {children[0] & ~kd_join_mask(scratch[3], scratch[4]),
                                 children[1] & ~kd_join_mask(scratch[5], scratch[6])};
    const uint child = atomic_add(next_free, 2u);
    nodes[id].axis = axis;
    nodes[id].split = split;
    nodes[id].child = child;
    for (uint side = 0; side < 2; ++side) {
        KdSmallLevelNode c;
        kd_store_level_box(kd_child_box(box, axis, split, side), c.box);
        const ulong root_mask =
            on_table ? kd_group_root_mask(&table, child_mask[side]) : child_mask[side];
        c.mask_lo = (uint)child_mask[side];
        c.mask_hi = (uint)(child_mask[side] >> 32);
        c.root_mask_lo = (uint)root_mask;
        c.root_mask_hi = (uint)(root_mask >> 32);
        kd_store_level_box(table_box, c.table_box);
        c.table_mask_lo = (uint)table_mask;
        c.table_mask_hi = (uint)(table_mask >> 32);
        c.root = n.root;
        c.depth = n.depth + 1;
        c.table_on = on_table;
        c.axis = KDRAY_LEAF_AXIS;
        c.split = 0.0f;
        c.child = 0;
        nodes[child + side] = c;
    }
}

/* Bottom up, one launch per level (begin.., count nodes; the next level's are done): each node's
 * subtree node count and leaf references. */
__kernel void kd_size_small_level(uint begin, uint count, __global const KdSmallLevelNode* nodes,
                                  __global uint* subtree_nodes, __global uint* subtree_refs) {
    const uint k = get_global_id(0);
    if (k >= count) return;
    const uint id = begin + k;
    const KdSmallLevelNode n = nodes[id];
    if (n.axis == KDRAY_LEAF_AXIS) {
        subtree_nodes[id] = 1;
        subtree_refs[id] = popcount(kd_join_mask(n.root_mask_lo, n.root_mask_hi));
    } else {
        subtree_nodes[id] = 1 + subtree_nodes[n.child] + subtree_nodes[n.child + 1];
        subtree_refs[id] = subtree_refs[n.child] + subtree_refs[n.child + 1];
    }
}

/* Top down, one launch per level: the children's preorder positions within their root's subtree
 * (below child right after its parent, above child after the below subtree) and first leaf
 * references, as kd_build_small_subtrees' depth-first walk numbers them. The roots' are 0. */
__kernel void kd_place_small_level(uint begin, uint count, __global const KdSmallLevelNode* nodes,
                                   __global const uint* subtree_nodes,
                                   __global const uint* subtree_refs, __global uint* position,
                                   __global uint* leaf_position) {
    const uint k = get_global_id(0);
    if (k >= count) return;
    const uint id = begin + k;
    const KdSmallLevelNode n = nodes[id];
    if (n.axis == KDRAY_LEAF_AXIS) return;
    kd_place_children(id, n.child, n.child + 1, subtree_nodes, subtree_refs, position,
                      leaf_position);
}

/* Per root of the batch (its first-level node g): its subtree's node and leaf reference counts,
 * where the output stage reads them. */
__kernel void kd_count_small_level(KdSmallBatchArgs a, __global const uint* subtree_nodes,
                                   __global const uint* subtree_refs,
                                   __global uint* subtree_node_count,
                                   __global uint* subtree_leaf_refs) {
    const uint g = get_global_id(0);
    if (g >= a.roots) return;
    subtree_node_count[a.root_begin + g] = subtree_nodes[g];
    subtree_leaf_refs[a.root_begin + g] = subtree_refs[g];
}

/* Every node of the batch (count of them): its KdSmallNode record at its preorder position in its
 * root's records, the first pass's (first_scale per reference and root, from the batch's
 * references and roots before it) when the subtree fits them, else the second pass's from
 * second_offset (kd_second_pass_records), as kd_build_small_subtrees lays them out. */
__kernel void kd_write_small_level(
    KdSmallBatchArgs a, uint count, __global const KdSmallRoot* small_roots,
    __global const KdSmallLevelNode* nodes, __global const uint* subtree_node_count,
    __global const uint* position, __global const uint* leaf_position,
    __global const uint* second_offset, __global KdSmallNode* first_nodes,
    __global KdSmallNode* second_nodes) {
    const uint id = get_global_id(0);
    if (id >= count) return;
    const KdSmallLevelNode n = nodes[id];
    const uint q = n.root;
    const KdSmallRoot root = small_roots[q];
    const uint first_scale = a.first_scale;
    __global KdSmallNode* out =
        subtree_node_count[q] <= first_scale * (root.ref_count + 1)
            ? first_nodes +
                  (size_t)first_scale * ((root.ref_start - a.ref_begin) + (q - a.root_begin))
            : second_nodes + second_offset[q - a.root_begin];
    if (n.axis == KDRAY_LEAF_AXIS) {
        const ulong leaf_mask = kd_join_mask(n.root_mask_lo, n.root_mask_hi);
        out[position[id]] = kd_small_leaf(leaf_position[id], popcount(leaf_mask), leaf_mask);
    } else {
        KdSmallNode r = kd_small_inner(n.axis, n.split);
        r.axis_and_offset = n.axis | (position[n.child + 1] << 2);
        out[position[id]] = r;
    }
}
