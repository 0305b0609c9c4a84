// sah_events.cpp — split event generation, sorting and the SAH sweep (Wald & Havran 2006).
#include "core/tree/sah_events.h"

#include <algorithm>
#include <limits>

namespace kdray {
namespace {

/// Surface area of `box` with its extent along `axis` replaced by `width`.
double area_with_width(const Vec3& extent, int axis, double width) {
    const double a = extent[(axis + 1) % 3], b = extent[(axis + 2) % 3];
    return 2.0 * (width * (a + b) + a * b);
}

}  // namespace

void append_events(NodeEvents& events, kd_u32 triangle, const Aabb& b) {
    for (int axis = 0; axis < 3; ++axis) {
        if (b.lo[axis] == b.hi[axis]) {
            events[axis].push_back(make_event(b.lo[axis], triangle, EventType::Planar));
        } else {
            events[axis].push_back(make_event(b.lo[axis], triangle, EventType::Start));
            events[axis].push_back(make_event(b.hi[axis], triangle, EventType::End));
        }
    }
}

void sort_events(NodeEvents& events) {
    for (auto& list : events) std::sort(list.begin(), list.end(), event_less);
}

SplitChoice find_best_split(const NodeEvents& events, std::size_t triangle_count, const Aabb& box,
                            const BuildParams& params) {
    const Vec3 extent = box.extent();
    const double inv_area = 1.0 / static_cast<double>(box.area());
    const double c_t = params.costs.traversal, c_i = params.costs.intersection;
    const double bonus = 1.0 - params.empty_bonus;

    SplitChoice best;
    best.cost = std::numeric_limits<double>::infinity();
    for (int axis = 0; axis < 3; ++axis) {
        const std::vector<SplitEvent>& list = events[axis];
        const float lo = box.lo[axis], hi = box.hi[axis];

        /// SAH of one plane with n_l triangles left and n_r right (paper Algorithm 4, "SAH").
        auto sah = [&](float pos, std::size_t n_l, std::size_t n_r) {
            if (n_l == triangle_count && n_r == triangle_count) {
                return std::numeric_limits<double>::infinity();
            }
            const double p_l = area_with_width(extent, axis, double(pos) - lo) * inv_area;
            const double p_r = area_with_width(extent, axis, double(hi) - pos) * inv_area;
            double cost = c_t + c_i * (p_l * double(n_l) + p_r * double(n_r));
            // Empty space is only cut off when the empty child has some width along the axis.
            if ((n_l == 0 && pos > lo) || (n_r == 0 && pos < hi)) cost *= bonus;
            return cost;
        };

        // Sweep the plane candidates in order (paper Algorithm 4): at each position count the
        // triangles ending (p−), lying in (p|) and starting (p+) at it.
        std::size_t n_l = 0, n_r = triangle_count;
        for (std::size_t i = 0; i < list.size();) {
            const float pos = list[i].pos;
            std::size_t ending = 0, planar = 0, starting = 0;
            while (i < list.size() && list[i].pos == pos && list[i].type() == EventType::End) {
                ++ending;
                ++i;
            }
            while (i < list.size() && list[i].pos == pos && list[i].type() == EventType::Planar) {
                ++planar;
                ++i;
            }
            while (i < list.size() && list[i].pos == pos && list[i].type() == EventType::Start) {
                ++starting;
                ++i;
            }
            // Move the plane onto pos: triangles ending or lying here leave the right side.
            n_r -= planar + ending;

            // Planar triangles go to the cheaper side (the paper's p_side).
            const double cost_left = sah(pos, n_l + planar, n_r);
            const double cost_right = sah(pos, n_l, n_r + planar);
            const bool left = cost_left <= cost_right;
            const double cost = left ? cost_left : cost_right;
            if (cost < best.cost) {
                best.axis = axis;
                best.pos = pos;
                best.planar_side = left ? PlanarSide::Left : PlanarSide::Right;
                best.cost = cost;
                best.left_count = left ? n_l + planar : n_l;
                best.right_count = left ? n_r : n_r + planar;
            }

            // Move the plane past pos: triangles starting or lying here are now on the left.
            n_l += starting + planar;
        }
    }
    if (best.cost == std::numeric_limits<double>::infinity()) best.axis = -1;
    return best;
}

}  // namespace kdray
