// triangle_clip.cpp — Sutherland–Hodgman clipping of a triangle to a box, for perfect splits.
#include "core/triangle_clip.h"

#include <array>
#include <cmath>
#include <cstddef>
#include <limits>

namespace kdray {
namespace {

struct DPoint {
    double v[3];
};

/// A triangle clipped by the six planes of a box gains at most one vertex per plane: 3 + 6 = 9.
constexpr std::size_t kMaxClipVertices = 9;

struct Polygon {
    std::array<DPoint, kMaxClipVertices> points;
    std::size_t size = 0;
};

/// Keeps the part of `in` on the inner side of the plane x[axis] = pos: x >= pos when keep_above,
/// x <= pos otherwise. Crossing points get exactly `pos` on the clip axis so that no rounding drift
/// pushes them outside the plane they lie on.
Polygon clip_against_plane(const Polygon& in, int axis, double pos, bool keep_above) {
    Polygon out;
    auto inside = [&](const DPoint& p) { return keep_above ? p.v[axis] >= pos : p.v[axis] <= pos; };
    for (std::size_t i = 0; i < in.size; ++i) {
        const DPoint& cur = in.points[i];
        const DPoint& next = in.points[(i + 1) % in.size];
        const bool cur_in = inside(cur), next_in = inside(next);
        if (cur_in) out.points[out.size++] = cur;
        if (cur_in != next_in) {
            // The edge crosses the plane, so the denominator is non-zero.
            const double t = (pos - cur.v[axis]) / (next.v[axis] - cur.v[axis]);
            DPoint x;
            for (int k = 0; k < 3; ++k) x.v[k] = cur.v[k] + t * (next.v[k] - cur.v[k]);
            x.v[axis] = pos;
            out.points[out.size++] = x;
        }
    }
    return out;
}

/// Largest float not above d.
float round_down(double d) {
    float f = static_cast<float>(d);
    if (static_cast<double>(f) > d) f = std::nextafter(f, -std::numeric_limits<float>::infinity());
    return f;
}

/// Smallest float not below d.
float round_up(double d) {
    float f = static_cast<float>(d);
    if (static_cast<double>(f) < d) f = std::nextafter(f, std::numeric_limits<float>::infinity());
    return f;
}

}  // namespace

Aabb clip_triangle_bounds(Vec3 a, Vec3 b, Vec3 c, const Aabb& box) {
    Polygon poly;
    for (Vec3 p : {a, b, c}) poly.points[poly.size++] = DPoint{{p.x, p.y, p.z}};

    // Clip against the box's six planes, stopping as soon as nothing is left.
    for (int axis = 0; axis < 3 && poly.size > 0; ++axis) {
        poly = clip_against_plane(poly, axis, box.lo[axis], true);
        if (poly.size > 0) poly = clip_against_plane(poly, axis, box.hi[axis], false);
    }
    Aabb result;
    if (poly.size == 0) return result;

    // Bounds of the clipped polygon, rounded outward to float and clamped to the box.
    for (int axis = 0; axis < 3; ++axis) {
        double lo = poly.points[0].v[axis], hi = lo;
        for (std::size_t i = 1; i < poly.size; ++i) {
            lo = std::min(lo, poly.points[i].v[axis]);
            hi = std::max(hi, poly.points[i].v[axis]);
        }
        result.lo[axis] = std::max(round_down(lo), box.lo[axis]);
        result.hi[axis] = std::min(round_up(hi), box.hi[axis]);
    }
    return result;
}

}  // namespace kdray
