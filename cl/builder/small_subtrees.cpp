// small_subtrees.cpp — the host side of the small-node stage (§4.2, build_small.cl;
// small_subtrees.h).
#include "cl/builder/small_subtrees.h"

#include <algorithm>
#include <array>
#include <cstdint>
#include <string>
#include <utility>

#include "cl/builder/small_levels.h"
#include "cl/runtime/launch.h"
#include "core/error.h"

namespace kdray::build_detail {

KdSmallBatchArgs SmallBatch::args(const BuildParams& params, cl_uint second_pass) const {
    return {root_begin,
            roots,
            ref_begin,
            first_scale,
            second_pass,
            cl_uint(params.max_depth),
            params.costs.traversal,
            params.costs.intersection,
            params.empty_bonus,
            cl_uint(params.small_reclip_refs),
            cl_uint(params.small_leaf_refs),
            cl_uint(params.small_split_bins)};
}

namespace {

/// The small roots in batches whose masks (mask_bytes per reference) and first records
/// (first_scale * (n + 1) per root of n references) take at most batch_bytes each: one batch
/// unless the scene is huge. Splitting needs the roots' reference counts, read back only then.
std::vector<SmallBatch> small_batches(BuildContext& ctx, const SmallRoots& small,
                                      cl_uint first_scale, std::size_t batch_bytes,
                                      std::size_t mask_bytes) {
    auto fits = [&](std::size_t refs, std::size_t roots) {
        return refs * mask_bytes <= batch_bytes &&
               first_scale * (refs + roots) * sizeof(KdSmallNode) <= batch_bytes;
    };
    std::vector<SmallBatch> batches(1);
    batches[0].first_scale = first_scale;
    if (fits(small.refs, small.count)) {
        batches[0].roots = small.count;
        batches[0].refs = small.refs;
        return batches;
    }
    std::vector<KdSmallRoot> roots(small.count);
    ctx.device.read(small.roots.buffer(), 0, roots.size() * sizeof(KdSmallRoot), roots.data(),
                    "reading the small roots' reference counts");
    for (cl_uint root = 0; root < small.count; ++root) {
        const cl_uint count = roots[root].ref_count;
        SmallBatch& batch = batches.back();
        if (batch.roots > 0 && !fits(std::size_t(batch.refs) + count, batch.roots + 1)) {
            SmallBatch next;
            next.root_begin = root;
            next.ref_begin = batch.ref_begin + batch.refs;
            next.first_scale = first_scale;
            batches.push_back(std::move(next));
        }
        // A root holds at most 64 references, so a batch of one always fits a sane limit.
        if (!fits(count, 1))
            throw Error("OpenCL kd-tree build: a small root's masks and records (" +
                        std::to_string(count * mask_bytes +
                                       first_scale * (count + 1) * sizeof(KdSmallNode)) +
                        " bytes) exceed the batch limit of " + std::to_string(batch_bytes) +
                        " bytes");
        ++batches.back().roots;
        batches.back().refs += count;
    }
    return batches;
}

/* Every subtree of the batch, into records set aside per root; the few subtrees that outgrow
 * theirs are only counted, and built again into exactly as many records (second pass). */
void build_batch_subtrees(BuildContext& ctx, const SmallRoots& small,
                          const TriangleBounds& triangles, SmallSubtrees& out, SmallBatch& batch,
                          const DeviceArray& totals) {
    ctx.primitives.fill(totals.buffer(), 0, 3);
    std::array<cl_uint, 3> total{};
    auto build_subtrees = [&](cl_uint second_pass, const DeviceArray& second_offset,
                              const DeviceArray& records) {
        enqueue_kernel(ctx.device, ctx.kernels.build_subtrees, batch.roots,
                       batch.args(ctx.params, second_pass), small.roots.buffer(),
                       small.ref_box.buffer(), out.side_masks.buffer(), small.ref_tri.buffer(),
                       triangles.triangles.buffer(), second_offset.buffer(), records.buffer(),
                       out.node_count.buffer(), out.leaf_refs.buffer(), totals.buffer());
    };
    const std::size_t budget_units = std::size_t(batch.refs) + batch.roots;
    batch.records[0] = ctx.allocate<KdSmallNode>(
        checked_u32(batch.first_scale * budget_units, "small node records"), "small node records");
    // The first pass reads no offsets; its argument is the totals buffer.
    build_subtrees(0, totals, batch.records[0]);
    ctx.device.read(totals.buffer(), 0, 3 * sizeof(cl_uint), total.data(),
                    "reading the small stage totals");
    if (total[1] > batch.first_scale) {
        const cl_uint second_records = place_second_pass(ctx, small, out, batch);
        batch.records[1] =
            ctx.allocate<KdSmallNode>(second_records, "small node records (second pass)");
        build_subtrees(1, batch.second_offset, batch.records[1]);
    }
    out.nodes = checked_u32(std::uint64_t(out.nodes) + total[0], "small nodes");
    out.levels = std::max(out.levels, int(total[2]));
}

}  // namespace

cl_uint place_second_pass(BuildContext& ctx, const SmallRoots& small, const SmallSubtrees& out,
                          SmallBatch& batch) {
    // Each outgrown subtree's node count, scanned into its place; the scan writes the total
    // after the last (one entry more).
    batch.second_offset =
        ctx.allocate<cl_uint>(std::size_t(batch.roots) + 1, "second-pass record offsets");
    enqueue_kernel(ctx.device, ctx.kernels.second_pass_records, batch.roots,
                   batch.args(ctx.params, 0), small.roots.buffer(), out.node_count.buffer(),
                   batch.second_offset.buffer());
    ctx.primitives.exclusive_scan(batch.second_offset.buffer(), batch.second_offset.buffer(),
                                  batch.roots);
    return ctx.read_uint(batch.second_offset, batch.roots);
}

/* Small-node stage (§4.2): split-candidate masks once, then every small root's subtree in one
 * launch (build_small.cl) instead of one launch, scan and read-back per level. Kitchen small_nodes
 * 153-199 -> 79 ms, bunny 112 -> 71 ms (median of 5 builds, same sitting, loaded 2-core machine);
 * CPU time (perf stat task-clock, 6 builds) kitchen 2912 -> 2380 ms, bunny 1903 -> 1465 ms.
 * Both launches go by batch of roots when the masks (KDRAY_MASK_BYTES_PER_REF per reference) or
 * the records would outgrow one allocation; the batches' trees are the ones a single batch
 * builds. per_level: each batch's subtrees level by level instead (small_levels.cpp, the paper's
 * shape for GPUs), into the same records. */
SmallSubtrees run_small_stage(BuildContext& ctx, const SmallRoots& small,
                              const TriangleBounds& triangles, cl_uint first_scale,
                              std::size_t batch_bytes, bool per_level) {
    SmallSubtrees out;
    // The output stage reads the subtree counts even when there are no small roots.
    const std::size_t roots = std::max<cl_uint>(small.count, 1);
    out.node_count = ctx.allocate<cl_uint>(roots, "subtree node counts");
    out.leaf_refs = ctx.allocate<cl_uint>(roots, "subtree leaf references");
    if (small.count == 0) return out;
    checked_u32(KDRAY_CANDIDATE_STRIDE * std::size_t(small.refs), "split candidates");
    // Binned searches (build_small_bins.cl) read no masks: none are made, and a word stands in
    // for the kernels' argument.
    const bool masks = ctx.params.small_split_bins == 0;
    out.batches =
        small_batches(ctx, small, first_scale, batch_bytes, masks ? KDRAY_MASK_BYTES_PER_REF : 0);

    // The per-root kernel's totals (read once per batch).
    DeviceArray totals = ctx.allocate<cl_uint>(3, "small stage totals");
    for (SmallBatch& batch : out.batches) {
        // The last batch's masks are held to the end of the build, whose arrays then go to the
        // device's BufferPool: a fresh buffer this size (40 MB for the dragon) every frame was
        // 10k page faults on PoCL. The batch before's are released first, for this one to reuse.
        out.side_masks = DeviceArray();
        out.side_masks = ctx.memory.allocate(
            masks ? std::size_t(batch.refs) * KDRAY_MASK_BYTES_PER_REF : sizeof(cl_ulong),
            "candidate masks");
        // The masks in the shape of the stage's schedule: a work-item per reference for the
        // per-level (GPU) stage, per KDRAY_MASK_GROUP references for the per-root (CPU) one. A
        // GPU asked for per-root runs the grouped kernel too (inside docs/gpu-kernels.md's
        // budgets), and Oclgrind, a GPU, runs it in the per-root cases.
        cl::Kernel& mask_kernel =
            per_level ? ctx.kernels.split_masks : ctx.kernels.split_masks_grouped;
        const std::size_t items =
            per_level ? batch.refs : (batch.refs + KDRAY_MASK_GROUP - 1) / KDRAY_MASK_GROUP;
        if (masks)
            enqueue_kernel(ctx.device, mask_kernel, items, batch.ref_begin, batch.refs,
                           small.ref_box.buffer(), small.ref_root.buffer(), small.roots.buffer(),
                           out.side_masks.buffer());
        if (per_level)
            build_batch_levels(ctx, small, triangles, out, batch);
        else
            build_batch_subtrees(ctx, small, triangles, out, batch, totals);
    }
    return out;
}

}  // namespace kdray::build_detail
