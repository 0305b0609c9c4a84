// test_tree_check.cpp — the invariant checker and the statistics on trees whose right answers are
// known by hand, and on deliberately broken trees: the checker is only worth something if it
// fails when a reference, an offset or a split plane is wrong.
#include <doctest/doctest.h>

#include <algorithm>
#include <map>
#include <random>
#include <string>

#include "core/tree/reference_builder.h"
#include "core/tree/tree_check.h"
#include "core/tree/tree_stats.h"
#include "tests/support.h"

using namespace kdray;

namespace {

/// Three triangles in the box [0,4] x [0,1] x [0,2]:
///   T0, T1 in x <= 1 (T0 reaches z = 2, T1 spans the box's y), T2 in x >= 1, z <= 0.5.
Scene small_scene() {
    return make_scene({0, 0, 0, 1, 0, 0, 0, 1, 2,  //
                       0, 0, 1, 1, 1, 1, 0, 1, 0,  //
                       1, 0, 0, 4, 0, 0, 4, 1, 0.5f},
                      "small");
}

/// The tree drawn by hand for small_scene(), in preorder:
///   0: inner x = 1, above child 2     box [0,4]x[0,1]x[0,2]  SA 28
///   1: leaf {T0, T1}                  box [0,1]x[0,1]x[0,2]  SA 10
///   2: inner z = 0.5, above child 4   box [1,4]x[0,1]x[0,2]  SA 22
///   3: leaf {T2}                      box [1,4]x[0,1]x[0,0.5] SA 10
///   4: empty leaf                     box [1,4]x[0,1]x[0.5,2] SA 18
KdTree small_tree() {
    KdTree tree;
    tree.bounds = small_scene().bounds();
    tree.nodes = {kd_make_inner(0, 1.0f, 2), kd_make_leaf(2, 0), kd_make_inner(2, 0.5f, 4),
                  kd_make_leaf(1, 2), kd_make_leaf(0, 3)};
    tree.leaf_indices = {0, 1, 2};
    tree.builder = "hand";
    return tree;
}

/// Removes entry `entry` of leaf_indices from the leaf that owns it and moves every later leaf's
/// offset down, so that the layout stays sound and only coverage can notice.
void drop_reference(KdTree& tree, std::size_t entry) {
    for (KdNode& node : tree.nodes) {
        if (!kd_node_is_leaf(node)) continue;
        const kd_u32 offset = kd_leaf_offset(node), count = kd_leaf_count(node);
        if (entry >= offset && entry < offset + count)
            node = kd_make_leaf(count - 1, offset);
        else if (offset > entry)
            node = kd_make_leaf(count, offset - 1);
    }
    tree.leaf_indices.erase(tree.leaf_indices.begin() + std::ptrdiff_t(entry));
}

std::string joined(const std::vector<std::string>& errors) {
    std::string s;
    for (const auto& e : errors) s += e + "\n";
    return s;
}

}  // namespace

TEST_CASE("a hand-built sound tree passes") {
    const Scene scene = small_scene();
    const auto errors = check_tree(small_tree(), scene);
    CHECK_MESSAGE(errors.empty(), joined(errors));
}

TEST_CASE("SAH cost of the hand-built tree matches its closed form") {
    // inner: C_t (28 + 22) / 28; leaves: C_i (2 * 10 + 1 * 10 + 0 * 18) / 28.
    const TreeStats s = compute_tree_stats(small_tree(), 3, SahCosts{15.0f, 20.0f});
    CHECK(s.sah_cost == doctest::Approx((15.0 * 50.0 + 20.0 * 30.0) / 28.0).epsilon(1e-12));
    const TreeStats unit = compute_tree_stats(small_tree(), 3, SahCosts{1.0f, 2.0f});
    CHECK(unit.sah_cost == doctest::Approx(110.0 / 28.0).epsilon(1e-12));

    CHECK(s.nodes == 5);
    CHECK(s.inner_nodes == 2);
    CHECK(s.leaves == 3);
    CHECK(s.empty_leaves == 1);
    CHECK(s.max_depth == 2);
    CHECK(s.triangle_references == 3);
    CHECK(s.references_per_triangle == doctest::Approx(1.0));
    CHECK(s.mean_triangles_per_leaf == doctest::Approx(1.5));  // over the two non-empty leaves
    CHECK(s.bytes == 5 * 8 + 3 * 4);

    const nlohmann::json j = to_json(s);
    for (const char* key :
         {"triangles", "nodes", "inner_nodes", "leaves", "empty_leaves", "tree_depth_reached",
          "triangle_references", "references_per_triangle", "mean_triangles_per_leaf", "bytes",
          "sah_cost", "cost_traversal", "cost_intersection"})
        CHECK_MESSAGE(j.contains(key), key);
    CHECK(j["sah_cost"].get<double>() == doctest::Approx(s.sah_cost));
    CHECK(j["cost_traversal"].get<double>() == 15.0);
    CHECK(j["cost_intersection"].get<double>() == 20.0);
}

TEST_CASE("leaf histograms of the hand-built tree and of the reference builder's") {
    // small_tree's leaves: node 1 (2 triangles, depth 1), nodes 3 (1, depth 2) and 4 (0, depth 2).
    const TreeStats s = compute_tree_stats(small_tree(), 3, SahCosts{});
    CHECK(s.leaf_depths == std::vector<std::size_t>{0, 1, 2});
    CHECK(s.leaf_sizes == std::map<std::size_t, std::size_t>{{0, 1}, {1, 1}, {2, 1}});
    const nlohmann::json j = to_json(s);
    CHECK(j["leaf_depth_histogram"] == nlohmann::json::parse("[0, 1, 2]"));
    CHECK(j["leaf_size_histogram"] == nlohmann::json::parse("[[0, 1], [1, 1], [2, 1]]"));

    // The reference builder on one triangle: nothing to cut (its box is the root box), one leaf.
    const Scene one = make_scene({0, 0, 0, 1, 0, 0, 0, 1, 1}, "one");
    const TreeStats single = compute_tree_stats(build_reference(one), 1, SahCosts{});
    CHECK(single.leaf_depths == std::vector<std::size_t>{1});
    CHECK(single.leaf_sizes == std::map<std::size_t, std::size_t>{{1, 1}});

    // On a real build the histograms account for every leaf and every reference.
    const Scene many = test::random_triangles(500, 7);
    const TreeStats r = compute_tree_stats(build_reference(many), 500, SahCosts{});
    std::size_t leaves = 0, references = 0;
    for (const std::size_t n : r.leaf_depths) leaves += n;
    for (const auto& [size, n] : r.leaf_sizes) references += size * n;
    CHECK(leaves == r.leaves);
    CHECK(references == r.triangle_references);
    CHECK(r.leaf_depths.size() == std::size_t(r.max_depth) + 1);
}

TEST_CASE("SAH cost of a single-leaf tree is C_i times the triangle count") {
    // The root leaf's box is the root box, so its weight is exactly 1.
    const Scene scene = small_scene();
    KdTree tree;
    tree.bounds = scene.bounds();
    tree.nodes = {kd_make_leaf(3, 0)};
    tree.leaf_indices = {0, 1, 2};
    CHECK(check_tree(tree, scene).empty());
    CHECK(compute_tree_stats(tree, 3, SahCosts{15, 20}).sah_cost == doctest::Approx(60.0));
}

TEST_CASE("an empty scene's tree is one empty leaf with cost 0") {
    const Scene empty = make_scene({}, "empty");
    KdTree tree;
    tree.nodes = {kd_make_leaf(0, 0)};
    CHECK(check_tree(tree, empty).empty());
    const TreeStats s = compute_tree_stats(tree, 0, SahCosts{});
    CHECK(s.sah_cost == 0.0);
    CHECK(s.leaves == 1);
    CHECK(s.empty_leaves == 1);
    CHECK(s.references_per_triangle == 0.0);
}

TEST_CASE("a dropped triangle reference is detected") {
    const Scene scene = small_scene();
    for (std::size_t entry = 0; entry < 3; ++entry) {
        CAPTURE(entry);
        KdTree tree = small_tree();
        drop_reference(tree, entry);
        const auto errors = check_tree(tree, scene);
        REQUIRE(errors.size() == 1);
        CHECK(errors[0].find("triangle " + std::to_string(entry)) != std::string::npos);
    }
}

TEST_CASE("dropped references in a reference-built tree are detected") {
    // Random references of a real tree, including ones of straddling, planar and zero-area
    // triangles: every reference the builder made is to a triangle that truly enters the leaf.
    for (const Scene& scene : {test::random_triangles(800, 11, 1.0f, 0.2f),
                               test::with_zero_area(400, 12), test::cube_lattice(3)}) {
        const KdTree built = build_reference(scene);
        REQUIRE(check_tree(built, scene).empty());
        std::mt19937 rng(7);
        for (int i = 0; i < 25; ++i) {
            KdTree tree = built;
            const std::size_t entry = rng() % tree.leaf_indices.size();
            CAPTURE(entry);
            CAPTURE(scene.path);
            drop_reference(tree, entry);
            CHECK_FALSE(check_tree(tree, scene).empty());
        }
    }
}

TEST_CASE("corrupted offsets are detected") {
    const Scene scene = small_scene();
    SUBCASE("above child pointing backwards") {
        KdTree tree = small_tree();
        tree.nodes[2] = kd_make_inner(2, 0.5f, 1);
        CHECK_FALSE(check_tree(tree, scene).empty());
    }
    SUBCASE("above child out of range") {
        KdTree tree = small_tree();
        tree.nodes[0] = kd_make_inner(0, 1.0f, 9);
        CHECK_FALSE(check_tree(tree, scene).empty());
    }
    SUBCASE("above child not after the below subtree (preorder broken)") {
        KdTree tree = small_tree();
        tree.nodes[0] = kd_make_inner(0, 1.0f, 3);
        CHECK_FALSE(check_tree(tree, scene).empty());
    }
    SUBCASE("leaf range past the end of leaf_indices") {
        KdTree tree = small_tree();
        tree.nodes[3] = kd_make_leaf(1, 3);
        CHECK_FALSE(check_tree(tree, scene).empty());
    }
    SUBCASE("triangle id out of range") {
        KdTree tree = small_tree();
        tree.leaf_indices[2] = 3;
        CHECK_FALSE(check_tree(tree, scene).empty());
    }
    SUBCASE("leaf_indices entry owned by no leaf") {
        KdTree tree = small_tree();
        tree.leaf_indices.push_back(1);
        CHECK_FALSE(check_tree(tree, scene).empty());
    }
    SUBCASE("tree bounds smaller than the scene") {
        KdTree tree = small_tree();
        tree.bounds.hi.x = 3.0f;
        CHECK_FALSE(check_tree(tree, scene).empty());
    }
}

TEST_CASE("misplaced split planes are detected") {
    const Scene scene = small_scene();
    SUBCASE("split outside its node's box") {
        KdTree tree = small_tree();
        tree.nodes[2] = kd_make_inner(2, 3.0f, 4);  // the node's box ends at z = 2
        CHECK_FALSE(check_tree(tree, scene).empty());
    }
    SUBCASE("root split moved left: T0 and T1 now enter the above subtree") {
        KdTree tree = small_tree();
        tree.nodes[0] = kd_make_inner(0, 0.5f, 2);
        const auto errors = check_tree(tree, scene);
        CHECK_FALSE(errors.empty());
        CHECK(joined(errors).find("does not list it") != std::string::npos);
    }
    SUBCASE("z split moved down: T2 now enters the empty leaf") {
        KdTree tree = small_tree();
        tree.nodes[2] = kd_make_inner(2, 0.25f, 4);
        CHECK_FALSE(check_tree(tree, scene).empty());
    }
    SUBCASE("split axis changed") {
        KdTree tree = small_tree();
        tree.nodes[0] = kd_make_inner(1, 0.5f, 2);
        CHECK_FALSE(check_tree(tree, scene).empty());
    }
    SUBCASE("a split inside a reference-built tree shifted by a tenth of its box") {
        const Scene random = test::random_triangles(500, 21);
        KdTree tree = build_reference(random);
        REQUIRE(tree.nodes.size() > 1);
        const KdNode root = tree.nodes[0];
        const int axis = int(kd_node_axis(root));
        const float width = tree.bounds.hi[axis] - tree.bounds.lo[axis];
        tree.nodes[0] = kd_make_inner(kd_node_axis(root), kd_node_split(root) + 0.1f * width,
                                      kd_node_above_child(root));
        CHECK_FALSE(check_tree(tree, random).empty());
    }
}

TEST_CASE("depth beyond params.max_depth is detected") {
    const Scene scene = small_scene();
    KdTree tree = small_tree();
    tree.params.max_depth = 1;  // the hand-built tree has leaves at depth 2
    CHECK_FALSE(check_tree(tree, scene).empty());
    tree.params.max_depth = KDRAY_MAX_DEPTH + 1;
    CHECK_FALSE(check_tree(tree, scene).empty());
}

TEST_CASE("a triangle touching a leaf only along its face need not be listed there") {
    // T2's vertex (1, 0, 0) lies on the root's plane x = 1 and T0's edge reaches x = 1: neither
    // enters the other side, so listing each on one side only is sound.
    CHECK(check_tree(small_tree(), small_scene()).empty());
    // A triangle lying in the plane x = 1 may sit in either child (the paper's p_side).
    Scene scene = make_scene({0, 0, 0, 1, 0, 0, 0, 1, 2,  //
                              0, 0, 1, 1, 1, 1, 0, 1, 0,  //
                              1, 0, 0, 4, 0, 0, 4, 1, 0.5f, 1, 0, 0, 1, 1, 0, 1, 0, 0.25f},
                             "in_plane");
    KdTree left = small_tree();
    left.leaf_indices = {0, 1, 3, 2};
    left.nodes[1] = kd_make_leaf(3, 0);
    left.nodes[3] = kd_make_leaf(1, 3);
    left.nodes[4] = kd_make_leaf(0, 4);
    CHECK(check_tree(left, scene).empty());
    KdTree right = small_tree();
    right.leaf_indices = {0, 1, 2, 3};
    right.nodes[3] = kd_make_leaf(2, 2);
    right.nodes[4] = kd_make_leaf(0, 4);
    CHECK(check_tree(right, scene).empty());
    KdTree neither = small_tree();
    CHECK_FALSE(check_tree(neither, scene).empty());
}
