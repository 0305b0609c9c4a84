// tree_check.h — the invariant checker every tree read back from a builder goes through in tests
// and debug builds: the layout is well formed (preorder, offsets in range, depth within
// KDRAY_MAX_DEPTH), split planes lie inside their node's box, and every triangle is referenced by
// every leaf whose box its clipped part overlaps.
#pragma once

#include <cstddef>
#include <string>
#include <vector>

#include "core/scene/scene.h"
#include "core/tree/tree.h"

namespace kdray {

/// Every violated invariant, one line each (empty when the tree is sound). Stops after `limit`.
std::vector<std::string> check_tree(const KdTree& tree, const Scene& scene, int limit = 20);

/// The layout checks alone (no scene at hand: a tree file read back), against a scene of
/// `triangle_count` triangles: offsets and leaf lists in range, preorder, depth, splits inside
/// their boxes, finite bounds.
std::vector<std::string> check_tree_layout(const KdTree& tree, std::size_t triangle_count,
                                           int limit = 20);

}  // namespace kdray
