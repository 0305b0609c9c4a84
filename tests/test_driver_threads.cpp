// test_driver_threads.cpp — PoCL's CPU threads pinned (cl/runtime/driver_threads.h): asked for
// only where the environment leaves it open and the process may run on every CPU, and what
// `kdray stats` says of it.
#include <doctest/doctest.h>
#include <sched.h>

#include <fstream>
#include <string>
#include <vector>

#include <nlohmann/json.hpp>

#include "cl/runtime/driver_threads.h"
#include "tests/support.h"

using namespace kdray;

TEST_CASE("pinned threads are asked for only where the environment and the CPUs allow") {
    const auto context = [](std::vector<int> allowed, std::vector<int> online) {
        CpuDriverThreadsContext c;
        c.allowed = allowed;
        c.online = online;
        c.possible = online;
        return c;
    };
    CHECK(should_pin_cpu_driver_threads(context({0, 1}, {0, 1})));
    CHECK(should_pin_cpu_driver_threads(context({3, 1, 2, 0}, {0, 1, 2, 3})));
    // The user's setting stands, either way, and so does a thread count of the user's: PoCL
    // would pin threads past the last CPU.
    CpuDriverThreadsContext set = context({0, 1}, {0, 1});
    set.pocl_affinity = "0";
    CHECK_FALSE(should_pin_cpu_driver_threads(set));
    set.pocl_affinity = "1";
    CHECK_FALSE(should_pin_cpu_driver_threads(set));
    CpuDriverThreadsContext counted = context({0, 1}, {0, 1});
    counted.thread_count_set = true;
    CHECK_FALSE(should_pin_cpu_driver_threads(counted));
    // A process confined to some CPUs (taskset, a cpuset): PoCL's thread 0 would go to CPU 0.
    CHECK_FALSE(should_pin_cpu_driver_threads(context({1}, {0, 1})));
    CHECK_FALSE(should_pin_cpu_driver_threads(context({2, 3}, {0, 1, 2, 3})));
    // CPU 1 offline: the online CPUs are not 0 to n - 1.
    CHECK_FALSE(should_pin_cpu_driver_threads(context({0, 2}, {0, 2})));
    // More possible CPUs than online ones (a PoCL without hwloc counts the possible).
    CpuDriverThreadsContext hotplug = context({0, 1}, {0, 1});
    hotplug.possible = {0, 1, 2, 3};
    CHECK_FALSE(should_pin_cpu_driver_threads(hotplug));
    // One CPU: nothing to keep apart.
    CHECK_FALSE(should_pin_cpu_driver_threads(context({0}, {0})));
}

namespace {

/// Shell commands that unset what would decide for kdray: POCL_AFFINITY and PoCL's thread count.
std::string unset_thread_variables() {
    std::string command = "unset POCL_AFFINITY";
    for (const char* name : kPoclThreadCountVariables) command += std::string(" ") + name;
    return command;
}

/// The "threads_pinned" of `kdray stats --json`'s PoCL pthread device, after `shell_setup` in its
/// shell; `found` says whether there is one.
bool stats_says_pinned(const std::string& shell_setup, bool* found) {
    const test::CommandResult r = test::run_kdray({"stats", "--json"}, 120, shell_setup);
    REQUIRE(r.status == 0);
    const nlohmann::json stats = nlohmann::json::parse(r.out);
    *found = false;
    for (const auto& device : stats["devices"])
        if (device.value("type", "") == "CPU" &&
            device.value("version", "").find("PoCL") != std::string::npos &&
            device.value("name", "").rfind("pthread", 0) == 0) {
            *found = true;
            return device.value("threads_pinned", false);
        }
    return false;
}

std::string first_line(const char* path) {
    std::ifstream file(path);
    std::string line;
    std::getline(file, line);
    return line;
}

/// The number of CPUs online when they are 0 to n - 1 and all of the possible ones, else 0 (the
/// kernel's own lists, read as text rather than through the code under test).
int contiguous_cpus() {
    const std::string online = first_line("/sys/devices/system/cpu/online");
    if (online.empty() || online != first_line("/sys/devices/system/cpu/possible")) return 0;
    if (online == "0") return 1;
    if (online.rfind("0-", 0) != 0 || online.find(',') != std::string::npos) return 0;
    return std::stoi(online.substr(2)) + 1;
}

/// Whether this process may run on every one of `cpus` CPUs, 0 to cpus - 1.
bool may_run_on(int cpus) {
    cpu_set_t mask;
    CPU_ZERO(&mask);
    if (sched_getaffinity(0, sizeof(mask), &mask) != 0) return false;
    return cpus > 0 && CPU_COUNT(&mask) == cpus && CPU_ISSET(cpus - 1, &mask);
}

}  // namespace

TEST_CASE("kdray stats says whether PoCL's threads are pinned: by default, by the user, confined") {
    const int cpus = contiguous_cpus();
    const bool every_cpu = may_run_on(cpus);
    bool found = false;
    const bool by_default = stats_says_pinned(unset_thread_variables(), &found);
    if (!found) {
        MESSAGE("no PoCL pthread device: nothing to check");
        return;
    }
    CHECK(by_default == (every_cpu && cpus > 1));
    CHECK_FALSE(stats_says_pinned("export POCL_AFFINITY=0", &found));
    CHECK_FALSE(
        stats_says_pinned(unset_thread_variables() + "; export POCL_MAX_PTHREAD_COUNT=2", &found));
    // Asked for by the user: only where PoCL can pin every thread (it aborts where it cannot).
    if (every_cpu) CHECK(stats_says_pinned("export POCL_AFFINITY=1", &found));
    if (every_cpu && cpus > 1) {
        // This process, and so the kdray it starts, confined to its last CPU: not asked for, and
        // kdray runs.
        cpu_set_t all, last;
        REQUIRE(sched_getaffinity(0, sizeof(all), &all) == 0);
        CPU_ZERO(&last);
        CPU_SET(cpus - 1, &last);
        REQUIRE(sched_setaffinity(0, sizeof(last), &last) == 0);
        const bool confined = stats_says_pinned(unset_thread_variables(), &found);
        REQUIRE(sched_setaffinity(0, sizeof(all), &all) == 0);
        CHECK_FALSE(confined);
    }
}
