// work_group.h — the work-group shape of a launch, chosen from what the device and the compiled
// kernel report instead of assumed: kdray prefers 64 work-items for the builder's 1-D kernels
// (KDRAY_LAUNCH_GROUP; launch.h lists the few that prefer other sizes), 8x8 pixel tiles for the
// render kernels and 4 packet tiles, but a GPU may compile a kernel that uses many registers for
// smaller groups (CL_KERNEL_WORK_GROUP_SIZE), and Oclgrind can be told any limit (--max-wgsize).
// Where a kernel allows a smaller group, a smaller one is chosen; where it cannot
// (reqd_work_group_size, local memory beyond the device's), the error names the kernel and the
// limit.
#pragma once

#include <cstddef>
#include <cstdint>
#include <string>

#include <CL/opencl.hpp>

namespace kdray {

/// What one kernel may run with on one device.
struct KernelLimits {
    std::size_t kernel_max_group = 0;         // CL_KERNEL_WORK_GROUP_SIZE
    std::size_t required_group[3] = {0, 0, 0};  // CL_KERNEL_COMPILE_WORK_GROUP_SIZE (0: none)
    std::size_t device_max_items[3] = {0, 0, 0};  // CL_DEVICE_MAX_WORK_ITEM_SIZES
    std::uint64_t kernel_local_bytes = 0;       // CL_KERNEL_LOCAL_MEM_SIZE
    std::uint64_t device_local_bytes = 0;       // CL_DEVICE_LOCAL_MEM_SIZE
};

/// The limits of `kernel` on `device` (the OpenCL queries above).
KernelLimits query_kernel_limits(const cl::Kernel& kernel, const cl_device_id device);

/// The work-items of a 1-D group of `kernel`: its required size when it has one, else
/// `preferred` (a power of two) halved until the kernel and the device allow it, so that it
/// still divides a global size rounded up to `preferred`. Throws Error naming the kernel and the
/// limit when its local memory exceeds the device's or its required size is not allowed.
std::size_t choose_group_1d(const std::string& kernel, const KernelLimits& limits,
                            std::size_t preferred);

/// A 2-D tile of pixels (work-items) per work-group.
struct Tile {
    std::size_t width = 0, height = 0;
};

/// `preferred` (powers of two), its longer side halved (the height on a tie) until the kernel and
/// the device allow it; the same errors as choose_group_1d.
Tile choose_tile(const std::string& kernel, const KernelLimits& limits, Tile preferred);

}  // namespace kdray
