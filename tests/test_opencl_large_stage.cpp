// test_opencl_large_stage.cpp — the OpenCL builder's large stage in the paper's element-parallel
// shape (--large-stage level: a work-item per reference, a work-group per reduction chunk;
// build_large_groups.cl) and in its depth-first schedule (--large-stage depth-first: chunked
// levels, then a work-item per subtree; build_large_depth_first.cl) against its chunked shape (a
// work-item per chunk, build_large.cl): the three must build the same tree node for node, at every
// quality, on scenes where the large stage runs many levels, cuts empty space, clips straddlers,
// makes leaves of coincident faces and splits at the median (no bins). A group kernel that ranked,
// binned, clipped or reduced one reference differently would show as a node or a leaf index that
// differs; each tree also traces as brute force does (check_same_tree).
#include <doctest/doctest.h>

#include <filesystem>
#include <string>
#include <utility>
#include <vector>

#include "cl/builder/opencl_builder.h"
#include "core/scene/scene.h"
#include "core/tree/build_quality.h"
#include "core/tree/tree_check.h"
#include "core/tree/tree_stats.h"
#include "tests/support.h"
#include "tests/test_opencl_fixture.h"

using namespace kdray;

namespace {

BuildParams with_stage(BuildParams params, LargeStage stage) {
    params.large_stage = stage;
    return params;
}

/// What check_same_as_chunked expects of the depth-first build beyond its tree.
enum class DepthFirst {
    Any,       // whatever the scene makes (a scene split into leaves at once makes no subtree)
    Subtrees,  // subtrees handed to the depth-first schedule
    OneRound,  // ... whose arenas all fit at the first run (real scenes)
    Retried,   // ... some of which ran out of arena and were built again
};

/// Builds `scene` with every large-stage shape and checks that the level and depth-first trees
/// are the chunked one, that each build says which shape ran, that both level-by-level shapes
/// took the same number of large levels, and what `expect` says of the depth-first schedule.
/// `limits` apply to the depth-first build.
void check_same_as_chunked(const Scene& scene, const std::string& name,
                           const BuildParams& params = {}, DepthFirst expect = DepthFirst::Any,
                           const detail::SmallStageLimits& limits = {}) {
    CAPTURE(name);
    ClDevice& device = test::opencl_test_device();
    BuildReport chunked_report, level_report, depth_first_report;
    const KdTree chunked =
        build_opencl(device, scene, with_stage(params, LargeStage::Chunked), &chunked_report);
    const KdTree level =
        build_opencl(device, scene, with_stage(params, LargeStage::Level), &level_report);
    const KdTree depth_first = detail::build_opencl_with_limits(
        device, scene, with_stage(params, LargeStage::DepthFirst), limits, &depth_first_report);
    CHECK(chunked_report.large_stage == "chunked");
    CHECK(level_report.large_stage == "level");
    CHECK(depth_first_report.large_stage == "depth-first");
    CHECK(level_report.large_node_levels == chunked_report.large_node_levels);
    CHECK(depth_first_report.budget_leaves == chunked_report.budget_leaves);
    if (expect != DepthFirst::Any) CHECK(depth_first_report.depth_first_subtrees > 0);
    if (expect == DepthFirst::OneRound) CHECK(depth_first_report.depth_first_rounds == 1);
    if (expect == DepthFirst::OneRound) CHECK(depth_first_report.depth_first_rebuilt == 0);
    if (expect == DepthFirst::Retried) {
        const std::size_t later_runs = std::size_t(depth_first_report.depth_first_rounds - 1);
        CHECK(later_runs > 0);
        CHECK(depth_first_report.depth_first_rebuilt > 0);
        CHECK(depth_first_report.depth_first_rebuilt <=
              depth_first_report.depth_first_subtrees * later_runs);
    }
    test::check_same_tree(level, chunked, scene, 31);
    test::check_same_tree(depth_first, chunked, scene, 31);
}

/// Clusters of random triangles far apart on a diagonal: the top levels cut the empty space
/// between them (chains of cuts) before any plane splits a cluster.
Scene far_clusters() {
    std::vector<float> tris;
    for (int c = 0; c < 4; ++c) {
        const Scene cluster = test::random_triangles(900, 40 + c);
        const float offset = float(c) * 10.0f;
        for (std::size_t t = 0; t < cluster.triangle_count(); ++t)
            for (int v = 0; v < 3; ++v) {
                const Vec3 p = cluster.vertex(t, v);
                tris.insert(tris.end(), {p.x + offset, p.y + offset * 0.5f, p.z - offset});
            }
    }
    return make_scene(std::move(tris), "far_clusters");
}

}  // namespace

TEST_CASE(
    "opencl large stage: the element-parallel and depth-first shapes build the chunked trees") {
    // Over 256 references per node at the top (several chunks per node, so ranks cross chunks),
    // at every quality of the ladder, and with the spatial median (large_split_bins 0: no bin
    // kernels at all).
    const std::vector<std::pair<std::string, Scene>> scenes = [] {
        std::vector<std::pair<std::string, Scene>> s;
        s.emplace_back("random_20000", test::random_triangles(20000, 2801));
        s.emplace_back("far_clusters", far_clusters());
        s.emplace_back("long_slivers", test::long_slivers(600, 7));
        s.emplace_back("coincident", test::coincident_triangles(400));
        s.emplace_back("planar", test::planar_triangles(3000, 5));
        return s;
    }();
    for (const auto& [name, scene] : scenes) {
        // Coincident faces make a leaf of the root: no subtree is left for the depth-first part.
        const DepthFirst expect = name == "coincident" ? DepthFirst::Any : DepthFirst::Subtrees;
        for (BuildQuality q : {BuildQuality::Low, BuildQuality::Medium, BuildQuality::High})
            check_same_as_chunked(scene, name + "_" + build_quality_name(q),
                                  with_build_quality({}, q), expect);
        BuildParams median;
        median.large_split_bins = 0;
        check_same_as_chunked(scene, name + "_median", median, expect);
        // 16 bins: kd_bin_references' counts in memory (low's 8 are in vector registers)
        // against the level shape's local atomics.
        BuildParams sixteen = with_build_quality({}, BuildQuality::Low);
        sixteen.large_split_bins = 16;
        check_same_as_chunked(scene, name + "_16_bins", sixteen, expect);
    }
}

/// Uniform random triangles and, beside them on x, long slivers that every split cuts: subtrees of
/// the slivers outgrow arenas that those of the others fit in.
Scene slivers_beside_random() {
    const Scene easy = test::random_triangles(20000, 2801);
    const Scene hard = test::long_slivers(2000, 7);
    std::vector<float> tris = easy.triangles;
    for (std::size_t i = 0; i < hard.triangles.size(); ++i)
        tris.push_back(hard.triangles[i] + (i % 3 == 0 ? 2.0f : 0.0f));
    return make_scene(std::move(tris), "slivers_beside_random");
}

TEST_CASE("opencl large stage: depth-first subtrees whose arenas run out are built again") {
    // Arenas a sixteenth of their size: most subtrees run out of records, small roots or their
    // references on the first try and are built again with larger ones; the tree is the same.
    detail::SmallStageLimits limits;
    limits.depth_first_arena_shift = 4;
    check_same_as_chunked(test::random_triangles(20000, 2801), "random_20000_small_arenas", {},
                          DepthFirst::Retried, limits);
    check_same_as_chunked(test::long_slivers(600, 7), "long_slivers_small_arenas", {},
                          DepthFirst::Retried, limits);
}

TEST_CASE("opencl large stage: only the subtrees whose arenas ran out are built again") {
    // At the usual arena sizes the slivers' subtrees run out, for a few runs, and the random
    // triangles' do not: each later run builds only those that ran out. The tree cannot depend on
    // the run that built a subtree: arenas a quarter the size (more runs, each building others)
    // make the same one. (The levels are no oracle here: the slivers fill the subtrees'
    // reference budgets, which bound other nodes than the levels' budget.)
    const Scene scene = slivers_beside_random();
    ClDevice& device = test::opencl_test_device();
    const BuildParams params = with_stage({}, LargeStage::DepthFirst);
    BuildReport usual_report, small_report;
    const KdTree usual = detail::build_opencl_with_limits(device, scene, params, {}, &usual_report);
    detail::SmallStageLimits small_arenas;
    small_arenas.depth_first_arena_shift = 2;
    const KdTree small =
        detail::build_opencl_with_limits(device, scene, params, small_arenas, &small_report);
    const std::size_t later_runs = std::size_t(usual_report.depth_first_rounds - 1);
    CHECK(later_runs > 0);
    CHECK(usual_report.depth_first_rebuilt > 0);
    CHECK(usual_report.depth_first_rebuilt < usual_report.depth_first_subtrees * later_runs);
    CHECK(small_report.depth_first_rounds > usual_report.depth_first_rounds);
    CHECK(check_tree(usual, scene).empty());
    test::check_same_tree(small, usual, scene, 37);
}

TEST_CASE("opencl large stage: the hard scenes build the same tree in every shape") {
    for (const test::NamedScene& s : test::hard_scenes()) check_same_as_chunked(s.scene, s.name);
}

TEST_CASE("opencl large stage: the bunny builds the same tree in every shape (../shared)") {
    const auto bunny = test::shared_dir() / "scenes" / "bunny" / "bunny.obj";
    if (!std::filesystem::exists(bunny)) {
        MESSAGE("skipped: " << bunny.string() << " is absent (../shared is not here)");
        return;
    }
    check_same_as_chunked(load_obj(bunny), "bunny", {}, DepthFirst::OneRound);
}
