// reference_builder.cpp — the CPU reference kd-tree builder of Wald & Havran (2006), "On building
// fast kd-trees for ray tracing, and on doing that in O(N log N)": full SAH over split events that
// are sorted once at the root and kept sorted by splicing and merging, perfect splits, and the
// empty-space bonus. The split events and the sweep live in core/sah_events.{h,cpp}; the clipping
// of straddling triangles in core/triangle_clip.{h,cpp}.
#include "core/tree/reference_builder.h"

#include <algorithm>
#include <cassert>
#include <chrono>
#include <cmath>
#include <cstdint>
#include <string>

#include "core/error.h"
#include "core/geometry/triangle_clip.h"
#include "core/tree/sah_events.h"

namespace kdray {
namespace {

/// Where a triangle goes when its node is split (paper Sec. 5.3, "classification").
enum class Side : std::uint8_t { Both, LeftOnly, RightOnly };

/// Number of distinct triangles in an event list: each has exactly one start or planar event.
std::size_t count_triangles(const std::vector<SplitEvent>& list) {
    return static_cast<std::size_t>(std::count_if(
        list.begin(), list.end(), [](const SplitEvent& e) { return e.type() != EventType::End; }));
}

/// Builds the tree depth first, writing nodes in preorder as it goes: a node's below child is
/// written right after it, so only the above child's index has to be patched in later.
class ReferenceBuilder {
  public:
    ReferenceBuilder(const Scene& scene, const BuildParams& params)
        : scene_(scene), params_(params), side_(scene.triangle_count(), Side::Both) {}

    KdTree build() {
        KdTree tree;
        tree.bounds = scene_.bounds();
        tree.params = params_;
        tree.builder = "reference";

        // Initial events from the triangles' bounds, sorted once for the whole build (paper
        // Sec. 5.2): every later node keeps its lists sorted without sorting them again.
        const std::size_t count = scene_.triangle_count();
        NodeEvents events;
        for (auto& list : events) list.reserve(2 * count);
        for (std::size_t t = 0; t < count; ++t)
            append_events(events, static_cast<kd_u32>(t), scene_.triangle_bounds(t));
        sort_events(events);

        build_node(std::move(events), count, tree.bounds, 0);
        tree.nodes = std::move(nodes_);
        tree.leaf_indices = std::move(leaf_indices_);
        return tree;
    }

  private:
    void build_node(NodeEvents events, std::size_t count, const Aabb& box, int depth) {
        // Initialize leaf node if termination criteria met: no triangles, the depth limit, or a
        // box without area, for which the SAH's probabilities are undefined.
        if (count == 0 || depth >= params_.max_depth || !(box.area() > 0.0f)) {
            make_leaf(events);
            return;
        }

        // Find the cheapest split plane over all axes by sweeping the sorted events.
        const SplitChoice split = find_best_split(events, count, box, params_);
        const double leaf_cost = double(params_.costs.intersection) * double(count);
        if (split.axis < 0 || !(split.cost < leaf_cost)) {
            make_leaf(events);
            return;
        }

        // Compute the children's boxes and split the events between them.
        Aabb left_box = box, right_box = box;
        left_box.hi[split.axis] = split.pos;
        right_box.lo[split.axis] = split.pos;
        NodeEvents left, right;
        split_events(events, split, left_box, right_box, left, right);
        events = NodeEvents{};  // the parent's events are no longer needed below this point
        const std::size_t left_count = count_triangles(left[0]);
        const std::size_t right_count = count_triangles(right[0]);
        // The classification must agree with the counts the sweep priced the split with.
        assert(left_count == split.left_count && right_count == split.right_count);

        // Emit the inner node, then its children in preorder.
        const std::size_t index = nodes_.size();
        nodes_.push_back(KdNode{});
        build_node(std::move(left), left_count, left_box, depth + 1);
        const std::size_t above = nodes_.size();
        if (above > KDRAY_MAX_OFFSET)
            throw Error("build_reference: node index " + std::to_string(above) +
                        " does not fit the 30 offset bits of KdNode");
        nodes_[index] =
            kd_make_inner(static_cast<kd_u32>(split.axis), split.pos, static_cast<kd_u32>(above));
        build_node(std::move(right), right_count, right_box, depth + 1);
    }

    /// A leaf lists its triangles (in id order, for reproducible output) in one run of
    /// leaf_indices.
    void make_leaf(const NodeEvents& events) {
        const std::size_t offset = leaf_indices_.size();
        if (offset > KDRAY_MAX_OFFSET || nodes_.size() > KDRAY_MAX_OFFSET)
            throw Error("build_reference: tree of " + std::to_string(nodes_.size()) +
                        " nodes and " + std::to_string(offset) +
                        " triangle references exceeds KdNode's 30 bits");
        for (const SplitEvent& e : events[0])
            if (e.type() != EventType::End) leaf_indices_.push_back(e.triangle());
        std::sort(leaf_indices_.begin() + static_cast<std::ptrdiff_t>(offset), leaf_indices_.end());
        nodes_.push_back(kd_make_leaf(static_cast<kd_u32>(leaf_indices_.size() - offset),
                                      static_cast<kd_u32>(offset)));
    }

    /// Distributes a node's sorted events to its children, keeping both lists sorted in linear
    /// time plus the sort of the straddlers' new events (paper Sec. 5.3): events of triangles
    /// entirely on one side are spliced over in order; triangles that straddle the plane are
    /// clipped to each child's box ("perfect splits", Sec. 4.3), and their new events, sorted
    /// apart, are merged in.
    void split_events(const NodeEvents& events, const SplitChoice& split, const Aabb& left_box,
                      const Aabb& right_box, NodeEvents& left, NodeEvents& right) {
        // Classify triangles as left only, right only or both (paper Algorithm 5): all start as
        // both, and the events on the split axis say which lie entirely on one side.
        const std::vector<SplitEvent>& axis_events = events[split.axis];
        for (const SplitEvent& e : axis_events)
            if (e.type() != EventType::End) side_[e.triangle()] = Side::Both;
        for (const SplitEvent& e : axis_events) {
            switch (e.type()) {
                case EventType::End:
                    if (e.pos <= split.pos) side_[e.triangle()] = Side::LeftOnly;
                    break;
                case EventType::Start:
                    if (e.pos >= split.pos) side_[e.triangle()] = Side::RightOnly;
                    break;
                case EventType::Planar:
                    if (e.pos < split.pos ||
                        (e.pos == split.pos && split.planar_side == PlanarSide::Left))
                        side_[e.triangle()] = Side::LeftOnly;
                    else
                        side_[e.triangle()] = Side::RightOnly;
                    break;
            }
        }

        // Splice the events of one-sided triangles into the children's lists; order is kept.
        NodeEvents left_only, right_only;
        for (int axis = 0; axis < 3; ++axis) {
            for (const SplitEvent& e : events[axis]) {
                const Side side = side_[e.triangle()];
                if (side == Side::LeftOnly)
                    left_only[axis].push_back(e);
                else if (side == Side::RightOnly)
                    right_only[axis].push_back(e);
            }
        }

        // Clip each straddling triangle to both children's boxes and make its new events.
        NodeEvents left_new, right_new;
        for (const SplitEvent& e : axis_events) {
            if (e.type() != EventType::Start || side_[e.triangle()] != Side::Both) continue;
            const kd_u32 t = e.triangle();
            append_events(left_new, t, clipped_bounds(t, left_box));
            append_events(right_new, t, clipped_bounds(t, right_box));
        }
        sort_events(left_new);
        sort_events(right_new);

        // Merge the two sorted sequences of each child and axis.
        for (int axis = 0; axis < 3; ++axis) {
            merge_into(left_only[axis], left_new[axis], left[axis]);
            merge_into(right_only[axis], right_new[axis], right[axis]);
        }
    }

    /// Bounds of triangle t clipped to a child's box. Rounding can make a triangle that touches
    /// the box only at a point or an edge clip to nothing although the classification put it on
    /// both sides; its bounds intersected with the box are then used, which over-approximates
    /// instead of losing the triangle.
    Aabb clipped_bounds(kd_u32 t, const Aabb& child) const {
        Aabb b = clip_triangle_bounds(scene_.vertex(t, 0), scene_.vertex(t, 1), scene_.vertex(t, 2),
                                      child);
        if (b.empty()) b = Aabb::intersection(scene_.triangle_bounds(t), child);
        return b;
    }

    static void merge_into(const std::vector<SplitEvent>& a, const std::vector<SplitEvent>& b,
                           std::vector<SplitEvent>& out) {
        out.resize(a.size() + b.size());
        std::merge(a.begin(), a.end(), b.begin(), b.end(), out.begin(), event_less);
    }

    const Scene& scene_;
    BuildParams params_;
    /// Per-triangle classification scratch, valid only for the node being split.
    std::vector<Side> side_;
    std::vector<KdNode> nodes_;
    std::vector<kd_u32> leaf_indices_;
};

}  // namespace

KdTree build_reference(const Scene& scene, const BuildParams& params) {
    validate_build_params(params);
    if (scene.triangle_count() > KDRAY_MAX_OFFSET)
        throw Error("build_reference: " + scene.path.string() + " has " +
                    std::to_string(scene.triangle_count()) +
                    " triangles, more than kd_shared.h's 30-bit triangle ids allow");
    return ReferenceBuilder(scene, params).build();
}

BuiltTree ReferenceTreeBuilder::build(const Scene& scene) {
    BuiltTree built;
    const auto start = std::chrono::steady_clock::now();
    built.tree = build_reference(scene, params_);
    built.report.build_ms =
        std::chrono::duration<double, std::milli>(std::chrono::steady_clock::now() - start).count();
    built.report.timings_ms.push_back({"build", built.report.build_ms});
    return built;
}

}  // namespace kdray
