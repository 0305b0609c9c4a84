/* build_large.cl — the first two steps of Zhou, Hou, Wang & Guo, "Real-time kd-tree construction
 * on graphics hardware" (ACM TOG 27(5), 2008): triangle bounding boxes, and the large-node stage
 * (§4.1), which processes every active large node of one tree level at once.
 *
 * One level, as the host chains it (cl/builder/large_level.cpp):
 *   node bounds       the root: segmented reduction of its reference boxes (primitives.cl);
 *                     below it, kd_union_parent_boxes of the boxes distribute wrote per chunk
 *   kd_bin_large_chunks        SAH bins of each reduction chunk (only with KDRAY_LARGE_BINS > 0)
 *   kd_split_large_nodes       empty-space cuts (a chain of them), then the binned SAH plane or
 *                              the spatial median, per node
 *   kd_classify_chunks         below/above per reference, counted per reduction chunk
 *   kd_count_large_children    the node's chunk counts ranked within the node (in place),
 *                              child sizes and kinds per node -> "slot" values, scanned
 *   kd_emit_large_children     node records, next level's large nodes, new small roots
 *   kd_distribute_chunks       references (clipped) into the next level / small roots / leaves,
 *                              and per chunk and side the union of the boxes it wrote
 *
 * The passes over the references go by reduction chunk (at most KDRAY_REDUCE_CHUNK references
 * of one node), one work-item each, in order: a reference's rank among its node's references
 * that go to the same child is its chunk's rank within the node plus a running count, so no per-
 * reference flags are written, scanned and read back. On the 2-core CPU the per-reference
 * version (flags, a scan over twice the references, child boxes for every reference) moved about
 * 260 bytes per reference and level, and the large stage was bound by memory.
 *
 * Slots: every node of the level owns two child slots (2i below, 2i+1 above), and the slot arrays
 * hold KDRAY_SLOT_KINDS segments of 2M values each (core/device/kd_build_shared.h numbers the
 * kinds). One scan over all segments at once gives, for each slot and kind, its rank: the index of
 * a new large node, its first reference, ... A value is the difference of neighbouring scanned
 * entries, so the scans run in place. */
#include "cl/builder/kernels/build_common.cl"
#include "cl/builder/kernels/build_large_rules.cl"

/* Step 1 of §4: each triangle's bounding box, and the identity reference list of the root. */
__kernel void kd_compute_aabbs(__global const float* triangles, uint count,
                               __global float* boxes, __global uint* ref_tri) {
    const uint i = get_global_id(0);
    if (i >= count) return;
    __global const float* t = triangles + (size_t)i * KDRAY_FLOATS_PER_TRIANGLE;
    const float3 a = (float3)(t[0], t[1], t[2]);
    const float3 b = (float3)(t[3], t[4], t[5]);
    const float3 c = (float3)(t[6], t[7], t[8]);
    KdBox box;
    box.lo = fmin(a, fmin(b, c));
    box.hi = fmax(a, fmax(b, c));
    kd_store_box(boxes, i, box);
    ref_tri[i] = i;
}

#if KDRAY_LARGE_BINS > 0
#include "cl/builder/kernels/build_large_sah.cl"

/* The SAH bins of chunk c's references (build_large_sah.cl). */
__kernel void kd_bin_large_chunks(__global const float* ref_box, __global const uint* node_start,
                                  __global const uint* node_count,
                                  __global const uint* node_chunk, uint nodes, uint chunks,
                                  __global const KdLargeNode* node,
                                  __global const float* tight_box, __global uint* chunk_bins) {
    const uint c = get_global_id(0);
    if (c >= chunks) return;
    const uint i = kd_find_segment(node_chunk, nodes, c);
    const uint begin = node_start[i] + (c - node_chunk[i]) * KDRAY_REDUCE_CHUNK;
    const uint end = min(node_start[i] + node_count[i], begin + KDRAY_REDUCE_CHUNK);
    uint counts[KDRAY_BIN_VALUES];
    kd_bin_references(ref_box, begin, end, kd_bin_box(kd_box_of(node[i].box), tight_box, i),
                      counts);
    __global uint* out = chunk_bins + (size_t)c * KDRAY_BIN_VALUES;
    for (uint k = 0; k < KDRAY_BIN_VALUES; ++k) out[k] = counts[k];
}

#endif


/* Split large nodes (§4.1): cut off empty space when the empty slab on one side of the node's
 * tight box exceeds C_e of the node's extent (the largest such slab wins), otherwise split the
 * node's box at the spatial median of its longest axis, or at its cheapest binned SAH plane
 * (above). Nodes at the depth limit, or on a level that would outgrow the reference budget
 * (force_leaf), become leaves.
 *
 * An empty-space cut keeps every reference, unchanged, in its kept child, whose tight box is the
 * same, so the cuts the following levels would make are decided here at once: up to
 * KDRAY_MAX_CUTS cuts (each side at most once) form a chain of nodes, each with an empty leaf,
 * and the last node of the chain gets the median split (or becomes a leaf). The tree is the one
 * a level per cut gives, with fewer levels, i.e. fewer passes over the references: trees
 * byte-identical on kitchen, bunny, dragon_res2, sponza, bart-robots; large levels kitchen 34 ->
 * 29, bunny 19 -> 15; large_nodes stage (loaded 2-core PoCL, same sitting, median of 7 runs)
 * kitchen 174 -> 130 ms, bunny 70 -> 56 ms. The node's box becomes the box of the chain's last
 * node (KdLargeCuts gives the chain). */
__kernel void kd_split_large_nodes(KdLargeSplitArgs a, __global KdLargeNode* node,
                                   __global const float* tight_box,
                                   __global const uint* node_chunk,
                                   __global const uint* node_count,
                                   __global const uint* chunk_bins, __global KdLargeSplit* split,
                                   __global KdLargeCuts* chain) {
    const uint i = get_global_id(0);
    if (i >= a.nodes) return;
    chain[i].count = 0;
    if (a.force_leaf) {
        split[i].axis = KDRAY_LEAF_AXIS;
        return;
    }
    KdBox box = kd_box_of(node[i].box);
    KdBox tight = kd_load_box(tight_box, i);
    tight.lo = fmax(tight.lo, box.lo);
    tight.hi = fmin(tight.hi, box.hi);
    const uint depth = node[i].depth;
    KdLargeCuts cuts;
    kd_empty_space_cuts(&box, tight, depth, a.max_depth, a.empty_ratio, &cuts);
    chain[i] = cuts;
    node[i].box = kd_build_box_of(box);

    uint axis;
    float pos;
    kd_median_plane(box, &axis, &pos);
#if KDRAY_LARGE_BINS > 0
    const uint bins_first = a.bins_by_node ? i : node_chunk[i];
    const uint bins_end = a.bins_by_node ? i + 1 : node_chunk[i + 1];
    kd_best_large_split(box, tight, chunk_bins, bins_first, bins_end, node_count[i],
                        a.cost_traversal, a.cost_intersection, a.empty_bonus, &axis, &pos);
#endif
    KdLargeSplit s;
    s.axis = kd_plane_or_leaf(box, axis, pos, depth + cuts.count, a.max_depth);
    s.pos = pos;
    split[i] = s;
}

/* Per reference of a chunk, the children it goes to (KDRAY_BELOW | KDRAY_ABOVE), and
 * KDRAY_CLIPPED when its box straddles the plane: its box in each child it enters is then in
 * child_box (at [side * refs + r]), not ref_box. */
#define KDRAY_CLIPPED 4u

/* Reference r of a node (box `node`) against its split plane: its sides, KDRAY_BELOW |
 * KDRAY_ABOVE, with KDRAY_CLIPPED and its box in each child it enters written to child_box (at
 * [side * refs + r]) when it straddles the plane. Always inlined, and called with a constant axis,
 * so that each copy reads that axis's coordinates directly (with the axis a variable, the loop
 * picked them by masked moves); with the clipping inlined too (no box copied to the stack per
 * call), Kitchen build 85.9 -> 76.8 ms (median of 6 interleaved rounds of 7 builds). Both large
 * stages call it: a chunk's loop (kd_classify_chunks) and a work-item per reference
 * (build_large_groups.cl). */
KDRAY_HOT_INLINE uint kd_classify_reference(uint r, uint refs, const uint axis, float split,
                                            uint planar, KdBox node, __global const uint* ref_tri,
                                            __global const float* ref_box,
                                            __global const float* triangles,
                                            __global float* child_box) {
    __global const float* box = ref_box + (size_t)r * KDRAY_BOX_FLOATS;
    uint sides = kd_classify(box[axis], box[3 + axis], split, planar);
    if (sides == (KDRAY_BELOW | KDRAY_ABOVE)) {
        KdBox below, above;
        __global const float* tri = triangles + (size_t)ref_tri[r] * KDRAY_FLOATS_PER_TRIANGLE;
        const uint entered =
            kd_clip_straddler(kd_load_box(ref_box, r), tri, axis, split, node, &below, &above);
        kd_store_box(child_box, r, below);
        kd_store_box(child_box, (size_t)refs + r, above);
        sides = (entered ? entered : sides) | KDRAY_CLIPPED;
    }
    return sides;
}

/* The references begin..end of one node against its split plane, kd_classify_chunks' loop:
 * returns the counts going below and above. */
KDRAY_HOT_INLINE uint2 kd_classify_references(uint begin, uint end, uint refs, const uint axis,
                                              float split, uint planar, KdBox node,
                                              __global const uint* ref_tri,
                                              __global const float* ref_box,
                                              __global const float* triangles,
                                              __global uchar* ref_sides,
                                              __global float* child_box) {
    uint below = 0, above = 0;
    for (uint r = begin; r < end; ++r) {
        const uint sides = kd_classify_reference(r, refs, axis, split, planar, node, ref_tri,
                                                 ref_box, triangles, child_box);
        ref_sides[r] = (uchar)sides;
        below += (sides & KDRAY_BELOW) != 0;
        above += (sides & KDRAY_ABOVE) != 0;
    }
    return (uint2)(below, above);
}

/* Classify chunk c's references (a leaf node's get no sides): ref_sides[r] as above, and the
 * chunk's counts of references going below (chunk_counts[c]) and above (chunk_counts[chunks +
 * c]), ranked within the node by kd_count_large_children. A reference lying flat in a large
 * node's plane goes below (the planar_sides of kd_classify). A box on one side of the plane
 * keeps it; a straddling one becomes the bounds of the triangle's part in each child (§4.1, at
 * worst the box cut at the plane), and a triangle that lies on one side within the node after
 * all (a diagonal sliver) enters that side only. Clipping here, once, rather than again when distributing, halved the clipping work
 * (10% of a kitchen build). */
__kernel void kd_classify_chunks(KdLargeLevelArgs a, __global const uint* node_ref_start,
                                 __global const uint* node_ref_count,
                                 __global const uint* node_chunk, __global const uint* ref_tri,
                                 __global const float* ref_box, __global const float* triangles,
                                 __global const KdLargeNode* large_node,
                                 __global const KdLargeSplit* node_split,
                                 __global uchar* ref_sides, __global float* child_box,
                                 __global uint* chunk_counts) {
    const uint c = get_global_id(0);
    const uint chunks = a.chunks, refs = a.refs;
    if (c >= chunks) return;
    const uint i = kd_find_segment(node_chunk, a.nodes, c);
    const uint begin = node_ref_start[i] + (c - node_chunk[i]) * KDRAY_REDUCE_CHUNK;
    const uint end = min(node_ref_start[i] + node_ref_count[i], begin + KDRAY_REDUCE_CHUNK);
    const uint axis = node_split[i].axis;
    uint2 counts = (uint2)(0, 0);
    if (axis == KDRAY_LEAF_AXIS) {
        for (uint r = begin; r < end; ++r) ref_sides[r] = 0;
    } else {
        const float split = node_split[i].pos;
        const uint planar = KDRAY_BELOW;
        const KdBox node = kd_box_of(large_node[i].box);
        if (axis == 0)
            counts = kd_classify_references(begin, end, refs, 0, split, planar, node, ref_tri,
                                            ref_box, triangles, ref_sides, child_box);
        else if (axis == 1)
            counts = kd_classify_references(begin, end, refs, 1, split, planar, node, ref_tri,
                                            ref_box, triangles, ref_sides, child_box);
        else
            counts = kd_classify_references(begin, end, refs, 2, split, planar, node, ref_tri,
                                            ref_box, triangles, ref_sides, child_box);
    }
    chunk_counts[c] = counts.x;
    chunk_counts[chunks + c] = counts.y;
}

/* Value of slot `s` of kind `k` and its rank among the level's slots of that kind, from the
 * in-place scanned slot array (slots = 2 * nodes per kind). */
KDRAY_INLINE uint kd_slot_value(__global const uint* slot_rank, uint slots, uint k, uint s) {
    return slot_rank[k * slots + s + 1] - slot_rank[k * slots + s];
}
KDRAY_INLINE uint kd_slot_rank(__global const uint* slot_rank, uint slots, uint k, uint s) {
    return slot_rank[k * slots + s] - slot_rank[k * slots];
}

/* Count each node's children and give every child its kind: more than T references stay large
 * (or, at most deep_refs of them, go to the depth-first schedule: a deep root), 1..T become small
 * roots (§4.2), none an empty leaf. A split that separates nothing (both
 * children keep all references, e.g. a stack of coincident triangles) would recurse forever, so
 * the node becomes a leaf instead. The node's chunk counts (classify's) become, in place, each
 * chunk's rank within the node per side: what distribute adds its own running count to. A scan
 * over all chunks of the level did that in 1-3 launches and a pass of its own; per node it is a
 * loop over the node's chunks (432 at Kitchen's root, fewer below), no more work than the scan. */
__kernel void kd_count_large_children(KdLargeLevelArgs a, __global const uint* node_ref_count,
                                      __global const uint* node_chunk,
                                      __global KdLargeSplit* split,
                                      __global const KdLargeCuts* chain,
                                      __global uint* chunk_rank, __global uint* slot_values) {
    const uint i = get_global_id(0);
    const uint nodes = a.nodes, chunks = a.chunks;
    if (i >= nodes) return;
    const uint slots = 2 * nodes;
    for (uint k = 0; k < KDRAY_SLOT_KINDS; ++k) {
        slot_values[k * slots + 2 * i] = 0;
        slot_values[k * slots + 2 * i + 1] = 0;
    }
    const uint count = node_ref_count[i];
    const uint first = node_chunk[i], last = node_chunk[i + 1];
    uint axis = split[i].axis;
    uint n[2] = {0, 0};
    if (axis != KDRAY_LEAF_AXIS) {
        for (uint c = first; c < last; ++c) {
            const uint below = chunk_rank[c], above = chunk_rank[chunks + c];
            chunk_rank[c] = n[0];
            chunk_rank[chunks + c] = n[1];
            n[0] += below;
            n[1] += above;
        }
        if (n[0] == count && n[1] == count) {
            axis = KDRAY_LEAF_AXIS;
            split[i].axis = axis;
        }
    }
    /* Generation g of the node's new nodes: the pair of the chain's g-th cut, then the pair of
     * the median split (kd_split_large_nodes). */
    const uint cuts = chain[i].count;
    for (uint g = 0; g < cuts; ++g) slot_values[(KDRAY_SLOT_CHILD + g) * slots + 2 * i] = 2;
    if (axis == KDRAY_LEAF_AXIS) {
        slot_values[KDRAY_SLOT_LEAF_REFS * slots + 2 * i] = count;
        return;
    }
    slot_values[(KDRAY_SLOT_CHILD + cuts) * slots + 2 * i] = 2;
    for (uint side = 0; side < 2; ++side) {
        const uint s = 2 * i + side;
        if (n[side] > a.large_threshold && n[side] <= a.deep_refs) {
            slot_values[KDRAY_SLOT_DEEP * slots + s] = 1;
            slot_values[KDRAY_SLOT_DEEP_REFS * slots + s] = n[side];
        } else if (n[side] > a.large_threshold) {
            slot_values[KDRAY_SLOT_LARGE * slots + s] = 1;
            slot_values[KDRAY_SLOT_LARGE_REFS * slots + s] = n[side];
            slot_values[KDRAY_SLOT_LARGE_CHUNKS * slots + s] =
                (n[side] + KDRAY_REDUCE_CHUNK - 1) / KDRAY_REDUCE_CHUNK;
        } else if (n[side] > 0) {
            slot_values[KDRAY_SLOT_SMALL * slots + s] = 1;
            slot_values[KDRAY_SLOT_SMALL_REFS * slots + s] = n[side];
        }
    }
}

/* Write this level's node records and create its children: the next level's large nodes, deep
 * roots (appended to the depth-first schedule's), new small roots (appended to the small stage's
 * roots) and empty leaves. The bases in `a` are where this level's new node ids, deep roots and
 * their references, small roots, small references and leaf references start. */
__kernel void kd_emit_large_children(KdLargeLevelArgs a, __global const KdLargeNode* node,
                                     __global const uint* node_ref_count,
                                     __global const KdLargeSplit* node_split,
                                     __global const KdLargeCuts* chain,
                                     __global const uint* slot_rank, __global KdBuildNode* records,
                                     __global KdLargeNode* next_node,
                                     __global uint* next_ref_start, __global uint* next_ref_count,
                                     __global uint* next_chunk_start, __global uint* next_parent,
                                     __global KdSmallRoot* small_roots,
                                     __global KdLargeNode* deep_node,
                                     __global uint* deep_ref_start,
                                     __global uint* deep_ref_count) {
    const uint i = get_global_id(0);
    const uint nodes = a.nodes;
    if (i >= nodes) return;
    const uint slots = 2 * nodes;
    if (i == 0) {
        /* The next level's chunk starts end with the total, as the reduction expects. */
        const uint next_nodes = kd_slot_rank(slot_rank, slots, KDRAY_SLOT_LARGE, slots);
        next_chunk_start[next_nodes] =
            kd_slot_rank(slot_rank, slots, KDRAY_SLOT_LARGE_CHUNKS, slots);
    }
    /* New ids come by generation (all first pairs, then all second pairs, ...), so that every
     * child's id lies in a later batch than its parent's (build_output.cl). */
    uint generation_base[KDRAY_MAX_CUTS + 1];
    for (uint g = 0, base = a.node_base; g <= KDRAY_MAX_CUTS; ++g) {
        generation_base[g] = base;
        base += kd_slot_rank(slot_rank, slots, KDRAY_SLOT_CHILD + g, slots);
    }
    /* The chain of empty-space cuts: each node's empty side is an empty leaf. */
    const uint cuts = chain[i].count;
    const KdLargeNode parent = node[i];
    uint self = parent.id;
    for (uint g = 0; g < cuts; ++g) {
        const uint id =
            generation_base[g] + kd_slot_rank(slot_rank, slots, KDRAY_SLOT_CHILD + g, 2 * i);
        const uint code = chain[i].code[g], keep_above = code & 1u;
        records[id] = kd_build_leaf(0, 0);
        records[self] = kd_build_inner(code >> 1, chain[i].pos[g], keep_above ? id : id + 1,
                                       keep_above ? id + 1 : id);
        self = id + 1;
    }
    const uint axis = node_split[i].axis;
    if (axis == KDRAY_LEAF_AXIS) {
        records[self] = kd_build_leaf(
            node_ref_count[i],
            a.leaf_ref_base + kd_slot_rank(slot_rank, slots, KDRAY_SLOT_LEAF_REFS, 2 * i));
        return;
    }
    const uint child_depth = parent.depth + cuts + 1;
    const float split = node_split[i].pos;
    const KdBox box = kd_box_of(parent.box);
    const uint first_child =
        generation_base[cuts] + kd_slot_rank(slot_rank, slots, KDRAY_SLOT_CHILD + cuts, 2 * i);
    uint child_id[2];
    for (uint side = 0; side < 2; ++side) {
        const uint s = 2 * i + side;
        const uint id = first_child + side;
        child_id[side] = id;
        const KdBox child = kd_child_box(box, axis, split, side);
        if (kd_slot_value(slot_rank, slots, KDRAY_SLOT_LARGE, s)) {
            const uint j = kd_slot_rank(slot_rank, slots, KDRAY_SLOT_LARGE, s);
            KdLargeNode large;
            large.box = kd_build_box_of(child);
            large.id = id;
            large.depth = child_depth;
            next_node[j] = large;
            next_ref_start[j] = kd_slot_rank(slot_rank, slots, KDRAY_SLOT_LARGE_REFS, s);
            next_ref_count[j] = kd_slot_value(slot_rank, slots, KDRAY_SLOT_LARGE_REFS, s);
            next_chunk_start[j] = kd_slot_rank(slot_rank, slots, KDRAY_SLOT_LARGE_CHUNKS, s);
            next_parent[j] = s;
        } else if (kd_slot_value(slot_rank, slots, KDRAY_SLOT_DEEP, s)) {
            const uint j = a.deep_root_base + kd_slot_rank(slot_rank, slots, KDRAY_SLOT_DEEP, s);
            KdLargeNode deep;
            deep.box = kd_build_box_of(child);
            deep.id = id;
            deep.depth = child_depth;
            deep_node[j] = deep;
            deep_ref_start[j] =
                a.deep_ref_base + kd_slot_rank(slot_rank, slots, KDRAY_SLOT_DEEP_REFS, s);
            deep_ref_count[j] = kd_slot_value(slot_rank, slots, KDRAY_SLOT_DEEP_REFS, s);
        } else if (kd_slot_value(slot_rank, slots, KDRAY_SLOT_SMALL, s)) {
            const uint q = a.small_root_base + kd_slot_rank(slot_rank, slots, KDRAY_SLOT_SMALL, s);
            KdSmallRoot root;
            root.box = kd_build_box_of(child);
            root.ref_start =
                a.small_ref_base + kd_slot_rank(slot_rank, slots, KDRAY_SLOT_SMALL_REFS, s);
            root.ref_count = kd_slot_value(slot_rank, slots, KDRAY_SLOT_SMALL_REFS, s);
            root.node_id = id;
            root.depth = child_depth;
            small_roots[q] = root;
            records[id] = kd_build_small_root(q);
        } else {
            records[id] = kd_build_leaf(0, 0);
        }
    }
    records[self] = kd_build_inner(axis, split, child_id[0], child_id[1]);
}

/* Where node i's children take chunk c's references (both distribute kernels): per side, the
 * index of the chunk's first reference there (the child's first reference, in the next level, in
 * the deep roots' list or in the small roots' list, plus the chunk's rank within the node), the
 * child's kind (KDRAY_SLOT_LARGE, KDRAY_SLOT_DEEP or KDRAY_SLOT_SMALL), and its small root. */
KDRAY_INLINE void kd_child_targets(KdLargeLevelArgs a, uint i, uint c,
                                   __global const uint* chunk_rank,
                                   __global const uint* slot_rank, uint* dst, uint* kind,
                                   uint* root) {
    const uint slots = 2 * a.nodes;
    for (uint side = 0; side < 2; ++side) {
        const uint s = 2 * i + side;
        const uint within = chunk_rank[side * a.chunks + c];
        if (kd_slot_value(slot_rank, slots, KDRAY_SLOT_LARGE, s)) {
            kind[side] = KDRAY_SLOT_LARGE;
            dst[side] = within + kd_slot_rank(slot_rank, slots, KDRAY_SLOT_LARGE_REFS, s);
        } else if (kd_slot_value(slot_rank, slots, KDRAY_SLOT_DEEP, s)) {
            kind[side] = KDRAY_SLOT_DEEP;
            dst[side] = within + a.deep_ref_base +
                        kd_slot_rank(slot_rank, slots, KDRAY_SLOT_DEEP_REFS, s);
        } else {
            kind[side] = KDRAY_SLOT_SMALL;
            dst[side] = within + a.small_ref_base +
                        kd_slot_rank(slot_rank, slots, KDRAY_SLOT_SMALL_REFS, s);
        }
        root[side] = a.small_root_base + kd_slot_rank(slot_rank, slots, KDRAY_SLOT_SMALL, s);
    }
}

/* The arrays a level's references go to (both distribute kernels): the next level's, the deep
 * roots' and the small roots'. */
typedef struct KdChildRefs {
    __global uint* next_tri;
    __global float* next_box;
    __global uint* deep_tri;
    __global float* deep_box;
    __global uint* small_tri;
    __global float* small_box;
    __global uint* small_root;
} KdChildRefs;

/* Reference r (triangle tri, KDRAY_BELOW/ABOVE/CLIPPED `sides`) to its child on `side` at index
 * `at`: its box (the clipped one when it straddled) to the next level, to the deep roots' list or
 * to the child's small root, and into sent[side], the union of what the chunk sends there. */
KDRAY_INLINE void kd_send_reference(uint r, uint refs, uint tri, uint sides, uint side, uint at,
                                    uint kind, uint root, __global const float* ref_box,
                                    __global const float* child_box, const KdChildRefs* out,
                                    KdBox* sent) {
    const KdBox b = kd_load_box(sides & KDRAY_CLIPPED ? child_box : ref_box,
                                sides & KDRAY_CLIPPED ? (size_t)side * refs + r : r);
    sent[side].lo = fmin(sent[side].lo, b.lo);
    sent[side].hi = fmax(sent[side].hi, b.hi);
    if (kind == KDRAY_SLOT_LARGE) {
        out->next_tri[at] = tri;
        kd_store_box(out->next_box, at, b);
    } else if (kind == KDRAY_SLOT_DEEP) {
        out->deep_tri[at] = tri;
        kd_store_box(out->deep_box, at, b);
    } else {
        out->small_tri[at] = tri;
        kd_store_box(out->small_box, at, b);
        out->small_root[at] = root;
    }
}

/* Move chunk c's references to their children (with the box kd_classify_chunks clipped to each
 * child of a straddling one), to the next level, to its small root's list, or to the leaf store,
 * in reference order: a reference's rank in its child is the chunk's scanned count plus those
 * before it in the chunk. side_box[side * chunks + c] gets the union of the boxes the chunk sent
 * to that side (empty for a leaf's chunk): a next-level node's tight box is the union of its
 * parent's chunks' (kd_union_parent_boxes), so no pass reads the next level's boxes again to
 * reduce them. */
__kernel void kd_distribute_chunks(
    KdLargeLevelArgs a, __global const uint* node_ref_start, __global const uint* node_ref_count,
    __global const uint* node_chunk, __global const uint* ref_tri, __global const float* ref_box,
    __global const uchar* ref_sides, __global const float* child_box,
    __global const KdLargeSplit* split, __global const uint* chunk_rank,
    __global const uint* slot_rank, __global uint* next_ref_tri, __global float* next_ref_box,
    __global uint* deep_ref_tri, __global float* deep_ref_box, __global uint* small_ref_tri,
    __global float* small_ref_box, __global uint* small_ref_root, __global uint* leaf_refs,
    __global float* side_box) {
    const uint c = get_global_id(0);
    const uint chunks = a.chunks, refs = a.refs, nodes = a.nodes;
    if (c >= chunks) return;
    const uint slots = 2 * nodes;
    const uint i = kd_find_segment(node_chunk, nodes, c);
    const uint start = node_ref_start[i];
    const uint begin = start + (c - node_chunk[i]) * KDRAY_REDUCE_CHUNK;
    const uint end = min(start + node_ref_count[i], begin + KDRAY_REDUCE_CHUNK);
    KdBox sent[2];
    sent[0].lo = sent[1].lo = (float3)(INFINITY);
    sent[0].hi = sent[1].hi = (float3)(-INFINITY);
    if (split[i].axis == KDRAY_LEAF_AXIS) {
        const uint first =
            a.leaf_ref_base + kd_slot_rank(slot_rank, slots, KDRAY_SLOT_LEAF_REFS, 2 * i) - start;
        for (uint r = begin; r < end; ++r) leaf_refs[first + r] = ref_tri[r];
        kd_store_box(side_box, c, sent[0]);
        kd_store_box(side_box, chunks + c, sent[1]);
        return;
    }
    uint dst[2], kind[2], root[2];
    kd_child_targets(a, i, c, chunk_rank, slot_rank, dst, kind, root);
    const KdChildRefs out = {next_ref_tri,  next_ref_box,  deep_ref_tri,  deep_ref_box,
                             small_ref_tri, small_ref_box, small_ref_root};
    for (uint r = begin; r < end; ++r) {
        const uint sides = ref_sides[r], tri = ref_tri[r];
        for (uint side = 0; side < 2; ++side)
            if (sides & (side == 0 ? KDRAY_BELOW : KDRAY_ABOVE))
                kd_send_reference(r, refs, tri, sides, side, dst[side]++, kind[side], root[side],
                                  ref_box, child_box, &out, sent);
    }
    kd_store_box(side_box, c, sent[0]);
    kd_store_box(side_box, chunks + c, sent[1]);
}

/* Node bounds below the root: node j of this level is side s = parent[j] & 1 of node
 * parent[j] >> 1 of the level before, whose chunks parent_chunk[p] .. parent_chunk[p + 1] each
 * left in side_box the union of the boxes they sent to that side; j's tight box is their union,
 * the same min and max that reducing j's references gives. */
__kernel void kd_union_parent_boxes(__global const uint* parent, __global const uint* parent_chunk,
                                    uint parent_chunks, __global const float* side_box,
                                    uint nodes, __global float* tight_box) {
    const uint j = get_global_id(0);
    if (j >= nodes) return;
    const uint p = parent[j] >> 1, side = parent[j] & 1u;
    KdBox box;
    box.lo = (float3)(INFINITY);
    box.hi = (float3)(-INFINITY);
    for (uint c = parent_chunk[p]; c < parent_chunk[p + 1]; ++c) {
        const KdBox b = kd_load_box(side_box, (size_t)side * parent_chunks + c);
        box.lo = fmin(box.lo, b.lo);
        box.hi = fmax(box.hi, b.hi);
    }
    kd_store_box(tight_box, j, box);
}

/* The same passes with a work-item per reference (the element-parallel large stage). */
#include "cl/builder/kernels/build_large_groups.cl"

/* The stage's depth-first schedule below the top levels (CPU devices). */
#include "cl/builder/kernels/build_large_depth_first.cl"
