// embedded_kernels.h — the OpenCL sources that CMake embedded into the binary (embed_kernels.cmake),
// each with its `#include "core/..."` headers already inlined.
#pragma once

#include <string_view>

namespace kdray::cl_embedded {

struct EmbeddedKernel {
    const char* file_name;  // e.g. "build_large.cl"
    const char* source;
};

extern const EmbeddedKernel kernels[];
extern const int kernel_count;

}  // namespace kdray::cl_embedded

namespace kdray {

/// The embedded source of a kernel file by its file name. Throws Error when there is none.
std::string_view embedded_kernel_source(std::string_view file_name);

}  // namespace kdray
