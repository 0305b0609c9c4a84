// output.cpp — the host side of the output stage (§4.3, build_output.cl; output.h).
#include "cl/builder/output.h"

#include <vector>

#include "cl/runtime/launch.h"

namespace kdray::build_detail {

PreorderTree write_preorder(BuildContext& ctx, const BuildOutput& output, const SmallRoots& small,
                            const SmallSubtrees& subtrees) {
    BuilderKernels& k = ctx.kernels;
    PreorderTree tree;
    // Each small root's record stands for its subtree, whose node count includes the root.
    const std::size_t records = output.node_count,
                      count = std::size_t(output.node_count) - small.count + subtrees.nodes;
    check_offset_limit(count, "nodes");
    tree.node_count = cl_uint(count);

    /* Subtree sizes bottom up: the depth-first subtrees', then one launch per batch of ids
     * (children lie in later batches). */
    DeviceArray subtree_nodes = ctx.allocate<cl_uint>(records, "subtree node counts");
    DeviceArray subtree_refs = ctx.allocate<cl_uint>(records, "subtree reference counts");
    DeviceArray position = ctx.allocate<cl_uint>(records, "preorder positions");
    DeviceArray leaf_position = ctx.allocate<cl_uint>(records, "leaf index positions");
    enqueue_per_item(ctx.device, k.size_regions, output.region_count, output.region_count,
                     output.regions.buffer(), output.records.buffer(), subtrees.node_count.buffer(),
                     subtrees.leaf_refs.buffer(), subtree_nodes.buffer(), subtree_refs.buffer());
    for (auto it = output.batches.rbegin(); it != output.batches.rend(); ++it)
        enqueue_kernel(ctx.device, k.size_subtrees, it->second, it->first, it->second,
                       output.records.buffer(), subtrees.node_count.buffer(),
                       subtrees.leaf_refs.buffer(), subtree_nodes.buffer(), subtree_refs.buffer());

    /* Preorder positions top down, from the root's. */
    ctx.write(position, std::vector<cl_uint>{0});
    ctx.write(leaf_position, std::vector<cl_uint>{0});
    for (const auto& [begin, n] : output.batches)
        enqueue_kernel(ctx.device, k.place_subtrees, n, begin, n, output.records.buffer(),
                       subtree_nodes.buffer(), subtree_refs.buffer(), position.buffer(),
                       leaf_position.buffer());
    enqueue_per_item(ctx.device, k.place_regions, output.region_count, output.region_count,
                     output.regions.buffer(), output.records.buffer(), subtree_nodes.buffer(),
                     subtree_refs.buffer(), position.buffer(), leaf_position.buffer());
    tree.leaf_index_count = ctx.read_uint(subtree_refs, 0);
    check_offset_limit(tree.leaf_index_count, "leaf references");

    /* The nodes: the large stage's records, then each small root's subtree moved into place. */
    tree.nodes = ctx.allocate<KdNode>(count, "kd-tree nodes");
    tree.leaf_indices = ctx.allocate<cl_uint>(tree.leaf_index_count, "kd-tree leaf indices");
    enqueue_kernel(ctx.device, k.write_nodes, records, cl_uint(records), output.records.buffer(),
                   position.buffer(), leaf_position.buffer(), output.leaf_store.buffer(),
                   tree.nodes.buffer(), tree.leaf_indices.buffer());
    for (const SmallBatch& batch : subtrees.batches) {
        // Without a second pass no root reads its records or offsets: any buffer will do.
        const bool second_pass = batch.records[1].bytes() != 0;
        const cl::Buffer& second = batch.records[second_pass ? 1 : 0].buffer();
        const cl::Buffer& offsets = (second_pass ? batch.second_offset : batch.records[0]).buffer();
        enqueue_kernel(ctx.device, k.write_small, batch.roots, batch.args(ctx.params, 0),
                       small.roots.buffer(), batch.records[0].buffer(), second, offsets,
                       subtrees.node_count.buffer(), position.buffer(), leaf_position.buffer(),
                       small.ref_tri.buffer(), tree.nodes.buffer(), tree.leaf_indices.buffer());
    }
    return tree;
}

}  // namespace kdray::build_detail
