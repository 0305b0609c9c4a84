// scene_frame.h — the frame kdray traces a scene in: the scene's own coordinates (read in double)
// moved near the origin and scaled to about unit extent, then rounded to float once.
//
// Float coordinates fail in two ways that have nothing to do with the scene's shape: far from the
// origin their spacing grows (1.0 at 1e7, so spheres of radius 10 there lose their detail on
// load), and at extreme scales the ray tests' products of three coordinates overflow (radius 1e15)
// or underflow (radius 1e-30). In the frame every scene has an extent between 0.5 and 1 and lies
// within a unit of the origin, whatever its size and position.
//
// The scale is a power of two and the offset a whole multiple of the extent's power of two, so a
// scene near the origin keeps its offset 0 and is only scaled: multiplying by a power of two is
// exact in float, every float operation of the build and the trace commutes with it, and such a
// scene builds the same tree and renders the same image, bit for bit, as it did unscaled.
// Distances and positions that kdray reports (the AOV's Z) are mapped back to the scene's units.
#pragma once

#include <string>

#include "core/geometry/math.h"

namespace kdray {

struct SceneFrame {
    /// frame = (scene - offset) * scale.
    DVec3 offset{0, 0, 0};
    double scale = 1.0;  // a power of two

    /// The frame for a scene whose bounds are [lo, hi] in its own units. Throws Error, beginning
    /// with `name`, when the extent is not finite or too small for a double to scale.
    static SceneFrame fit(DVec3 lo, DVec3 hi, const std::string& name);

    /// A point of the scene in the frame, rounded to float once. Not finite when the point lies
    /// beyond float range of the frame (about 1e38 scene extents away).
    Vec3 point(DVec3 p) const {
        const DVec3 f = (p - offset) * scale;
        return {float(f.x), float(f.y), float(f.z)};
    }
    /// A point of the frame in the scene's units (exact for a frame that only scales).
    DVec3 scene_point(Vec3 p) const { return DVec3(p) * (1.0 / scale) + offset; }
    /// A length of the frame in the scene's units (exact unless it leaves float range).
    float scene_length(float length) const { return float(double(length) / scale); }
    bool is_identity() const { return scale == 1.0 && offset == DVec3{0, 0, 0}; }
};

}  // namespace kdray
