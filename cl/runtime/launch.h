// launch.h — one-dimensional kernel launches with kdray's error context. Every kernel of the
// builder takes its element count as an argument and returns early past it, so the global size is
// rounded up to a multiple of the launch's work-group size, which is fixed per kernel:
// KDRAY_LAUNCH_GROUP (core/device/kd_build_shared.h, where the per-level small stage's kernel
// reads it too) for most (enqueue_kernel), one for the depth-first subtrees (enqueue_per_item),
// up to KDRAY_REDUCE_CHUNK for the element-parallel large stage (enqueue_chunk_groups), and 16 for
// the chunked large stage's passes on CPU devices (enqueue_chunk_items).
//
// Why a fixed work-group size: PoCL compiles a separate work-group function for every local size
// it meets, and left to itself it picks the local size from the global size, which changes at
// every level of a build. Each new size was a compile (first run) or a dlopen of the cached
// variant (every later run): 8% of a kitchen build's profile sat in ld.so's symbol lookup. With
// one size each kernel has one variant. 64 is a warp/wavefront multiple on GPUs. A device or
// kernel that allows less gets the largest power of two it allows (work_group.h), which still
// divides the rounded global size; ClDevice::group_1d asks the device once per kernel and
// preferred size, and keeps the kernel with the answer.
#pragma once

#include <cstddef>
#include <string>
#include <utility>

#include <CL/opencl.hpp>

#include "cl/runtime/cl_error.h"
#include "cl/runtime/device.h"
#include "cl/runtime/work_group.h"
#include "core/device/kd_build_shared.h"

namespace kdray {

/// Sets the kernel's arguments in order.
template <class... Args>
void set_kernel_args(cl::Kernel& kernel, const Args&... args) {
    cl_uint index = 0;
    (kernel.setArg(index++, args), ...);
}

/// The one launch path of the functions below: nothing when count is 0 (OpenCL forbids empty
/// launches), else `args` set, then `kernel` over the global and local sizes that `shape` gives
/// (a std::pair); errors name the kernel and its count of `unit`.
template <class Shape, class... Args>
void enqueue_shaped(ClDevice& device, cl::Kernel& kernel, std::size_t count, const char* unit,
                    Shape shape, const Args&... args) {
    if (count == 0) return;
    try {
        set_kernel_args(kernel, args...);
        const auto [global, local] = shape();
        device.launch(kernel, cl::NDRange(global), cl::NDRange(local));
    } catch (const cl::Error& e) {
        throw_cl_error("running kernel " + kernel.getInfo<CL_KERNEL_FUNCTION_NAME>() + " over " +
                           std::to_string(count) + " " + unit,
                       e.what(), e.err());
    }
}

/// The global and local sizes of `count` work-items in work-groups of `group` (a power of two, or
/// whatever smaller power of two the kernel allows, which still divides the rounded count).
inline std::pair<std::size_t, std::size_t> groups_of(ClDevice& device, cl::Kernel& kernel,
                                                     std::size_t count, std::size_t group) {
    return {(count + group - 1) / group * group, device.group_1d(kernel, group)};
}

/// Enqueues `kernel` over `count` work-items (nothing when count is 0). `args` are set first.
/// Errors name the kernel.
template <class... Args>
void enqueue_kernel(ClDevice& device, cl::Kernel& kernel, std::size_t count, const Args&... args) {
    enqueue_shaped(
        device, kernel, count, "items",
        [&] { return groups_of(device, kernel, count, KDRAY_LAUNCH_GROUP); }, args...);
}

/// Enqueues `kernel` over `count` work-items that each walk a chunk of up to KDRAY_REDUCE_CHUNK
/// references (the chunked large stage's passes). On a CPU device, in work-groups of
/// kCpuChunkGroup: with KDRAY_LAUNCH_GROUP a level's few hundred chunks made a few work-groups,
/// which the device's compute units shared unevenly (the Kitchen's root level: 448 chunks in 7
/// groups, 4 for one of 2 cores and 3 for the other; in groups of 16, its `low` build's large
/// stage took 14.0 ms instead of 15.2, the median of 3 alternated runs of 9 builds). Other devices
/// keep KDRAY_LAUNCH_GROUP, a warp multiple on GPUs. Either way one size per kernel, as above.
inline constexpr std::size_t kCpuChunkGroup = 16;
static_assert((kCpuChunkGroup & (kCpuChunkGroup - 1)) == 0,
              "a smaller group that a kernel allows must divide the rounded global size");

template <class... Args>
void enqueue_chunk_items(ClDevice& device, cl::Kernel& kernel, std::size_t count,
                         const Args&... args) {
    const std::size_t group = device.is_cpu() ? kCpuChunkGroup : KDRAY_LAUNCH_GROUP;
    enqueue_shaped(
        device, kernel, count, "chunks", [&] { return groups_of(device, kernel, count, group); },
        args...);
}

/// Enqueues `kernel` over `count` work-items in work-groups of one: for kernels whose every item
/// walks a large piece of work of its own (a subtree), few of them, so that a CPU device spreads
/// the items over its cores (with groups of KDRAY_LAUNCH_GROUP, a group's items run one after
/// another on one core). One local size, so one compiled variant. Nothing when count is 0.
template <class... Args>
void enqueue_per_item(ClDevice& device, cl::Kernel& kernel, std::size_t count,
                      const Args&... args) {
    enqueue_shaped(
        device, kernel, count, "items", [&] { return std::pair(count, std::size_t(1)); }, args...);
}

/// Enqueues `kernel` over `groups` work-groups of one KDRAY_REDUCE_CHUNK-sized chunk each: the
/// local size is the largest power of two up to KDRAY_REDUCE_CHUNK that the kernel and the
/// device allow (choose_group_1d), and the kernel walks its chunk in rounds of that many
/// work-items (build_large_groups.cl). Nothing when groups is 0.
template <class... Args>
void enqueue_chunk_groups(ClDevice& device, cl::Kernel& kernel, std::size_t groups,
                          const Args&... args) {
    enqueue_shaped(
        device, kernel, groups, "work-groups",
        [&] {
            const std::size_t group = device.group_1d(kernel, KDRAY_REDUCE_CHUNK);
            return std::pair(groups * group, group);
        },
        args...);
}

}  // namespace kdray
