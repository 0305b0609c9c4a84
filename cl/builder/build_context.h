// build_context.h — what every host stage of the OpenCL kd-tree builder uses (internal to
// cl/builder/): the device, its queue, the build's counted memory, the primitives and the builder's
// kernels (BuildContext), and the records that cross stages (BuildOutput: the node records by id,
// their batches and the large stage's leaf store). The stages themselves are bounds.cpp,
// large_level.cpp, small_roots.cpp, small_subtrees.cpp and output.cpp, chained by
// opencl_builder.cpp.
#pragma once

#include <cstdint>
#include <string>
#include <utility>
#include <vector>

#include "cl/builder/opencl_builder.h"
#include "cl/runtime/cl_error.h"
#include "cl/runtime/device_memory.h"
#include "cl/runtime/primitives.h"
#include "core/device/kd_build_shared.h"

namespace kdray::build_detail {

/// The builder's kernels, created once per device and large_split_bins (builder_kernels).
struct BuilderKernels {
    cl::Kernel compute_aabbs, bin_large, split_large, classify, count_large, emit_large, distribute,
        union_parent_boxes;
    // The large stage's element-parallel shape (build_large_groups.cl, in the large program).
    cl::Kernel reduce_box_groups, bin_large_groups, sum_node_bins, classify_groups,
        distribute_groups;
    cl::Kernel split_masks, split_masks_grouped, build_subtrees, second_pass_records;
    // The small stage's per-level shape (build_small_level.cl, in the small program).
    cl::Kernel start_small_level, split_small_level, size_small_level, place_small_level,
        count_small_level, write_small_level;
    // The large stage's depth-first schedule (build_large_depth_first.cl).
    cl::Kernel build_depth_first, commit_depth_first;
    cl::Kernel size_subtrees, place_subtrees, size_regions, place_regions, write_nodes, write_small;
};

/// The kernels of `device` for large_split_bins (BuildParams::large_split_bins, compiled into the
/// large stage's program), from programs built once (program cache) and kernels created once
/// (cached_kernels). A cl::Kernel carries its arguments, so one set serves one build at a time:
/// kdray builds one after another on the device's one queue, which every build uses.
BuilderKernels& builder_kernels(const ClDevice& device, int large_split_bins);

/// The -D options of the large stage's program (build_large.cl) for large_split_bins, and of the
/// small stage's (build_small.cl) on a CPU device or not: the only compile-time choices of the
/// builder's programs (cl/program_catalogue.cpp lists them all from here).
std::string large_program_defines(int large_split_bins);
std::string small_program_defines(bool cpu_device);

/// The device side of one build, shared by its stages.
struct BuildContext {
    BuildContext(ClDevice& d, const BuildParams& p)
        : device(d),
          queue(d.queue()),
          memory(d),
          primitives(d, &memory),
          kernels(builder_kernels(d, p.large_split_bins)),
          params(p),
          element_parallel_large(p.large_stage == LargeStage::Level ||
                                 (p.large_stage == LargeStage::Auto && d.is_gpu())),
          depth_first_large(p.large_stage == LargeStage::DepthFirst ||
                            (p.large_stage == LargeStage::Auto && !d.is_gpu())) {}
    /// An upload may still read host memory when a stage throws: wait for it before that memory
    /// goes.
    ~BuildContext();
    BuildContext(const BuildContext&) = delete;
    BuildContext& operator=(const BuildContext&) = delete;

    ClDevice& device;
    cl::CommandQueue& queue;
    DeviceMemory memory;
    ClPrimitives primitives;
    BuilderKernels& kernels;
    BuildParams params;
    /// The large stage's shape: a work-item per reference (LargeStage::Level) or per chunk, and
    /// whether subtrees go depth first once a level has enough nodes (LargeStage::DepthFirst).
    bool element_parallel_large, depth_first_large;
    /// The shape's name for the build's report.
    LargeStage large_stage() const {
        return depth_first_large        ? LargeStage::DepthFirst
               : element_parallel_large ? LargeStage::Level
                                        : LargeStage::Chunked;
    }

    /// A counted array of `count` elements of T (sized by the shared struct, not by hand); a new
    /// buffer has room for `room` elements if that is more (DeviceMemory::allocate).
    template <class T>
    DeviceArray allocate(std::size_t count, const std::string& what, std::size_t room = 0) {
        return memory.allocate(count * sizeof(T), what, room * sizeof(T));
    }
    /// Makes `array` hold `count` elements of T, keeping its first `used`.
    template <class T>
    void reserve(DeviceArray& array, std::size_t count, std::size_t used, const std::string& what) {
        memory.reserve(array, count * sizeof(T), used * sizeof(T), what, primitives);
    }
    /// Uploads `values` without waiting (a wait per upload was a round trip each: the root
    /// level's four, the output stage's two); a copy lives until uploads_done().
    template <class T>
    void write(const DeviceArray& array, const std::vector<T>& values) {
        const char* data = reinterpret_cast<const char*>(values.data());
        staged_.emplace_back(data, data + values.size() * sizeof(T));
        upload(array, staged_.back().data(), staged_.back().size());
    }
    /// Uploads `bytes` from `data` into the array's first bytes without waiting: `data` must live
    /// until uploads_done(). Through a buffer of exactly that size and a copy kernel: a host
    /// write into part of a (recycled, larger) array would be simpler, but Oclgrind 21.10 then
    /// forgets which of the array's other bytes kernels have written (it resizes the buffer's
    /// initialisation record to the host write) and reports each later read of them.
    void upload(const DeviceArray& array, const void* data, std::size_t bytes) {
        if (bytes == 0) return;
        uploads_pending_ = true;
        const cl::Buffer staging = device.allocate(bytes, "staged build data");
        device.enqueue_write(staging, 0, bytes, data, "uploading build data");
        primitives.copy(staging, array.buffer(), bytes);
    }
    /// After a wait on the queue: every upload so far has read its host memory.
    void uploads_done() {
        staged_.clear();
        uploads_pending_ = false;
    }
    cl_uint read_uint(const DeviceArray& array, std::size_t index);

  private:
    std::vector<std::vector<char>> staged_;  // write()'s copies (a move keeps their data)
    bool uploads_pending_ = false;
};

/// The node records by id (KdBuildNode) and the id ranges in creation order, children after
/// their parents (the batches the output stage walks), with the large stage's leaf store.
struct BuildOutput {
    DeviceArray records;
    cl_uint node_count = 0;
    std::vector<std::pair<cl_uint, cl_uint>> batches;  // (first id, count)
    // Leaves of the large stage keep their triangles here (KdBuildNode.leaf_first).
    DeviceArray leaf_store;
    cl_uint leaf_refs = 0;
    // The depth-first schedule's subtrees (KdLargeRegion each): records outside the batches.
    DeviceArray regions;
    cl_uint region_count = 0;

    /// Room for `nodes` records in all; throws when they exceed the layout's offsets.
    void reserve_records(BuildContext& ctx, std::size_t nodes);
    /// The next `count` ids, as one batch.
    void add_batch(cl_uint count);
};

/// A KdBuildBox of an Aabb.
KdBuildBox build_box(const Aabb& b);

/// `value` as 32 bits; throws naming `what` when it does not fit.
cl_uint checked_u32(std::uint64_t value, const char* what);

/// Throws when `count` things named `what` exceed the layout's 30 offset bits.
void check_offset_limit(std::size_t count, const char* what);

}  // namespace kdray::build_detail
