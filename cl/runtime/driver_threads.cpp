#include "cl/runtime/driver_threads.h"

#ifdef __linux__
#include <sched.h>
#endif

#include <algorithm>
#include <cstdlib>
#include <exception>
#include <fstream>
#include <optional>
#include <string>

namespace kdray {
namespace {

/// The CPUs of a kernel CPU list file ("0-3,6"), or nothing when it cannot be read or parsed.
/// Read from sysfs rather than sysconf(_SC_NPROCESSORS_ONLN), which some C libraries answer
/// with the process's affinity mask.
std::optional<std::vector<int>> read_cpu_list(const char* path) {
    std::ifstream file(path);
    std::string text;
    if (!std::getline(file, text)) return std::nullopt;
    std::vector<int> cpus;
    std::size_t at = 0;
    while (at < text.size()) {
        const std::size_t end = std::min(text.find(',', at), text.size());
        const std::string range = text.substr(at, end - at);
        const std::size_t dash = range.find('-');
        try {
            const int first = std::stoi(range.substr(0, dash));
            const int last = dash == std::string::npos ? first : std::stoi(range.substr(dash + 1));
            if (first < 0 || last < first || last > 65535) return std::nullopt;
            for (int cpu = first; cpu <= last; ++cpu) cpus.push_back(cpu);
        } catch (const std::exception&) {
            return std::nullopt;
        }
        at = end + 1;
    }
    return cpus;
}

bool is_pocl_affinity_on(const char* value) {
    return value && value[0] == '1';  // as PoCL reads a boolean option
}

}  // namespace

bool should_pin_cpu_driver_threads(const CpuDriverThreadsContext& context) {
    if (context.pocl_affinity || context.thread_count_set) return false;
    std::vector<int> online = context.online, possible = context.possible,
                     allowed = context.allowed;
    for (std::vector<int>* cpus : {&online, &possible, &allowed}) {
        std::sort(cpus->begin(), cpus->end());
        cpus->erase(std::unique(cpus->begin(), cpus->end()), cpus->end());
    }
    if (online.size() < 2 || online != possible || online != allowed) return false;
    for (std::size_t i = 0; i < online.size(); ++i)
        if (online[i] != int(i)) return false;
    return true;
}

void ask_cpu_driver_to_pin_threads() {
#ifdef __linux__
    CpuDriverThreadsContext context;
    context.pocl_affinity = std::getenv("POCL_AFFINITY");
    for (const char* name : kPoclThreadCountVariables)
        context.thread_count_set = context.thread_count_set || std::getenv(name);
    cpu_set_t mask;
    CPU_ZERO(&mask);
    if (::sched_getaffinity(0, sizeof(mask), &mask) != 0) return;
    for (int cpu = 0; cpu < CPU_SETSIZE; ++cpu)
        if (CPU_ISSET(cpu, &mask)) context.allowed.push_back(cpu);
    const auto online = read_cpu_list("/sys/devices/system/cpu/online");
    const auto possible = read_cpu_list("/sys/devices/system/cpu/possible");
    if (!online || !possible) return;
    context.online = *online;
    context.possible = *possible;
    if (should_pin_cpu_driver_threads(context)) ::setenv("POCL_AFFINITY", "1", 0);
#endif
}

bool pins_its_threads(const ClDeviceInfo& device) {
#ifdef __linux__
    return device.type == "CPU" && device.version.find("PoCL") != std::string::npos &&
           device.name.rfind("pthread", 0) == 0 &&
           is_pocl_affinity_on(std::getenv("POCL_AFFINITY"));
#else
    (void)device;
    return false;
#endif
}

}  // namespace kdray
