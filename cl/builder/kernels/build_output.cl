/* build_output.cl — the output stage of Zhou et al. (2008), §4.3: the builder's node records
 * become the preorder KdNode array and leaf index list of core/device/kd_shared.h.
 *
 *   kd_size_subtrees         bottom up, one launch per batch of node ids (children are always in a
 *                            later batch than their parent): nodes and leaf references per subtree
 *                            (a small root's come from the small stage)
 *   kd_place_subtrees        top down, one launch per batch: each child's preorder position (below
 *                            child right after its parent, above child after the below subtree)
 *                            and its first leaf index
 *   kd_size_regions,         the same for the records of the large stage's depth-first
 *   kd_place_regions         schedule, a work-item per subtree (build_large_depth_first.cl)
 *   kd_write_nodes           the large stage's nodes: KdNode and leaf triangle ids
 *   kd_write_small_subtrees  per small root: its subtree, already in preorder, moved into place */
#include "cl/builder/kernels/build_common.cl"

/* Record id's subtree: its nodes and leaf references, from its children's. */
KDRAY_INLINE void kd_size_subtree(uint id, __global const KdBuildNode* records,
                                  __global const uint* small_node_count,
                                  __global const uint* small_leaf_refs,
                                  __global uint* subtree_nodes, __global uint* subtree_refs) {
    const KdBuildNode n = records[id];
    if (n.axis == KDRAY_SMALL_ROOT_AXIS) {
        subtree_nodes[id] = small_node_count[n.leaf_first];
        subtree_refs[id] = small_leaf_refs[n.leaf_first];
    } else if (n.axis == KDRAY_LEAF_AXIS) {
        subtree_nodes[id] = 1;
        subtree_refs[id] = n.leaf_count;
    } else {
        subtree_nodes[id] = 1 + subtree_nodes[n.child[0]] + subtree_nodes[n.child[1]];
        subtree_refs[id] = subtree_refs[n.child[0]] + subtree_refs[n.child[1]];
    }
}

__kernel void kd_size_subtrees(uint begin, uint count, __global const KdBuildNode* records,
                               __global const uint* small_node_count,
                               __global const uint* small_leaf_refs, __global uint* subtree_nodes,
                               __global uint* subtree_refs) {
    const uint k = get_global_id(0);
    if (k >= count) return;
    kd_size_subtree(begin + k, records, small_node_count, small_leaf_refs, subtree_nodes,
                    subtree_refs);
}

/* Record id's children, when it is an inner node. */
KDRAY_INLINE void kd_place_record(uint id, __global const KdBuildNode* records,
                                  __global const uint* subtree_nodes,
                                  __global const uint* subtree_refs, __global uint* position,
                                  __global uint* leaf_position) {
    const KdBuildNode n = records[id];
    if (n.axis == KDRAY_LEAF_AXIS || n.axis == KDRAY_SMALL_ROOT_AXIS) return;
    kd_place_children(id, n.child[0], n.child[1], subtree_nodes, subtree_refs, position,
                      leaf_position);
}

__kernel void kd_place_subtrees(uint begin, uint count, __global const KdBuildNode* records,
                                __global const uint* subtree_nodes,
                                __global const uint* subtree_refs, __global uint* position,
                                __global uint* leaf_position) {
    const uint k = get_global_id(0);
    if (k >= count) return;
    kd_place_record(begin + k, records, subtree_nodes, subtree_refs, position, leaf_position);
}

/* The depth-first large stage's regions (KdLargeRegion, build_large_depth_first.cl): one
 * work-item each walks its records, made parents before children, backwards to size them (its
 * root last: a root's record is also in a batch, which sizes it again, alike) and forwards from
 * its root to place them. Sizes before the batches' sizes, places after the batches' places. */
__kernel void kd_size_regions(uint regions, __global const KdLargeRegion* region,
                              __global const KdBuildNode* records,
                              __global const uint* small_node_count,
                              __global const uint* small_leaf_refs, __global uint* subtree_nodes,
                              __global uint* subtree_refs) {
    const uint w = get_global_id(0);
    if (w >= regions) return;
    const KdLargeRegion r = region[w];
    for (uint k = r.count; k-- > 0;)
        kd_size_subtree(r.first + k, records, small_node_count, small_leaf_refs, subtree_nodes,
                        subtree_refs);
    kd_size_subtree(r.root, records, small_node_count, small_leaf_refs, subtree_nodes,
                    subtree_refs);
}

__kernel void kd_place_regions(uint regions, __global const KdLargeRegion* region,
                               __global const KdBuildNode* records,
                               __global const uint* subtree_nodes,
                               __global const uint* subtree_refs, __global uint* position,
                               __global uint* leaf_position) {
    const uint w = get_global_id(0);
    if (w >= regions) return;
    const KdLargeRegion r = region[w];
    kd_place_record(r.root, records, subtree_nodes, subtree_refs, position, leaf_position);
    for (uint k = 0; k < r.count; ++k)
        kd_place_record(r.first + k, records, subtree_nodes, subtree_refs, position,
                        leaf_position);
}

/* Nodes of the large stage; its leaves list their triangles in the builder's leaf store. */
__kernel void kd_write_nodes(uint count, __global const KdBuildNode* records,
                             __global const uint* position, __global const uint* leaf_position,
                             __global const uint* leaf_store, __global KdNode* nodes,
                             __global uint* leaf_indices) {
    const uint id = get_global_id(0);
    if (id >= count) return;
    const KdBuildNode n = records[id];
    const uint at = position[id];
    if (n.axis == KDRAY_SMALL_ROOT_AXIS) return;
    if (n.axis != KDRAY_LEAF_AXIS) {
        nodes[at] = kd_make_inner(n.axis, n.split, position[n.child[1]]);
        return;
    }
    const uint first = leaf_position[id];
    nodes[at] = kd_make_leaf(n.leaf_count, first);
    for (uint k = 0; k < n.leaf_count; ++k) leaf_indices[first + k] = leaf_store[n.leaf_first + k];
}

/* A small root's subtree (kd_build_small_subtrees, KdSmallNode records) lies in
 * preorder from the root's position on: its child indices and leaf offsets only shift by where
 * the root and its first leaf reference landed. A leaf's mask names its small root's triangles.
 * One launch per batch of small roots (a.roots roots from a.root_begin, references from
 * a.ref_begin), whose records are laid out as kd_build_small_subtrees wrote them; subtrees that
 * outgrew the first pass's records (a.first_scale per reference) are the second's, from
 * second_offset on. */
__kernel void kd_write_small_subtrees(
    KdSmallBatchArgs a, __global const KdSmallRoot* small_roots,
    __global const KdSmallNode* first_nodes, __global const KdSmallNode* second_nodes,
    __global const uint* second_offset, __global const uint* subtree_node_count,
    __global const uint* position, __global const uint* leaf_position,
    __global const uint* small_ref_tri, __global KdNode* nodes, __global uint* leaf_indices) {
    if (get_global_id(0) >= a.roots) return;
    const uint root_begin = a.root_begin, first_scale = a.first_scale;
    const uint q = root_begin + (uint)get_global_id(0);
    const KdSmallRoot root = small_roots[q];
    const uint start = root.ref_start, count = subtree_node_count[q];
    const size_t units = (start - a.ref_begin) + (q - root_begin);
    __global const KdSmallNode* in = count <= first_scale * (root.ref_count + 1)
                                         ? first_nodes + (size_t)first_scale * units
                                         : second_nodes + second_offset[q - root_begin];
    const uint at = position[root.node_id], first = leaf_position[root.node_id];
    for (uint j = 0; j < count; ++j) {
        const KdSmallNode r = in[j];
        const uint axis = r.axis_and_offset & 3u, offset = r.axis_and_offset >> 2;
        if (axis != KDRAY_LEAF_AXIS) {
            nodes[at + j] = kd_make_inner(axis, as_float(r.split_or_count), at + offset);
            continue;
        }
        nodes[at + j] = kd_make_leaf(r.split_or_count, first + offset);
        uint out = first + offset;
        for (ulong rest = ((ulong)r.mask_hi << 32) | (ulong)r.mask_lo; rest != 0;
             rest &= rest - 1) {
            leaf_indices[out++] = small_ref_tri[start + kd_lowest_bit(rest)];
        }
    }
}
