// driver_threads.h — asking PoCL's CPU driver to keep each worker thread on one CPU. PoCL runs
// kernels on one worker thread per logical CPU. On a 2-core virtual machine Linux kept its two
// threads on one CPU after the process's single-threaded start (the OBJ and the programs loaded)
// and through the builder's kernels of a few milliseconds each, so that they took turns: the same
// CPU time in up to half as long again, in a first build and in smaller scenes' later builds too
// (docs/performance.md, "Pinned threads"; docs/cold-build.md measures both placements). PoCL
// pins its thread i to CPU i when POCL_AFFINITY starts with 1; other drivers ignore the variable.
#pragma once

#include <vector>

#include "cl/runtime/device.h"

namespace kdray {

/// The variables with which a user sets PoCL's thread count (3.x and later releases' names).
inline constexpr const char* kPoclThreadCountVariables[] = {
    "POCL_MAX_PTHREAD_COUNT", "POCL_PTHREAD_MIN_THREADS", "POCL_CPU_MAX_CU_COUNT",
    "POCL_MAX_COMPUTE_UNITS"};

/// What decides whether to ask for pinned threads.
struct CpuDriverThreadsContext {
    const char* pocl_affinity = nullptr;  // POCL_AFFINITY's value, nullptr when unset
    bool thread_count_set = false;        // a variable that sets PoCL's thread count is set
    std::vector<int> allowed;             // the CPUs this process may run on
    std::vector<int> online;              // /sys/devices/system/cpu/online
    std::vector<int> possible;            // /sys/devices/system/cpu/possible
};

/// Whether to ask: only when the environment leaves POCL_AFFINITY open and PoCL's thread count
/// alone, and only when the process may run on every CPU and those are 0 to n - 1, all of the
/// possible ones (n >= 2). PoCL pins its thread i to CPU i and, since 3.0, aborts when that fails:
/// a process in a cgroup's cpuset without CPU i, or more threads than CPUs (POCL_MAX_PTHREAD_COUNT
/// and the like; a PoCL without hwloc counts the possible CPUs). Under taskset the pinning would
/// not fail but leave the CPUs the user chose.
bool should_pin_cpu_driver_threads(const CpuDriverThreadsContext& context);

/// Sets POCL_AFFINITY=1 for this process where should_pin_cpu_driver_threads says so (Linux only),
/// before the first OpenCL call: PoCL reads it as it starts its threads.
void ask_cpu_driver_to_pin_threads();

/// Whether `device` keeps each worker thread on one CPU: PoCL's pthread device on Linux, with
/// POCL_AFFINITY starting with 1 (set by ask_cpu_driver_to_pin_threads or by the user).
bool pins_its_threads(const ClDeviceInfo& device);

}  // namespace kdray
