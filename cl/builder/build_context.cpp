// build_context.cpp — the builder's kernels (made once per device), and the records and helpers
// that its stages share (build_context.h).
#include "cl/builder/build_context.h"

#include <string>

#include "cl/runtime/program_cache.h"
#include "core/error.h"

namespace kdray::build_detail {

BuilderKernels& builder_kernels(const ClDevice& device, int large_split_bins) {
    return cached_kernels<BuilderKernels>(device, std::to_string(large_split_bins), [&] {
        // -D only for compile-time choices; the layouts and constants are
        // core/device/kd_build_shared.h's.
        const cl::Program large =
            cached_program(device, "build_large.cl", large_program_defines(large_split_bins));
        const cl::Program small =
            cached_program(device, "build_small.cl", small_program_defines(device.is_cpu()));
        const cl::Program output = cached_program(device, "build_output.cl");
        BuilderKernels k;
        k.compute_aabbs = make_kernel(large, "kd_compute_aabbs");
        if (large_split_bins > 0) k.bin_large = make_kernel(large, "kd_bin_large_chunks");
        k.split_large = make_kernel(large, "kd_split_large_nodes");
        k.classify = make_kernel(large, "kd_classify_chunks");
        k.count_large = make_kernel(large, "kd_count_large_children");
        k.emit_large = make_kernel(large, "kd_emit_large_children");
        k.distribute = make_kernel(large, "kd_distribute_chunks");
        k.union_parent_boxes = make_kernel(large, "kd_union_parent_boxes");
        k.reduce_box_groups = make_kernel(large, "kd_reduce_box_chunk_groups");
        if (large_split_bins > 0) {
            k.bin_large_groups = make_kernel(large, "kd_bin_large_groups");
            k.sum_node_bins = make_kernel(large, "kd_sum_node_bins");
        }
        k.classify_groups = make_kernel(large, "kd_classify_chunk_groups");
        k.distribute_groups = make_kernel(large, "kd_distribute_chunk_groups");
        k.build_depth_first = make_kernel(large, "kd_build_large_depth_first");
        k.commit_depth_first = make_kernel(large, "kd_commit_depth_first");
        k.split_masks = make_kernel(small, "kd_compute_split_masks");
        k.split_masks_grouped = make_kernel(small, "kd_compute_split_masks_grouped");
        k.build_subtrees = make_kernel(small, "kd_build_small_subtrees");
        k.second_pass_records = make_kernel(small, "kd_second_pass_records");
        k.start_small_level = make_kernel(small, "kd_start_small_level");
        k.split_small_level = make_kernel(small, "kd_split_small_level");
        k.size_small_level = make_kernel(small, "kd_size_small_level");
        k.place_small_level = make_kernel(small, "kd_place_small_level");
        k.count_small_level = make_kernel(small, "kd_count_small_level");
        k.write_small_level = make_kernel(small, "kd_write_small_level");
        k.size_subtrees = make_kernel(output, "kd_size_subtrees");
        k.place_subtrees = make_kernel(output, "kd_place_subtrees");
        k.size_regions = make_kernel(output, "kd_size_regions");
        k.place_regions = make_kernel(output, "kd_place_regions");
        k.write_nodes = make_kernel(output, "kd_write_nodes");
        k.write_small = make_kernel(output, "kd_write_small_subtrees");
        return k;
    });
}

BuildContext::~BuildContext() {
    if (!uploads_pending_) return;
    try {
        device.finish("waiting for a failed build's uploads");
    } catch (const Error&) {
        // A failed queue runs nothing more, so nothing reads the memory either.
    }
}

std::string large_program_defines(int large_split_bins) {
    return "-DKDRAY_LARGE_BINS=" + std::to_string(large_split_bins) + "u";
}

std::string small_program_defines(bool cpu_device) {
    // CPU compilers may have no vector popcount (build_small_search.cl, kd_popcount8).
    return std::string("-DKDRAY_SWAR_POPCOUNT=") + (cpu_device ? "1" : "0");
}

cl_uint BuildContext::read_uint(const DeviceArray& array, std::size_t index) {
    cl_uint value = 0;
    device.read(array.buffer(), index * sizeof(cl_uint), sizeof(value), &value,
                "reading a build count");
    return value;
}

void BuildOutput::reserve_records(BuildContext& ctx, std::size_t nodes) {
    check_offset_limit(nodes, "nodes");
    ctx.reserve<KdBuildNode>(records, nodes, node_count, "kd-tree node records");
}

void BuildOutput::add_batch(cl_uint count) {
    if (count == 0) return;
    batches.emplace_back(node_count, count);
    node_count += count;
}

KdBuildBox build_box(const Aabb& b) {
    return {{b.lo.x, b.lo.y, b.lo.z}, {b.hi.x, b.hi.y, b.hi.z}};
}

cl_uint checked_u32(std::uint64_t value, const char* what) {
    if (value > 0xFFFFFFFFull)
        throw Error(std::string("OpenCL kd-tree build: ") + what + " overflow 32 bits (" +
                    std::to_string(value) + ")");
    return static_cast<cl_uint>(value);
}

void check_offset_limit(std::size_t count, const char* what) {
    if (count > KDRAY_MAX_OFFSET)
        throw Error("OpenCL kd-tree build: " + std::to_string(count) + " " + what +
                    " exceed the layout's limit of " + std::to_string(KDRAY_MAX_OFFSET));
}

}  // namespace kdray::build_detail
