// tree_check.cpp — the tree invariant checker (tree_check.h). It trusts nothing a builder says:
// it walks the nodes, rebuilds every box from the split planes, and for coverage clips each
// triangle down the tree (in double, with the shared clipping routine of core/device/kd_clip.h), so
// a builder's bug in choosing splits, boxes or leaf lists cannot hide in code the checker shares.
#include "core/tree/tree_check.h"

#include <algorithm>
#include <array>
#include <cmath>
#include <cstdint>
#include <sstream>
#include <string>
#include <vector>

// The checker clips in double (kd_clip.h's coordinate type).
#define KDRAY_CLIP_REAL double
#include "core/device/kd_clip.h"

namespace kdray {
namespace {

std::string box_string(const Aabb& b) {
    std::ostringstream s;
    s.precision(9);
    s << "[" << b.lo.x << ", " << b.lo.y << ", " << b.lo.z << "] - [" << b.hi.x << ", " << b.hi.y
      << ", " << b.hi.z << "]";
    return s.str();
}

/// A convex polygon in double precision: a triangle clipped by planes (a zero-area triangle
/// degenerates to its segment or point and clips the same way).
using Polygon = std::vector<std::array<double, 3>>;
static_assert(sizeof(std::array<double, 3>) == 3 * sizeof(double), "points are double[3]");

/// Part of `poly` with x[axis] <= pos (keep_above false) or x[axis] >= pos, by the one
/// Sutherland–Hodgman routine (core/device/kd_clip.h). The checker's own logic (boxes rebuilt from
/// the splits, coverage down the tree) is independent of the builders; the routine itself is tested
/// against closed forms (tests/test_reference_builder.cpp).
Polygon clip_half_space(const Polygon& poly, int axis, double pos, bool keep_above) {
    Polygon out(poly.size() + 1);
    const kd_u32 count = kd_clip_polygon_to_plane(
        reinterpret_cast<const double(*)[3]>(poly.data()), kd_u32(poly.size()), kd_u32(axis), pos,
        keep_above, reinterpret_cast<double(*)[3]>(out.data()));
    out.resize(count);
    return out;
}

class TreeChecker {
  public:
    /// scene: null for the layout checks alone, against a scene of `triangle_count` triangles.
    TreeChecker(const KdTree& tree, const Scene* scene, std::size_t triangle_count, int limit)
        : tree_(tree),
          scene_(scene),
          triangle_count_(triangle_count),
          limit_(static_cast<std::size_t>(std::max(limit, 1))) {}

    std::vector<std::string> run() {
        check_layout();
        // Coverage walks the tree by its offsets, which is only safe once the layout is sound.
        if (errors_.empty() && scene_) check_coverage();
        return std::move(errors_);
    }

  private:
    bool full() const { return errors_.size() >= limit_; }
    void fail(const std::string& message) {
        if (!full()) errors_.push_back(message);
    }

    // ---- Layout ------------------------------------------------------------------------------

    void check_layout() {
        const int max_depth = tree_.params.max_depth;
        if (max_depth < 0 || max_depth > KDRAY_MAX_DEPTH)
            fail("params.max_depth " + std::to_string(max_depth) + " is outside [0, " +
                 std::to_string(KDRAY_MAX_DEPTH) + "]");
        if (tree_.nodes.empty()) {
            fail("the tree has no nodes (an empty scene still needs one empty leaf)");
            return;
        }
        if (tree_.nodes.size() - 1 > KDRAY_MAX_OFFSET)
            fail("the tree has " + std::to_string(tree_.nodes.size()) +
                 " nodes, more than 30-bit offsets address");
        // An empty scene's tree keeps the empty box (lo = +inf, hi = -inf); any other must be
        // a finite box.
        const Aabb empty_box;
        const bool empty_tree = tree_.bounds.lo == empty_box.lo && tree_.bounds.hi == empty_box.hi;
        for (int a = 0; a < 3 && !empty_tree; ++a)
            if (!(std::isfinite(tree_.bounds.lo[a]) && std::isfinite(tree_.bounds.hi[a]) &&
                  tree_.bounds.lo[a] <= tree_.bounds.hi[a])) {
                fail("tree bounds " + box_string(tree_.bounds) + " are not a finite box");
                return;
            }
        const Aabb scene_bounds = scene_ ? scene_->bounds() : Aabb{};
        if (!scene_bounds.empty() && !tree_.bounds.contains(scene_bounds))
            fail("tree bounds " + box_string(tree_.bounds) + " do not contain the scene bounds " +
                 box_string(scene_bounds));

        // Walk in preorder with an explicit stack: the k-th node reached must be node k, which
        // is what kd_shared.h's layout (below child next, above child after its subtree) means.
        struct Entry {
            std::size_t index;
            Aabb box;
            int depth;
        };
        std::vector<bool> reached(tree_.nodes.size(), false);
        std::vector<bool> entry_used(tree_.leaf_indices.size(), false);
        std::vector<Entry> stack{{0, tree_.bounds, 0}};
        std::size_t expected = 0;
        while (!stack.empty() && !full()) {
            const Entry e = stack.back();
            stack.pop_back();
            const std::string where = "node " + std::to_string(e.index);
            if (reached[e.index]) {
                fail(where + " is reached twice");
                continue;
            }
            reached[e.index] = true;
            if (e.index != expected)
                fail(where + " is reached at preorder position " + std::to_string(expected));
            ++expected;
            if (e.depth > max_depth)
                fail(where + " has depth " + std::to_string(e.depth) + " > max_depth " +
                     std::to_string(max_depth));
            const KdNode node = tree_.nodes[e.index];
            if (kd_node_is_leaf(node)) {
                check_leaf(e.index, node, entry_used);
                continue;
            }
            // Inner node: the split must lie inside the node's box, the above child after it.
            const int axis = static_cast<int>(kd_node_axis(node));
            const float split = kd_node_split(node);
            if (!(split >= e.box.lo[axis] && split <= e.box.hi[axis]))
                fail(where + " splits axis " + std::to_string(axis) + " at " +
                     std::to_string(split) + ", outside its box " + box_string(e.box));
            const std::size_t above = kd_node_above_child(node);
            if (above <= e.index || above >= tree_.nodes.size()) {
                fail(where + " has above child " + std::to_string(above) + ", not in (" +
                     std::to_string(e.index) + ", " + std::to_string(tree_.nodes.size()) + ")");
                continue;
            }
            if (e.index + 1 >= tree_.nodes.size()) {
                fail(where + " is inner but is the last node: it has no below child");
                continue;
            }
            // Past the traversal stack's size the walk stops: the depth error is reported.
            if (e.depth >= KDRAY_MAX_DEPTH + 1) continue;
            Aabb below_box = e.box, above_box = e.box;
            below_box.hi[axis] = split;
            above_box.lo[axis] = split;
            stack.push_back({above, above_box, e.depth + 1});
            stack.push_back({e.index + 1, below_box, e.depth + 1});
        }
        if (full()) return;
        const auto unreached = std::count(reached.begin(), reached.end(), false);
        if (unreached > 0)
            fail(
                std::to_string(unreached) + " nodes are never reached from the root, the first " +
                std::to_string(std::find(reached.begin(), reached.end(), false) - reached.begin()));
        const auto unused = std::count(entry_used.begin(), entry_used.end(), false);
        if (unused > 0)
            fail(std::to_string(unused) + " leaf_indices entries belong to no leaf, the first " +
                 std::to_string(std::find(entry_used.begin(), entry_used.end(), false) -
                                entry_used.begin()));
    }

    void check_leaf(std::size_t index, KdNode node, std::vector<bool>& entry_used) {
        const std::uint64_t offset = kd_leaf_offset(node), count = kd_leaf_count(node);
        if (offset + count > tree_.leaf_indices.size()) {
            fail("leaf " + std::to_string(index) + " names entries [" + std::to_string(offset) +
                 ", " + std::to_string(offset + count) + ") of " +
                 std::to_string(tree_.leaf_indices.size()) + " leaf_indices");
            return;
        }
        for (std::uint64_t i = offset; i < offset + count; ++i) {
            entry_used[i] = true;
            if (tree_.leaf_indices[i] >= triangle_count_)
                fail("leaf " + std::to_string(index) + " lists triangle " +
                     std::to_string(tree_.leaf_indices[i]) + " of a scene of " +
                     std::to_string(triangle_count_));
        }
    }

    // ---- Coverage ----------------------------------------------------------------------------

    void check_coverage() {
        // For every triangle, the leaves that list it, sorted (compressed rows).
        const std::size_t triangle_count = triangle_count_;
        std::vector<std::size_t> first(triangle_count + 1, 0);
        for_each_leaf([&](std::size_t, kd_u32 t) { ++first[t + 1]; });
        for (std::size_t t = 0; t < triangle_count; ++t) first[t + 1] += first[t];
        leaves_of_start_ = first;
        leaves_of_.assign(first[triangle_count], 0);
        for_each_leaf([&](std::size_t leaf, kd_u32 t) { leaves_of_[first[t]++] = leaf; });
        for (std::size_t t = 0; t < triangle_count; ++t)
            std::sort(leaves_of_.begin() + std::ptrdiff_t(leaves_of_start_[t]),
                      leaves_of_.begin() + std::ptrdiff_t(leaves_of_start_[t + 1]));

        // One float ulp of the scene's largest coordinate: a triangle must be listed where it
        // enters a box by more than this. Builders round clipped bounds to float, so anything
        // finer is noise, not a missing reference.
        const Aabb& b = tree_.bounds;
        double magnitude = 0;
        for (int k = 0; k < 3; ++k)
            magnitude =
                std::max({magnitude, std::fabs(double(b.lo[k])), std::fabs(double(b.hi[k]))});
        tolerance_ = std::isfinite(magnitude) ? magnitude * 0x1p-23 : 0.0;

        for (std::size_t t = 0; t < triangle_count && !full(); ++t) {
            Polygon poly;
            for (int corner = 0; corner < 3; ++corner) {
                const Vec3 v = scene_->vertex(t, corner);
                poly.push_back({v.x, v.y, v.z});
            }
            std::size_t missing = 0;
            if (!covered(0, tree_.bounds, poly, static_cast<kd_u32>(t), missing))
                fail("triangle " + std::to_string(t) + " overlaps leaf " + std::to_string(missing) +
                     " (box " + box_string(leaf_box_) + ") but the leaf does not list it");
        }
    }

    template <typename F>
    void for_each_leaf(F&& f) const {
        for (std::size_t n = 0; n < tree_.nodes.size(); ++n) {
            const KdNode node = tree_.nodes[n];
            if (!kd_node_is_leaf(node)) continue;
            for (kd_u32 i = 0; i < kd_leaf_count(node); ++i)
                f(n, tree_.leaf_indices[kd_leaf_offset(node) + i]);
        }
    }

    bool listed(std::size_t leaf, kd_u32 t) const {
        return std::binary_search(leaves_of_.begin() + std::ptrdiff_t(leaves_of_start_[t]),
                                  leaves_of_.begin() + std::ptrdiff_t(leaves_of_start_[t + 1]),
                                  leaf);
    }

    /// Whether every leaf below `index` that `poly` (the triangle's part inside `box`) enters
    /// lists triangle t; on failure `missing` names a leaf that does not.
    bool covered(std::size_t index, const Aabb& box, const Polygon& poly, kd_u32 t,
                 std::size_t& missing) {
        const KdNode node = tree_.nodes[index];
        if (kd_node_is_leaf(node)) {
            if (listed(index, t)) return true;
            missing = index;
            leaf_box_ = box;
            return false;
        }
        const int axis = static_cast<int>(kd_node_axis(node));
        const double split = kd_node_split(node);
        double lo = poly[0][axis], hi = lo;
        for (const auto& p : poly) {
            lo = std::min(lo, p[axis]);
            hi = std::max(hi, p[axis]);
        }
        Aabb below_box = box, above_box = box;
        below_box.hi[axis] = kd_node_split(node);
        above_box.lo[axis] = kd_node_split(node);
        const std::size_t below = index + 1, above = kd_node_above_child(node);
        const bool enters_below = lo<split - tolerance_, enters_above = hi> split + tolerance_;

        // A part lying in the split plane (within the tolerance) may belong to either child
        // (the paper's p_side): one of them must cover it. It is still clipped to each child, so
        // that a piece smaller than the tolerance, which splits near a vertex do produce, is not
        // carried whole into a child it only partly enters.
        if (!enters_below && !enters_above) {
            const Polygon below_part = clip_half_space(poly, axis, split, false);
            const Polygon above_part = clip_half_space(poly, axis, split, true);
            if (below_part.empty()) return covered(above, above_box, above_part, t, missing);
            if (above_part.empty()) return covered(below, below_box, below_part, t, missing);
            return covered(below, below_box, below_part, t, missing) ||
                   covered(above, above_box, above_part, t, missing);
        }
        if (enters_below &&
            !covered(below, below_box, clip_half_space(poly, axis, split, false), t, missing))
            return false;
        if (enters_above &&
            !covered(above, above_box, clip_half_space(poly, axis, split, true), t, missing))
            return false;
        return true;
    }

    const KdTree& tree_;
    const Scene* scene_;
    std::size_t triangle_count_;
    std::size_t limit_;
    std::vector<std::string> errors_;
    std::vector<std::size_t> leaves_of_start_;
    std::vector<std::size_t> leaves_of_;
    double tolerance_ = 0;
    Aabb leaf_box_;
};

}  // namespace

std::vector<std::string> check_tree(const KdTree& tree, const Scene& scene, int limit) {
    return TreeChecker(tree, &scene, scene.triangle_count(), limit).run();
}

std::vector<std::string> check_tree_layout(const KdTree& tree, std::size_t triangle_count,
                                           int limit) {
    return TreeChecker(tree, nullptr, triangle_count, limit).run();
}

}  // namespace kdray
