// small_levels.cpp — the host side of the per-level small stage (§4.2, build_small_level.cl;
// small_levels.h).
#include "cl/builder/small_levels.h"

#include <algorithm>
#include <cstdint>
#include <utility>
#include <vector>

#include "cl/runtime/launch.h"

namespace kdray::build_detail {

/* The paper's shape: a launch per level, a work-group per node, the host reading back the next
 * level's size (one read per level, as the large stage does). The nodes of every level stay in
 * one array, so that the subtrees' preorder can be laid out afterwards: sizes bottom up and
 * positions top down, a launch per level (the output stage's method, build_output.cl), then
 * every node's record written where the per-root kernel writes it.
 *
 * On PoCL's CPU device this shape is the slower one, which is why auto keeps per-root there:
 * BART Kitchen frame 0, small_nodes 8373 ms per level against 525 ms per root, the same tree
 * (690461 nodes, SAH 338.03), peak device memory 232 against 79 MB (median of 5 interleaved
 * `kdray build --repeat 3` processes, the last build's stage time, a 2-core machine shared at a
 * load of about 7). A group of 64 works for every node, however few its references, and each
 * node on a re-clipped table clips its ancestor's triangles again: with --reclip-refs 0 the
 * figures were 5863 against 928 ms (one build each, same load). */
void build_batch_levels(BuildContext& ctx, const SmallRoots& small, const TriangleBounds& triangles,
                        SmallSubtrees& out, SmallBatch& batch) {
    BuilderKernels& k = ctx.kernels;
    const KdSmallBatchArgs args = batch.args(ctx.params, 0);

    /* The levels, from the roots down; each appends the next level's nodes. Room for about 3
     * nodes per reference up front (subtrees average 2.8 on the BART Kitchen), doubling when
     * short. */
    DeviceArray nodes = ctx.allocate<KdSmallLevelNode>(batch.roots, "small level nodes",
                                                       3 * (std::size_t(batch.refs) + batch.roots));
    DeviceArray next_free = ctx.allocate<cl_uint>(1, "small level node count");
    enqueue_kernel(ctx.device, k.start_small_level, batch.roots, args, small.roots.buffer(),
                   nodes.buffer());
    std::vector<std::pair<cl_uint, cl_uint>> levels;  // (first node, count)
    cl_uint begin = 0, count = batch.roots;
    while (count > 0) {
        levels.emplace_back(begin, count);
        const cl_uint end = begin + count;
        // A split node has two children.
        const cl_uint room =
            checked_u32(std::uint64_t(end) + 2 * std::uint64_t(count), "small level nodes");
        ctx.reserve<KdSmallLevelNode>(nodes, room, end, "small level nodes");
        ctx.primitives.fill(next_free.buffer(), end, 1);
        enqueue_kernel(ctx.device, k.split_small_level, std::size_t(count) * KDRAY_LAUNCH_GROUP,
                       args, begin, count, small.roots.buffer(), small.ref_box.buffer(),
                       out.side_masks.buffer(), small.ref_tri.buffer(),
                       triangles.triangles.buffer(), nodes.buffer(), next_free.buffer());
        begin = end;
        count = ctx.read_uint(next_free, 0) - end;
    }
    const cl_uint total = begin;

    /* Each subtree's preorder: sizes bottom up, then positions from the roots' 0 down. */
    DeviceArray subtree_nodes = ctx.allocate<cl_uint>(total, "small subtree node counts");
    DeviceArray subtree_refs = ctx.allocate<cl_uint>(total, "small subtree reference counts");
    DeviceArray position = ctx.allocate<cl_uint>(total, "small preorder positions");
    DeviceArray leaf_position = ctx.allocate<cl_uint>(total, "small leaf positions");
    for (auto it = levels.rbegin(); it != levels.rend(); ++it)
        enqueue_kernel(ctx.device, k.size_small_level, it->second, it->first, it->second,
                       nodes.buffer(), subtree_nodes.buffer(), subtree_refs.buffer());
    ctx.primitives.fill(position.buffer(), 0, batch.roots);
    ctx.primitives.fill(leaf_position.buffer(), 0, batch.roots);
    for (const auto& [first, n] : levels)
        enqueue_kernel(ctx.device, k.place_small_level, n, first, n, nodes.buffer(),
                       subtree_nodes.buffer(), subtree_refs.buffer(), position.buffer(),
                       leaf_position.buffer());
    enqueue_kernel(ctx.device, k.count_small_level, batch.roots, args, subtree_nodes.buffer(),
                   subtree_refs.buffer(), out.node_count.buffer(), out.leaf_refs.buffer());

    /* The records, laid out as the per-root kernel's: the first pass's run per root, and exactly
     * the node counts of the subtrees that outgrow it. */
    batch.records[0] = ctx.allocate<KdSmallNode>(
        checked_u32(std::uint64_t(batch.first_scale) * (std::uint64_t(batch.refs) + batch.roots),
                    "small node records"),
        "small node records");
    const cl_uint second_records = place_second_pass(ctx, small, out, batch);
    if (second_records > 0)
        batch.records[1] =
            ctx.allocate<KdSmallNode>(second_records, "small node records (second pass)");
    const DeviceArray& second = batch.records[second_records > 0 ? 1 : 0];
    enqueue_kernel(ctx.device, k.write_small_level, total, args, total, small.roots.buffer(),
                   nodes.buffer(), out.node_count.buffer(), position.buffer(),
                   leaf_position.buffer(), batch.second_offset.buffer(), batch.records[0].buffer(),
                   second.buffer());
    out.nodes = checked_u32(std::uint64_t(out.nodes) + total, "small nodes");
    out.levels = std::max(out.levels, int(levels.size()));
}

}  // namespace kdray::build_detail
