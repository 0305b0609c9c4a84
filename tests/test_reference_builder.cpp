// test_reference_builder.cpp — the Wald & Havran (2006) reference builder: its trees pass the
// invariant checker and trace exactly like brute force on the hard scenes, its SAH finds the
// obvious split of a closed-form scene, and its trees cost no more than a naive spatial-median
// tree's.
#include <doctest/doctest.h>

#include <algorithm>
#include <cmath>
#include <sstream>
#include <string>
#include <vector>

#include "core/device/kd_traverse.h"
#include "core/error.h"
#include "core/geometry/triangle_clip.h"
#include "core/tree/reference_builder.h"
#include "core/tree/sah_events.h"
#include "core/tree/tree_check.h"
#include "core/tree/tree_stats.h"
#include "tests/support.h"

using namespace kdray;

namespace {

std::string joined(const std::vector<std::string>& errors) {
    std::string s;
    for (const auto& e : errors) s += e + "\n";
    return s;
}

KdHit trace(const KdTree& tree, const Scene& scene, const KdRay& ray) {
    const float bounds[6] = {tree.bounds.lo.x, tree.bounds.lo.y, tree.bounds.lo.z,
                             tree.bounds.hi.x, tree.bounds.hi.y, tree.bounds.hi.z};
    KdHit hit;
    kd_trace_closest(tree.nodes.data(), tree.leaf_indices.data(), scene.triangles.data(), bounds,
                     &ray, &hit);
    return hit;
}

/// Traces `count` rays through the tree and by brute force and checks them ray by ray, naming
/// the first mismatches.
void check_traces_match_brute_force(const KdTree& tree, const Scene& scene, int count,
                                    std::uint32_t seed) {
    const std::vector<KdRay> rays = test::random_rays(scene, count, seed);
    int mismatches = 0;
    std::ostringstream first;
    first.precision(9);
    for (std::size_t i = 0; i < rays.size(); ++i) {
        const KdHit a = trace(tree, scene, rays[i]);
        const KdHit b = test::brute_force_closest(scene, rays[i]);
        if (test::hits_agree(a, b)) continue;
        if (++mismatches <= 5) {
            const KdRay& r = rays[i];
            first << "ray " << i << " org (" << r.org[0] << ", " << r.org[1] << ", " << r.org[2]
                  << ") dir (" << r.dir[0] << ", " << r.dir[1] << ", " << r.dir[2]
                  << "): tree prim " << a.prim << " t " << a.t << ", brute force prim " << b.prim
                  << " t " << b.t << "\n";
        }
    }
    CHECK_MESSAGE(mismatches == 0, mismatches << " of " << rays.size() << " rays disagree\n"
                                              << first.str());
}

/// Depth of the deepest node, walking the preorder layout.
int tree_depth(const KdTree& tree, kd_u32 node = 0, int depth = 0) {
    const KdNode n = tree.nodes[node];
    if (kd_node_is_leaf(n)) return depth;
    return std::max(tree_depth(tree, node + 1, depth + 1),
                    tree_depth(tree, kd_node_above_child(n), depth + 1));
}

/// A naive tree to compare against: split the longest axis at its middle until a node holds
/// few triangles, every triangle whose bounds touch a child going to it.
class SpatialMedianBuilder {
  public:
    explicit SpatialMedianBuilder(const Scene& scene) : scene_(scene) {}

    KdTree build(int max_depth, std::size_t leaf_size) {
        max_depth_ = max_depth;
        leaf_size_ = leaf_size;
        KdTree tree;
        tree.bounds = scene_.bounds();
        tree.params.max_depth = max_depth;
        tree.builder = "spatial_median";
        std::vector<kd_u32> all(scene_.triangle_count());
        for (std::size_t i = 0; i < all.size(); ++i) all[i] = kd_u32(i);
        node(all, tree.bounds, 0);
        tree.nodes = std::move(nodes_);
        tree.leaf_indices = std::move(indices_);
        return tree;
    }

  private:
    void node(const std::vector<kd_u32>& tris, const Aabb& box, int depth) {
        if (tris.size() <= leaf_size_ || depth >= max_depth_) {
            nodes_.push_back(kd_make_leaf(kd_u32(tris.size()), kd_u32(indices_.size())));
            indices_.insert(indices_.end(), tris.begin(), tris.end());
            return;
        }
        const int axis = box.longest_axis();
        const float split = 0.5f * (box.lo[axis] + box.hi[axis]);
        std::vector<kd_u32> below, above;
        for (kd_u32 t : tris) {
            const Aabb b = scene_.triangle_bounds(t);
            if (b.lo[axis] <= split) below.push_back(t);
            if (b.hi[axis] >= split) above.push_back(t);
        }
        Aabb below_box = box, above_box = box;
        below_box.hi[axis] = split;
        above_box.lo[axis] = split;
        const std::size_t index = nodes_.size();
        nodes_.push_back(KdNode{});
        node(below, below_box, depth + 1);
        nodes_[index] = kd_make_inner(kd_u32(axis), split, kd_u32(nodes_.size()));
        node(above, above_box, depth + 1);
    }

    const Scene& scene_;
    int max_depth_ = 0;
    std::size_t leaf_size_ = 0;
    std::vector<KdNode> nodes_;
    std::vector<kd_u32> indices_;
};

}  // namespace

TEST_CASE("reference trees of the hard scenes pass check_tree and trace like brute force") {
    for (const test::NamedScene& named : test::hard_scenes()) {
        CAPTURE(named.name);
        const Scene& scene = named.scene;
        const KdTree tree = build_reference(scene);
        CHECK(tree.builder == "reference");
        CHECK(tree.bounds.lo == scene.bounds().lo);
        CHECK(tree.bounds.hi == scene.bounds().hi);
        const auto errors = check_tree(tree, scene);
        CHECK_MESSAGE(errors.empty(), joined(errors));
        const TreeStats stats = compute_tree_stats(tree, scene.triangle_count(), SahCosts{});
        CHECK(stats.max_depth <= tree.params.max_depth);
        CHECK(std::isfinite(stats.sah_cost));
        // Every triangle is referenced, and the SAH's termination, not the depth limit, ends the
        // build: a runaway recursion would make millions of nodes.
        CHECK(stats.triangle_references >= scene.triangle_count());
        CHECK(stats.nodes <= 32 * scene.triangle_count() + 1);
        if (errors.empty()) check_traces_match_brute_force(tree, scene, 3000, 99);
    }
}

TEST_CASE("coincident triangles make one leaf: no split can separate them") {
    // Every plane through the triangle's box leaves all copies on both sides, and the planes on
    // its faces cut off only flat slabs: the SAH must stop at the root, not recurse to the depth
    // limit.
    const Scene scene = test::coincident_triangles(3000);
    const KdTree tree = build_reference(scene);
    CHECK(tree.nodes.size() == 1);
    CHECK(tree.leaf_indices.size() == 3000);
}

TEST_CASE("reference trees of random scenes trace like brute force") {
    const std::uint32_t seeds[] = {101, 102, 103, 104};
    for (std::uint32_t seed : seeds) {
        CAPTURE(seed);
        // Mix of sizes: small triangles, and large ones that straddle many planes.
        const Scene scene = test::random_triangles(1500, seed, 1.0f, seed % 2 ? 0.05f : 0.3f);
        const KdTree tree = build_reference(scene);
        const auto errors = check_tree(tree, scene);
        CHECK_MESSAGE(errors.empty(), joined(errors));
        check_traces_match_brute_force(tree, scene, 2000, seed + 7);
    }
}

TEST_CASE("an empty scene gives a single empty leaf") {
    const Scene scene = make_scene({}, "empty");
    const KdTree tree = build_reference(scene);
    REQUIRE(tree.nodes.size() == 1);
    CHECK(kd_node_is_leaf(tree.nodes[0]));
    CHECK(kd_leaf_count(tree.nodes[0]) == 0);
    CHECK(tree.leaf_indices.empty());
    CHECK(check_tree(tree, scene).empty());
    KdRay ray{{0, 0, -1}, 0, {0, 0, 1}, INFINITY};
    CHECK(trace(tree, scene, ray).prim == KDRAY_NO_HIT);
}

TEST_CASE("a scene without area (one point) is a single leaf") {
    const Scene scene = make_scene({1, 2, 3, 1, 2, 3, 1, 2, 3, 1, 2, 3, 1, 2, 3, 1, 2, 3}, "point");
    const KdTree tree = build_reference(scene);
    CHECK(tree.nodes.size() == 1);
    CHECK(check_tree(tree, scene).empty());
}

TEST_CASE("the SAH split of two far-apart clusters lies in the gap") {
    // 200 triangles in [0,1]^3 and 200 in [9,10] x [0,1]^2: any plane with x in [1, 9] separates
    // them and cuts off empty space, which beats every other plane by far.
    Scene a = test::random_triangles(200, 31, 0.9f, 0.05f, 0.05f);
    Scene b = test::random_triangles(200, 32, 0.9f, 0.05f, 0.05f);
    std::vector<float> tris = a.triangles;
    for (std::size_t i = 0; i < b.triangles.size(); ++i)
        tris.push_back(i % 3 == 0 ? b.triangles[i] + 9.0f : b.triangles[i]);
    const Scene scene = make_scene(std::move(tris), "two_clusters");
    const KdTree tree = build_reference(scene);
    REQUIRE(!kd_node_is_leaf(tree.nodes[0]));
    CHECK(kd_node_axis(tree.nodes[0]) == 0);
    const float split = kd_node_split(tree.nodes[0]);
    CHECK(split >= a.bounds().hi.x);
    CHECK(split <= b.bounds().lo.x + 9.0f);
    CHECK(check_tree(tree, scene).empty());
}

TEST_CASE("reference trees cost no more than a naive spatial-median tree") {
    const std::uint32_t seeds[] = {201, 202, 203};
    for (std::uint32_t seed : seeds) {
        CAPTURE(seed);
        const Scene scene = test::random_triangles(3000, seed, 1.0f, 0.04f);
        const SahCosts costs{};
        const KdTree reference = build_reference(scene);
        const KdTree median = SpatialMedianBuilder(scene).build(20, 4);
        // The naive builder also exercises the checker on a tree it did not build.
        CHECK(check_tree(median, scene).empty());
        const double reference_cost =
            compute_tree_stats(reference, scene.triangle_count(), costs).sah_cost;
        const double median_cost =
            compute_tree_stats(median, scene.triangle_count(), costs).sah_cost;
        CAPTURE(reference_cost);
        CAPTURE(median_cost);
        CHECK(reference_cost <= median_cost);
    }
}

TEST_CASE("perfect splits: a leaf lists only triangles that truly enter its box") {
    // Large random triangles: their bounds overlap many leaves that the triangles themselves
    // miss. With perfect splits (clipped bounds) such leaves must not list them.
    const Scene scene = test::random_triangles(400, 41, 1.0f, 0.4f);
    const KdTree tree = build_reference(scene);
    std::size_t false_references = 0, references = 0;
    struct Entry {
        kd_u32 node;
        Aabb box;
    };
    std::vector<Entry> stack{{0, tree.bounds}};
    while (!stack.empty()) {
        const Entry e = stack.back();
        stack.pop_back();
        const KdNode n = tree.nodes[e.node];
        if (!kd_node_is_leaf(n)) {
            const int axis = int(kd_node_axis(n));
            Aabb below = e.box, above = e.box;
            below.hi[axis] = above.lo[axis] = kd_node_split(n);
            stack.push_back({e.node + 1, below});
            stack.push_back({kd_node_above_child(n), above});
            continue;
        }
        for (kd_u32 i = 0; i < kd_leaf_count(n); ++i) {
            const kd_u32 t = tree.leaf_indices[kd_leaf_offset(n) + i];
            ++references;
            if (clip_triangle_bounds(scene.vertex(t, 0), scene.vertex(t, 1), scene.vertex(t, 2),
                                     e.box)
                    .empty())
                ++false_references;
        }
    }
    CAPTURE(references);
    CHECK(false_references == 0);
}

TEST_CASE("the depth limit is respected") {
    const Scene scene = test::random_triangles(2000, 51);
    for (int max_depth : {0, 1, 3, 8}) {
        CAPTURE(max_depth);
        BuildParams params;
        params.max_depth = max_depth;
        const KdTree tree = build_reference(scene, params);
        CHECK(tree_depth(tree) <= max_depth);
        CHECK(tree.params.max_depth == max_depth);
        const auto errors = check_tree(tree, scene);
        CHECK_MESSAGE(errors.empty(), joined(errors));
    }
}

TEST_CASE("the empty-space bonus scales the SAH of a plane that cuts off empty space") {
    // Two triangles spanning x in [0, 0.8] and all of y, z in the node box [0, 1]^3: the only
    // plane that cuts off empty space is x = 0.8, of SAH C_t + C_i * 2 * SA([0,0.8]x[0,1]^2) /
    // SA([0,1]^3) = 15 + 40 * 5.2 / 6 = 49.67 without the bonus: dearer than the leaf (C_i * 2 =
    // 40), so no split pays. A bonus of 0.5 halves exactly that plane's cost, to 24.83, and makes
    // it the split; a bonus of 0.2 (0.8 * 49.67 = 39.73) just beats the leaf too.
    NodeEvents events;
    Aabb tri;
    tri.lo = {0, 0, 0};
    tri.hi = {0.8f, 1, 1};
    append_events(events, 0, tri);
    append_events(events, 1, tri);
    sort_events(events);
    Aabb box;
    box.lo = {0, 0, 0};
    box.hi = {1, 1, 1};
    const double leaf = 20.0 * 2;
    const double cut_off = 15.0 + 20.0 * 2 * (2.0 * (0.8 + 1 + 0.8) / 6.0);
    for (const float bonus : {0.0f, 0.2f, 0.5f}) {
        CAPTURE(bonus);
        BuildParams params;
        params.empty_bonus = bonus;
        const SplitChoice choice = find_best_split(events, 2, box, params);
        REQUIRE(choice.axis == 0);
        CHECK(choice.pos == 0.8f);
        CHECK(choice.left_count == 2);
        CHECK(choice.right_count == 0);
        CHECK(choice.cost == doctest::Approx(cut_off * (1.0 - bonus)).epsilon(1e-6));
        CHECK((choice.cost < leaf) == (bonus > 0));
    }
}

TEST_CASE("the traversal cost changes the tree as the SAH says") {
    const Scene scene = test::random_triangles(2000, 61, 1.0f, 0.03f);
    BuildParams cheap_traversal;
    cheap_traversal.costs.traversal = 1.0f;
    BuildParams dear_traversal;
    dear_traversal.costs.traversal = 200.0f;
    // Dearer traversal steps make the SAH stop earlier: fewer, fuller leaves.
    CHECK(build_reference(scene, dear_traversal).nodes.size() <
          build_reference(scene, cheap_traversal).nodes.size());
}

TEST_CASE("invalid build parameters are rejected with their value") {
    const Scene scene = test::random_triangles(10, 71);
    BuildParams deep;
    deep.max_depth = KDRAY_MAX_DEPTH + 1;
    CHECK_THROWS_AS(build_reference(scene, deep), Error);
    BuildParams negative;
    negative.max_depth = -1;
    CHECK_THROWS_AS(build_reference(scene, negative), Error);
    BuildParams bonus;
    bonus.empty_bonus = 1.0f;
    CHECK_THROWS_AS(build_reference(scene, bonus), Error);
    BuildParams cost;
    cost.costs.intersection = NAN;
    CHECK_THROWS_AS(build_reference(scene, cost), Error);
}

TEST_CASE("clip_triangle_bounds returns the clipped part's bounds") {
    // The triangle (0,0,0) (2,0,0) (0,2,0) clipped to [1,2] x [0,2] x [-1,1] is the corner
    // (1,0,0) (2,0,0) (1,1,0): its bounds are [1,2] x [0,1] x [0,0].
    Aabb box;
    box.lo = {1, 0, -1};
    box.hi = {2, 2, 1};
    const Aabb b = clip_triangle_bounds({0, 0, 0}, {2, 0, 0}, {0, 2, 0}, box);
    CHECK(b.lo == Vec3{1, 0, 0});
    CHECK(b.hi == Vec3{2, 1, 0});
    // A box the triangle's bounds overlap but the triangle misses.
    box.lo = {1.5f, 1.5f, -1};
    box.hi = {2, 2, 1};
    CHECK(clip_triangle_bounds({0, 0, 0}, {2, 0, 0}, {0, 2, 0}, box).empty());
}
