// opencl_builder_small.cpp — the host side of the OpenCL builder's small-node stage (§4.2,
// build_small.cl) and output stage (§4.3, build_output.cl), after the large-node stage of
// opencl_builder.cpp.
#include <algorithm>
#include <array>
#include <cstdint>
#include <string>
#include <utility>
#include <vector>

#include "cl/runtime/launch.h"
#include "cl/build/opencl_build_state.h"

namespace kdray::build_detail {

namespace {

// Bytes of split-candidate masks per small-root reference: 6 candidates below and 6 above, each
// group padded to a ulong8.
constexpr std::size_t kMaskBytesPerRef = 16 * 8;
// Bytes of one small-stage node record (a uint4, build_common.cl).
constexpr std::size_t kRecordBytes = 16;

/// The small roots in batches whose masks and first records (first_scale * (n + 1) per root of n
/// references) take at most batch_bytes each: one batch unless the scene is huge. Splitting
/// needs the roots' reference counts, read back only then.
std::vector<SmallBatch> small_batches(Build& b, cl_uint first_scale, std::size_t batch_bytes) {
    auto fits = [&](std::size_t refs, std::size_t roots) {
        return refs * kMaskBytesPerRef <= batch_bytes &&
               first_scale * (refs + roots) * kRecordBytes <= batch_bytes;
    };
    std::vector<SmallBatch> batches;
    if (fits(b.small_refs, b.small_roots)) {
        batches.push_back(SmallBatch{0, b.small_roots, 0, b.small_refs, {}, 0, {}});
        return batches;
    }
    std::vector<cl_uint> counts(b.small_roots);
    with_cl_context("reading the small roots' reference counts", [&] {
        b.queue.enqueueReadBuffer(b.root_ref_count.buffer(), CL_TRUE, 0, counts.size() * 4,
                                  counts.data());
    });
    SmallBatch batch;
    for (cl_uint root = 0; root < b.small_roots; ++root) {
        if (batch.roots > 0 && !fits(std::size_t(batch.refs) + counts[root], batch.roots + 1)) {
            const cl_uint ref_end = batch.ref_begin + batch.refs;
            batches.push_back(std::move(batch));
            batch = SmallBatch{root, 0, ref_end, 0, {}, 0, {}};
        }
        // A root holds at most 64 references, so a batch of one always fits a sane limit.
        if (!fits(counts[root], 1))
            throw Error("OpenCL kd-tree build: a small root's masks and records (" +
                        std::to_string(counts[root] * kMaskBytesPerRef) +
                        " bytes) exceed the batch limit of " + std::to_string(batch_bytes) +
                        " bytes");
        ++batch.roots;
        batch.refs += counts[root];
    }
    batches.push_back(std::move(batch));
    return batches;
}

}  // namespace

/* Small-node stage (§4.2): split-candidate masks once, then every small root's subtree in one
 * launch (build_small.cl) instead of one launch, scan and read-back per level. Kitchen small_nodes
 * 153-199 -> 79 ms, bunny 112 -> 71 ms (median of 5 builds, same sitting, loaded 2-core machine);
 * CPU time (perf stat task-clock, 6 builds) kitchen 2912 -> 2380 ms, bunny 1903 -> 1465 ms.
 * Both launches go by batch of roots when the masks (128 bytes per reference) or the records
 * would outgrow one allocation; the batches' trees are the ones a single batch builds. */
void run_small_stage(Build& b, int max_depth, cl_uint first_scale, std::size_t batch_bytes) {
    // The output stage reads the subtree counts even when there are no small roots.
    const std::size_t roots = std::max<cl_uint>(b.small_roots, 1);
    b.subtree_node_count = b.allocate(roots * 4, "subtree node counts");
    b.subtree_leaf_refs = b.allocate(roots * 4, "subtree leaf references");
    if (b.small_roots == 0) return;
    cl::CommandQueue& q = b.queue;
    Kernels& k = b.kernels;
    checked_u32(6 * std::size_t(b.small_refs), "split candidates");
    b.small_batches = small_batches(b, first_scale, batch_bytes);

    DeviceArray totals = b.allocate(3 * 4, "small stage totals");
    for (SmallBatch& batch : b.small_batches) {
        // The last batch's masks are held to the end of the build, whose arrays then go to the
        // device's BufferPool: a fresh buffer this size (40 MB for the dragon) every frame was
        // 10k page faults on PoCL. The batch before's are released first, for this one to reuse.
        b.side_masks = DeviceArray();
        b.side_masks = b.allocate(std::size_t(batch.refs) * kMaskBytesPerRef, "candidate masks");
        const DeviceArray& side_masks = b.side_masks;
        enqueue_kernel(q, k.split_masks, batch.refs, batch.ref_begin, batch.refs,
                       b.small_ref_box.buffer(), b.small_ref_root.buffer(),
                       b.root_ref_start.buffer(), b.root_ref_count.buffer(), side_masks.buffer());

        /* Every subtree, into records set aside per root; the few subtrees that outgrow theirs
         * are only counted, and built again into exactly as many records (second pass). */
        with_cl_context("clearing the small stage totals",
                        [&] { q.enqueueFillBuffer(totals.buffer(), cl_uint(0), 0, 3 * 4); });
        std::array<cl_uint, 3> total{};
        auto build_subtrees = [&](cl_uint second_pass, const DeviceArray& second_offset,
                                  const DeviceArray& records) {
            enqueue_kernel(
                q, k.build_subtrees, batch.roots, batch.root_begin, batch.roots, batch.ref_begin,
                b.small_first.box.buffer(), b.small_first.depth.buffer(), b.root_ref_start.buffer(),
                b.root_ref_count.buffer(), b.small_ref_box.buffer(), side_masks.buffer(),
                b.small_ref_tri.buffer(), b.triangle_data.buffer(),
                cl_float(b.params.costs.traversal), cl_float(b.params.costs.intersection),
                cl_float(b.params.empty_bonus), cl_uint(max_depth), first_scale, second_pass,
                second_offset.buffer(), records.buffer(), b.subtree_node_count.buffer(),
                b.subtree_leaf_refs.buffer(), totals.buffer());
        };
        const std::size_t budget_units = std::size_t(batch.refs) + batch.roots;
        batch.first_scale = first_scale;
        batch.records[0] =
            b.allocate(checked_u32(first_scale * budget_units, "small node records") * kRecordBytes,
                       "small node records");
        // The first pass reads no offsets; its argument is the totals buffer.
        build_subtrees(0, totals, batch.records[0]);
        with_cl_context("reading the small stage totals", [&] {
            q.enqueueReadBuffer(totals.buffer(), CL_TRUE, 0, 3 * 4, total.data());
        });
        if (total[1] > first_scale) {
            // Each outgrown subtree's node count, scanned into its place (one entry more: the
            // total).
            batch.second_offset =
                b.allocate((std::size_t(batch.roots) + 1) * 4, "second-pass record offsets");
            with_cl_context("clearing the second-pass record offsets", [&] {
                q.enqueueFillBuffer(batch.second_offset.buffer(), cl_uint(0),
                                    std::size_t(batch.roots) * 4, 4);
            });
            enqueue_kernel(q, k.second_pass_records, batch.roots, batch.root_begin, batch.roots,
                           first_scale, b.root_ref_count.buffer(), b.subtree_node_count.buffer(),
                           batch.second_offset.buffer());
            b.primitives.exclusive_scan(batch.second_offset.buffer(), batch.second_offset.buffer(),
                                        std::size_t(batch.roots) + 1);
            const cl_uint second_records = read_uint(q, batch.second_offset, batch.roots);
            batch.records[1] = b.allocate(std::size_t(second_records) * kRecordBytes,
                                          "small node records (second pass)");
            build_subtrees(1, batch.second_offset, batch.records[1]);
        }
        b.small_nodes = checked_u32(std::uint64_t(b.small_nodes) + total[0], "small nodes");
        b.small_levels = std::max(b.small_levels, int(total[2]));
    }
}

/* Output stage (§4.3): subtree sizes bottom-up, preorder positions top-down, then the nodes. */
DeviceArray write_preorder(Build& b, DeviceArray& leaf_indices, cl_uint& leaf_index_count) {
    cl::CommandQueue& q = b.queue;
    Kernels& k = b.kernels;
    // Each small root's record stands for its subtree, whose node count includes the root.
    const std::size_t records = b.node_count,
                      count = std::size_t(b.node_count) - b.small_roots + b.small_nodes;
    if (count > KDRAY_MAX_OFFSET)
        throw Error("OpenCL kd-tree build: " + std::to_string(count) +
                    " nodes exceed the layout's limit of " + std::to_string(KDRAY_MAX_OFFSET));
    DeviceArray subtree_nodes = b.allocate(records * 4, "subtree node counts");
    DeviceArray subtree_refs = b.allocate(records * 4, "subtree reference counts");
    DeviceArray position = b.allocate(records * 4, "preorder positions");
    DeviceArray leaf_position = b.allocate(records * 4, "leaf index positions");
    for (auto it = b.batches.rbegin(); it != b.batches.rend(); ++it)
        enqueue_kernel(q, k.size_subtrees, it->second, it->first, it->second, b.records.buffer(),
                       b.subtree_node_count.buffer(), b.subtree_leaf_refs.buffer(),
                       subtree_nodes.buffer(), subtree_refs.buffer());
    write_array(q, position, std::vector<cl_uint>{0});
    write_array(q, leaf_position, std::vector<cl_uint>{0});
    for (const auto& [begin, n] : b.batches)
        enqueue_kernel(q, k.place_subtrees, n, begin, n, b.records.buffer(), subtree_nodes.buffer(),
                       subtree_refs.buffer(), position.buffer(), leaf_position.buffer());
    leaf_index_count = read_uint(q, subtree_refs, 0);
    if (leaf_index_count > KDRAY_MAX_OFFSET)
        throw Error("OpenCL kd-tree build: " + std::to_string(leaf_index_count) +
                    " leaf references exceed the layout's limit of " +
                    std::to_string(KDRAY_MAX_OFFSET));
    DeviceArray nodes = b.allocate(count * sizeof(KdNode), "kd-tree nodes");
    leaf_indices = b.allocate(std::size_t(leaf_index_count) * 4, "kd-tree leaf indices");
    enqueue_kernel(q, k.write_nodes, records, cl_uint(records), b.records.buffer(),
                   position.buffer(), leaf_position.buffer(), b.leaf_store.buffer(), nodes.buffer(),
                   leaf_indices.buffer());
    for (const SmallBatch& batch : b.small_batches) {
        // Without a second pass no root reads its records or offsets: any buffer will do.
        const bool second_pass = batch.records[1].bytes() != 0;
        const cl::Buffer& second = batch.records[second_pass ? 1 : 0].buffer();
        const cl::Buffer& offsets = (second_pass ? batch.second_offset : batch.records[0]).buffer();
        enqueue_kernel(q, k.write_small, batch.roots, batch.root_begin, batch.roots,
                       batch.ref_begin, b.small_first.id.buffer(), b.root_ref_start.buffer(),
                       b.root_ref_count.buffer(), batch.first_scale, batch.records[0].buffer(),
                       second, offsets, b.subtree_node_count.buffer(), position.buffer(),
                       leaf_position.buffer(), b.small_ref_tri.buffer(), nodes.buffer(),
                       leaf_indices.buffer());
    }
    return nodes;
}

}  // namespace kdray::build_detail
