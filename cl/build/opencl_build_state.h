// opencl_build_state.h — what the host stages of the OpenCL kd-tree builder share (internal to
// cl/: opencl_builder.cpp runs the upload and the large-node stage, opencl_builder_small.cpp the
// small-node and output stages): the kernels, the build's device arrays and a few helpers.
#pragma once

#include <cstdint>
#include <string>
#include <utility>
#include <vector>

#include "cl/runtime/cl_error.h"
#include "cl/runtime/device_memory.h"
#include "cl/build/opencl_builder.h"
#include "cl/runtime/primitives.h"
#include "core/error.h"

namespace kdray::build_detail {

// KdBuildNode.axis of a small root, whose subtree the small stage writes (build_common.cl).
constexpr cl_uint kSmallRootAxis = 4;

/// The builder's kernels, from programs built once per device and options (program cache).
struct Kernels {
    cl::Kernel compute_aabbs, bin_large, split_large, classify, count_large, emit_large, distribute;
    cl::Kernel split_masks, build_subtrees, second_pass_records;
    cl::Kernel size_subtrees, place_subtrees, write_nodes, write_small;

    /// large_split_bins: BuildParams::large_split_bins, compiled into the large stage's program.
    Kernels(const ClDevice& device, int large_split_bins);
};

/// The small roots (structure of arrays, one entry per root): box, depth and node id.
struct SmallRoots {
    DeviceArray box, depth, id;
};

/// Small roots whose split-candidate masks and node records the small stage holds at once: roots
/// root_begin.. and their references ref_begin.. (a root's references are contiguous, and so are
/// consecutive roots'). A batch's records stay until the output stage has moved them into place.
struct SmallBatch {
    cl_uint root_begin = 0, roots = 0, ref_begin = 0, refs = 0;
    // [0] the first pass's records, first_scale * (n + 1) per root of n references; [1] the
    // second's, exactly the node counts of the subtrees that outgrew the first (empty when none
    // did).
    DeviceArray records[2];
    cl_uint first_scale = 0;
    // Where each root's second-pass records start (roots entries; read only for those that
    // outgrew the first pass).
    DeviceArray second_offset;
};

/// Everything one build holds on the device between its stages.
struct Build {
    Build(ClDevice& d, const BuildParams& p, std::size_t triangle_count)
        : device(d),
          queue(d.queue()),
          memory(d),
          primitives(d),
          kernels(d, p.large_split_bins),
          params(p),
          triangles(static_cast<cl_uint>(triangle_count)) {}
    // The arrays below are released after this body: all of them go to the device's BufferPool.
    ~Build() { memory.close(); }

    ClDevice& device;
    cl::CommandQueue& queue;
    DeviceMemory memory;
    ClPrimitives primitives;
    Kernels kernels;
    BuildParams params;
    cl_uint triangles;

    DeviceArray triangle_data, triangle_boxes, triangle_ids;
    // Node records by id, and the id ranges in creation order (children after their parents).
    DeviceArray records;
    cl_uint node_count = 0;
    std::vector<std::pair<cl_uint, cl_uint>> batches;
    // Leaves of the large stage keep their triangles here.
    DeviceArray leaf_store;
    cl_uint leaf_refs = 0;
    // Small roots: their reference lists (triangle, clipped box, root) and their ranges.
    DeviceArray small_ref_tri, small_ref_box, small_ref_root, root_ref_start, root_ref_count;
    cl_uint small_refs = 0, small_roots = 0;
    // The small roots' nodes, and the subtrees the small stage builds from them: node records
    // per batch of roots, node and leaf reference counts per root.
    SmallRoots small_first;
    std::vector<SmallBatch> small_batches;
    // The split-candidate masks of the last batch (build_small.cl).
    DeviceArray side_masks;
    DeviceArray subtree_node_count, subtree_leaf_refs;
    cl_uint small_nodes = 0;
    int large_levels = 0, small_levels = 0;

    DeviceArray allocate(std::size_t bytes, const std::string& what) {
        return memory.allocate(bytes, what);
    }
    void add_batch(cl_uint count) {
        if (count == 0) return;
        batches.emplace_back(node_count, count);
        node_count += count;
    }
    void reserve_records(std::size_t nodes) {
        if (nodes > KDRAY_MAX_OFFSET)
            throw Error("OpenCL kd-tree build: " + std::to_string(nodes) +
                        " nodes exceed the layout's limit of " + std::to_string(KDRAY_MAX_OFFSET));
        memory.reserve(records, nodes * sizeof(KdBuildNode), node_count * sizeof(KdBuildNode),
                       "kd-tree node records");
    }
    void reserve_small_roots(std::size_t roots, std::size_t refs) {
        const std::size_t r = small_roots, n = small_refs;
        memory.reserve(small_ref_tri, refs * 4, n * 4, "small root triangle ids");
        memory.reserve(small_ref_box, refs * 24, n * 24, "small root triangle boxes");
        memory.reserve(small_ref_root, refs * 4, n * 4, "small root of each reference");
        memory.reserve(root_ref_start, roots * 4, r * 4, "small root reference starts");
        memory.reserve(root_ref_count, roots * 4, r * 4, "small root reference counts");
        memory.reserve(small_first.box, roots * 24, r * 24, "small node boxes");
        memory.reserve(small_first.depth, roots * 4, r * 4, "small node depths");
        memory.reserve(small_first.id, roots * 4, r * 4, "small node ids");
    }
};

template <class T>
void write_array(cl::CommandQueue& queue, const DeviceArray& array, const std::vector<T>& values) {
    with_cl_context("uploading build data", [&] {
        queue.enqueueWriteBuffer(array.buffer(), CL_TRUE, 0, values.size() * sizeof(T),
                                 values.data());
    });
}

inline cl_uint read_uint(cl::CommandQueue& queue, const DeviceArray& array, std::size_t index) {
    cl_uint value = 0;
    with_cl_context("reading a build count", [&] {
        queue.enqueueReadBuffer(array.buffer(), CL_TRUE, index * sizeof(cl_uint), sizeof(value),
                                &value);
    });
    return value;
}

inline std::vector<float> box_floats(const Aabb& b) {
    return {b.lo.x, b.lo.y, b.lo.z, b.hi.x, b.hi.y, b.hi.z};
}

inline cl_uint checked_u32(std::uint64_t value, const char* what) {
    if (value > 0xFFFFFFFFull)
        throw Error(std::string("OpenCL kd-tree build: ") + what + " overflow 32 bits (" +
                    std::to_string(value) + ")");
    return static_cast<cl_uint>(value);
}

/* Small-node stage (§4.2): every small root's subtree (opencl_builder_small.cpp), in batches of
 * roots whose masks and first records take at most batch_bytes each. */
void run_small_stage(Build& b, int max_depth, cl_uint first_scale, std::size_t batch_bytes);

/* Output stage (§4.3): the preorder nodes; the leaf indices go to leaf_indices. */
DeviceArray write_preorder(Build& b, DeviceArray& leaf_indices, cl_uint& leaf_index_count);

}  // namespace kdray::build_detail
