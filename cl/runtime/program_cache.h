// program_cache.h — OpenCL programs built from the embedded kernel sources, once per process.
//
// A cold PoCL compile takes about a second per program, so a program is built at most once for a
// given (context, device, file, options) and reused by every later build or trace in the process;
// across processes PoCL's own on-disk kernel cache (left enabled) skips the compile again.
#pragma once

#include <string>
#include <string_view>

#include <CL/opencl.hpp>

#include "cl/runtime/device.h"

namespace kdray {

/// The program of embedded kernel file `file` ("primitives.cl") built for `device` with the
/// options "-cl-std=CL1.2 <defines>". Thread-safe. A failed build throws Error with the build
/// log, the device's name and the options.
cl::Program cached_program(const ClDevice& device, std::string_view file,
                           const std::string& defines = "");

/// Kernel `name` of `program`; throws Error naming the kernel when it does not exist.
cl::Kernel make_kernel(const cl::Program& program, const char* name);

/// How many programs the cache has built in this process (tests check that nothing is rebuilt).
int program_build_count();

}  // namespace kdray
