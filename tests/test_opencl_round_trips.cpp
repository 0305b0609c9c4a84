// test_opencl_round_trips.cpp — the OpenCL builder's round trips with its device (#26), counted by
// ClDevice (DeviceTraffic): a large level waits on the device once, a level of the per-level
// small stage once, the rest of a build a stated number of times; the trees stay valid, agree
// with brute force ray by ray, and are the same with either small stage.
#include <doctest/doctest.h>

#include <cstdint>
#include <string>
#include <vector>

#include "cl/builder/opencl_builder.h"
#include "cl/runtime/primitives.h"
#include "core/tree/tree_check.h"
#include "tests/support.h"
#include "tests/test_opencl_fixture.h"

using namespace kdray;

namespace {

// The waits that are not a level's: a finish per stage for the stage times (6), the per-root
// small stage's totals, the second pass's record count, and the output's leaf index count.
constexpr std::uint64_t kWaitsBesideLevels = 9;
// The transfers that are not a level's read: the triangles, the root level's four arrays, the
// output's two start positions, the small stage's totals and second-pass count, the leaf index
// count, the tree's nodes and leaf indices.
constexpr std::uint64_t kTransfersBesideLevels = 12;

BuildParams with_stage(SmallStage stage, LargeStage large = LargeStage::Chunked) {
    BuildParams params;
    params.small_stage = stage;
    params.large_stage = large;
    return params;
}

/// The buffer of `values`, written and waited for.
cl::Buffer uploaded(ClDevice& device, const std::vector<cl_uint>& values) {
    cl::Buffer buffer = device.allocate(values.size() * sizeof(cl_uint), "test values");
    device.write(buffer, 0, values.size() * sizeof(cl_uint), values.data(), "test upload");
    return buffer;
}

}  // namespace

TEST_CASE("opencl round trips: a scan waits for nothing, a compaction once, each counted") {
    ClDevice& device = test::opencl_test_device();
    ClPrimitives primitives(device);
    // Long enough for the chunked scan with its recursive scan of the chunk sums.
    std::vector<cl_uint> flags(200000);
    for (std::size_t i = 0; i < flags.size(); ++i) flags[i] = (i % 3 == 0) ? 1u : 0u;
    const cl::Buffer in = uploaded(device, flags);
    const cl::Buffer out = device.allocate((flags.size() + 1) * sizeof(cl_uint), "test scan");

    const DeviceTraffic before = device.traffic();
    primitives.exclusive_scan(in, out, flags.size());
    const DeviceTraffic scanned = device.traffic();
    CHECK(scanned.syncs == before.syncs);
    CHECK(scanned.transfers == before.transfers);
    CHECK(scanned.launches >= before.launches + 3);  // chunks, their sums' scan, the offsets

    cl_uint total = 0;
    device.read(out, flags.size() * sizeof(cl_uint), sizeof(total), &total, "test read");
    CHECK(total == (flags.size() + 2) / 3);
    CHECK(device.traffic().syncs == scanned.syncs + 1);

    const cl::Buffer values = uploaded(device, flags);
    const cl::Buffer compacted = device.allocate(flags.size() * sizeof(cl_uint), "test compact");
    const DeviceTraffic before_compact = device.traffic();
    CHECK(primitives.compact(values, in, compacted, flags.size()) == total);
    CHECK(device.traffic().syncs == before_compact.syncs + 1);
}

TEST_CASE("opencl round trips: a build waits once per level and a stated number of times more") {
    ClDevice& device = test::opencl_test_device();
    // Many large levels (threshold 64): each used to read its totals in 15 transfers.
    const Scene scene = test::random_triangles(20000, 11);
    BuildReport root_report, level_report;
    const KdTree per_root =
        build_opencl(device, scene, with_stage(SmallStage::PerRoot), &root_report);
    const KdTree per_level =
        build_opencl(device, scene, with_stage(SmallStage::PerLevel), &level_report);
    for (const BuildReport* report : {&root_report, &level_report}) {
        CAPTURE(report->small_stage);
        CAPTURE(report->device_syncs);
        CAPTURE(report->device_transfers);
        CAPTURE(report->kernel_launches);
        REQUIRE(report->large_node_levels >= 5);
        const std::uint64_t levels =
            std::uint64_t(report->large_node_levels) +
            (report == &level_report ? std::uint64_t(report->small_node_levels) : 0);
        CHECK(report->device_syncs >= std::uint64_t(report->large_node_levels));
        CHECK(report->device_syncs <= levels + kWaitsBesideLevels);
        CHECK(report->device_transfers <= levels + kTransfersBesideLevels);
        // Each large level launches its bounds, split, classification, counts, scans and
        // writes: about a dozen kernels.
        CHECK(report->kernel_launches >= 8 * std::uint64_t(report->large_node_levels));
    }
    REQUIRE(check_tree(per_root, scene).empty());
    CHECK(test::count_disagreements(per_root, scene, test::random_rays(scene, 2000, 5)) == 0);
    test::check_same_tree(per_level, per_root, scene, 31);

    // The depth-first large stage: fewer levels, then its subtrees' sizes read once, and per run
    // of its kernel (more than one when arenas ran out) the arenas' starts written and the
    // subtrees' counts read; then their output bases written.
    BuildReport depth_first_report;
    const KdTree depth_first =
        build_opencl(device, scene, with_stage(SmallStage::PerRoot, LargeStage::DepthFirst),
                     &depth_first_report);
    const BuildReport& d = depth_first_report;
    CAPTURE(d.device_syncs);
    CAPTURE(d.device_transfers);
    CAPTURE(d.depth_first_rounds);
    REQUIRE(d.depth_first_subtrees > 0);
    CHECK(d.large_node_levels < root_report.large_node_levels);
    const std::uint64_t rounds = std::uint64_t(d.depth_first_rounds);
    CHECK(d.device_syncs <= std::uint64_t(d.large_node_levels) + kWaitsBesideLevels + 1 + rounds);
    CHECK(d.device_transfers <=
          std::uint64_t(d.large_node_levels) + kTransfersBesideLevels + 2 + 2 * rounds);
    CHECK(d.kernel_launches < root_report.kernel_launches);
    test::check_same_tree(depth_first, per_root, scene, 31);
}

TEST_CASE("opencl round trips: a build's scans take their scratch from its memory") {
    // The scans' chunk sums were a new buffer per scan, per level, per build; from the build's
    // DeviceMemory they are recycled, so a second scan allocates nothing.
    ClDevice& device = test::opencl_test_device();
    DeviceMemory memory(device);
    // An array in use, as a build holds its level's: the memory keeps spares beside it.
    const DeviceArray held = memory.allocate(1 << 20, "test array in use");
    ClPrimitives primitives(device, &memory);
    const std::vector<cl_uint> ones(200000, 1u);
    const cl::Buffer in = uploaded(device, ones);
    const cl::Buffer out = device.allocate((ones.size() + 1) * sizeof(cl_uint), "test scan");
    primitives.exclusive_scan(in, out, ones.size());
    const std::uint64_t before = device.allocated_bytes();
    primitives.exclusive_scan(in, out, ones.size());
    CHECK(device.allocated_bytes() == before);
    cl_uint total = 0;
    device.read(out, ones.size() * sizeof(cl_uint), sizeof(total), &total, "test read");
    CHECK(total == ones.size());
}
