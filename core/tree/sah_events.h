// sah_events.h — split events and the SAH sweep over them, the heart of Wald & Havran's (2006)
// O(N log N) kd-tree construction ("On building fast kd-trees for ray tracing, and on doing that
// in O(N log N)", Sec. 4–5). Used by the reference builder (core/tree/reference_builder.cpp).
//
// Every triangle contributes, per axis, either one planar event (its clipped bounds are flat on
// that axis) or a start and an end event. Each axis keeps its events sorted by position and, at
// equal positions, by type end < planar < start, which is the order the sweep needs to count the
// triangles left of, right of and in each candidate plane.
#pragma once

#include <array>
#include <cstddef>
#include <vector>

#include "core/device/kd_shared.h"
#include "core/geometry/math.h"
#include "core/tree/tree.h"

namespace kdray {

/// Event type, numbered in the sort order the sweep relies on (paper Sec. 5.1: "−" < "|" < "+").
enum class EventType : kd_u32 { End = 0, Planar = 1, Start = 2 };

/// One split event: 8 bytes, the triangle id and type packed into one word (ids < 2^30).
struct SplitEvent {
    float pos;
    kd_u32 key;  // triangle << 2 | type

    kd_u32 triangle() const { return key >> 2; }
    EventType type() const { return static_cast<EventType>(key & 3u); }
};

inline SplitEvent make_event(float pos, kd_u32 triangle, EventType type) {
    return {pos, (triangle << 2) | static_cast<kd_u32>(type)};
}

/// Sort order of the sweep: position, then type; the triangle id breaks ties so that builds are
/// deterministic.
inline bool event_less(const SplitEvent& a, const SplitEvent& b) {
    if (a.pos != b.pos) return a.pos < b.pos;
    const kd_u32 type_a = a.key & 3u, type_b = b.key & 3u;
    if (type_a != type_b) return type_a < type_b;
    return a.key < b.key;
}

/// A node's events: one sorted list per axis.
using NodeEvents = std::array<std::vector<SplitEvent>, 3>;

/// Appends the events of one triangle whose (clipped) bounds are `b` to the lists of each axis.
void append_events(NodeEvents& events, kd_u32 triangle, const Aabb& b);

/// Sorts each axis's list into sweep order.
void sort_events(NodeEvents& events);

/// Which child gets the triangles that lie in the split plane (the paper's p_side).
enum class PlanarSide { Left, Right };

/// The cheapest split the sweep found. axis == -1 when no candidate plane exists.
struct SplitChoice {
    int axis = -1;
    float pos = 0;
    PlanarSide planar_side = PlanarSide::Left;
    double cost = 0;
    std::size_t left_count = 0, right_count = 0;
};

/// Sweeps the sorted events of all three axes of a node with `triangle_count` triangles and box
/// `box` (area > 0) and returns the plane of least SAH cost (paper Algorithm 4–5):
///     cost = λ (C_t + C_i (N_L SA_L + N_R SA_R) / SA_node),
/// where λ = 1 - empty_bonus when one side holds no triangles and that side's box has non-zero
/// width along the split axis (cutting off empty space), and 1 otherwise. For each plane the
/// planar triangles are tried on both sides and put on the cheaper one. A plane that leaves all
/// triangles on both sides is never chosen: it cannot make progress.
SplitChoice find_best_split(const NodeEvents& events, std::size_t triangle_count, const Aabb& box,
                            const BuildParams& params);

}  // namespace kdray
