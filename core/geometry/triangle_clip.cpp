// triangle_clip.cpp — the bounds of a triangle clipped to a box, for the reference builder's
// perfect splits, by the shared Sutherland–Hodgman routine of core/device/kd_clip.h in double
// precision.
#include "core/geometry/triangle_clip.h"

#include <algorithm>
#include <cmath>
#include <limits>

// The reference builder clips in double (kd_clip.h's coordinate type).
#define KDRAY_CLIP_REAL double
#include "core/device/kd_clip.h"

namespace kdray {
namespace {

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
    double poly[2][KDRAY_CLIP_MAX_VERTICES][3];
    kd_u32 count = 0;
    for (Vec3 p : {a, b, c}) {
        poly[0][count][0] = p.x, poly[0][count][1] = p.y, poly[0][count][2] = p.z;
        ++count;
    }
    // Clip against the box's six planes, stopping as soon as nothing is left.
    int cur = 0;
    for (kd_u32 plane = 0; plane < 6 && count > 0; ++plane) {
        const kd_u32 axis = plane / 2;
        const bool keep_above = plane % 2 == 0;  // even planes: x >= lo; odd: x <= hi
        const double pos = keep_above ? box.lo[axis] : box.hi[axis];
        count = kd_clip_polygon_to_plane(poly[cur], count, axis, pos, keep_above, poly[1 - cur]);
        cur = 1 - cur;
    }
    Aabb result;
    if (count == 0) return result;

    // Bounds of the clipped polygon, rounded outward to float and clamped to the box.
    for (int axis = 0; axis < 3; ++axis) {
        double lo = poly[cur][0][axis], hi = lo;
        for (kd_u32 i = 1; i < count; ++i) {
            lo = std::min(lo, poly[cur][i][axis]);
            hi = std::max(hi, poly[cur][i][axis]);
        }
        result.lo[axis] = std::max(round_down(lo), box.lo[axis]);
        result.hi[axis] = std::min(round_up(hi), box.hi[axis]);
    }
    return result;
}

}  // namespace kdray
