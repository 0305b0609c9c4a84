// program_cache.cpp — the process-wide cache of built OpenCL programs.
#include "cl/runtime/program_cache.h"

#include <chrono>
#include <map>
#include <mutex>
#include <utility>

#include "cl/runtime/cl_error.h"
#include "cl/runtime/embedded_kernels.h"
#include "core/error.h"

namespace kdray {
namespace {

// Process-wide counts and the listener (no OpenCL objects: those live in each device's cache).
std::mutex counts_mutex;
int builds = 0;
std::function<void(const ProgramBuildEvent&)> build_listener;  // under counts_mutex
// compile_ms_total: its own lock, since cached_program holds counts_mutex while it builds.
std::mutex compile_mutex;
double compile_ms = 0;

}  // namespace

std::string program_build_options(const std::string& defines) {
    // -w: PoCL prints its compiler's warnings on stderr ("145 warnings generated.", clang's
    // -Wpsabi notes on 16-lane vectors wherever the CPU lacks AVX-512), where they would land
    // between kdray's own lines; errors still fail the build with the log.
    return "-cl-std=CL1.2 -w" + (defines.empty() ? "" : " " + defines);
}

cl::Program cached_program(const ClDevice& device, std::string_view file,
                           const std::string& defines) {
    const std::string options = program_build_options(defines);
    ProgramCache& cache = device.program_cache();
    ProgramCache::Key key{std::string(file), options};
    std::lock_guard<std::mutex> lock(cache.programs_mutex);
    if (auto it = cache.programs.find(key); it != cache.programs.end()) return it->second;
    // Builds of different devices may overlap; the listener and the counts are the process's.
    std::lock_guard<std::mutex> counts_lock(counts_mutex);

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
    cache.programs.emplace(std::move(key), program);
    return program;
}

cl::Kernel make_kernel(const cl::Program& program, const char* name) {
    cl_int status = CL_SUCCESS;
    cl_kernel kernel = clCreateKernel(program(), name, &status);
    check_cl(status, std::string("creating OpenCL kernel ") + name, "clCreateKernel");
    return cl::Kernel(kernel);
}

std::shared_ptr<void> detail_cached_object(const ClDevice& device, const std::string& key,
                                           const std::function<std::shared_ptr<void>()>& make) {
    ProgramCache& cache = device.program_cache();
    std::lock_guard<std::mutex> lock(cache.objects_mutex);
    if (auto it = cache.objects.find(key); it != cache.objects.end()) return it->second;
    std::shared_ptr<void> object = make();
    cache.objects.emplace(key, object);
    return object;
}

void set_program_build_listener(std::function<void(const ProgramBuildEvent&)> listener) {
    std::lock_guard<std::mutex> lock(counts_mutex);
    build_listener = std::move(listener);
}

int program_build_count() {
    std::lock_guard<std::mutex> lock(counts_mutex);
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
