// cl_error.h — turns every OpenCL failure into a kdray::Error that names the call, the error
// code's name (CL_OUT_OF_RESOURCES, ...) and what kdray was doing, so a user reading
// "kdray: error: ..." knows which step failed on which device without a debugger.
#pragma once

#include <cstddef>
#include <string>
#include <utility>

#include <CL/opencl.hpp>

#include "core/error.h"

namespace kdray {

/// The name of an OpenCL error code ("CL_OUT_OF_RESOURCES"), or "unknown OpenCL error <code>".
std::string cl_error_name(cl_int code);

/// Throws Error("<what>: <call> failed with <NAME> (<code>)").
[[noreturn]] void throw_cl_error(const std::string& what, const std::string& call, cl_int code);

/// Throws as throw_cl_error when code is not CL_SUCCESS (for the C API calls).
inline void check_cl(cl_int code, const std::string& what, const char* call) {
    if (code != CL_SUCCESS) throw_cl_error(what, call, code);
}

/// Runs f() and rethrows a cl::Error from the C++ bindings as a kdray::Error with `what` as
/// context. The bindings put the failing call's name in cl::Error::what().
template <class F>
auto with_cl_context(const std::string& what, F&& f) -> decltype(f()) {
    try {
        return std::forward<F>(f)();
    } catch (const cl::Error& e) {
        throw_cl_error(what, e.what(), e.err());
    }
}

/// Allocation failures name the size asked for: the commonest failure on a real GPU is a build
/// that outgrows CL_DEVICE_MAX_MEM_ALLOC_SIZE or global memory.
[[noreturn]] void throw_cl_allocation_error(const std::string& what, std::size_t bytes,
                                            cl_int code);

}  // namespace kdray
