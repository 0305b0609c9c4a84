/* build_large_depth_first.cl — the large-node stage's depth-first schedule for CPU devices
 * (included by build_large.cl, after the split rules it shares with the level-by-level stage).
 *
 * The level-by-level stage (Zhou et al. 2008, §4.1) reads and writes every reference of a level
 * in 4-5 passes over memory and 20-30 commands a level: on a GPU that is the parallelism the
 * paper needs, on a CPU of a few cores it is memory traffic and command overhead. With this
 * schedule the levels hand every child of more than T and at most deep_refs references (a deep
 * root; cl/builder/large_depth_first.cpp picks the size: a core's cache, a few subtrees per
 * compute unit) to a list of their own, and here a work-item builds each deep root's whole
 * large subtree (on CPUs one after another, largest first), depth first, down to its small
 * roots and leaves: per node, one pass bins its references for the SAH and one classifies,
 * clips and partitions them, in the work-item's own workspace, which stays in its core's cache. The
 * rules are the level stage's own (build_large_rules.cl, and build_large_sah.cl's bins and plane)
 * and the references keep their order, so the tree is the same node for node
 * (tests/test_opencl_large_stage.cpp), unless a reference budget makes leaves: the levels' and a
 * subtree's (below) bound different sets of nodes, so on input whose splits cut most triangles they
 * may make different budget leaves. On the 2-core PoCL CPU device the large stage takes 0.67-0.82
 * of the chunked levels' time (docs/large-stage.md, measured at a54da79).
 *
 *   kd_build_large_depth_first   the deep roots of the run, taken one at a time off a counter:
 *                                each subtree's records, small roots (and their references) and
 *                                leaf references, in arenas of its own
 *   kd_commit_depth_first        per deep root of a run that fitted: the arenas copied into the
 *                                build's stores, ids made global, and its KdLargeRegion for the
 *                                output stage
 *
 * Workspace of an item, [0, cap): a stack of reference ranges, a node's range on top. Splitting
 * the top node [b, b + n) writes its below references in place (a reference goes below at most
 * once, so the write never passes the read) and its above references after the range, at
 * [b + n, b + n + na), then moves them down to follow the below ones: the above child on top
 * (processed next), the below child under it. Both lists keep the node's order. As the levels
 * bound the references of a level (kReferenceBudgetPerTriangle per triangle: splits that cut
 * most triangles would otherwise double them level after level), an item bounds those its nodes
 * of each depth hold to ref_budget per reference of its root: a node whose children could pass
 * that (2n, before it is split), or whose above list would not fit the workspace, becomes a leaf
 * (a budget leaf). The output arenas only count when full: the item stops and reports which ran
 * out, and the host runs the kernel again for those items alone, with them larger. */
#ifndef KDRAY_BUILD_LARGE_DEPTH_FIRST_CL
#define KDRAY_BUILD_LARGE_DEPTH_FIRST_CL

#include "cl/builder/kernels/build_common.cl"

/* A waiting node (KdDepthFirstTask) to and from the item's stack. */
KDRAY_INLINE void kd_push_task(__global KdDepthFirstTask* slot, KdBox box, KdBox tight, uint begin,
                               uint count, uint depth, uint record) {
    KdDepthFirstTask t;
    t.box = kd_build_box_of(box);
    t.tight = kd_build_box_of(tight);
    t.begin = begin;
    t.count = count;
    t.depth = depth;
    t.record = record;
    *slot = t;
}

/* One item's arenas: start and capacity per kind (KDRAY_DF_*), and what it has used. */
typedef struct KdArenas {
    uint start[KDRAY_DF_KINDS], cap[KDRAY_DF_KINDS], used[KDRAY_DF_KINDS];
    uint full; /* bit k: kind k ran out */
} KdArenas;

/* `n` more entries of arena `kind`: their first index (arena-relative), or ~0 when it is full. */
KDRAY_INLINE uint kd_arena_take(KdArenas* a, uint kind, uint n) {
    if (a->cap[kind] - a->used[kind] < n) {
        a->full |= 1u << kind;
        return ~0u;
    }
    const uint at = a->used[kind];
    a->used[kind] += n;
    return at;
}

KDRAY_INLINE KdBox kd_empty_box(void) {
    KdBox b;
    b.lo = (float3)(INFINITY);
    b.hi = (float3)(-INFINITY);
    return b;
}

KDRAY_INLINE void kd_grow_box(KdBox* b, KdBox x) {
    b->lo = fmin(b->lo, x.lo);
    b->hi = fmax(b->hi, x.hi);
}

/* The workspace's references [from, from + n) to a new small root on record `record` (of the
 * item's records, `records`). */
KDRAY_INLINE void kd_df_small_root(KdArenas* a, uint from, uint n, KdBox box, uint depth,
                                   uint record, __global const uint* work_tri,
                                   __global const float* work_box, __global KdBuildNode* records,
                                   __global KdSmallRoot* roots, __global uint* small_tri,
                                   __global float* small_box) {
    const uint q = kd_arena_take(a, KDRAY_DF_ROOTS, 1);
    const uint at = kd_arena_take(a, KDRAY_DF_SMALL_REFS, n);
    if (a->full) return;
    KdSmallRoot root;
    root.box = kd_build_box_of(box);
    root.ref_start = at;
    root.ref_count = n;
    root.node_id = record;
    root.depth = depth;
    roots[a->start[KDRAY_DF_ROOTS] + q] = root;
    const uint out = a->start[KDRAY_DF_SMALL_REFS] + at;
    for (uint k = 0; k < n; ++k) {
        small_tri[out + k] = work_tri[from + k];
        kd_store_box(small_box, out + k, kd_load_box(work_box, from + k));
    }
    records[record] = kd_build_small_root(q);
}

/* The workspace's references [b, b + n) against the plane: the below ones written over the range
 * from b on, the above ones from b + n on, in order; returns (below, above) and their bounds. */
KDRAY_HOT_INLINE uint2 kd_df_partition(uint b, uint n, const uint axis, float split, KdBox node,
                                       __global const float* triangles, __global uint* work_tri,
                                       __global float* work_box, KdBox* sent) {
    uint below = 0, above = 0;
    KdBox sent_below = kd_empty_box(), sent_above = kd_empty_box();
    for (uint r = b; r < b + n; ++r) {
        const uint tri = work_tri[r];
        const KdBox box = kd_load_box(work_box, r);
        uint sides =
            kd_classify(kd_axis_of(box.lo, axis), kd_axis_of(box.hi, axis), split, KDRAY_BELOW);
        KdBox to_below = box, to_above = box;
        if (sides == (KDRAY_BELOW | KDRAY_ABOVE)) {
            const uint entered =
                kd_clip_straddler(box, triangles + (size_t)tri * KDRAY_FLOATS_PER_TRIANGLE, axis,
                                  split, node, &to_below, &to_above);
            if (entered) sides = entered;
        }
        if (sides & KDRAY_BELOW) {
            work_tri[b + below] = tri;
            kd_store_box(work_box, b + below, to_below);
            sent_below.lo = fmin(sent_below.lo, to_below.lo);
            sent_below.hi = fmax(sent_below.hi, to_below.hi);
            ++below;
        }
        if (sides & KDRAY_ABOVE) {
            work_tri[b + n + above] = tri;
            kd_store_box(work_box, b + n + above, to_above);
            sent_above.lo = fmin(sent_above.lo, to_above.lo);
            sent_above.hi = fmax(sent_above.hi, to_above.hi);
            ++above;
        }
    }
    sent[0] = sent_below;
    sent[1] = sent_above;
    return (uint2)(below, above);
}

/* The arena starts of a run (kd_build_large_depth_first, kd_commit_depth_first): arena[k * (nodes
 * + 1) + w] is deep root w's first entry of arena kind k and the next root's is its end (a root
 * the run does not build has none); after them, from KDRAY_DF_KINDS * (nodes + 1) on, the run's
 * items, the deep roots it builds: every root in the first run, then only those whose arenas ran
 * out (cl/builder/large_depth_first.cpp); last, the count of items taken (0 from the host). */
KDRAY_INLINE uint kd_depth_first_root(__global const uint* arena, uint nodes, uint item) {
    return arena[KDRAY_DF_KINDS * (nodes + 1) + item];
}

/* Item g of a run builds deep root w = kd_depth_first_root(arena, args.nodes, g) (its references
 * root_ref_start[w] .., root_ref_count[w] of them, its box, record id and depth in deep_root[w])
 * and its whole large subtree: records, small roots, leaves. counts[g * KDRAY_DF_COUNTS + k]: what
 * it used of arena k (records: with its root), and at KDRAY_DF_WORK the arenas that ran out
 * (bits), at KDRAY_DF_BUDGET_LEAVES the budget leaves. Always inlined: inlined as a plain
 * static function it took the 32-bin program's AMD VGPRs from 132 to 248 (gpu_compile). */
KDRAY_HOT_INLINE void kd_build_deep_root(
    uint g, KdDepthFirstArgs args, __global const KdLargeNode* deep_root,
    __global const uint* root_ref_start, __global const uint* root_ref_count,
    __global const uint* ref_tri, __global const float* ref_box, __global const float* triangles,
    __global const uint* arena, __global uint* work_tri, __global float* work_box,
    __global KdBuildNode* records, __global KdSmallRoot* roots, __global uint* small_tri,
    __global float* small_box, __global uint* leaf_refs, __global KdDepthFirstTask* stacks,
    __global uint* counts) {
    const uint w = kd_depth_first_root(arena, args.nodes, g);
    KdArenas a;
    for (uint k = 0; k < KDRAY_DF_KINDS; ++k) {
        a.start[k] = arena[k * (args.nodes + 1) + w];
        a.cap[k] = arena[k * (args.nodes + 1) + w + 1] - a.start[k];
        a.used[k] = 0;
    }
    a.full = 0;
    __global uint* wt = work_tri + a.start[KDRAY_DF_WORK];
    __global float* wb = work_box + (size_t)a.start[KDRAY_DF_WORK] * KDRAY_BOX_FLOATS;
    __global KdBuildNode* rec = records + a.start[KDRAY_DF_RECORDS];
    uint budget_leaves = 0;
    uint held[KDRAY_DF_STACK]; /* references of the subtree's nodes of each depth below the root */
    for (uint d = 0; d < KDRAY_DF_STACK; ++d) held[d] = 0;

    /* The root's references into the workspace (the host gives it room for them), bounded on
     * the way. */
    const uint n0 = root_ref_count[w], from = root_ref_start[w];
    const uint depth0 = deep_root[w].depth, budget = args.ref_budget * n0;
    __global KdDepthFirstTask* stack = stacks + (size_t)g * KDRAY_DF_STACK;
    KdBox root_tight = kd_empty_box();
    for (uint r = 0; r < n0; ++r) {
        const KdBox box = kd_load_box(ref_box, from + r);
        wt[r] = ref_tri[from + r];
        kd_store_box(wb, r, box);
        kd_grow_box(&root_tight, box);
    }
    const uint root_record = kd_arena_take(&a, KDRAY_DF_RECORDS, 1);
    kd_push_task(&stack[0], kd_box_of(deep_root[w].box), root_tight, 0, n0, deep_root[w].depth,
                 root_record);
    uint top = a.full ? 0 : 1;

    while (top > 0) {
        const KdDepthFirstTask t = stack[--top];
        const uint b = t.begin, n = t.count;
        KdBox box = kd_box_of(t.box), tight = kd_box_of(t.tight);
        tight.lo = fmax(tight.lo, box.lo);
        tight.hi = fmin(tight.hi, box.hi);

        /* The chain of empty-space cuts, each with an empty leaf (kd_emit_large_children). */
        KdLargeCuts cuts;
        kd_empty_space_cuts(&box, tight, t.depth, args.max_depth, args.empty_ratio, &cuts);
        uint self = t.record;
        for (uint cut = 0; cut < cuts.count; ++cut) {
            const uint id = kd_arena_take(&a, KDRAY_DF_RECORDS, 2);
            if (a.full) break;
            const uint code = cuts.code[cut], keep_above = code & 1u;
            rec[id] = kd_build_leaf(0, 0);
            rec[self] = kd_build_inner(code >> 1, cuts.pos[cut], keep_above ? id : id + 1,
                                       keep_above ? id + 1 : id);
            self = id + 1;
        }
        if (a.full) break;

        /* The plane: kd_split_large_nodes' rule, over bins of this node's references. */
        uint axis;
        float pos;
        kd_median_plane(box, &axis, &pos);
#if KDRAY_LARGE_BINS > 0
        {
            uint bins[KDRAY_BIN_VALUES];
            kd_bin_references(wb, b, b + n, tight, bins);
            kd_best_binned_plane(box, tight, bins, n, args.cost_traversal, args.cost_intersection,
                                 args.empty_bonus, &axis, &pos);
        }
#endif
        const uint child_depth = t.depth + cuts.count + 1;
        axis = kd_plane_or_leaf(box, axis, pos, t.depth + cuts.count, args.max_depth);
        /* The above list goes after the range: no room, no split; nor past the budget. */
        const uint level = child_depth - depth0;
        if (axis != KDRAY_LEAF_AXIS &&
            (b + 2 * n > a.cap[KDRAY_DF_WORK] || held[level] + 2 * n > budget)) {
            axis = KDRAY_LEAF_AXIS;
            ++budget_leaves;
        }
        uint2 side_count = (uint2)(n, n);
        KdBox sent[2];
        if (axis == 0)
            side_count = kd_df_partition(b, n, 0, pos, box, triangles, wt, wb, sent);
        else if (axis == 1)
            side_count = kd_df_partition(b, n, 1, pos, box, triangles, wt, wb, sent);
        else if (axis == 2)
            side_count = kd_df_partition(b, n, 2, pos, box, triangles, wt, wb, sent);
        /* A split that separates nothing would recurse forever (kd_count_large_children). The
         * references are the node's own, in order: below the plane is all of them. */
        if (side_count.x == n && side_count.y == n) axis = KDRAY_LEAF_AXIS;
        if (axis == KDRAY_LEAF_AXIS) {
            const uint at = kd_arena_take(&a, KDRAY_DF_LEAF_REFS, n);
            if (a.full) break;
            __global uint* leaf_out = leaf_refs + a.start[KDRAY_DF_LEAF_REFS] + at;
            for (uint k = 0; k < n; ++k) leaf_out[k] = wt[b + k];
            rec[self] = kd_build_leaf(n, at);
            continue;
        }

        held[level] += side_count.x + side_count.y;
        const uint child = kd_arena_take(&a, KDRAY_DF_RECORDS, 2);
        if (a.full) break;
        rec[self] = kd_build_inner(axis, pos, child, child + 1);
        uint end = b; /* the stack's end once the children are placed */
        for (uint side = 0; side < 2; ++side) {
            const uint count = side == 0 ? side_count.x : side_count.y;
            const uint at = side == 0 ? b : b + n; /* where the partition left the list */
            const KdBox child_box = kd_child_box(box, axis, pos, side);
            if (count > args.large_threshold) {
                /* The above list moves down to the stack's end (a move to lower indices). */
                for (uint k = 0; at != end && k < count; ++k) {
                    wt[end + k] = wt[at + k];
                    kd_store_box(wb, end + k, kd_load_box(wb, at + k));
                }
                kd_push_task(&stack[top++], child_box, sent[side], end, count, child_depth,
                             child + side);
                end += count;
            } else if (count > 0) {
                kd_df_small_root(&a, at, count, child_box, child_depth, child + side, wt, wb, rec,
                                 roots, small_tri, small_box);
                if (a.full) break;
            } else {
                rec[child + side] = kd_build_leaf(0, 0);
            }
        }
        if (a.full) break;
    }
    __global uint* out = counts + (size_t)g * KDRAY_DF_COUNTS;
    for (uint k = 1; k < KDRAY_DF_KINDS; ++k) out[k] = a.used[k];
    out[KDRAY_DF_WORK] = a.full;
    out[KDRAY_DF_BUDGET_LEAVES] = budget_leaves;
}

/* The run's items (the host lists them largest first) taken one at a time off the counter after
 * them in arena (0 from the host) by however many work-items the host launches: one per compute
 * unit on CPUs, so that a work-item that finishes a small subtree takes the next and the cores
 * end together whatever the device's scheduler does with work-groups; one per item on GPUs,
 * which run them all at once. With one work-item per item on CPUs the split was the
 * scheduler's: PoCL gives each thread a contiguous half of the work-groups, which balanced the
 * Kitchen's subtrees by their order alone (and any order by size worse). */
__kernel void kd_build_large_depth_first(
    KdDepthFirstArgs args, uint items, __global const KdLargeNode* deep_root,
    __global const uint* root_ref_start, __global const uint* root_ref_count,
    __global const uint* ref_tri, __global const float* ref_box, __global const float* triangles,
    __global uint* arena, __global uint* work_tri, __global float* work_box,
    __global KdBuildNode* records, __global KdSmallRoot* roots, __global uint* small_tri,
    __global float* small_box, __global uint* leaf_refs, __global KdDepthFirstTask* stacks,
    __global uint* counts) {
    __global uint* next_item = arena + KDRAY_DF_KINDS * (args.nodes + 1) + items;
    for (uint g = atomic_inc(next_item); g < items; g = atomic_inc(next_item))
        kd_build_deep_root(g, args, deep_root, root_ref_start, root_ref_count, ref_tri, ref_box,
                           triangles, arena, work_tri, work_box, records, roots, small_tri,
                           small_box, leaf_refs, stacks, counts);
}

/* Work-item g commits deep root w = item g of a run (whose arenas, starts and counts it is
 * given), unless its arenas ran out in that run (a later run builds and commits it): its arenas
 * copied to the build's stores, its records from base[KDRAY_DF_RECORDS * nodes + w] on (its
 * root's to the deep root's record id), its small roots, their references and its leaf references
 * from their bases; child ids, small root indices and reference offsets made global. Its
 * KdLargeRegion lists the records for the output stage. */
__kernel void kd_commit_depth_first(
    uint nodes, uint items, __global const uint* arena, __global const uint* counts,
    __global const uint* base, __global const KdLargeNode* deep_root,
    __global const KdBuildNode* rec_arena, __global const KdSmallRoot* root_arena,
    __global const uint* small_tri_arena, __global const float* small_box_arena,
    __global const uint* leaf_arena, __global KdBuildNode* records,
    __global KdSmallRoot* small_roots, __global uint* small_ref_tri, __global float* small_ref_box,
    __global uint* small_ref_root, __global uint* leaf_store, __global KdLargeRegion* regions) {
    const uint g = get_global_id(0);
    if (g >= items) return;
    __global const uint* used = counts + (size_t)g * KDRAY_DF_COUNTS;
    if (used[KDRAY_DF_WORK] != 0) return;
    const uint w = kd_depth_first_root(arena, nodes, g);
    const uint root_id = deep_root[w].id;
    const uint rec_base = base[KDRAY_DF_RECORDS * nodes + w];
    const uint root_base = base[KDRAY_DF_ROOTS * nodes + w];
    const uint sref_base = base[KDRAY_DF_SMALL_REFS * nodes + w];
    const uint lref_base = base[KDRAY_DF_LEAF_REFS * nodes + w];
#define KD_ARENA(kind) arena[(kind) * (nodes + 1) + w]
    /* Record j of the arena: the subtree's root first, the others from rec_base on. */
#define KD_GLOBAL_ID(j) ((j) == 0 ? root_id : rec_base + (j)-1)
    for (uint j = 0; j < used[KDRAY_DF_RECORDS]; ++j) {
        KdBuildNode r = rec_arena[KD_ARENA(KDRAY_DF_RECORDS) + j];
        if (r.axis == KDRAY_SMALL_ROOT_AXIS) {
            r.leaf_first += root_base;
        } else if (r.axis == KDRAY_LEAF_AXIS) {
            if (r.leaf_count > 0) r.leaf_first += lref_base;
        } else {
            r.child[0] = KD_GLOBAL_ID(r.child[0]);
            r.child[1] = KD_GLOBAL_ID(r.child[1]);
        }
        records[KD_GLOBAL_ID(j)] = r;
    }
    for (uint q = 0; q < used[KDRAY_DF_ROOTS]; ++q) {
        KdSmallRoot root = root_arena[KD_ARENA(KDRAY_DF_ROOTS) + q];
        const uint first = KD_ARENA(KDRAY_DF_SMALL_REFS) + root.ref_start;
        root.ref_start += sref_base;
        root.node_id = KD_GLOBAL_ID(root.node_id);
        small_roots[root_base + q] = root;
        for (uint k = 0; k < root.ref_count; ++k) {
            small_ref_tri[root.ref_start + k] = small_tri_arena[first + k];
            kd_store_box(small_ref_box, root.ref_start + k,
                         kd_load_box(small_box_arena, first + k));
            small_ref_root[root.ref_start + k] = root_base + q;
        }
    }
    for (uint k = 0; k < used[KDRAY_DF_LEAF_REFS]; ++k)
        leaf_store[lref_base + k] = leaf_arena[KD_ARENA(KDRAY_DF_LEAF_REFS) + k];
    KdLargeRegion region;
    region.root = root_id;
    region.first = rec_base;
    region.count = used[KDRAY_DF_RECORDS] - 1;
    region.pad = 0;
    regions[w] = region;
#undef KD_GLOBAL_ID
#undef KD_ARENA
}

#endif /* KDRAY_BUILD_LARGE_DEPTH_FIRST_CL */
