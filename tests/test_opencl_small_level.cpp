// test_opencl_small_level.cpp — the OpenCL builder's small stage in the paper's level-parallel
// shape (Zhou et al. 2008, §4.2; cl/builder/small_levels.cpp) against its per-root shape: the two
// must build the same tree node for node on the scenes where the small stage's rarer paths run
// (re-clipping, flat faces, planar triangles, the second pass, batches), and each tree must pass
// the checker and trace as brute force does. A per-level kernel that priced, picked, re-clipped
// or laid out one node differently would show as a node that differs.
#include <doctest/doctest.h>

#include <cmath>
#include <string>
#include <utility>
#include <vector>

#include "cl/builder/opencl_builder.h"
#include "core/scene/scene.h"
#include "core/tree/build_quality.h"
#include "core/tree/tree_stats.h"
#include "tests/support.h"
#include "tests/test_opencl_fixture.h"

using namespace kdray;

namespace {

BuildParams with_stage(BuildParams params, SmallStage stage) {
    params.small_stage = stage;
    return params;
}

/// Builds `scene` with both shapes (and `limits`) and checks that the per-level tree is the
/// per-root one, that each build reports the shape it ran, and that the SAH is the same.
void check_same_as_per_root(const Scene& scene, const std::string& name,
                            const BuildParams& params = {},
                            const detail::SmallStageLimits& limits = {}) {
    CAPTURE(name);
    ClDevice& device = test::opencl_test_device();
    BuildReport root_report, level_report;
    const KdTree per_root = detail::build_opencl_with_limits(
        device, scene, with_stage(params, SmallStage::PerRoot), limits, &root_report);
    const KdTree per_level = detail::build_opencl_with_limits(
        device, scene, with_stage(params, SmallStage::PerLevel), limits, &level_report);
    CHECK(root_report.small_stage == "per-root");
    CHECK(level_report.small_stage == "per-level");
    CHECK(level_report.small_node_levels == root_report.small_node_levels);
    CHECK(compute_tree_stats(per_level, scene.triangle_count(), params.costs).sah_cost ==
          compute_tree_stats(per_root, scene.triangle_count(), params.costs).sah_cost);
    test::check_same_tree(per_level, per_root, scene, 29);
}

/// 64 tiny triangles scattered through a cube: one small root whose SAH isolates each triangle
/// and cuts the empty space around it, deeper than the per-root stage's first records allow.
Scene scattered() {
    std::vector<float> tris;
    for (int i = 0; i < 64; ++i) {
        const float x = (float(i) + 0.5f) / 64.0f, y = std::fmod(x * 7.0f, 1.0f);
        const float z = std::fmod(x * 13.0f, 1.0f), d = 0.001f;
        tris.insert(tris.end(), {x, y, z, x + d, y, z + d, x, y + d, z + d});
    }
    return make_scene(std::move(tris), "scattered");
}

}  // namespace

TEST_CASE("opencl small stage: per-level builds the per-root trees of the hard scenes") {
    for (const test::NamedScene& s : test::hard_scenes()) check_same_as_per_root(s.scene, s.name);
    check_same_as_per_root(scattered(), "scattered");
    check_same_as_per_root(test::random_triangles(5000, 1005), "random_5000");
}

TEST_CASE("opencl small stage: per-level re-clips as per-root does") {
    // Long slivers and needles cross many small nodes, which re-clip them (a table rebuilt by
    // every descendant's work-group from the re-clipping node's box); planar triangles take the
    // cheaper side and flat faces become leaves through the same candidate lanes.
    for (std::uint32_t seed : {1u, 2u, 3u})
        check_same_as_per_root(test::long_slivers(60, seed),
                               "long_slivers_" + std::to_string(seed));
    check_same_as_per_root(test::needles(300, 6), "needles");
    check_same_as_per_root(test::planar_triangles(1500, 2), "planar");
}

TEST_CASE("opencl small stage: per-level builds the per-root trees at every build quality") {
    for (BuildQuality q : {BuildQuality::Low, BuildQuality::Medium, BuildQuality::High}) {
        const BuildParams params = with_build_quality({}, q);
        const std::string level = build_quality_name(q);
        check_same_as_per_root(test::random_triangles(3000, 37), "random_3000 " + level, params);
        check_same_as_per_root(test::long_slivers(60, 4), "long_slivers " + level, params);
    }
    BuildParams shallow;
    shallow.max_depth = 6;
    check_same_as_per_root(test::random_triangles(2000, 21), "depth 6", shallow);
}

TEST_CASE("opencl small stage: per-level bins small nodes as per-root does, re-clipped or not") {
    // Binned nodes (no masks) above the re-clip size, then the exact search over the re-clipped
    // tables below it; with no re-clipping, bins all the way down, flat faces and planar
    // triangles included.
    for (int reclip : {0, 32}) {
        BuildParams params;
        params.small_split_bins = 8;
        params.small_reclip_refs = reclip;
        const std::string tag = " bins 8 reclip " + std::to_string(reclip);
        for (std::uint32_t seed : {1u, 2u})
            check_same_as_per_root(test::long_slivers(60, seed),
                                   "long_slivers_" + std::to_string(seed) + tag, params);
        check_same_as_per_root(test::planar_triangles(1500, 2), "planar" + tag, params);
        check_same_as_per_root(test::cube_lattice(5), "cube_lattice" + tag, params);
        check_same_as_per_root(scattered(), "scattered" + tag, params);
    }
    BuildParams params;
    params.small_split_bins = 16;
    for (const test::NamedScene& s : test::hard_scenes())
        check_same_as_per_root(s.scene, s.name + " bins 16", params);
}

TEST_CASE("opencl small stage: per-level lays out batches and second-pass records as per-root") {
    // Batches of 16 KB of masks (tens of batches) and a first-pass scale of 1 (most subtrees
    // outgrow their first records): the per-level stage writes its records where the per-root
    // one does, which the output stage reads.
    for (const detail::SmallStageLimits limits :
         {detail::SmallStageLimits{10, 16384}, detail::SmallStageLimits{1, 0},
          detail::SmallStageLimits{1, 16384}}) {
        CAPTURE(limits.subtree_budget_scale);
        CAPTURE(limits.batch_bytes);
        check_same_as_per_root(test::random_triangles(3000, 31), "random_3000", {}, limits);
        check_same_as_per_root(test::cube_lattice(5), "cube_lattice", {}, limits);
        check_same_as_per_root(scattered(), "scattered", {}, limits);
    }
}

TEST_CASE("opencl small stage: per-level builds the per-root trees of the testdata scenes") {
    for (const char* file : {"testdata/cornell/room.obj", "testdata/anim/frame_000.obj",
                             "testdata/anim/frame_007.obj"})
        check_same_as_per_root(load_obj(test::source_dir() / file), file);
}

TEST_CASE("opencl small stage: auto takes per-level on a GPU and per-root elsewhere") {
    ClDevice& device = test::opencl_test_device();
    BuildReport report;
    build_opencl(device, test::random_triangles(500, 3), {}, &report);
    CHECK(report.small_stage == (device.is_gpu() ? "per-level" : "per-root"));
    // An empty scene builds no small stage, but says which it would have run.
    build_opencl(device, make_scene({}, "empty"), with_stage({}, SmallStage::PerLevel), &report);
    CHECK(report.small_stage == "per-level");
}
