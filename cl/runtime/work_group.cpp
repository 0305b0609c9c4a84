#include "cl/runtime/work_group.h"

#include "cl/runtime/cl_error.h"
#include "core/error.h"

namespace kdray {
namespace {

void check_local_memory(const std::string& kernel, const KernelLimits& limits) {
    if (limits.kernel_local_bytes > limits.device_local_bytes)
        throw Error("OpenCL kernel " + kernel + " needs " +
                    std::to_string(limits.kernel_local_bytes) +
                    " bytes of local memory per work-group (CL_KERNEL_LOCAL_MEM_SIZE); the device "
                    "has " +
                    std::to_string(limits.device_local_bytes) + " (CL_DEVICE_LOCAL_MEM_SIZE)");
}

/// Whether a group of w x h work-items is allowed.
bool fits(const KernelLimits& limits, std::size_t w, std::size_t h) {
    return w * h <= limits.kernel_max_group && w <= limits.device_max_items[0] &&
           h <= limits.device_max_items[1];
}

[[noreturn]] void throw_group(const std::string& kernel, const std::string& group,
                              const KernelLimits& limits) {
    throw Error("OpenCL kernel " + kernel + " cannot run in work-groups of " + group +
                " work-items on this device: it allows " +
                std::to_string(limits.kernel_max_group) +
                " (CL_KERNEL_WORK_GROUP_SIZE), at most " +
                std::to_string(limits.device_max_items[0]) + " x " +
                std::to_string(limits.device_max_items[1]) + " (CL_DEVICE_MAX_WORK_ITEM_SIZES)");
}

}  // namespace

KernelLimits query_kernel_limits(const cl::Kernel& kernel, const cl_device_id device) {
    KernelLimits l;
    const std::string what = "querying the work-group limits of an OpenCL kernel";
    check_cl(clGetKernelWorkGroupInfo(kernel(), device, CL_KERNEL_WORK_GROUP_SIZE,
                                      sizeof(l.kernel_max_group), &l.kernel_max_group, nullptr),
             what, "clGetKernelWorkGroupInfo");
    check_cl(clGetKernelWorkGroupInfo(kernel(), device, CL_KERNEL_COMPILE_WORK_GROUP_SIZE,
                                      sizeof(l.required_group), l.required_group, nullptr),
             what, "clGetKernelWorkGroupInfo");
    cl_ulong local = 0;
    check_cl(clGetKernelWorkGroupInfo(kernel(), device, CL_KERNEL_LOCAL_MEM_SIZE, sizeof(local),
                                      &local, nullptr),
             what, "clGetKernelWorkGroupInfo");
    l.kernel_local_bytes = local;
    check_cl(clGetDeviceInfo(device, CL_DEVICE_LOCAL_MEM_SIZE, sizeof(local), &local, nullptr),
             what, "clGetDeviceInfo");
    l.device_local_bytes = local;
    // Every device has at least three dimensions (OpenCL 1.2: CL_DEVICE_MAX_WORK_ITEM_DIMENSIONS).
    check_cl(clGetDeviceInfo(device, CL_DEVICE_MAX_WORK_ITEM_SIZES, sizeof(l.device_max_items),
                             l.device_max_items, nullptr),
             what, "clGetDeviceInfo");
    return l;
}

std::size_t choose_group_1d(const std::string& kernel, const KernelLimits& limits,
                            std::size_t preferred) {
    check_local_memory(kernel, limits);
    if (const std::size_t required = limits.required_group[0]; required != 0) {
        if (!fits(limits, required, 1))
            throw_group(kernel, std::to_string(required) + " (its reqd_work_group_size)", limits);
        return required;
    }
    std::size_t group = preferred;
    while (group > 1 && !fits(limits, group, 1)) group /= 2;
    if (!fits(limits, group, 1)) throw_group(kernel, "1", limits);
    return group;
}

Tile choose_tile(const std::string& kernel, const KernelLimits& limits, Tile preferred) {
    check_local_memory(kernel, limits);
    Tile t = preferred;
    while (t.width * t.height > 1 && !fits(limits, t.width, t.height)) {
        if (t.height >= t.width)
            t.height /= 2;
        else
            t.width /= 2;
    }
    if (!fits(limits, t.width, t.height)) throw_group(kernel, "1 x 1", limits);
    return t;
}

}  // namespace kdray
