// tree_stats.cpp — statistics of a finished tree, recomputed from the nodes alone (boxes rebuilt
// from the split planes), with the SAH cost of conventions.md.
#include "core/tree/tree_stats.h"

#include <algorithm>
#include <string>
#include <vector>

#include "core/error.h"

namespace kdray {
namespace {

struct StatsWalker {
    const KdTree& tree;
    SahCosts costs;
    double root_area;
    TreeStats& stats;
    std::vector<bool> visited = std::vector<bool>(tree.nodes.size(), false);
    std::size_t non_empty_leaves = 0;

    /// Preorder walk; the recursion depth is the tree's depth, which a sound tree keeps within
    /// KDRAY_MAX_DEPTH. A node index out of range, a node reached twice or a path deeper than that
    /// throws, so a broken tree can never make the walk loop or read out of bounds.
    void visit(std::size_t index, const Aabb& box, int depth) {
        if (index >= tree.nodes.size())
            throw Error("compute_tree_stats: node index " + std::to_string(index) +
                        " is out of range (" + std::to_string(tree.nodes.size()) + " nodes)");
        if (depth > KDRAY_MAX_DEPTH)
            throw Error("compute_tree_stats: a path is deeper than KDRAY_MAX_DEPTH at node " +
                        std::to_string(index));
        if (visited[index])
            throw Error("compute_tree_stats: node " + std::to_string(index) + " is reached twice");
        visited[index] = true;
        ++stats.nodes;
        stats.max_depth = std::max(stats.max_depth, depth);
        // SA(n) / SA(root); a root without area gives every node weight 0 (see compute_tree_stats).
        const double weight = root_area > 0 ? double(box.area()) / root_area : 0.0;
        const KdNode node = tree.nodes[index];
        if (kd_node_is_leaf(node)) {
            const kd_u32 count = kd_leaf_count(node);
            ++stats.leaves;
            if (stats.leaf_depths.size() <= std::size_t(depth)) stats.leaf_depths.resize(depth + 1);
            ++stats.leaf_depths[depth];
            ++stats.leaf_sizes[count];
            if (count == 0)
                ++stats.empty_leaves;
            else
                ++non_empty_leaves;
            stats.triangle_references += count;
            stats.sah_cost += double(costs.intersection) * double(count) * weight;
            return;
        }
        ++stats.inner_nodes;
        stats.sah_cost += double(costs.traversal) * weight;
        const int axis = static_cast<int>(kd_node_axis(node));
        const float split = kd_node_split(node);
        Aabb below = box, above = box;
        below.hi[axis] = split;
        above.lo[axis] = split;
        visit(index + 1, below, depth + 1);
        visit(kd_node_above_child(node), above, depth + 1);
    }
};

}  // namespace

/// SAH cost as conventions.md defines it. When the root box has no area (an empty scene, or one
/// whose triangles all lie on a line or a point) no ray meets it with positive probability, so by
/// convention every term, and the cost, is 0.
TreeStats compute_tree_stats(const KdTree& tree, std::size_t triangle_count, SahCosts costs) {
    TreeStats stats;
    stats.triangles = triangle_count;
    stats.costs = costs;
    stats.bytes = tree.nodes.size() * sizeof(KdNode) + tree.leaf_indices.size() * sizeof(kd_u32);
    if (tree.nodes.empty()) return stats;

    StatsWalker walker{tree, costs, double(tree.bounds.area()), stats};
    walker.visit(0, tree.bounds, 0);
    if (triangle_count > 0)
        stats.references_per_triangle = double(stats.triangle_references) / double(triangle_count);
    if (walker.non_empty_leaves > 0)
        stats.mean_triangles_per_leaf =
            double(stats.triangle_references) / double(walker.non_empty_leaves);
    return stats;
}

nlohmann::json to_json(const TreeStats& stats) {
    // [[size, leaves], ...] by size: exact counts, as long as the distinct sizes (a dense array
    // would run to the largest leaf, which a budget leaf can make thousands long).
    nlohmann::json leaf_sizes = nlohmann::json::array();
    for (const auto& [size, leaves] : stats.leaf_sizes) leaf_sizes.push_back({size, leaves});
    return nlohmann::json{
        {"triangles", stats.triangles},
        {"nodes", stats.nodes},
        {"inner_nodes", stats.inner_nodes},
        {"leaves", stats.leaves},
        {"empty_leaves", stats.empty_leaves},
        {"tree_depth_reached", stats.max_depth},
        {"triangle_references", stats.triangle_references},
        {"references_per_triangle", stats.references_per_triangle},
        {"mean_triangles_per_leaf", stats.mean_triangles_per_leaf},
        {"bytes", stats.bytes},
        {"sah_cost", stats.sah_cost},
        {"cost_traversal", stats.costs.traversal},
        {"cost_intersection", stats.costs.intersection},
        {"leaf_depth_histogram", stats.leaf_depths},
        {"leaf_size_histogram", leaf_sizes},
    };
}

}  // namespace kdray
