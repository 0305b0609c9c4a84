#include "cl/runtime/embedded_kernels.h"

#include <string>

#include "core/error.h"

namespace kdray {

std::string_view embedded_kernel_source(std::string_view file_name) {
    for (int i = 0; i < cl_embedded::kernel_count; ++i)
        if (file_name == cl_embedded::kernels[i].file_name) return cl_embedded::kernels[i].source;
    throw Error("no embedded OpenCL source named '" + std::string(file_name) + "'");
}

}  // namespace kdray
