// launch.h — one-dimensional kernel launches with kdray's error context. Every kernel of the
// builder takes its element count as an argument and returns early past it, so the global size is
// rounded up to a multiple of 64 (a warp/wavefront multiple on GPUs) and the work-group size is
// left to the implementation.
#pragma once

#include <cstddef>
#include <string>

#include <CL/opencl.hpp>

#include "cl/cl_error.h"

namespace kdray {

/// Sets the kernel's arguments in order.
template <class... Args>
void set_kernel_args(cl::Kernel& kernel, const Args&... args) {
    cl_uint index = 0;
    (kernel.setArg(index++, args), ...);
}

/// Enqueues `kernel` over `count` work-items (nothing when count is 0: OpenCL forbids empty
/// launches). `args` are set first. Errors name the kernel.
template <class... Args>
void enqueue_kernel(cl::CommandQueue& queue, cl::Kernel& kernel, std::size_t count,
                    const Args&... args) {
    if (count == 0) return;
    try {
        set_kernel_args(kernel, args...);
        const std::size_t global = (count + 63) / 64 * 64;
        queue.enqueueNDRangeKernel(kernel, cl::NullRange, cl::NDRange(global), cl::NullRange);
    } catch (const cl::Error& e) {
        throw_cl_error("running kernel " + kernel.getInfo<CL_KERNEL_FUNCTION_NAME>() + " over " +
                           std::to_string(count) + " items",
                       e.what(), e.err());
    }
}

}  // namespace kdray
