/* build_output.cl — the output stage of Zhou et al. (2008), §4.3: the builder's node records
 * become the preorder KdNode array and leaf index list of core/kd_shared.h.
 *
 *   kd_size_subtrees    bottom up, one launch per batch of node ids (children are always in a
 *                       later batch than their parent): nodes and leaf references per subtree
 *   kd_place_subtrees   top down, one launch per batch: each child's preorder position (below
 *                       child right after its parent, above child after the below subtree) and
 *                       its first leaf index
 *   kd_write_nodes      every node at once: the KdNode and its leaf's triangle ids */
#include "cl/kernels/build_common.cl"

__kernel void kd_size_subtrees(uint begin, uint count, __global const KdBuildNode* records,
                               __global uint* subtree_nodes, __global uint* subtree_refs) {
    const uint k = get_global_id(0);
    if (k >= count) return;
    const uint id = begin + k;
    const KdBuildNode n = records[id];
    if (n.axis == KDRAY_LEAF_AXIS) {
        subtree_nodes[id] = 1;
        subtree_refs[id] = n.leaf_count;
    } else {
        subtree_nodes[id] = 1 + subtree_nodes[n.child[0]] + subtree_nodes[n.child[1]];
        subtree_refs[id] = subtree_refs[n.child[0]] + subtree_refs[n.child[1]];
    }
}

__kernel void kd_place_subtrees(uint begin, uint count, __global const KdBuildNode* records,
                                __global const uint* subtree_nodes,
                                __global const uint* subtree_refs, __global uint* position,
                                __global uint* leaf_position) {
    const uint k = get_global_id(0);
    if (k >= count) return;
    const uint id = begin + k;
    const KdBuildNode n = records[id];
    if (n.axis == KDRAY_LEAF_AXIS) return;
    const uint below = n.child[0], above = n.child[1];
    position[below] = position[id] + 1;
    position[above] = position[id] + 1 + subtree_nodes[below];
    leaf_position[below] = leaf_position[id];
    leaf_position[above] = leaf_position[id] + subtree_refs[below];
}

/* Leaves of the small-node stage name their triangles by a mask over their small root's list;
 * the others by a run of the large stage's leaf store. */
__kernel void kd_write_nodes(uint count, __global const KdBuildNode* records,
                             __global const uint* position, __global const uint* leaf_position,
                             __global const uint* leaf_store, __global const uint* small_ref_tri,
                             __global const uint* root_ref_start, __global KdNode* nodes,
                             __global uint* leaf_indices) {
    const uint id = get_global_id(0);
    if (id >= count) return;
    const KdBuildNode n = records[id];
    const uint at = position[id];
    if (n.axis != KDRAY_LEAF_AXIS) {
        nodes[at] = kd_make_inner(n.axis, n.split, position[n.child[1]]);
        return;
    }
    const uint first = leaf_position[id];
    nodes[at] = kd_make_leaf(n.leaf_count, first);
    const ulong mask = ((ulong)n.mask_hi << 32) | (ulong)n.mask_lo;
    if (mask != 0) {
        const uint start = root_ref_start[n.leaf_first];
        uint out = first;
        for (ulong rest = mask; rest != 0; rest &= rest - 1) {
            const uint j = (uint)popcount((rest & (0ul - rest)) - 1ul);
            leaf_indices[out++] = small_ref_tri[start + j];
        }
    } else {
        for (uint k = 0; k < n.leaf_count; ++k) leaf_indices[first + k] = leaf_store[n.leaf_first + k];
    }
}
