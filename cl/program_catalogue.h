// program_catalogue.h — every OpenCL program kdray can build on a device, with the options it
// builds it with, enumerated from the same functions the builder and the renderer call (no list
// kept by hand). scripts/kdray_programs.cpp prints it; scripts/gpu_compile.py compiles each entry
// for NVIDIA and AMD targets (docs/gpu-kernels.md).
#pragma once

#include <string>
#include <vector>

namespace kdray {

/// One program: its embedded kernel file and the full options cached_program passes.
struct ProgramSpec {
    std::string file, options;
};

/// Every program kdray builds on a CPU device (`cpu_device`: the packet kernels, the SWAR
/// popcount) or on any other, which does or does not offer correctly rounded divide and sqrt.
/// The large stage is listed at the build ladder's bin counts and at both ends of
/// --large-bins' range (its arrays grow with the count, so the largest is the costliest).
std::vector<ProgramSpec> buildable_programs(bool cpu_device, bool correctly_rounded_divide_sqrt);

}  // namespace kdray
