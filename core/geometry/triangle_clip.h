// triangle_clip.h — the bounds of the part of a triangle inside a box, for the reference builder's
// "perfect splits" (Wald & Havran 2006, Sec. 4.3): a triangle that straddles a split plane is
// clipped to each child's box and only the clipped part's bounds make its new split events.
#pragma once

#include "core/geometry/math.h"

namespace kdray {

/// Bounds of triangle (a, b, c) ∩ box, found by clipping the triangle polygon against the box's
/// six planes (Sutherland–Hodgman) in double precision. The result is rounded outward to float and
/// then clamped to `box`, so it always contains the exact clipped part and never leaves the box.
/// Returns an empty Aabb when the triangle misses the box. Zero-area triangles work: their polygon
/// degenerates to the clipped segment or point.
Aabb clip_triangle_bounds(Vec3 a, Vec3 b, Vec3 c, const Aabb& box);

}  // namespace kdray
