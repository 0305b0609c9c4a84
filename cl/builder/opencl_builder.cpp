// opencl_builder.cpp — the entry points of the OpenCL kd-tree builder (Zhou et al. 2008): the
// build's stages chained, each in a file of its own in cl/builder/: bounds.cpp (upload and triangle
// boxes), large_level.cpp (large-node stage), small_subtrees.cpp (small-node stage), output.cpp
// (preorder output), sharing build_context.h. The host reads back only the few counts that size
// the next launch (one read per level). The algorithm itself lives in the kernels; the comments
// there cite the paper's sections.
#include "cl/builder/opencl_builder.h"

#include <algorithm>
#include <chrono>
#include <string>

#include "cl/builder/bounds.h"
#include "cl/builder/build_context.h"
#include "cl/builder/build_prewarm.h"
#include "cl/builder/large_level.h"
#include "cl/builder/output.h"
#include "cl/builder/small_roots.h"
#include "cl/builder/small_subtrees.h"
#include "cl/runtime/cl_error.h"
#include "cl/runtime/program_cache.h"
#include "core/error.h"

namespace kdray {
namespace {

using namespace build_detail;

/// Per-stage wall times. Each lap waits for the queue, so a stage's time is its own kernels'.
class StageClock {
  public:
    StageClock(ClDevice& device, BuildReport* report) : device_(device), report_(report) {}
    void lap(const char* stage) {
        device_.finish(std::string("finishing build stage ") + stage);
        const auto now = std::chrono::steady_clock::now();
        if (report_)
            report_->timings_ms.emplace_back(
                stage, std::chrono::duration<double, std::milli>(now - last_).count());
        last_ = now;
    }

  private:
    ClDevice& device_;
    BuildReport* report_;
    std::chrono::steady_clock::time_point last_ = std::chrono::steady_clock::now();
};

/// The parameters a build uses: `params`, once checked against what the builder supports (the
/// depth that sizes the traversal stack, the masks' 64 bits, the bins' private arrays).
BuildParams supported_params(const BuildParams& params) {
    // Parameters out of range are an error, not silently clamped (validate_build_params names
    // the one that is off); the small stage's masks bound the large-node threshold.
    validate_build_params(params);
    return params;
}

/// One build's stages and their records, in the order the stages make them. The destructor
/// closes the memory first, so that the records' arrays, released after its body, all go to the
/// device's BufferPool for the next build.
struct Build {
    Build(ClDevice& device, const BuildParams& params) : ctx(device, params) {}
    ~Build() { ctx.memory.close(); }

    BuildContext ctx;
    TriangleBounds triangles;
    BuildOutput output;
    SmallRoots small_roots;
    SmallSubtrees small;
    PreorderTree tree;
};

}  // namespace

void prepare_opencl_builder(ClDevice& device, const BuildParams& params, std::size_t triangles) {
    // First, so that the device fills the buffers while the host builds (or loads) programs.
    prewarm_build_buffers(device, triangles, params);
    builder_kernels(device, supported_params(params).large_split_bins);
    const ClPrimitives primitives(device);
    if (triangles > 0) {
        // The warm-up build's first launches are where the device compiles each kernel for its
        // work-group size (PoCL: seconds with a cold cache), so its time is compilation, as the
        // render warm-up's is (warm_up_opencl_render); uncounted, a cold first frame's other_ms
        // held 3 s of it.
        const auto start = std::chrono::steady_clock::now();
        warm_up_launches(device, params, triangles);
        add_compile_ms(
            std::chrono::duration<double, std::milli>(std::chrono::steady_clock::now() - start)
                .count());
    }
}

KdTree build_opencl(ClDevice& device, const Scene& scene, const BuildParams& params,
                    BuildReport* report, DeviceTree* on_device, KdTree* host_storage) {
    return detail::build_opencl_with_limits(device, scene, params, {}, report, on_device,
                                            host_storage);
}

KdTree detail::build_opencl_with_limits(ClDevice& device, const Scene& scene,
                                        const BuildParams& params, const SmallStageLimits& limits,
                                        BuildReport* report, DeviceTree* on_device,
                                        KdTree* host_storage) {
    const auto start = std::chrono::steady_clock::now();
    const DeviceTraffic traffic_before = device.traffic();
    KdTree tree;
    if (host_storage) {
        tree.nodes = std::move(host_storage->nodes);
        tree.leaf_indices = std::move(host_storage->leaf_indices);
        tree.nodes.clear();
        tree.leaf_indices.clear();
    }
    tree.bounds = scene.bounds();
    tree.params = supported_params(params);
    tree.builder = "opencl";
    // The small stage's shape: the paper's level-parallel one on GPUs (one work-item's private
    // tables spill there), the per-root one elsewhere; the tree is the same.
    const bool per_level = tree.params.small_stage == SmallStage::PerLevel ||
                           (tree.params.small_stage == SmallStage::Auto && device.is_gpu());
    if (report) {
        *report = BuildReport{};
        report->small_stage =
            small_stage_name(per_level ? SmallStage::PerLevel : SmallStage::PerRoot);
    }
    const std::size_t n = scene.triangle_count();
    check_offset_limit(n, "triangles");
    if (n == 0) {
        // Nothing to launch: OpenCL forbids empty kernels and buffers.
        tree.nodes = {kd_make_leaf(0, 0)};
        if (report)
            for (const char* stage :
                 {"upload", "aabbs", "large_nodes", "small_nodes", "output", "download"})
                report->timings_ms.emplace_back(stage, 0.0);
        return tree;
    }

    Build b(device, tree.params);
    BuildContext& ctx = b.ctx;
    if (report) report->large_stage = large_stage_name(ctx.large_stage());
    StageClock clock(device, report);
    b.output.reserve_records(ctx, 1);
    b.output.add_batch(1);  // the root, id 0
    b.small_roots.reserve(ctx, 1, 1);
    ctx.reserve<cl_uint>(b.output.leaf_store, 1, 0, "leaf references");

    b.triangles = upload_triangles(ctx, scene);
    clock.lap("upload");
    compute_triangle_boxes(ctx, b.triangles);
    clock.lap("aabbs");
    const LargeStageResult large = run_large_stage(ctx, b.triangles, tree.bounds, b.output,
                                                   b.small_roots, limits.depth_first_arena_shift);
    clock.lap("large_nodes");
    b.small = run_small_stage(
        ctx, b.small_roots, b.triangles, std::max(1u, limits.subtree_budget_scale),
        limits.batch_bytes ? limits.batch_bytes : device.info().max_alloc_bytes, per_level);
    clock.lap("small_nodes");
    b.tree = write_preorder(ctx, b.output, b.small_roots, b.small);
    clock.lap("output");

    tree.nodes.resize(b.tree.node_count);
    tree.leaf_indices.resize(b.tree.leaf_index_count);
    // Both reads wait in the download stage's lap.
    const std::string downloading = "downloading the kd-tree";
    device.enqueue_read(b.tree.nodes.buffer(), 0, tree.nodes.size() * sizeof(KdNode),
                        tree.nodes.data(), downloading);
    if (!tree.leaf_indices.empty())
        device.enqueue_read(b.tree.leaf_indices.buffer(), 0,
                            tree.leaf_indices.size() * sizeof(kd_u32), tree.leaf_indices.data(),
                            downloading);
    clock.lap("download");
    ctx.uploads_done();
    if (on_device)
        *on_device = {b.tree.nodes.detach(), b.tree.leaf_indices.detach(),
                      b.triangles.triangles.detach()};
    if (report) {
        report->build_ms =
            std::chrono::duration<double, std::milli>(std::chrono::steady_clock::now() - start)
                .count();
        report->large_node_levels = large.levels;
        report->depth_first_subtrees = large.depth_first_subtrees;
        report->depth_first_rounds = large.depth_first_rounds;
        report->depth_first_rebuilt = large.depth_first_rebuilt;
        report->budget_leaves = large.budget_leaves;
        if (large.budget_leaves > 0)
            report->warnings.push_back(
                std::to_string(large.budget_leaves) +
                " large node(s) became leaves unsplit: their level (or their depth-first "
                "subtree) would have held more than " +
                std::to_string(kReferenceBudgetPerTriangle) +
                " references per triangle (splits cut most triangles), so those leaves hold many "
                "triangles and trace slowly");
        report->small_node_levels = b.small.levels;
        report->device_bytes = ctx.memory.peak_bytes();
        const DeviceTraffic& traffic = device.traffic();
        report->device_syncs = traffic.syncs - traffic_before.syncs;
        report->kernel_launches = traffic.launches - traffic_before.launches;
        report->device_transfers = traffic.transfers - traffic_before.transfers;
    }
    return tree;
}

}  // namespace kdray
