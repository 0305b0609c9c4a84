// sanitizer_leak_probe.cpp — the sanitizer build's check of its leak checks. LeakSanitizer's
// suppressions (tests/lsan.supp) hide what the OpenCL runtime keeps alive until exit (its platform
// and device state, the compiler's), and with it every cl_mem, so ClDevice checks kdray's buffers
// itself. This program does what a build does, opening a device, compiling a program, creating a
// kernel, filling and reading a buffer and waiting on an event, and then releases all of it: it
// must exit 0. With --leak-buffer it keeps one reference to its buffer's cl_mem, as a kdray that
// forgot a buffer would, and closing the device must name that buffer and fail.
#include <cstdio>
#include <cstring>
#include <exception>
#include <vector>

#include <CL/opencl.hpp>

#include "cl/runtime/device.h"

namespace {

// A program of its own rather than kdray's kernels: the probe depends on the runtime alone.
constexpr const char* kProbeSource =
    "__kernel void probe_add_one(__global uint* data) { data[get_global_id(0)] += 1u; }\n";

int run(bool leak_buffer) {
    kdray::ClDevice device;
    cl::Program program(device.context(), kProbeSource);
    program.build({device.device()}, "-w");
    cl::Kernel kernel(program, "probe_add_one");

    constexpr std::size_t kCount = 1 << 16;
    std::vector<cl_uint> data(kCount, 41u);
    cl::Buffer buffer = device.allocate(kCount * sizeof(cl_uint), "leak probe");
    cl::CommandQueue& queue = device.queue();
    queue.enqueueWriteBuffer(buffer, CL_TRUE, 0, kCount * sizeof(cl_uint), data.data());
    kernel.setArg(0, buffer);
    cl::Event done;
    queue.enqueueNDRangeKernel(kernel, cl::NullRange, cl::NDRange(kCount), cl::NullRange, nullptr,
                               &done);
    done.wait();
    queue.enqueueReadBuffer(buffer, CL_TRUE, 0, kCount * sizeof(cl_uint), data.data());
    for (cl_uint value : data)
        if (value != 42u) {
            std::fprintf(stderr, "sanitizer_leak_probe: the kernel computed %u, not 42\n", value);
            return 2;
        }
    // What a forgotten cl::Buffer amounts to: a reference to the cl_mem that nobody releases.
    if (leak_buffer) clRetainMemObject(buffer());
    return 0;
}

}  // namespace

int main(int argc, char** argv) {
    const bool leak_buffer = argc > 1 && std::strcmp(argv[1], "--leak-buffer") == 0;
    try {
        return run(leak_buffer);
    } catch (const std::exception& e) {
        std::fprintf(stderr, "sanitizer_leak_probe: %s\n", e.what());
        return 2;
    }
}
