// camera.h — primary rays exactly as conventions.md defines them, so that kdray, its reference
// and Embree shoot bit-identical centre rays.
#pragma once

#include "core/device/kd_shared.h"
#include "core/geometry/math.h"
#include "core/render/render_file.h"

namespace kdray {

/// Precomputed camera basis for one image size.
struct CameraRays {
    Vec3 origin, forward, right, up;
    float tan_half_fov, aspect;
    int width, height;

    CameraRays(const Camera& camera, int width, int height);
    /// The ray through image position (px, py) in pixels, (x + 0.5, y + 0.5) being pixel (x, y)'s
    /// centre; the direction is unit length, tmin 0, tmax +inf. It is kd_camera_ray of
    /// core/device/kd_render.h, the code the render kernel runs too.
    KdRay ray(float px, float py) const;
    /// The camera part of the shared KdView (origin, basis, tan_half_fov, aspect, size); the
    /// render settings' fields are left zero.
    const KdView& view() const { return view_; }

  private:
    KdView view_;  // the fields above in the shared layout, made once: ray() runs per pixel
};

/// A camera that looks at a scene's bounds from the front (+z), used when no render file gives one.
Camera frame_bounds(const Aabb& bounds, float fov_y = 45.0f);

}  // namespace kdray
