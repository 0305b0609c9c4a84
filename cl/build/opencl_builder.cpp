// opencl_builder.cpp — the host side of the OpenCL kd-tree builder (Zhou et al. 2008): the build's
// entry points and its upload and large-node stages (build_large.cl); the small-node and output
// stages are in opencl_builder_small.cpp, the state they share in opencl_build_state.h. The host
// reads back only the few counts that size the next launch (one read per level). The algorithm
// itself lives in the kernels; the comments there cite the paper's sections.
#include "cl/build/opencl_builder.h"

#include <algorithm>
#include <array>
#include <chrono>
#include <cstdint>
#include <string>
#include <utility>
#include <vector>

#include "cl/runtime/cl_error.h"
#include "cl/runtime/device_memory.h"
#include "cl/runtime/launch.h"
#include "cl/build/opencl_build_state.h"
#include "cl/runtime/primitives.h"
#include "cl/runtime/program_cache.h"
#include "core/error.h"

namespace kdray {
namespace build_detail {
namespace {

// Segments of the large stage's per-child slot arrays (build_large.cl passes through these
// numbers as -D defines, so this enum is their one definition).
enum SlotKind : unsigned {
    kSlotLarge,        // the child stays a large node (1/0)
    kSlotLargeRefs,    // ... its reference count
    kSlotLargeChunks,  // ... its reduction chunks
    kSlotSmall,        // the child becomes a small root (1/0)
    kSlotSmallRefs,    // ... its reference count
    kSlotLeafRefs,     // references of a node that becomes a leaf (in its slot 2i)
    kSlotChild,        // new nodes of generation 0 (then 1, ..., kMaxCuts): they get node ids
};

// Empty-space cuts one large node may chain in one level (each side of its box at most once).
constexpr unsigned kMaxCuts = 6;
constexpr unsigned kSlotKinds = kSlotChild + kMaxCuts + 1;

// A large-stage level holding more references than this many per triangle splits no further: its
// nodes become leaves. Real scenes stay well below it (about 1.2 to 2 in the large stage); it
// bounds memory on pathological input where every median plane cuts most triangles.
constexpr std::size_t kReferenceBudgetPerTriangle = 4;

std::string build_defines() {
    static const char* names[kSlotChild + 1] = {"LARGE",      "LARGE_REFS", "LARGE_CHUNKS", "SMALL",
                                                "SMALL_REFS", "LEAF_REFS",  "CHILD"};
    std::string defines = primitives_defines();
    defines += " -DKDRAY_MAX_CUTS=" + std::to_string(kMaxCuts) + "u";
    for (unsigned k = 0; k <= kSlotChild; ++k)
        defines += " -DKDRAY_SLOT_" + std::string(names[k]) + "=" + std::to_string(k) + "u";
    defines += " -DKDRAY_SMALL_ROOT_AXIS=" + std::to_string(kSmallRootAxis) + "u";
    return defines + " -DKDRAY_SLOT_KINDS=" + std::to_string(unsigned(kSlotKinds)) + "u";
}

}  // namespace

Kernels::Kernels(const ClDevice& device, int large_split_bins) {
    const std::string defines = build_defines();
    const cl::Program large =
        cached_program(device, "build_large.cl",
                       defines + " -DKDRAY_LARGE_BINS=" + std::to_string(large_split_bins) + "u");
    // CPU compilers may have no vector popcount (build_small_search.cl, kd_popcount8).
    const cl::Program small = cached_program(
        device, "build_small.cl",
        defines + " -DKDRAY_SWAR_POPCOUNT=" + (device.is_cpu() ? "1" : "0"));
    const cl::Program output = cached_program(device, "build_output.cl", defines);
    compute_aabbs = make_kernel(large, "kd_compute_aabbs");
    if (large_split_bins > 0) bin_large = make_kernel(large, "kd_bin_large_chunks");
    split_large = make_kernel(large, "kd_split_large_nodes");
    classify = make_kernel(large, "kd_classify_chunks");
    count_large = make_kernel(large, "kd_count_large_children");
    emit_large = make_kernel(large, "kd_emit_large_children");
    distribute = make_kernel(large, "kd_distribute_chunks");
    split_masks = make_kernel(small, "kd_compute_split_masks");
    build_subtrees = make_kernel(small, "kd_build_small_subtrees");
    second_pass_records = make_kernel(small, "kd_second_pass_records");
    size_subtrees = make_kernel(output, "kd_size_subtrees");
    place_subtrees = make_kernel(output, "kd_place_subtrees");
    write_nodes = make_kernel(output, "kd_write_nodes");
    write_small = make_kernel(output, "kd_write_small_subtrees");
}

namespace {

/// Per-stage wall times. Each lap waits for the queue, so a stage's time is its own kernels'.
class StageClock {
  public:
    StageClock(cl::CommandQueue& queue, BuildReport* report) : queue_(queue), report_(report) {}
    void lap(const char* stage) {
        with_cl_context(std::string("finishing build stage ") + stage, [&] { queue_.finish(); });
        const auto now = std::chrono::steady_clock::now();
        if (report_)
            report_->timings_ms.emplace_back(
                stage, std::chrono::duration<double, std::milli>(now - last_).count());
        last_ = now;
    }

  private:
    cl::CommandQueue& queue_;
    BuildReport* report_;
    std::chrono::steady_clock::time_point last_ = std::chrono::steady_clock::now();
};

/* Upload and triangle bounding boxes (§4, first step). */
void compute_triangle_boxes(Build& b, const Scene& scene, StageClock& clock) {
    const std::size_t n = b.triangles;
    b.triangle_data = b.allocate(scene.triangles.size() * sizeof(float), "triangles");
    write_array(b.queue, b.triangle_data, scene.triangles);
    clock.lap("upload");
    b.triangle_boxes = b.allocate(n * 24, "triangle boxes");
    b.triangle_ids = b.allocate(n * 4, "triangle references");
    enqueue_kernel(b.queue, b.kernels.compute_aabbs, n, b.triangle_data.buffer(), cl_uint(n),
                   b.triangle_boxes.buffer(), b.triangle_ids.buffer());
    clock.lap("aabbs");
}

/* A scene of at most T triangles is a small root from the start: the large stage has nothing to
 * do, and the root's references are the triangles' own boxes. */
void make_root_small(Build& b, const Aabb& bounds) {
    const cl_uint n = b.triangles;
    b.reserve_small_roots(1, n);
    with_cl_context("setting up the small root", [&] {
        b.queue.enqueueCopyBuffer(b.triangle_ids.buffer(), b.small_ref_tri.buffer(), 0, 0, n * 4);
        b.queue.enqueueCopyBuffer(b.triangle_boxes.buffer(), b.small_ref_box.buffer(), 0, 0,
                                  n * 24);
        b.queue.enqueueFillBuffer(b.small_ref_root.buffer(), cl_uint(0), 0, n * 4);
    });
    write_array(b.queue, b.root_ref_start, std::vector<cl_uint>{0});
    write_array(b.queue, b.root_ref_count, std::vector<cl_uint>{n});
    write_array(b.queue, b.small_first.box, box_floats(bounds));
    write_array(b.queue, b.records,
                std::vector<KdBuildNode>{{kSmallRootAxis, 0, {0, 0}, 0, 0, 0, 0}});
    write_array(b.queue, b.small_first.depth, std::vector<cl_uint>{0});
    write_array(b.queue, b.small_first.id, std::vector<cl_uint>{0});
    b.small_roots = 1;
    b.small_refs = n;
}

/* Large-node stage (§4.1): one iteration per tree level over every active large node. */
void run_large_stage(Build& b, const Aabb& bounds, int max_depth, cl_uint threshold) {
    const cl_uint n = b.triangles;
    if (n <= threshold) {
        make_root_small(b, bounds);
        return;
    }
    cl::CommandQueue& q = b.queue;
    Kernels& k = b.kernels;
    // Level 0: the root, holding every triangle.
    cl_uint nodes = 1, refs = n, chunks = cl_uint((n + kReduceChunk - 1) / kReduceChunk);
    DeviceArray node_box = b.allocate(24, "large node boxes");
    DeviceArray node_start = b.allocate(4, "large node reference starts");
    DeviceArray node_count = b.allocate(4, "large node reference counts");
    DeviceArray node_chunk = b.allocate(8, "large node chunk starts");
    DeviceArray node_id = b.allocate(4, "large node ids");
    DeviceArray node_depth = b.allocate(4, "large node depths");
    write_array(q, node_box, box_floats(bounds));
    write_array(q, node_start, std::vector<cl_uint>{0});
    write_array(q, node_count, std::vector<cl_uint>{n});
    write_array(q, node_chunk, std::vector<cl_uint>{0, chunks});
    write_array(q, node_id, std::vector<cl_uint>{0});
    write_array(q, node_depth, std::vector<cl_uint>{0});
    DeviceArray ref_tri = std::move(b.triangle_ids), ref_box = std::move(b.triangle_boxes);
    const std::size_t budget = kReferenceBudgetPerTriangle * std::size_t(n);

    while (nodes > 0) {
        ++b.large_levels;
        // Nodes at the depth limit become leaves in kd_split_large_nodes.
        const cl_uint force_leaf = refs > budget;
        const cl_uint slots = 2 * nodes;

        /* Node bounds: segmented reduction of the reference boxes, then the split decision. */
        DeviceArray tight = b.allocate(std::size_t(nodes) * 24, "large node tight boxes");
        if (!force_leaf) {
            DeviceArray chunk_boxes = b.allocate(std::size_t(chunks) * 24, "reduction chunks");
            b.primitives.reduce_box_segments(ref_box.buffer(), node_start.buffer(),
                                             node_count.buffer(), node_chunk.buffer(), nodes,
                                             chunks, chunk_boxes.buffer(), tight.buffer());
        }
        DeviceArray split_axis = b.allocate(nodes * 4, "large split axes");
        DeviceArray split_pos = b.allocate(nodes * 4, "large split positions");
        DeviceArray planar = b.allocate(nodes * 4, "large split planar sides");
        DeviceArray cut_count = b.allocate(nodes * 4, "empty-space cuts per node");
        DeviceArray cut_code = b.allocate(std::size_t(nodes) * kMaxCuts * 4, "empty-space cuts");
        DeviceArray cut_pos = b.allocate(std::size_t(nodes) * kMaxCuts * 4, "empty-space planes");
        const unsigned bins = unsigned(b.params.large_split_bins);
        // With the spatial median no kernel reads the bins; the argument still needs a buffer.
        DeviceArray chunk_bins =
            b.allocate(bins > 0 ? std::size_t(chunks) * 6 * bins * 4 : 4, "large node SAH bins");
        if (bins > 0 && !force_leaf)
            enqueue_kernel(q, k.bin_large, chunks, ref_box.buffer(), node_start.buffer(),
                           node_count.buffer(), node_chunk.buffer(), nodes, chunks,
                           node_box.buffer(), tight.buffer(), chunk_bins.buffer());
        enqueue_kernel(q, k.split_large, nodes, nodes, node_box.buffer(), tight.buffer(),
                       node_depth.buffer(), cl_uint(max_depth), force_leaf,
                       cl_float(b.params.empty_space_ratio), node_chunk.buffer(),
                       node_count.buffer(), chunk_bins.buffer(), cl_float(b.params.costs.traversal),
                       cl_float(b.params.costs.intersection), cl_float(b.params.empty_bonus),
                       split_axis.buffer(), split_pos.buffer(), planar.buffer(), cut_count.buffer(),
                       cut_code.buffer(), cut_pos.buffer());

        /* Classify references, counted per chunk; one scan of the counts ranks the chunks. */
        DeviceArray sides = b.allocate(std::max<std::size_t>(refs, 4), "reference sides");
        DeviceArray child_box = b.allocate(2 * std::size_t(refs) * 24, "reference child boxes");
        DeviceArray chunk_rank = b.allocate((2 * std::size_t(chunks) + 1) * 4, "chunk ranks");
        enqueue_kernel(q, k.classify, chunks, chunks, refs, nodes, node_start.buffer(),
                       node_count.buffer(), node_chunk.buffer(), ref_tri.buffer(), ref_box.buffer(),
                       b.triangle_data.buffer(), node_box.buffer(), split_axis.buffer(),
                       split_pos.buffer(), planar.buffer(), sides.buffer(), child_box.buffer(),
                       chunk_rank.buffer());
        b.primitives.exclusive_scan(chunk_rank.buffer(), chunk_rank.buffer(),
                                    2 * std::size_t(chunks));

        /* Child sizes and kinds, ranked by one scan over all slot kinds. */
        const std::size_t slot_values = std::size_t(kSlotKinds) * slots;
        DeviceArray slot = b.allocate((slot_values + 1) * 4, "child slots");
        enqueue_kernel(q, k.count_large, nodes, nodes, node_count.buffer(), node_chunk.buffer(),
                       split_axis.buffer(), cut_count.buffer(), chunk_rank.buffer(), chunks,
                       threshold, slot.buffer());
        b.primitives.exclusive_scan(slot.buffer(), slot.buffer(), slot_values);

        /* The level's one read-back: the totals of every slot kind. */
        std::array<cl_uint, kSlotKinds + 1> at{};
        with_cl_context("reading the large level's totals", [&] {
            for (unsigned kind = 0; kind <= kSlotKinds; ++kind)
                q.enqueueReadBuffer(slot.buffer(), CL_FALSE,
                                    std::size_t(kind) * slots * sizeof(cl_uint), sizeof(cl_uint),
                                    &at[kind]);
            q.finish();
        });
        auto total = [&](unsigned kind) { return at[kind + 1] - at[kind]; };
        const cl_uint next_nodes = total(kSlotLarge), next_refs = total(kSlotLargeRefs);
        const cl_uint next_chunks = total(kSlotLargeChunks), new_roots = total(kSlotSmall);
        const cl_uint new_small_refs = total(kSlotSmallRefs), new_leaf_refs = total(kSlotLeafRefs);
        cl_uint new_nodes = 0;
        for (unsigned g = 0; g <= kMaxCuts; ++g) new_nodes += total(kSlotChild + g);

        /* Room for what this level creates, then write it. */
        b.reserve_records(std::size_t(b.node_count) + new_nodes);
        b.reserve_small_roots(
            checked_u32(std::uint64_t(b.small_roots) + new_roots, "small roots"),
            checked_u32(std::uint64_t(b.small_refs) + new_small_refs, "small references"));
        const cl_uint leaf_total =
            checked_u32(std::uint64_t(b.leaf_refs) + new_leaf_refs, "leaf references");
        b.memory.reserve(b.leaf_store, std::size_t(leaf_total) * 4, std::size_t(b.leaf_refs) * 4,
                         "leaf references");
        DeviceArray next_box = b.allocate(std::size_t(next_nodes) * 24, "large node boxes");
        DeviceArray next_start = b.allocate(next_nodes * 4, "large node reference starts");
        DeviceArray next_count = b.allocate(next_nodes * 4, "large node reference counts");
        DeviceArray next_chunk = b.allocate((next_nodes + 1) * 4, "large node chunk starts");
        DeviceArray next_id = b.allocate(next_nodes * 4, "large node ids");
        DeviceArray next_depth = b.allocate(next_nodes * 4, "large node depths");
        DeviceArray next_tri = b.allocate(std::size_t(next_refs) * 4, "triangle references");
        DeviceArray next_ref_box = b.allocate(std::size_t(next_refs) * 24, "reference boxes");
        enqueue_kernel(
            q, k.emit_large, nodes, nodes, node_box.buffer(), node_count.buffer(), node_id.buffer(),
            split_axis.buffer(), split_pos.buffer(), cut_count.buffer(), cut_code.buffer(),
            cut_pos.buffer(), node_depth.buffer(), slot.buffer(), b.node_count, b.small_roots,
            b.small_refs, b.leaf_refs, b.records.buffer(), next_box.buffer(), next_start.buffer(),
            next_count.buffer(), next_chunk.buffer(), next_id.buffer(), next_depth.buffer(),
            b.root_ref_start.buffer(), b.root_ref_count.buffer(), b.small_first.box.buffer(),
            b.small_first.id.buffer(), b.small_first.depth.buffer());
        enqueue_kernel(q, k.distribute, chunks, chunks, refs, nodes, node_start.buffer(),
                       node_count.buffer(), node_chunk.buffer(), ref_tri.buffer(), ref_box.buffer(),
                       sides.buffer(), child_box.buffer(), split_axis.buffer(), chunk_rank.buffer(),
                       slot.buffer(), b.small_roots, b.small_refs, b.leaf_refs, next_tri.buffer(),
                       next_ref_box.buffer(), b.small_ref_tri.buffer(), b.small_ref_box.buffer(),
                       b.small_ref_root.buffer(), b.leaf_store.buffer());
        // One batch per generation: a chain's nodes are each other's parents (build_output.cl).
        for (unsigned g = 0; g <= kMaxCuts; ++g) b.add_batch(total(kSlotChild + g));
        b.small_roots += new_roots;
        b.small_refs += new_small_refs;
        b.leaf_refs = leaf_total;

        nodes = next_nodes, refs = next_refs, chunks = next_chunks;
        node_box = std::move(next_box), node_start = std::move(next_start);
        node_count = std::move(next_count), node_chunk = std::move(next_chunk);
        node_id = std::move(next_id), node_depth = std::move(next_depth);
        ref_tri = std::move(next_tri);
        ref_box = std::move(next_ref_box);
    }
}

}  // namespace
}  // namespace build_detail

using namespace build_detail;

namespace {

/// The parameters a build uses: `params` with each bounded to what the builder supports (the
/// depth that sizes the traversal stack, the masks' 64 bits, the bins' private arrays).
BuildParams supported_params(const BuildParams& params) {
    BuildParams p = params;
    p.max_depth = std::clamp(params.max_depth, 0, KDRAY_MAX_DEPTH);
    p.large_node_threshold = std::clamp(params.large_node_threshold, 1, 64);
    p.large_split_bins = std::clamp(params.large_split_bins, 0, kMaxLargeSplitBins);
    return p;
}

}  // namespace

void prepare_opencl_builder(ClDevice& device, const BuildParams& params) {
    const Kernels kernels(device, supported_params(params).large_split_bins);
    const ClPrimitives primitives(device);
}

KdTree build_opencl(ClDevice& device, const Scene& scene, const BuildParams& params,
                    BuildReport* report, DeviceTree* on_device) {
    return detail::build_opencl_with_limits(device, scene, params, {}, report, on_device);
}

KdTree detail::build_opencl_with_limits(ClDevice& device, const Scene& scene,
                                        const BuildParams& params, const SmallStageLimits& limits,
                                        BuildReport* report, DeviceTree* on_device) {
    const auto start = std::chrono::steady_clock::now();
    KdTree tree;
    tree.bounds = scene.bounds();
    tree.params = supported_params(params);
    tree.builder = "opencl";
    if (report) *report = BuildReport{};
    const std::size_t n = scene.triangle_count();
    if (n > KDRAY_MAX_OFFSET)
        throw Error("OpenCL kd-tree build: " + std::to_string(n) +
                    " triangles exceed the layout's limit of " + std::to_string(KDRAY_MAX_OFFSET));
    if (n == 0) {
        // Nothing to launch: OpenCL forbids empty kernels and buffers.
        tree.nodes = {kd_make_leaf(0, 0)};
        if (report)
            for (const char* stage :
                 {"upload", "aabbs", "large_nodes", "small_nodes", "output", "download"})
                report->timings_ms.emplace_back(stage, 0.0);
        return tree;
    }

    Build b(device, tree.params, n);
    StageClock clock(b.queue, report);
    b.reserve_records(1);
    b.add_batch(1);  // the root, id 0
    b.reserve_small_roots(1, 1);
    b.memory.reserve(b.leaf_store, 4, 0, "leaf references");
    const cl_uint threshold = cl_uint(tree.params.large_node_threshold);

    compute_triangle_boxes(b, scene, clock);
    run_large_stage(b, tree.bounds, tree.params.max_depth, threshold);
    clock.lap("large_nodes");
    run_small_stage(b, tree.params.max_depth, std::max(1u, limits.subtree_budget_scale),
                    limits.batch_bytes ? limits.batch_bytes : device.info().max_alloc_bytes);
    clock.lap("small_nodes");
    DeviceArray leaf_indices;
    cl_uint leaf_index_count = 0;
    DeviceArray nodes = write_preorder(b, leaf_indices, leaf_index_count);
    clock.lap("output");

    tree.nodes.resize(std::size_t(b.node_count) - b.small_roots + b.small_nodes);
    tree.leaf_indices.resize(leaf_index_count);
    with_cl_context("downloading the kd-tree", [&] {
        b.queue.enqueueReadBuffer(nodes.buffer(), CL_TRUE, 0, tree.nodes.size() * sizeof(KdNode),
                                  tree.nodes.data());
        if (leaf_index_count)
            b.queue.enqueueReadBuffer(leaf_indices.buffer(), CL_TRUE, 0,
                                      tree.leaf_indices.size() * sizeof(kd_u32),
                                      tree.leaf_indices.data());
    });
    clock.lap("download");
    if (on_device) *on_device = {nodes.detach(), leaf_indices.detach(), b.triangle_data.detach()};
    if (report) {
        report->build_ms =
            std::chrono::duration<double, std::milli>(std::chrono::steady_clock::now() - start)
                .count();
        report->large_node_levels = b.large_levels;
        report->small_node_levels = b.small_levels;
        report->device_bytes = b.memory.peak_bytes();
    }
    return tree;
}

}  // namespace kdray
