// cl_error.cpp — the OpenCL error-code name table and the kdray::Error messages built from it.
#include "cl/runtime/cl_error.h"

namespace kdray {

std::string cl_error_name(cl_int code) {
    switch (code) {
#define KDRAY_CL_ERROR_CASE(name) \
    case name:                    \
        return #name;
        KDRAY_CL_ERROR_CASE(CL_SUCCESS)
        KDRAY_CL_ERROR_CASE(CL_DEVICE_NOT_FOUND)
        KDRAY_CL_ERROR_CASE(CL_DEVICE_NOT_AVAILABLE)
        KDRAY_CL_ERROR_CASE(CL_COMPILER_NOT_AVAILABLE)
        KDRAY_CL_ERROR_CASE(CL_MEM_OBJECT_ALLOCATION_FAILURE)
        KDRAY_CL_ERROR_CASE(CL_OUT_OF_RESOURCES)
        KDRAY_CL_ERROR_CASE(CL_OUT_OF_HOST_MEMORY)
        KDRAY_CL_ERROR_CASE(CL_PROFILING_INFO_NOT_AVAILABLE)
        KDRAY_CL_ERROR_CASE(CL_MEM_COPY_OVERLAP)
        KDRAY_CL_ERROR_CASE(CL_IMAGE_FORMAT_MISMATCH)
        KDRAY_CL_ERROR_CASE(CL_IMAGE_FORMAT_NOT_SUPPORTED)
        KDRAY_CL_ERROR_CASE(CL_BUILD_PROGRAM_FAILURE)
        KDRAY_CL_ERROR_CASE(CL_MAP_FAILURE)
        KDRAY_CL_ERROR_CASE(CL_MISALIGNED_SUB_BUFFER_OFFSET)
        KDRAY_CL_ERROR_CASE(CL_EXEC_STATUS_ERROR_FOR_EVENTS_IN_WAIT_LIST)
        KDRAY_CL_ERROR_CASE(CL_COMPILE_PROGRAM_FAILURE)
        KDRAY_CL_ERROR_CASE(CL_LINKER_NOT_AVAILABLE)
        KDRAY_CL_ERROR_CASE(CL_LINK_PROGRAM_FAILURE)
        KDRAY_CL_ERROR_CASE(CL_DEVICE_PARTITION_FAILED)
        KDRAY_CL_ERROR_CASE(CL_KERNEL_ARG_INFO_NOT_AVAILABLE)
        KDRAY_CL_ERROR_CASE(CL_INVALID_VALUE)
        KDRAY_CL_ERROR_CASE(CL_INVALID_DEVICE_TYPE)
        KDRAY_CL_ERROR_CASE(CL_INVALID_PLATFORM)
        KDRAY_CL_ERROR_CASE(CL_INVALID_DEVICE)
        KDRAY_CL_ERROR_CASE(CL_INVALID_CONTEXT)
        KDRAY_CL_ERROR_CASE(CL_INVALID_QUEUE_PROPERTIES)
        KDRAY_CL_ERROR_CASE(CL_INVALID_COMMAND_QUEUE)
        KDRAY_CL_ERROR_CASE(CL_INVALID_HOST_PTR)
        KDRAY_CL_ERROR_CASE(CL_INVALID_MEM_OBJECT)
        KDRAY_CL_ERROR_CASE(CL_INVALID_IMAGE_FORMAT_DESCRIPTOR)
        KDRAY_CL_ERROR_CASE(CL_INVALID_IMAGE_SIZE)
        KDRAY_CL_ERROR_CASE(CL_INVALID_SAMPLER)
        KDRAY_CL_ERROR_CASE(CL_INVALID_BINARY)
        KDRAY_CL_ERROR_CASE(CL_INVALID_BUILD_OPTIONS)
        KDRAY_CL_ERROR_CASE(CL_INVALID_PROGRAM)
        KDRAY_CL_ERROR_CASE(CL_INVALID_PROGRAM_EXECUTABLE)
        KDRAY_CL_ERROR_CASE(CL_INVALID_KERNEL_NAME)
        KDRAY_CL_ERROR_CASE(CL_INVALID_KERNEL_DEFINITION)
        KDRAY_CL_ERROR_CASE(CL_INVALID_KERNEL)
        KDRAY_CL_ERROR_CASE(CL_INVALID_ARG_INDEX)
        KDRAY_CL_ERROR_CASE(CL_INVALID_ARG_VALUE)
        KDRAY_CL_ERROR_CASE(CL_INVALID_ARG_SIZE)
        KDRAY_CL_ERROR_CASE(CL_INVALID_KERNEL_ARGS)
        KDRAY_CL_ERROR_CASE(CL_INVALID_WORK_DIMENSION)
        KDRAY_CL_ERROR_CASE(CL_INVALID_WORK_GROUP_SIZE)
        KDRAY_CL_ERROR_CASE(CL_INVALID_WORK_ITEM_SIZE)
        KDRAY_CL_ERROR_CASE(CL_INVALID_GLOBAL_OFFSET)
        KDRAY_CL_ERROR_CASE(CL_INVALID_EVENT_WAIT_LIST)
        KDRAY_CL_ERROR_CASE(CL_INVALID_EVENT)
        KDRAY_CL_ERROR_CASE(CL_INVALID_OPERATION)
        KDRAY_CL_ERROR_CASE(CL_INVALID_GL_OBJECT)
        KDRAY_CL_ERROR_CASE(CL_INVALID_BUFFER_SIZE)
        KDRAY_CL_ERROR_CASE(CL_INVALID_MIP_LEVEL)
        KDRAY_CL_ERROR_CASE(CL_INVALID_GLOBAL_WORK_SIZE)
        KDRAY_CL_ERROR_CASE(CL_INVALID_PROPERTY)
        KDRAY_CL_ERROR_CASE(CL_INVALID_IMAGE_DESCRIPTOR)
        KDRAY_CL_ERROR_CASE(CL_INVALID_COMPILER_OPTIONS)
        KDRAY_CL_ERROR_CASE(CL_INVALID_LINKER_OPTIONS)
        KDRAY_CL_ERROR_CASE(CL_INVALID_DEVICE_PARTITION_COUNT)
#undef KDRAY_CL_ERROR_CASE
        // Codes of later OpenCL versions and of ICD loaders, which an OpenCL 1.2 build's headers
        // may not define but a 2.x/3.x driver can still return.
        case -69:
            return "CL_INVALID_PIPE_SIZE";
        case -70:
            return "CL_INVALID_DEVICE_QUEUE";
        case -71:
            return "CL_INVALID_SPEC_ID";
        case -72:
            return "CL_MAX_SIZE_RESTRICTION_EXCEEDED";
        case -1001:
            return "CL_PLATFORM_NOT_FOUND_KHR";
        default:
            return "unknown OpenCL error " + std::to_string(code);
    }
}

void throw_cl_error(const std::string& what, const std::string& call, cl_int code) {
    throw Error(what + ": " + call + " failed with " + cl_error_name(code) + " (" +
                std::to_string(code) + ")");
}

void throw_cl_allocation_error(const std::string& what, std::size_t bytes, cl_int code) {
    throw Error(what + ": allocating " + std::to_string(bytes) + " bytes (" +
                std::to_string(bytes / (1024.0 * 1024.0)) + " MiB) of device memory failed with " +
                cl_error_name(code) + " (" + std::to_string(code) + ")");
}

}  // namespace kdray
