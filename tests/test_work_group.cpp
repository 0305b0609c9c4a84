// test_work_group.cpp — work-group shapes chosen from the limits a device reports
// (cl/runtime/work_group.h). The limits here are those of devices kdray had not met: a GPU that
// compiles a register-heavy kernel for 32 work-items, Oclgrind told --max-wgsize 16, a device
// with 16 KiB of local memory; each must yield a smaller group that still divides the launch's
// rounded global size, or an error that names the kernel and the limit.
#include <doctest/doctest.h>

#include <string>

#include "cl/renderer/opencl_renderer.h"
#include "cl/runtime/program_cache.h"
#include "cl/runtime/work_group.h"
#include "core/device/kd_build_shared.h"
#include "core/error.h"
#include "tests/test_opencl_fixture.h"

using namespace kdray;

namespace {

KernelLimits limits(std::size_t kernel_max, std::size_t local = 0, std::size_t required = 0) {
    KernelLimits l;
    l.kernel_max_group = kernel_max;
    l.required_group[0] = required;
    l.required_group[1] = l.required_group[2] = required ? 1 : 0;
    l.device_max_items[0] = l.device_max_items[1] = l.device_max_items[2] = 1024;
    l.kernel_local_bytes = local;
    l.device_local_bytes = 32768;
    return l;
}

std::string error_of(auto&& f) {
    try {
        f();
    } catch (const Error& e) {
        return e.what();
    }
    return "";
}

}  // namespace

TEST_CASE("1-D groups: the preferred size where allowed, else the largest power of two below") {
    CHECK(choose_group_1d("k", limits(1024), 64) == 64);
    CHECK(choose_group_1d("k", limits(64), 64) == 64);
    CHECK(choose_group_1d("k", limits(48), 64) == 32);  // 48 does not divide a multiple of 64
    CHECK(choose_group_1d("k", limits(1), 64) == 1);
    KernelLimits narrow = limits(1024);
    narrow.device_max_items[0] = 16;  // CL_DEVICE_MAX_WORK_ITEM_SIZES bounds each dimension
    CHECK(choose_group_1d("k", narrow, 64) == 16);
}

TEST_CASE("a required group size the device does not allow is an error naming kernel and limit") {
    CHECK(choose_group_1d("kd_split_small_level", limits(256, 0, 64), 64) == 64);
    const std::string e =
        error_of([] { choose_group_1d("kd_split_small_level", limits(32, 0, 64), 64); });
    CHECK(e.find("kd_split_small_level") != std::string::npos);
    CHECK(e.find("64") != std::string::npos);
    CHECK(e.find("allows 32 (CL_KERNEL_WORK_GROUP_SIZE)") != std::string::npos);
}

TEST_CASE("local memory beyond the device's is an error naming kernel and both sizes") {
    const std::string e = error_of([] { choose_group_1d("kd_x", limits(256, 40000, 64), 64); });
    CHECK(e.find("kd_x needs 40000 bytes of local memory") != std::string::npos);
    CHECK(e.find("has 32768 (CL_DEVICE_LOCAL_MEM_SIZE)") != std::string::npos);
    CHECK(error_of([] { choose_tile("kd_render_pixels", limits(256, 32769), {8, 8}); }) != "");
}

TEST_CASE("render tiles shrink, longer side first, to what the kernel allows") {
    auto tile = [](std::size_t max) { return choose_tile("k", limits(max), {8, 8}); };
    CHECK(tile(256).width == 8);
    CHECK(tile(256).height == 8);
    CHECK(tile(32).width == 8);
    CHECK(tile(32).height == 4);
    CHECK(tile(16).width == 4);
    CHECK(tile(16).height == 4);
    CHECK(tile(1).width * tile(1).height == 1);
}

TEST_CASE("a kernel on this device: its limits are read and 64 fits the builder's kernels") {
    ClDevice& device = test::opencl_test_device();
    cl::Kernel k = make_kernel(cached_program(device, "primitives.cl"), "kd_fill_uint");
    const KernelLimits l = query_kernel_limits(k, device.device()());
    CHECK(l.kernel_max_group >= 1);
    CHECK(l.device_local_bytes > 0);
    CHECK(choose_group_1d("kd_fill_uint", l, KDRAY_LAUNCH_GROUP) ==
          std::min<std::size_t>(KDRAY_LAUNCH_GROUP, l.kernel_max_group));
}

TEST_CASE("pixel tile: one pixel per group for the path integrator on a CPU device, else 8x8") {
    // PoCL runs a work-group as a loop over its work-items, which cost the path kernel 6-10% of
    // its time (opencl_renderer.cpp); a GPU keeps its square tiles for coherent SIMD lanes.
    OpenClRenderChoice path, whitted;
    path.effects = KDRAY_EFFECT_PATH | KDRAY_EFFECT_AREA_LIGHTS;
    whitted.effects = KDRAY_EFFECT_SHADOWS | KDRAY_EFFECT_AREA_LIGHTS;
    const Tile cpu_path = preferred_pixel_tile(true, path);
    CHECK(cpu_path.width * cpu_path.height == 1u);
    for (const Tile t : {preferred_pixel_tile(false, path), preferred_pixel_tile(true, whitted),
                         preferred_pixel_tile(false, whitted)}) {
        CHECK(t.width == 8u);
        CHECK(t.height == 8u);
    }
}
