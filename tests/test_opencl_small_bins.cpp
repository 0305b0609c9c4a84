// test_opencl_small_bins.cpp — the small stage's binned search (BuildParams::small_split_bins,
// cl/builder/kernels/build_small_bins.cl) against an oracle written here from its rule alone: a
// node's bins divide the tight box of its triangles' boxes within the node into B equal slabs per
// axis; the B + 1 slab boundaries strictly inside the node are its candidate planes, each priced
// by SAH = C_t + C_i (N_L SA_L + N_R SA_R) / SA with exact counts (a triangle below when its box
// starts before the plane, above when it ends after it), an empty side scaled by 1 - empty_bonus;
// the first cheapest in (axis, plane) order splits the node when it costs less than the leaf's
// C_i N. The oracle walks every node of an OpenCL tree of one small root: the triangles a node
// held are those of the leaves below it, so each node's choice can be priced again here.
#include <doctest/doctest.h>

#include <algorithm>
#include <cmath>
#include <cstdint>
#include <string>
#include <vector>

#include "cl/builder/opencl_builder.h"
#include "core/device/kd_shared.h"
#include "core/scene/scene.h"
#include "tests/support.h"
#include "tests/test_opencl_fixture.h"

using namespace kdray;

namespace {

struct OracleNode {
    Aabb box;
    int depth = 0;
};

struct Plane {
    double cost = INFINITY;
    int axis = -1;
    float pos = 0.0f;
};

struct OracleCounts {
    int nodes_checked = 0, splits_checked = 0, leaves_checked = 0, near_ties = 0;
};

Aabb triangle_box(const Scene& scene, std::uint32_t t) {
    const float* v = &scene.triangles[std::size_t(t) * KDRAY_FLOATS_PER_TRIANGLE];
    Aabb b;
    for (int k = 0; k < 3; ++k) b.grow(Vec3{v[3 * k], v[3 * k + 1], v[3 * k + 2]});
    return b;
}

double half_area(const Aabb& b) {
    const double x = b.hi.x - b.lo.x, y = b.hi.y - b.lo.y, z = b.hi.z - b.lo.z;
    return x * y + y * z + z * x;
}

/// Every triangle in a leaf under node `index`.
void triangles_under(const KdTree& tree, std::size_t index, std::vector<std::uint32_t>& out) {
    const KdNode n = tree.nodes[index];
    if (kd_node_is_leaf(n)) {
        for (kd_u32 k = 0; k < kd_leaf_count(n); ++k)
            out.push_back(tree.leaf_indices[kd_leaf_offset(n) + k]);
        return;
    }
    triangles_under(tree, index + 1, out);
    triangles_under(tree, kd_node_above_child(n), out);
}

/// The two cheapest binned planes of a node holding `refs` (the cheapest first).
std::pair<Plane, Plane> cheapest_planes(const Scene& scene, const std::vector<std::uint32_t>& refs,
                                        const Aabb& box, int bins, const BuildParams& params) {
    Aabb refs_box;
    for (std::uint32_t t : refs) refs_box.grow(triangle_box(scene, t));
    const Aabb tight = Aabb::intersection(refs_box, box);
    Plane best, second;
    for (int a = 0; a < 3; ++a)
        for (int b = 0; b <= bins; ++b) {
            const float t_lo = tight.lo[a], t_hi = tight.hi[a];
            const float p = b == 0      ? t_lo
                            : b == bins ? t_hi
                                        : t_lo + (t_hi - t_lo) * (float(b) / float(bins));
            if (!(p > box.lo[a] && p < box.hi[a])) continue;
            int below = 0, above = 0;
            for (std::uint32_t t : refs) {
                const Aabb tb = triangle_box(scene, t);
                below += tb.lo[a] < p;
                above += tb.hi[a] > p;
            }
            Aabb left = box, right = box;
            left.hi[a] = p;
            right.lo[a] = p;
            double cost = params.costs.traversal +
                          params.costs.intersection *
                              (below * half_area(left) + above * half_area(right)) / half_area(box);
            if (below == 0 || above == 0) cost *= 1.0 - double(params.empty_bonus);
            const Plane plane{cost, a, p};
            if (cost < best.cost) {
                second = best;
                best = plane;
            } else if (cost < second.cost) {
                second = plane;
            }
        }
    return {best, second};
}

/// Walks `tree` (one small root: the whole scene) and checks each node's split or leaf against
/// the oracle. Nodes whose choice is a near tie (the two cheapest planes, or the cheapest and the
/// leaf, within 1e-4 relative, where float rounding may pick either) are counted, not checked.
void check_against_oracle(const KdTree& tree, const Scene& scene, const BuildParams& params,
                          int bins, std::size_t index, const OracleNode& node,
                          OracleCounts& counts) {
    std::vector<std::uint32_t> refs;
    triangles_under(tree, index, refs);
    std::sort(refs.begin(), refs.end());
    refs.erase(std::unique(refs.begin(), refs.end()), refs.end());
    const KdNode n = tree.nodes[index];
    if (refs.empty() || node.depth >= params.max_depth || half_area(node.box) <= 0.0) {
        CHECK(kd_node_is_leaf(n));
        return;
    }
    ++counts.nodes_checked;
    const auto [best, second] = cheapest_planes(scene, refs, node.box, bins, params);
    const double leaf = params.costs.intersection * double(refs.size());
    // A tie is common: where as many triangles lie below a plane as above it, the cost does not
    // change along the slab between them, and float rounding picks the plane.
    const auto near = [](double a, double b) { return std::fabs(a - b) <= 1e-4 * std::max(a, b); };
    if (near(best.cost, leaf) ||
        (best.axis >= 0 && second.axis >= 0 && near(best.cost, second.cost))) {
        ++counts.near_ties;
    } else if (!(best.cost < leaf)) {
        CAPTURE(index);
        CHECK(kd_node_is_leaf(n));
        ++counts.leaves_checked;
    } else {
        CAPTURE(index);
        CAPTURE(best.cost);
        REQUIRE(!kd_node_is_leaf(n));
        CHECK(int(kd_node_axis(n)) == best.axis);
        CHECK(kd_node_split(n) == doctest::Approx(best.pos).epsilon(1e-6));
        ++counts.splits_checked;
    }
    if (kd_node_is_leaf(n)) return;
    const int axis = int(kd_node_axis(n));
    OracleNode below = node, above = node;
    below.box.hi[axis] = kd_node_split(n);
    above.box.lo[axis] = kd_node_split(n);
    below.depth = above.depth = node.depth + 1;
    check_against_oracle(tree, scene, params, bins, index + 1, below, counts);
    check_against_oracle(tree, scene, params, bins, kd_node_above_child(n), above, counts);
}

BuildParams binned(int bins, SmallStage stage) {
    BuildParams params;
    params.small_split_bins = bins;
    params.small_reclip_refs = 0;  // the oracle prices triangle boxes, not re-clipped ones
    params.small_leaf_refs = 0;
    params.small_stage = stage;
    return params;
}

}  // namespace

TEST_CASE("opencl small stage: binned nodes split where the binned SAH of their triangles says") {
    ClDevice& device = test::opencl_test_device();
    OracleCounts counts;
    for (SmallStage stage : {SmallStage::PerRoot, SmallStage::PerLevel})
        for (int bins : {4, 8, 16})
            for (std::uint32_t seed : {1u, 2u, 3u, 4u}) {
                // One small root: at most 64 triangles, the large stage never runs. Larger
                // triangles (seed 4) overlap, and their nodes stop sooner.
                const Scene scene =
                    test::random_triangles(60, seed, 1.0f, seed == 4 ? 0.6f : 0.15f);
                CAPTURE(seed);
                CAPTURE(bins);
                const BuildParams params = binned(bins, stage);
                BuildReport report;
                const KdTree tree = build_opencl(device, scene, params, &report);
                REQUIRE(report.large_node_levels == 0);
                OracleNode root;
                root.box = tree.bounds;
                check_against_oracle(tree, scene, params, bins, 0, root, counts);
                CHECK(test::count_disagreements(tree, scene, test::random_rays(scene, 500, seed)) ==
                      0);
            }
    MESSAGE("nodes " << counts.nodes_checked << ", splits " << counts.splits_checked << ", leaves "
                     << counts.leaves_checked << ", near ties " << counts.near_ties);
    // The oracle saw splits and leaves, and most nodes were no tie.
    CHECK(counts.splits_checked > 1000);
    CHECK(counts.leaves_checked > 300);
    CHECK(counts.near_ties * 10 < counts.nodes_checked);
}

TEST_CASE("opencl small stage: a node whose triangles span it is a binned leaf") {
    // Ten triangles through the whole unit cube's diagonal plane: every plane has all ten on both
    // sides, which costs more than the leaf (closed form: C_t + C_i 10 (SA_L + SA_R) / SA > C_i
    // 10).
    std::vector<float> tris;
    for (int i = 0; i < 10; ++i) {
        const float d = 0.001f * float(i);
        tris.insert(tris.end(), {0.0f, 0.0f, d, 1.0f, 1.0f, d, 1.0f, d, 1.0f});
    }
    const Scene scene = make_scene(std::move(tris), "spanning");
    for (SmallStage stage : {SmallStage::PerRoot, SmallStage::PerLevel}) {
        const KdTree tree = build_opencl(test::opencl_test_device(), scene, binned(8, stage));
        REQUIRE(tree.nodes.size() == 1);
        CHECK(kd_leaf_count(tree.nodes[0]) == 10);
    }
}
