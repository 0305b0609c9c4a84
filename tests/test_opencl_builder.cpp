// test_opencl_builder.cpp — the OpenCL kd-tree builder (Zhou et al. 2008) against the invariant
// checker, the brute-force oracle ray by ray, the reference builder's SAH cost, and closed-form
// scenes whose tree is known in advance. The hard scenes (coincident, planar, lattice, far, tiny,
// zero-area) are where a GPU builder hangs, explodes or drops triangles.
#include <doctest/doctest.h>

#include <algorithm>
#include <array>
#include <cmath>
#include <cstdint>
#include <random>
#include <set>
#include <string>
#include <utility>
#include <vector>

#include "cl/builder/opencl_builder.h"
#include "cl/runtime/program_cache.h"
#include "core/device/kd_traverse.h"
#include "core/error.h"
#include "core/tree/build_quality.h"
#include "core/tree/reference_builder.h"
#include "core/tree/tree_check.h"
#include "core/tree/tree_stats.h"
#include "tests/support.h"
#include "tests/test_opencl_fixture.h"

using namespace kdray;

namespace {

void check_build(const Scene& scene, const std::string& name, const BuildParams& params = {}) {
    CAPTURE(name);
    BuildReport report;
    const KdTree tree = build_opencl(test::opencl_test_device(), scene, params, &report);
    CHECK(tree.builder == "opencl");
    const std::vector<std::string> problems = check_tree(tree, scene);
    for (const std::string& p : problems) CAPTURE(p);
    CHECK(problems.empty());
    if (!problems.empty()) FAIL_CHECK(problems.front());
    // Bounded size: no explosion of nodes or references on any of the hard scenes, judged
    // against the reference builder's tree of the same scene. The factor is 3, not less, for the
    // cube lattice: spatial-median planes (x = 2.25, 6.75, ...) cut through cubes whose faces the
    // full SAH would split along, so its faces are listed about 2.8 times as often.
    const std::size_t n = scene.triangle_count();
    const KdTree ref = build_reference(scene, {});
    CHECK(tree.nodes.size() <= 16 * n + 16);
    CHECK(tree.leaf_indices.size() <= 3 * ref.leaf_indices.size() + 64);
    CHECK(test::count_disagreements(tree, scene, test::random_rays(scene, 2000, 99)) == 0);
}

Scene two_clusters() {
    // Two clusters of 100 triangles, each exactly filling a unit cube (its first triangle spans
    // the cube), at x in [0, 1] and [9, 10]. The root's box is the scene's, so it has no empty
    // space; its median plane x = 5 falls in the gap, and then each child has 80% empty space on
    // one side (> C_e = 25%): both must cut it off at the cluster's face.
    std::vector<float> tris;
    for (float offset : {0.0f, 9.0f}) {
        tris.insert(tris.end(), {offset, 0, 0, offset + 1, 0, 1, offset, 1, 1});
        for (int i = 1; i < 100; ++i) {
            const float x = offset + 0.01f * i, y = 0.005f * i, z = 0.009f * i;
            tris.insert(tris.end(), {x, y, z, x, y + 0.1f, z, x, y, z + 0.05f});
        }
    }
    return make_scene(std::move(tris), "two_clusters");
}

Scene cluster_in_corner() {
    // 100 triangles exactly filling the unit cube (as in two_clusters) and one small triangle at
    // the far corner (10, 10, 10). The root's median x = 5 leaves the cluster in a child of box
    // [0, 5] x [0, 10] x [0, 10] with empty slabs of 80%, 90% and 90% of its extent: three
    // empty-space cuts in a row (y = 1, then z = 1, then x = 1), which kd_split_large_nodes
    // chains in one level (§4.1, one level per cut in the paper) before the median split.
    std::vector<float> tris = {0, 0, 0, 1, 0, 1, 0, 1, 1};
    for (int i = 1; i < 100; ++i) {
        const float x = 0.01f * i, y = 0.005f * i, z = 0.009f * i;
        tris.insert(tris.end(), {x, y, z, x, y + 0.1f, z, x, y, z + 0.05f});
    }
    tris.insert(tris.end(), {9.5f, 9.5f, 10, 10, 9.5f, 10, 10, 10, 9.5f});
    return make_scene(std::move(tris), "cluster_in_corner");
}

Scene box_room() {
    // An open-fronted room [0, 2]^3 (floor, ceiling, back and side walls) with two axis-aligned
    // boxes standing on the floor: 34 triangles, one small root, every one of them lying in a
    // plane that is some node's face. The full SAH puts the triangles lying in a split plane on
    // the cheaper side and cuts a node's flat faces (the floor, a wall) off into flat leaves; with
    // planar triangles always below and only planes strictly inside a node, the small stage's
    // tree of the McGuire Cornell box cost 1.25 times the reference builder's.
    std::vector<float> tris;
    auto quad = [&](Vec3 a, Vec3 b, Vec3 c, Vec3 d) {
        tris.insert(tris.end(), {a.x, a.y, a.z, b.x, b.y, b.z, c.x, c.y, c.z});
        tris.insert(tris.end(), {a.x, a.y, a.z, c.x, c.y, c.z, d.x, d.y, d.z});
    };
    auto box = [&](Vec3 lo, Vec3 hi) {
        quad({lo.x, lo.y, lo.z}, {hi.x, lo.y, lo.z}, {hi.x, hi.y, lo.z}, {lo.x, hi.y, lo.z});
        quad({lo.x, lo.y, hi.z}, {hi.x, lo.y, hi.z}, {hi.x, hi.y, hi.z}, {lo.x, hi.y, hi.z});
        quad({lo.x, lo.y, lo.z}, {lo.x, hi.y, lo.z}, {lo.x, hi.y, hi.z}, {lo.x, lo.y, hi.z});
        quad({hi.x, lo.y, lo.z}, {hi.x, hi.y, lo.z}, {hi.x, hi.y, hi.z}, {hi.x, lo.y, hi.z});
        quad({lo.x, lo.y, lo.z}, {hi.x, lo.y, lo.z}, {hi.x, lo.y, hi.z}, {lo.x, lo.y, hi.z});
        quad({lo.x, hi.y, lo.z}, {hi.x, hi.y, lo.z}, {hi.x, hi.y, hi.z}, {lo.x, hi.y, hi.z});
    };
    quad({0, 0, 0}, {2, 0, 0}, {2, 0, 2}, {0, 0, 2});  // floor
    quad({0, 2, 0}, {2, 2, 0}, {2, 2, 2}, {0, 2, 2});  // ceiling
    quad({0, 0, 0}, {2, 0, 0}, {2, 2, 0}, {0, 2, 0});  // back wall
    quad({0, 0, 0}, {0, 2, 0}, {0, 2, 2}, {0, 0, 2});  // left wall
    quad({2, 0, 0}, {2, 2, 0}, {2, 2, 2}, {2, 0, 2});  // right wall
    box({0.3f, 0, 0.3f}, {0.8f, 0.5f, 0.8f});
    box({1.1f, 0, 1.1f}, {1.6f, 1.2f, 1.6f});
    return make_scene(std::move(tris), "box_room");
}

Scene uneven_clusters() {
    // 100 triangles in the unit cube and 10 in [3, 4] x [0, 1]^2, each spanning its cube in x
    // (the first also in y and z, so that the cubes are the clusters' bounds). Every plane in the
    // gap has the same counts, 100 below and 10 above, and every plane inside a cluster cuts all
    // of its triangles, so the SAH is least at the dense cluster's face, x = 1: a bin boundary of
    // the root's tight box [0, 4] (32 bins of 0.125) that the triangles' ends lie exactly on,
    // which the bins must not count on both sides. The median is x = 2.
    std::vector<float> tris;
    for (auto [offset, count] : {std::pair{0.0f, 100}, std::pair{3.0f, 10}}) {
        tris.insert(tris.end(), {offset, 0, 0, offset + 1, 0, 1, offset, 1, 1});
        for (int i = 1; i < count; ++i) {
            const float y = 0.009f * float(i), z = 0.008f * float(i);
            tris.insert(tris.end(), {offset, y, z, offset + 1, y + 0.05f, z, offset, y, z + 0.05f});
        }
    }
    return make_scene(std::move(tris), "uneven_clusters");
}

/// SAH cost of the OpenCL builder's tree and of the reference builder's, with `params`.
std::pair<double, double> sah_costs(const Scene& scene, const BuildParams& params) {
    const KdTree gpu = build_opencl(test::opencl_test_device(), scene, params);
    const KdTree ref = build_reference(scene, params);
    return {compute_tree_stats(gpu, scene.triangle_count(), params.costs).sah_cost,
            compute_tree_stats(ref, scene.triangle_count(), params.costs).sah_cost};
}

// The paper's large-node split, the spatial median, which some tests pin down.
BuildParams median_split() {
    BuildParams params;
    params.large_split_bins = 0;
    return params;
}

}  // namespace

TEST_CASE("opencl builder: hard scenes pass the checker and trace like brute force") {
    for (const test::NamedScene& s : test::hard_scenes()) check_build(s.scene, s.name);
}

TEST_CASE("opencl builder: every build quality passes the checker and traces like brute force") {
    for (BuildQuality q : {BuildQuality::Low, BuildQuality::Medium}) {
        CAPTURE(std::string(build_quality_name(q)));
        const BuildParams params = with_build_quality({}, q);
        for (const test::NamedScene& s : test::hard_scenes()) check_build(s.scene, s.name, params);
        check_build(test::random_triangles(5000, 1005), "random_5000", params);
    }
}

TEST_CASE("opencl builder: the quality ladder builds smaller trees level by level, SAH bounded") {
    // On 4000 random triangles: each level down has fewer nodes than the one above; high stays
    // within the reference builder's SAH bound of the test above, and low within 1.5 times it (a
    // usable tree). The SAH itself need not rise level by level: the search prices an empty side
    // at (1 - empty_bonus), which the tree's SAH does not, so it splits some nodes of a few
    // triangles that a leaf would cost less as (medium 1690 against high 1731 here).
    const Scene scene = test::random_triangles(4000, 81, 1.0f, 0.05f);
    const BuildParams defaults;
    const double ref_sah =
        compute_tree_stats(build_reference(scene, defaults), scene.triangle_count(), defaults.costs)
            .sah_cost;
    double sah = 0;
    std::size_t previous_nodes = std::size_t(-1);
    for (BuildQuality q : {BuildQuality::High, BuildQuality::Medium, BuildQuality::Low}) {
        CAPTURE(std::string(build_quality_name(q)));
        const BuildParams params = with_build_quality(defaults, q);
        const KdTree tree = build_opencl(test::opencl_test_device(), scene, params);
        sah = compute_tree_stats(tree, scene.triangle_count(), params.costs).sah_cost;
        CAPTURE(sah);
        CAPTURE(ref_sah);
        CHECK(tree.nodes.size() < previous_nodes);
        if (q == BuildQuality::High) CHECK(sah <= 1.12 * ref_sah);
        previous_nodes = tree.nodes.size();
    }
    CHECK(sah <= 1.5 * ref_sah);  // low
}

/// The distinct triangles under node `i` of `tree`, into `out`.
void subtree_triangles(const KdTree& tree, kd_u32 i, std::set<kd_u32>& out) {
    const KdNode n = tree.nodes[i];
    if (kd_node_is_leaf(n)) {
        for (kd_u32 k = 0; k < kd_leaf_count(n); ++k)
            out.insert(tree.leaf_indices[kd_leaf_offset(n) + k]);
        return;
    }
    subtree_triangles(tree, i + 1, out);
    subtree_triangles(tree, kd_node_above_child(n), out);
}

/// The fewest distinct triangles under any inner node of `tree`.
std::size_t fewest_under_inner_node(const KdTree& tree) {
    std::size_t fewest = std::size_t(-1);
    for (kd_u32 i = 0; i < tree.nodes.size(); ++i) {
        if (kd_node_is_leaf(tree.nodes[i])) continue;
        std::set<kd_u32> under;
        subtree_triangles(tree, i, under);
        fewest = std::min(fewest, under.size());
    }
    return fewest;
}

TEST_CASE("opencl builder: a node at or below the leaf size is a leaf, without a search") {
    // 40 triangles in a row along x, each in its own slab with gaps between (one small root): the
    // full SAH splits nodes of a few triangles; with a leaf size of 8 no inner node has 8 or fewer
    // triangles under it.
    std::vector<float> tris;
    for (int i = 0; i < 40; ++i) {
        const float x = 3.0f * float(i);
        tris.insert(tris.end(), {x, 0, 0, x + 0.5f, 0, 1, x, 1, 0});
    }
    const Scene scene = make_scene(std::move(tris), "row");
    BuildParams params;
    const KdTree searched = build_opencl(test::opencl_test_device(), scene, params);
    CHECK(fewest_under_inner_node(searched) <= 8);
    params.small_leaf_refs = 8;
    const KdTree stopped = build_opencl(test::opencl_test_device(), scene, params);
    CHECK(check_tree(stopped, scene).empty());
    CHECK(fewest_under_inner_node(stopped) > 8);
    CHECK(stopped.nodes.size() < searched.nodes.size());
    CHECK(test::count_disagreements(stopped, scene, test::random_rays(scene, 500, 5)) == 0);
}

TEST_CASE("opencl builder: needles across the whole scene give valid trees that trace right") {
    // 300 triangles 1e4 long through a 10-unit box, each crossing most of the scene: valid at
    // every level and tracing as brute force does. Not size-bounded like the hard scenes: every
    // large-node split straddles nearly all of them, and the large stage (Zhou et al.) always
    // splits, so references multiply until the clipped boxes part (18k nodes against the
    // reference builder's 1.2k leaf references; noted on the numerical-stability issue).
    const Scene scene = test::needles(300, 6);
    for (BuildQuality q : {BuildQuality::Low, BuildQuality::Medium, BuildQuality::High}) {
        CAPTURE(std::string(build_quality_name(q)));
        const KdTree tree =
            build_opencl(test::opencl_test_device(), scene, with_build_quality({}, q));
        CHECK(check_tree(tree, scene).empty());
        CHECK(test::count_disagreements(tree, scene, test::random_rays(scene, 1000, 17)) == 0);
    }
}

TEST_CASE("opencl builder: random scenes of several sizes") {
    for (int count : {1, 2, 63, 64, 65, 500, 5000})
        check_build(test::random_triangles(count, 1000 + count), "random_" + std::to_string(count));
}

TEST_CASE("opencl builder: SAH cost within a reasonable factor of the reference builder") {
    for (int seed = 0; seed < 3; ++seed) {
        const Scene scene = test::random_triangles(4000, 77 + seed, 1.0f, 0.05f);
        const auto [gpu_cost, ref_cost] = sah_costs(scene, {});
        CAPTURE(gpu_cost);
        CAPTURE(ref_cost);
        // 1.06 here, with the binned split or the spatial median alike (random triangles fill
        // their cube evenly); the shared scenes' figures are docs/bench-build.md's.
        CHECK(gpu_cost <= 1.12 * ref_cost);
    }
}

TEST_CASE("opencl builder: a small node's long triangles are clipped to it before its SAH") {
    // Priced with the small root's boxes (the paper's small stage), these trees cost 1.38-1.53
    // times the reference builder's (perfect splits); with each subtree of at most 32 triangles
    // pricing its own clipped boxes (build_small.cl, re-clipping), 1.06-1.18.
    for (std::uint32_t seed : {1u, 2u, 3u}) {
        const Scene scene = test::long_slivers(60, seed);
        check_build(scene, "long_slivers");
        const auto [gpu_cost, ref_cost] = sah_costs(scene, {});
        CAPTURE(seed);
        CAPTURE(gpu_cost);
        CAPTURE(ref_cost);
        CHECK(gpu_cost <= 1.25 * ref_cost);
    }
}

TEST_CASE("opencl builder: planar triangles take the cheaper side, flat faces become leaves") {
    const Scene scene = box_room();
    check_build(scene, "box_room");
    const auto [gpu_cost, ref_cost] = sah_costs(scene, {});
    CAPTURE(gpu_cost);
    CAPTURE(ref_cost);
    // What still separates the two is the reference's clipping of each triangle to every node
    // (the small stage clips to its root, and once more to a node of at most 32 triangles):
    // 1.020 here, 1.32 before planar triangles had a side to choose and faces could be cut off.
    CHECK(gpu_cost <= 1.05 * ref_cost);
}

TEST_CASE("opencl builder: large nodes split at the binned SAH plane, or at the median") {
    const Scene scene = uneven_clusters();
    check_build(scene, "uneven_clusters");
    BuildParams params;
    params.large_split_bins = 32;
    const KdTree sah = build_opencl(test::opencl_test_device(), scene, params);
    REQUIRE(check_tree(sah, scene).empty());
    REQUIRE(!kd_node_is_leaf(sah.nodes[0]));
    CHECK(kd_node_axis(sah.nodes[0]) == 0);
    CHECK(kd_node_split(sah.nodes[0]) == 1.0f);
    const KdTree median = build_opencl(test::opencl_test_device(), scene, median_split());
    REQUIRE(!kd_node_is_leaf(median.nodes[0]));
    CHECK(kd_node_axis(median.nodes[0]) == 0);
    CHECK(kd_node_split(median.nodes[0]) == 2.0f);
    CHECK(test::count_disagreements(median, scene, test::random_rays(scene, 1000, 5)) == 0);
}

TEST_CASE("opencl builder: empty space is cut off around two far clusters") {
    const Scene scene = two_clusters();
    const KdTree tree = build_opencl(test::opencl_test_device(), scene, median_split());
    REQUIRE(check_tree(tree, scene).empty());
    const KdNode root = tree.nodes[0];
    REQUIRE(!kd_node_is_leaf(root));
    CHECK(kd_node_axis(root) == 0);
    CHECK(kd_node_split(root) == 5.0f);
    // Below child: cut at the first cluster's face x = 1, the empty part above it a leaf.
    const KdNode below = tree.nodes[1];
    REQUIRE(!kd_node_is_leaf(below));
    CHECK(kd_node_axis(below) == 0);
    CHECK(kd_node_split(below) == 1.0f);
    const KdNode below_above = tree.nodes[kd_node_above_child(below)];
    CHECK(kd_node_is_leaf(below_above));
    CHECK(kd_leaf_count(below_above) == 0);
    // Above child: cut at the second cluster's face x = 9, the empty part below it a leaf.
    const kd_u32 above_index = kd_node_above_child(root);
    const KdNode above = tree.nodes[above_index];
    REQUIRE(!kd_node_is_leaf(above));
    CHECK(kd_node_axis(above) == 0);
    CHECK(kd_node_split(above) == 9.0f);
    const KdNode above_below = tree.nodes[above_index + 1];
    CHECK(kd_node_is_leaf(above_below));
    CHECK(kd_leaf_count(above_below) == 0);
}

TEST_CASE("opencl builder: a chain of empty-space cuts in one level") {
    // The chain's nodes are each other's parents although one level creates them all: the
    // output stage must still place every subtree (ids by generation), and the tree must be the
    // one a level per cut gives.
    const Scene scene = cluster_in_corner();
    check_build(scene, "cluster_in_corner");
    BuildReport report;
    BuildParams levels = median_split();
    levels.large_stage = LargeStage::Chunked;  // level by level (depth-first: the same tree)
    const KdTree tree = build_opencl(test::opencl_test_device(), scene, levels, &report);
    REQUIRE(check_tree(tree, scene).empty());
    CHECK(report.large_node_levels == 2);  // the root; the chain and its median split
    const KdTree depth_first = build_opencl(test::opencl_test_device(), scene, median_split());
    test::check_same_tree(depth_first, tree, scene, 17);
    REQUIRE(!kd_node_is_leaf(tree.nodes[0]));
    CHECK(kd_node_split(tree.nodes[0]) == 5.0f);
    const int axes[3] = {1, 2, 0};
    kd_u32 at = 1;  // the root's below child, then each cut's kept (below) child
    for (int cut = 0; cut < 3; ++cut) {
        CAPTURE(cut);
        const KdNode node = tree.nodes[at];
        REQUIRE(!kd_node_is_leaf(node));
        CHECK(kd_node_axis(node) == kd_u32(axes[cut]));
        CHECK(kd_node_split(node) == 1.0f);
        const KdNode empty = tree.nodes[kd_node_above_child(node)];
        CHECK(kd_node_is_leaf(empty));
        CHECK(kd_leaf_count(empty) == 0);
        at += 1;
    }
    // The chain's last node: the median of the unit cube.
    REQUIRE(!kd_node_is_leaf(tree.nodes[at]));
    CHECK(kd_node_split(tree.nodes[at]) == 0.5f);
}

TEST_CASE("opencl builder: empty scene, report, and programs built once") {
    ClDevice& device = test::opencl_test_device();
    BuildReport report;
    const KdTree empty = build_opencl(device, make_scene({}, "empty"), {}, &report);
    REQUIRE(empty.nodes.size() == 1);
    CHECK(kd_node_is_leaf(empty.nodes[0]));
    CHECK(kd_leaf_count(empty.nodes[0]) == 0);
    CHECK(empty.leaf_indices.empty());

    const Scene scene = test::random_triangles(3000, 5);
    build_opencl(device, scene);
    const int builds = program_build_count();
    build_opencl(device, scene, {}, &report);
    CHECK(program_build_count() == builds);
    const std::vector<std::string> stages = {"upload",      "aabbs",  "large_nodes",
                                             "small_nodes", "output", "download"};
    REQUIRE(report.timings_ms.size() == stages.size());
    for (std::size_t i = 0; i < stages.size(); ++i) CHECK(report.timings_ms[i].first == stages[i]);
    CHECK(report.large_node_levels > 0);
    CHECK(report.small_node_levels > 0);
    CHECK(report.device_bytes > scene.triangles.size() * sizeof(float));
    CHECK(report.build_ms > 0);
}

TEST_CASE("opencl builder: prepare_opencl_builder builds every program a build needs") {
    // A fresh context has an empty program cache (it is keyed by context), so this proves that
    // prepare covers every program, not only that a second build reuses the first's.
    ClDevice device("");
    const BuildParams params;
    prepare_opencl_builder(device, params);
    const int builds = program_build_count();
    // 3000 triangles take every stage: large nodes, small roots, small levels and output.
    const Scene scene = test::random_triangles(3000, 8);
    const KdTree tree = build_opencl(device, scene, params);
    CHECK(program_build_count() == builds);
    CHECK(check_tree(tree, scene).empty());
    prepare_opencl_builder(device, params);
    CHECK(program_build_count() == builds);
}

TEST_CASE("opencl builder: depth limit and leaf threshold are respected") {
    const Scene scene = test::random_triangles(2000, 21);
    BuildParams params;
    params.max_depth = 6;
    const KdTree shallow = build_opencl(test::opencl_test_device(), scene, params);
    CHECK(check_tree(shallow, scene).empty());
    CHECK(compute_tree_stats(shallow, scene.triangle_count(), params.costs).max_depth <= 6);
    params = {};
    params.large_node_threshold = 16;
    const KdTree small_t = build_opencl(test::opencl_test_device(), scene, params);
    CHECK(check_tree(small_t, scene).empty());
    CHECK(test::count_disagreements(small_t, scene, test::random_rays(scene, 500, 3)) == 0);
}

TEST_CASE("opencl builder: the small stage in batches of roots gives the same tree") {
    // A scene of ten million triangles wants 4 GB of split-candidate masks, past many devices'
    // largest allocation, so the small stage goes by batches of roots whose masks and records
    // fit it. Batches of 16 KB (about 100 references) split these scenes into tens of batches,
    // alone and with the second pass of subtrees that outgrow their first records (scale 1).
    for (const Scene& scene : {test::random_triangles(3000, 37), test::cube_lattice(5)}) {
        CAPTURE(scene.triangle_count());
        const KdTree tree = build_opencl(test::opencl_test_device(), scene);
        for (unsigned scale : {10u, 1u}) {
            CAPTURE(scale);
            test::check_same_tree(detail::build_opencl_with_limits(test::opencl_test_device(),
                                                                   scene, {}, {scale, 16384}),
                                  tree, scene, 19);
        }
    }
}

TEST_CASE("opencl builder: subtrees that outgrow their first records give the same tree") {
    // The small stage sets aside scale * (n + 1) node records per small root of n references and
    // builds the subtrees that outgrow them again in a second pass, into records of their own.
    // With scale 1 nearly every subtree of these scenes takes that path, and the 64 tiny
    // triangles scattered through a cube (one small root whose SAH isolates each triangle and cuts
    // the empty space around it) need more than the default 10 per reference in any case. The
    // tree must not depend on which pass built a subtree.
    std::vector<float> tris;
    for (int i = 0; i < 64; ++i) {
        const float x = (float(i) + 0.5f) / 64.0f, y = std::fmod(x * 7.0f, 1.0f);
        const float z = std::fmod(x * 13.0f, 1.0f), d = 0.001f;
        tris.insert(tris.end(), {x, y, z, x + d, y, z + d, x, y + d, z + d});
    }
    for (const Scene& scene :
         {make_scene(std::move(tris), "scattered"), test::random_triangles(3000, 31)}) {
        CAPTURE(scene.triangle_count());
        const KdTree tree = build_opencl(test::opencl_test_device(), scene);
        test::check_same_tree(
            detail::build_opencl_with_limits(test::opencl_test_device(), scene, {}, {1, 0}), tree,
            scene, 17);
    }
}

TEST_CASE("opencl builder: buffers kept from an earlier build give the same tree") {
    // Builds take their arrays from the device's BufferPool, filled by earlier builds with their
    // data: no kernel may rely on what a buffer held before. The tree handed to the renderer
    // (DeviceTree) must stay out of the pool, or the next build would overwrite it.
    ClDevice& device = test::opencl_test_device();
    const Scene scene = test::random_triangles(3000, 41), other = test::random_triangles(5000, 43);
    device.buffer_pool().clear();
    const KdTree fresh = build_opencl(device, scene);
    CHECK(device.buffer_pool().bytes() > 0);
    DeviceTree on_device;
    const KdTree first = build_opencl(device, other, {}, nullptr, &on_device);
    const KdTree reused = build_opencl(device, scene);
    test::check_same_tree(reused, fresh, scene, 23);
    std::vector<KdNode> nodes(first.nodes.size());
    device.queue().enqueueReadBuffer(on_device.nodes, CL_TRUE, 0, nodes.size() * sizeof(KdNode),
                                     nodes.data());
    std::size_t differ = 0;
    for (std::size_t i = 0; i < nodes.size(); ++i)
        differ += nodes[i].axis_and_offset != first.nodes[i].axis_and_offset ||
                  nodes[i].split_or_count != first.nodes[i].split_or_count;
    CHECK(differ == 0);
}

namespace {

/// A UV sphere of 2 * rings * segments triangles, centred at (0.5, 0.5, 0.5) with radius 0.5: a
/// closed surface of small triangles, as scanned meshes are (the poles' triangles are slivers).
Scene tessellated_sphere(int rings, int segments) {
    auto point = [&](int ring, int segment, std::vector<float>& out) {
        const double theta = M_PI * ring / rings, phi = 2 * M_PI * segment / segments;
        out.push_back(float(0.5 + 0.5 * std::sin(theta) * std::cos(phi)));
        out.push_back(float(0.5 + 0.5 * std::cos(theta)));
        out.push_back(float(0.5 + 0.5 * std::sin(theta) * std::sin(phi)));
    };
    std::vector<float> tris;
    for (int r = 0; r < rings; ++r)
        for (int g = 0; g < segments; ++g)
            for (const auto& [a, b, c] :
                 {std::array<std::array<int, 2>, 3>{{{r, g}, {r + 1, g}, {r + 1, g + 1}}},
                  std::array<std::array<int, 2>, 3>{{{r, g}, {r + 1, g + 1}, {r, g + 1}}}}) {
                point(a[0], a[1], tris);
                point(b[0], b[1], tris);
                point(c[0], c[1], tris);
            }
    return make_scene(std::move(tris), "sphere");
}

}  // namespace

TEST_CASE("opencl builder: a first build allocates about its peak, not a fresh set per level") {
    // A build with nothing kept from an earlier one must reuse its own arrays from level to
    // level: on a CPU device every new byte is a new page that a kernel faults in. Sized exactly,
    // each large level's arrays were a few percent larger than the last (clipping), so none
    // fitted the next: this sphere allocated 2.25 times its peak (the Kitchen 4.6), now 1.5.
    // The depth-first large stage runs fewer levels and then arenas of its own: the same bound.
    ClDevice& device = test::opencl_test_device();
    const Scene scene = tessellated_sphere(100, 200);
    for (LargeStage stage : {LargeStage::Chunked, LargeStage::DepthFirst}) {
        CAPTURE(std::string(large_stage_name(stage)));
        BuildParams params;
        params.large_stage = stage;
        device.buffer_pool().clear();
        const std::uint64_t before = device.allocated_bytes();
        BuildReport report;
        build_opencl(device, scene, params, &report);
        const std::uint64_t allocated = device.allocated_bytes() - before;
        INFO("allocated " << allocated << " bytes, peak " << report.device_bytes);
        if (stage == LargeStage::Chunked) REQUIRE(report.large_node_levels >= 8);
        CHECK(allocated >= report.device_bytes);  // what it held at its peak came from somewhere
        CHECK(allocated <= 7 * report.device_bytes / 4);
    }
}

TEST_CASE("opencl builder: nodes the reference budget makes leaves are counted and warned about") {
    // 300 triangles each joining three random points on three different faces of the unit cube:
    // every plane through the cube cuts most of them, so each level of spatial-median splits
    // nearly doubles the references until a level would outgrow kReferenceBudgetPerTriangle per
    // triangle, and that level's nodes become leaves unsplit.
    std::mt19937 rng(51);
    std::uniform_real_distribution<float> u(0.0f, 1.0f);
    std::vector<float> tris;
    for (int t = 0; t < 300; ++t)
        for (int axis = 0; axis < 3; ++axis) {
            float p[3] = {u(rng), u(rng), u(rng)};
            p[axis] = float(t % 2);  // a point on face `axis`, low or high
            tris.insert(tris.end(), {p[0], p[1], p[2]});
        }
    const Scene big = make_scene(std::move(tris), "cube-spanning");
    BuildParams median;
    median.large_split_bins = 0;
    // Both schedules: the levels' budget, and the depth-first subtrees' per depth (the whole
    // scene is one deep root here).
    for (LargeStage stage : {LargeStage::Chunked, LargeStage::DepthFirst}) {
        CAPTURE(std::string(large_stage_name(stage)));
        median.large_stage = stage;
        BuildReport report;
        const KdTree tree = build_opencl(test::opencl_test_device(), big, median, &report);
        CHECK(report.budget_leaves > 0);
        REQUIRE(report.warnings.size() == 1);
        CHECK(report.warnings[0].find(std::to_string(report.budget_leaves) + " large node(s)") ==
              0);
        const std::vector<std::string> errors = check_tree(tree, big);
        CHECK_MESSAGE(errors.empty(), (errors.empty() ? std::string() : errors.front()));
    }
    median.large_stage = LargeStage::Auto;
    // An ordinary scene never meets the budget.
    BuildReport ordinary;
    build_opencl(test::opencl_test_device(), test::random_triangles(3000, 52), median, &ordinary);
    CHECK(ordinary.budget_leaves == 0);
    CHECK(ordinary.warnings.empty());
}
