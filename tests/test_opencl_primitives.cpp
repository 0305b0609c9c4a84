// test_opencl_primitives.cpp — the device layer and the parallel primitives of
// cl/runtime/kernels/primitives.cl checked against std:: on random inputs, at the sizes where
// chunked scans go wrong: empty, one element, powers of two and one either side, and sizes that
// need several recursion levels; 4096 and 4097 either side of the longest single-item scan on a
// CPU.
#include <doctest/doctest.h>

#include <algorithm>
#include <cmath>
#include <numeric>
#include <random>
#include <vector>

#include "cl/runtime/cl_error.h"
#include "cl/runtime/device.h"
#include "cl/runtime/primitives.h"
#include "cl/runtime/program_cache.h"
#include "core/device/kd_build_shared.h"
#include "core/device/kd_shared.h"
#include "core/error.h"
#include "tests/test_opencl_fixture.h"

using namespace kdray;

namespace {

const std::size_t kSizes[] = {0, 1, 2, 255, 256, 257, 1000, 4096, 4097, 100003};

cl::Buffer upload(ClDevice& device, const std::vector<cl_uint>& v) {
    cl::Buffer b = device.allocate((v.size() + 1) * sizeof(cl_uint), "test input");
    if (!v.empty())
        device.queue().enqueueWriteBuffer(b, CL_TRUE, 0, v.size() * sizeof(cl_uint), v.data());
    return b;
}

template <class T>
std::vector<T> download(ClDevice& device, const cl::Buffer& b, std::size_t n) {
    std::vector<T> v(n);
    if (n) device.queue().enqueueReadBuffer(b, CL_TRUE, 0, n * sizeof(T), v.data());
    return v;
}

}  // namespace

TEST_CASE("opencl device: listing, default selection and bad selectors") {
    const std::vector<ClDeviceInfo> devices = list_cl_devices();
    REQUIRE(!devices.empty());
    for (const ClDeviceInfo& d : devices) {
        CHECK(!d.name.empty());
        CHECK(d.compute_units > 0);
        CHECK(d.global_mem_bytes > 0);
        CHECK(d.max_alloc_bytes > 0);
    }
    ClDevice& device = test::opencl_test_device();
    CHECK(!device.info().name.empty());
    // An index past the end and a name nobody has must fail, and the message must list devices.
    try {
        ClDevice bad(std::to_string(devices.size()));
        FAIL("selecting a device index past the end did not throw");
    } catch (const Error& e) {
        CHECK(std::string(e.what()).find(devices.front().name) != std::string::npos);
    }
    CHECK_THROWS_AS(ClDevice("no-such-device-kdray"), Error);
}

TEST_CASE("a device lists the buffers it allocated until the runtime deletes them") {
    // The sanitizer build's check of kdray's own buffers (device.cpp) rests on this ledger: a
    // buffer named while any reference to it lives, and no longer once the last is released.
    ClDevice& device = test::opencl_test_device();
    const auto named = [&](const std::string& what) {
        const std::vector<std::string> live = device.live_buffers();
        return std::count(live.begin(), live.end(), what);
    };
    {
        cl::Buffer buffer = device.allocate(4096, "ledger test buffer");
        cl::Buffer copy = buffer;
        CHECK(named("ledger test buffer") == 1);
        buffer = cl::Buffer();
        CHECK(named("ledger test buffer") == 1);  // the copy still holds it
    }
    device.queue().finish();
    CHECK(named("ledger test buffer") == 0);
}

TEST_CASE("opencl errors carry the call and the code's name") {
    CHECK(cl_error_name(CL_OUT_OF_RESOURCES) == "CL_OUT_OF_RESOURCES");
    CHECK(cl_error_name(CL_MEM_OBJECT_ALLOCATION_FAILURE) == "CL_MEM_OBJECT_ALLOCATION_FAILURE");
    CHECK(cl_error_name(CL_INVALID_KERNEL_ARGS) == "CL_INVALID_KERNEL_ARGS");
    try {
        check_cl(CL_INVALID_VALUE, "doing a thing", "clDoThing");
        FAIL("check_cl did not throw");
    } catch (const Error& e) {
        const std::string msg = e.what();
        CHECK(msg.find("clDoThing") != std::string::npos);
        CHECK(msg.find("CL_INVALID_VALUE") != std::string::npos);
    }
    // An allocation beyond the device's limit names the size asked for.
    ClDevice& device = test::opencl_test_device();
    const std::size_t too_big = device.info().max_alloc_bytes + 1;
    try {
        device.allocate(too_big, "a huge buffer");
        FAIL("an oversized allocation did not throw");
    } catch (const Error& e) {
        CHECK(std::string(e.what()).find(std::to_string(too_big)) != std::string::npos);
    }
}

TEST_CASE("opencl programs are built once and failures carry the log") {
    ClDevice& device = test::opencl_test_device();
    ClPrimitives first(device);
    const int builds = program_build_count();
    cached_program(device, "primitives.cl");
    ClPrimitives again(device);
    CHECK(program_build_count() == builds);
    // A define that breaks the source must fail with the options in the message.
    try {
        cached_program(device, "layout.cl", "-Dreturn=kdray_undeclared_identifier");
        FAIL("a broken program built");
    } catch (const Error& e) {
        const std::string msg = e.what();
        CHECK(msg.find("-Dreturn=kdray_undeclared_identifier") != std::string::npos);
        CHECK(msg.find(device.info().name) != std::string::npos);
    }
}

TEST_CASE("opencl layout: the device's sizeof of every shared struct equals the host's") {
    ClDevice& device = test::opencl_test_device();
    cl::Kernel kernel = make_kernel(cached_program(device, "layout.cl"), "kd_report_layout");
    std::vector<cl_uint> host = {
        sizeof(KdNode),           sizeof(KdRay),           sizeof(KdHit),
        sizeof(KdMaterial),       sizeof(KdLight),         sizeof(KdView),
        sizeof(KdRayCounts),      sizeof(KdBuildBox),      sizeof(KdBuildNode),
        sizeof(KdSmallNode),      sizeof(KdLargeNode),     sizeof(KdLargeSplit),
        sizeof(KdLargeCuts),      sizeof(KdSmallRoot),     sizeof(KdLargeSplitArgs),
        sizeof(KdLargeLevelArgs), sizeof(KdSmallBatchArgs)};
    host.push_back(sizeof(KdEmitter));  // layout.cl reports these nine last
    host.push_back(sizeof(KdTexture));
    host.push_back(sizeof(KdSmallLevelNode));
    host.push_back(sizeof(KdSceneLayout));
    host.push_back(sizeof(KdRenderLaunch));
    host.push_back(sizeof(KdTraceCost));
    host.push_back(sizeof(KdDepthFirstArgs));
    host.push_back(sizeof(KdLargeRegion));
    host.push_back(sizeof(KdDepthFirstTask));
    cl::Buffer out = device.allocate((1 + host.size()) * sizeof(cl_uint), "layout report");
    kernel.setArg(0, out);
    device.queue().enqueueNDRangeKernel(kernel, cl::NullRange, cl::NDRange(1));
    const std::vector<cl_uint> dev = download<cl_uint>(device, out, 1 + host.size());
    REQUIRE(dev[0] == host.size());
    for (std::size_t i = 0; i < host.size(); ++i) CHECK(dev[1 + i] == host[i]);
}

TEST_CASE("opencl exclusive scan matches std::exclusive_scan") {
    ClDevice& device = test::opencl_test_device();
    ClPrimitives prims(device);
    std::mt19937 rng(7);
    for (std::size_t n : kSizes) {
        CAPTURE(n);
        std::vector<cl_uint> in(n);
        for (cl_uint& v : in) v = rng() % 100;
        cl::Buffer b_in = upload(device, in);
        cl::Buffer b_out = device.allocate((n + 1) * sizeof(cl_uint), "scan out");
        prims.exclusive_scan(b_in, b_out, n);
        std::vector<cl_uint> expect(n + 1, 0);
        std::exclusive_scan(in.begin(), in.end(), expect.begin(), cl_uint(0));
        expect[n] = std::accumulate(in.begin(), in.end(), cl_uint(0));
        CHECK(download<cl_uint>(device, b_out, n + 1) == expect);
        // In place as well: the builder scans its flag arrays in place.
        prims.exclusive_scan(b_in, b_in, n);
        CHECK(download<cl_uint>(device, b_in, n + 1) == expect);
    }
}

TEST_CASE("opencl compaction keeps the flagged values in order") {
    ClDevice& device = test::opencl_test_device();
    ClPrimitives prims(device);
    std::mt19937 rng(11);
    for (std::size_t n : kSizes) {
        CAPTURE(n);
        std::vector<cl_uint> values(n), flags(n);
        for (std::size_t i = 0; i < n; ++i) values[i] = rng(), flags[i] = rng() % 3 == 0;
        std::vector<cl_uint> expect;
        for (std::size_t i = 0; i < n; ++i)
            if (flags[i]) expect.push_back(values[i]);
        cl::Buffer out = device.allocate((n + 1) * sizeof(cl_uint), "compact out");
        const std::size_t count =
            prims.compact(upload(device, values), upload(device, flags), out, n);
        REQUIRE(count == expect.size());
        CHECK(download<cl_uint>(device, out, count) == expect);
    }
}

TEST_CASE("opencl segmented box reduction matches a host min/max") {
    ClDevice& device = test::opencl_test_device();
    ClPrimitives prims(device);
    std::mt19937 rng(13);
    std::uniform_real_distribution<float> coord(-100.0f, 100.0f);
    for (std::size_t n : kSizes) {
        CAPTURE(n);
        std::vector<float> boxes(6 * n);
        for (std::size_t i = 0; i < n; ++i)
            for (int a = 0; a < 3; ++a) {
                float x = coord(rng), y = coord(rng);
                boxes[6 * i + a] = std::min(x, y), boxes[6 * i + 3 + a] = std::max(x, y);
            }
        // Random segment boundaries, including empty segments and ones longer than a chunk.
        std::vector<cl_uint> start, count;
        for (std::size_t at = 0; at < n || start.empty();) {
            const std::size_t len = std::min<std::size_t>(n - at, rng() % 700);
            start.push_back(cl_uint(at)), count.push_back(cl_uint(len));
            at += len;
            if (n == 0) break;
        }
        const std::size_t segs = start.size();
        cl::Buffer b_boxes = device.allocate(boxes.size() * sizeof(float) + 4, "boxes");
        if (n)
            device.queue().enqueueWriteBuffer(b_boxes, CL_TRUE, 0, boxes.size() * 4, boxes.data());
        cl::Buffer chunk_start = device.allocate((segs + 1) * sizeof(cl_uint), "chunk starts");
        prims.box_chunk_starts(upload(device, count), segs, chunk_start);
        const cl_uint total_chunks = download<cl_uint>(device, chunk_start, segs + 1)[segs];
        cl::Buffer chunk_boxes = device.allocate(total_chunks * 6 * sizeof(float), "chunk boxes");
        cl::Buffer seg_boxes = device.allocate(segs * 6 * sizeof(float), "segment boxes");
        prims.reduce_box_segments(b_boxes, upload(device, start), upload(device, count),
                                  chunk_start, segs, total_chunks, chunk_boxes, seg_boxes);
        const std::vector<float> got = download<float>(device, seg_boxes, 6 * segs);
        for (std::size_t s = 0; s < segs; ++s)
            for (int a = 0; a < 3; ++a) {
                float lo = INFINITY, hi = -INFINITY;
                for (std::size_t i = start[s]; i < start[s] + count[s]; ++i)
                    lo = std::min(lo, boxes[6 * i + a]), hi = std::max(hi, boxes[6 * i + 3 + a]);
                CHECK(got[6 * s + a] == lo);
                CHECK(got[6 * s + 3 + a] == hi);
            }
    }
}
