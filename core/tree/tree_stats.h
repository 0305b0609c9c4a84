// tree_stats.h — the figures kdray reports for a tree, computed from the tree itself (never taken
// from the builder's word), with the SAH cost exactly as conventions.md defines it.
#pragma once

#include <cstddef>
#include <map>
#include <vector>

#include <nlohmann/json.hpp>

#include "core/tree/tree.h"

namespace kdray {

struct TreeStats {
    std::size_t triangles = 0;
    std::size_t nodes = 0, inner_nodes = 0, leaves = 0, empty_leaves = 0;
    int max_depth = 0;
    std::size_t triangle_references = 0;
    double references_per_triangle = 0;
    double mean_triangles_per_leaf = 0;  // over non-empty leaves
    std::size_t bytes = 0;               // nodes + leaf indices
    SahCosts costs;                      // the C_t and C_i the cost was computed with
    double sah_cost = 0;
    /// leaf_depths[d]: leaves at depth d (the root is at 0), for d = 0 .. max_depth.
    std::vector<std::size_t> leaf_depths;
    /// leaf_sizes[n]: leaves holding n triangle references, for every n that occurs.
    std::map<std::size_t, std::size_t> leaf_sizes;
};

/// Statistics of `tree` over a scene of `triangle_count` triangles, the SAH cost with `costs`.
TreeStats compute_tree_stats(const KdTree& tree, std::size_t triangle_count, SahCosts costs);

nlohmann::json to_json(const TreeStats& stats);

}  // namespace kdray
