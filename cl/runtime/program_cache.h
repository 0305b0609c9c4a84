// program_cache.h — OpenCL programs built from the embedded kernel sources, once per device.
//
// A cold PoCL compile takes about a second per program, so a program is built at most once for a
// given (device, file, options) and reused by every later build or trace of the device; across
// processes PoCL's own on-disk kernel cache (left enabled) skips the compile again.
//
// The cache belongs to its ClDevice and is released with it, before main returns: an OpenCL call
// made from a static destructor runs after the runtime's thread-local state is gone (exit destroys
// thread_local objects first), and Oclgrind's clReleaseProgram then wrote into its freed API-call
// stack ("corrupted double-linked list" after a failed run).
#pragma once

#include <functional>
#include <map>
#include <memory>
#include <mutex>
#include <string>
#include <string_view>
#include <typeinfo>
#include <utility>

#include <CL/opencl.hpp>

#include "cl/runtime/device.h"

namespace kdray {

/// One device's built programs and the kernel sets made from them (cached_program,
/// cached_kernels); ClDevice owns it.
class ProgramCache {
  public:
    ProgramCache() = default;
    ProgramCache(const ProgramCache&) = delete;
    ProgramCache& operator=(const ProgramCache&) = delete;

  private:
    friend cl::Program cached_program(const ClDevice&, std::string_view, const std::string&);
    friend std::shared_ptr<void> detail_cached_object(
        const ClDevice&, const std::string&, const std::function<std::shared_ptr<void>()>&);
    using Key = std::pair<std::string, std::string>;  // (file, options), or (object key, "")
    std::mutex programs_mutex;
    std::map<Key, cl::Program> programs;
    // Its own lock: making an object builds programs, under programs_mutex.
    std::mutex objects_mutex;
    std::map<std::string, std::shared_ptr<void>> objects;
};

/// The program of embedded kernel file `file` ("primitives.cl") built for `device` with the
/// options "-cl-std=CL1.2 -w <defines>" (-w: no warnings on stderr). Thread-safe. A failed build
/// throws Error with the build log, the device's name and the options.
cl::Program cached_program(const ClDevice& device, std::string_view file,
                           const std::string& defines = "");

/// The build options cached_program passes for `defines`: "-cl-std=CL1.2 -w <defines>" (-w: no
/// warnings on stderr). Also what kdray_programs prints for the GPU compile check.
std::string program_build_options(const std::string& defines);

/// What the cache tells its listener: a program's build starting (done false) or ended (done
/// true, after ms milliseconds, failed or not).
struct ProgramBuildEvent {
    std::string file, device;
    bool done = false;
    double ms = 0;
};
/// The one listener of the process (empty: none), told of every build cached_program starts and
/// ends, so that a command line can say why its first frame takes seconds. Called on the
/// building thread, with the cache locked: it must not build programs itself.
void set_program_build_listener(std::function<void(const ProgramBuildEvent&)> listener);

/// Kernel `name` of `program`; throws Error naming the kernel when it does not exist.
cl::Kernel make_kernel(const cl::Program& program, const char* name);

/// How many programs the cache has built in this process (tests check that nothing is rebuilt).
int program_build_count();
/// Milliseconds this process has spent compiling (what a frame's compile_ms is the growth of):
/// building programs here (from source, clBuildProgram, failed builds included), and what
/// add_compile_ms adds.
double compile_ms_total();
/// Counts `ms` of compilation done outside cached_program: a first launch that only makes the
/// device compile a kernel for its work-group size (PoCL compiles there, not in clBuildProgram).
void add_compile_ms(double ms);

/// The object of `key` in the device's cache, made by make() the first time.
std::shared_ptr<void> detail_cached_object(const ClDevice& device, const std::string& key,
                                           const std::function<std::shared_ptr<void>()>& make);

/// A set of kernels (a struct of cl::Kernel) that make() creates once per (device, type, key) and
/// the device keeps: clCreateKernel for every kernel of every build cost each build its own
/// kernel objects. A cl::Kernel carries its arguments and is not thread-safe, so a set
/// serves one caller at a time; kdray's builds and renders run one after another on the device's
/// one in-order queue. Creating a set is thread-safe.
template <class Set, class Make>
Set& cached_kernels(const ClDevice& device, const std::string& key, Make&& make) {
    const std::string full_key = std::string(typeid(Set).name()) + "|" + key;
    return *static_cast<Set*>(detail_cached_object(device, full_key, [&] {
                                  return std::shared_ptr<void>(std::make_shared<Set>(make()));
                              }).get());
}

}  // namespace kdray
