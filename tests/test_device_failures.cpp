// test_device_failures.cpp — what a user sees when the OpenCL side fails: no platform at all, a
// kernel that does not compile, an allocation larger than the device allows, and a frame larger
// than its memory. Each must be a kdray::Error that says what happened and what to do, never a
// crash.
#include <doctest/doctest.h>

#include <algorithm>
#include <cstdint>
#include <cstdlib>
#include <filesystem>
#include <string>

#include <nlohmann/json.hpp>

#include "cl/runtime/device.h"
#include "cl/runtime/program_cache.h"
#include "core/error.h"
#include "tests/support.h"
#include "tests/test_opencl_fixture.h"

using namespace kdray;

TEST_CASE("no OpenCL platform: one error line that says how to install PoCL") {
    // ocl-icd looks for vendor files in OCL_ICD_VENDORS when it is set: an empty folder means no
    // platform at all, as on a machine without any OpenCL driver.
    const auto empty = test::fresh_temp_dir("no-icd");
    ::setenv("OCL_ICD_VENDORS", empty.c_str(), 1);
    const auto dir = test::fresh_temp_dir("no-icd-scene");
    const auto obj = test::write_text_file(dir / "t.obj", "v 0 0 0\nv 1 0 0\nv 0 1 0\nf 1 2 3\n");
    const test::CommandResult r = test::run_kdray({"build", obj.string()});
    ::unsetenv("OCL_ICD_VENDORS");
    CHECK(r.status == 1);
    CHECK(r.err.rfind("kdray: error: ", 0) == 0);
    CHECK(r.err.find("no OpenCL platform") != std::string::npos);
    CHECK(r.err.find("pocl-opencl-icd") != std::string::npos);
    CHECK(std::count(r.err.begin(), r.err.end(), '\n') == 1);
}

TEST_CASE("a kernel that does not compile: the error names the device, the options and the log") {
    ClDevice& device = test::opencl_test_device();
    // render.cl refuses to compile without a value for its effects (an #error in kd_render.h).
    const std::string broken = "-DKDRAY_COMPILED_EFFECTS_MISSING=1 -UKDRAY_COMPILED_EFFECTS";
    try {
        cached_program(device, "render.cl", broken);
        FAIL("a broken program built");
    } catch (const Error& e) {
        const std::string message = e.what();
        CHECK(message.find(device.info().name) != std::string::npos);
        CHECK(message.find(broken) != std::string::npos);
        CHECK(message.find("KDRAY_COMPILED_EFFECTS") != std::string::npos);  // from the build log
    }
}

TEST_CASE("an allocation beyond the device's limit names the size asked for") {
    ClDevice& device = test::opencl_test_device();
    const std::size_t too_big = std::size_t(device.info().max_alloc_bytes) + 4096;
    try {
        device.allocate(too_big, "the triangles of a huge scene");
        FAIL("an impossible allocation succeeded");
    } catch (const Error& e) {
        const std::string message = e.what();
        CHECK(message.find(std::to_string(too_big)) != std::string::npos);
        CHECK(message.find("the triangles of a huge scene") != std::string::npos);
    }
}

TEST_CASE("a frame larger than the device's memory is refused with the figures, before it traces") {
    // PoCL's POCL_MEMORY_LIMIT (GiB) gives its CPU device 1 GiB: a 6000 x 6000 frame's per-pixel
    // buffers need more, and the host has room for them. Another OpenCL implementation ignores
    // the variable; then the device's real size decides, and the case says so and stops.
    ::setenv("POCL_MEMORY_LIMIT", "1", 1);
    const test::CommandResult devices = test::run_kdray({"stats", "--json"});
    const auto dir = test::fresh_temp_dir("device-memory");
    const auto obj = test::write_text_file(dir / "t.obj", "v 0 0 0\nv 1 0 0\nv 0 1 0\nf 1 2 3\n");
    const auto camera = test::write_text_file(
        dir / "c.json",
        R"({"image":{"width":64,"height":48},"camera":{"position":[0.3,0.3,3],"look_at":[0.3,0.3,0]}})");
    const test::CommandResult r =
        test::run_kdray({"render", obj.string(), "--camera", camera.string(), "--size", "6000x6000",
                         "-o", (dir / "out").string(), "-q"},
                        120);
    ::unsetenv("POCL_MEMORY_LIMIT");
    const nlohmann::json listed = nlohmann::json::parse(devices.out);
    const std::uint64_t global = listed["devices"][0].value("global_mem_bytes", std::uint64_t(0));
    if (global != (std::uint64_t(1) << 30)) {
        MESSAGE("the first device ignores POCL_MEMORY_LIMIT (not PoCL): skipped");
        return;
    }
    INFO("stderr: " << r.err);
    CHECK(r.status == 1);
    CHECK(r.err.rfind("kdray: error: a 6000 x 6000 frame needs about ", 0) == 0);
    CHECK(r.err.find("MiB of device memory") != std::string::npos);
    CHECK(r.err.find("has 1024 MiB") != std::string::npos);
    CHECK(std::count(r.err.begin(), r.err.end(), '\n') == 1);
    CHECK(!std::filesystem::exists(dir / "out" / "t.png"));
    CHECK(!std::filesystem::exists(dir / "out" / "stats.json"));
}
