// program_cache.cpp — the process-wide cache of built OpenCL programs.
#include "cl/runtime/program_cache.h"

#include <chrono>
#include <map>
#include <mutex>
#include <tuple>
#include <utility>

#include "cl/runtime/cl_error.h"
#include "cl/runtime/embedded_kernels.h"
#include "core/error.h"

namespace kdray {
namespace {

using ProgramKey = std::tuple<cl_context, cl_device_id, std::string, std::string>;

std::mutex cache_mutex;
std::map<ProgramKey, cl::Program> cache;
int builds = 0;
// compile_ms_total: its own lock, since cached_program holds cache_mutex while it builds.
std::mutex compile_mutex;
double compile_ms = 0;
std::function<void(const ProgramBuildEvent&)> build_listener;  // under cache_mutex

}  // namespace

cl::Program cached_program(const ClDevice& device, std::string_view file,
                           const std::string& defines) {
    // -w: PoCL prints its compiler's warnings on stderr ("145 warnings generated.", clang's
    // -Wpsabi notes on 16-lane vectors wherever the CPU lacks AVX-512), where they would land
    // between kdray's own lines; errors still fail the build with the log.
    const std::string options = "-cl-std=CL1.2 -w" + (defines.empty() ? "" : " " + defines);
    ProgramKey key{device.context()(), device.device()(), std::string(file), options};
    std::lock_guard<std::mutex> lock(cache_mutex);
    if (auto it = cache.find(key); it != cache.end()) return it->second;

    const std::string what = "building OpenCL program " + std::string(file);
    const std::string_view source = embedded_kernel_source(file);
    if (build_listener) build_listener({std::string(file), device.info().name, false, 0});
    const auto start = std::chrono::steady_clock::now();
    cl::Program program =
        with_cl_context(what, [&] { return cl::Program(device.context(), std::string(source)); });
    const cl_device_id id = device.device()();
    const cl_int status = clBuildProgram(program(), 1, &id, options.c_str(), nullptr, nullptr);
    const double ms =
        std::chrono::duration<double, std::milli>(std::chrono::steady_clock::now() - start).count();
    add_compile_ms(ms);
    if (build_listener) build_listener({std::string(file), device.info().name, true, ms});
    if (status != CL_SUCCESS) {
        std::string log;
        try {
            log = program.getBuildInfo<CL_PROGRAM_BUILD_LOG>(device.device());
        } catch (const cl::Error&) {
            log = "(no build log available)";
        }
        while (!log.empty() && (log.back() == '\0' || log.back() == '\n')) log.pop_back();
        throw Error(what + " for device '" + device.info().name + "' with options '" + options +
                    "' failed with " + cl_error_name(status) + ":\n" + log);
    }
    ++builds;
    cache.emplace(std::move(key), program);
    return program;
}

cl::Kernel make_kernel(const cl::Program& program, const char* name) {
    cl_int status = CL_SUCCESS;
    cl_kernel kernel = clCreateKernel(program(), name, &status);
    check_cl(status, std::string("creating OpenCL kernel ") + name, "clCreateKernel");
    return cl::Kernel(kernel);
}

std::shared_ptr<void> detail::cached_object(const ClDevice& device, const std::string& key,
                                            const std::function<std::shared_ptr<void>()>& make) {
    // Its own lock: make() builds programs, under cache_mutex.
    static std::mutex objects_mutex;
    static std::map<ProgramKey, std::shared_ptr<void>> objects;
    ProgramKey object_key{device.context()(), device.device()(), key, ""};
    std::lock_guard<std::mutex> lock(objects_mutex);
    if (auto it = objects.find(object_key); it != objects.end()) return it->second;
    std::shared_ptr<void> object = make();
    objects.emplace(std::move(object_key), object);
    return object;
}

void set_program_build_listener(std::function<void(const ProgramBuildEvent&)> listener) {
    std::lock_guard<std::mutex> lock(cache_mutex);
    build_listener = std::move(listener);
}

int program_build_count() {
    std::lock_guard<std::mutex> lock(cache_mutex);
    return builds;
}

double compile_ms_total() {
    std::lock_guard<std::mutex> lock(compile_mutex);
    return compile_ms;
}

void add_compile_ms(double ms) {
    std::lock_guard<std::mutex> lock(compile_mutex);
    compile_ms += ms;
}

}  // namespace kdray
