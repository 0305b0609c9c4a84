// test_driver_threads.cpp — PoCL's CPU threads pinned (driver_environment.h's
// pin_cpu_driver_threads): only where the environment leaves it open and the process may run on
// every online CPU, and what `kdray stats` says of it.
#include <doctest/doctest.h>
#include <sched.h>
#include <unistd.h>

#include <cstdlib>
#include <string>
#include <vector>

#include <nlohmann/json.hpp>

#include "cl/runtime/driver_environment.h"
#include "tests/support.h"

using namespace kdray;

TEST_CASE("threads are pinned only when the environment leaves it open and every CPU is allowed") {
    CHECK(should_pin_cpu_driver_threads(nullptr, {0, 1}, 2));
    CHECK(should_pin_cpu_driver_threads(nullptr, {3, 1, 2, 0}, 4));
    // The user's setting stands, either way.
    CHECK_FALSE(should_pin_cpu_driver_threads("0", {0, 1}, 2));
    CHECK_FALSE(should_pin_cpu_driver_threads("1", {0, 1}, 2));
    // A process confined to some CPUs (taskset, a cpuset): PoCL's thread 0 would go to CPU 0.
    CHECK_FALSE(should_pin_cpu_driver_threads(nullptr, {1}, 2));
    CHECK_FALSE(should_pin_cpu_driver_threads(nullptr, {2, 3}, 4));
    // CPU 1 offline: the online CPUs are not 0 to n - 1.
    CHECK_FALSE(should_pin_cpu_driver_threads(nullptr, {0, 2}, 2));
    // One CPU: nothing to keep apart.
    CHECK_FALSE(should_pin_cpu_driver_threads(nullptr, {0}, 1));
}

namespace {

/// The "threads_pinned" of `kdray stats --json`'s first PoCL CPU device, after `shell_setup` in
/// its shell; `found` says whether there is one.
bool stats_says_pinned(const std::string& shell_setup, bool* found) {
    const test::CommandResult r = test::run_kdray({"stats", "--json"}, 120, shell_setup);
    REQUIRE(r.status == 0);
    *found = false;
    for (const auto& device : nlohmann::json::parse(r.out)["devices"])
        if (device.value("type", "") == "CPU" &&
            device.value("version", "").find("PoCL") != std::string::npos) {
            *found = true;
            return device.value("threads_pinned", false);
        }
    return false;
}

/// Whether this process may run on CPUs 0 to n - 1, n the online CPUs (read from the kernel's
/// lists rather than through the code under test).
bool may_run_on_every_cpu() {
    cpu_set_t mask;
    CPU_ZERO(&mask);
    if (sched_getaffinity(0, sizeof(mask), &mask) != 0) return false;
    const long online = sysconf(_SC_NPROCESSORS_ONLN);
    for (long cpu = 0; cpu < online; ++cpu)
        if (!CPU_ISSET(int(cpu), &mask)) return false;
    return CPU_COUNT(&mask) == online;
}

}  // namespace

TEST_CASE("kdray stats says whether PoCL's threads are pinned: the user's choice, and taskset") {
    bool found = false;
    const bool by_default = stats_says_pinned("unset POCL_AFFINITY", &found);
    if (!found) {
        MESSAGE("no PoCL CPU device: nothing to check");
        return;
    }
    CHECK(by_default == (may_run_on_every_cpu() && sysconf(_SC_NPROCESSORS_ONLN) > 1));
    CHECK_FALSE(stats_says_pinned("export POCL_AFFINITY=0", &found));
    CHECK(stats_says_pinned("export POCL_AFFINITY=1", &found));
    if (sysconf(_SC_NPROCESSORS_ONLN) > 1 && std::system("command -v taskset >/dev/null") == 0) {
        // The shell confined to one CPU (kdray inherits it): left as it was, and kdray runs.
        CHECK_FALSE(
            stats_says_pinned("unset POCL_AFFINITY; taskset -p -c 0 $$ >/dev/null", &found));
    }
}
