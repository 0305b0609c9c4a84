// camera.cpp — primary rays of conventions.md's camera model.
//
// The arithmetic mirrors /work/shared/peers/embree/embree_ref.cpp operation for operation, in
// float: normalising multiplies by the reciprocal of the length (not a division, as
// kdray::normalize does), tan takes the half angle as fov_y * 0.5 * pi / 180, and the direction
// is f + (r * sx + u * sy) (kd_camera_ray, shared with the kernels). Any other order rounds
// differently, and the centre rays would no longer be bit-identical with the Embree peer's, which
// the pixel-by-pixel AOV comparison needs.
#include "core/render/camera.h"

#include "core/device/kd_render.h"

#include <cmath>
#include <numbers>

namespace kdray {
namespace {

/// embree_ref's norm(): a * (1 / sqrt(x*x + y*y + z*z)).
Vec3 peer_normalize(Vec3 a) {
    const float l = std::sqrt(a.x * a.x + a.y * a.y + a.z * a.z);
    const float s = 1.0f / l;
    return {a.x * s, a.y * s, a.z * s};
}

}  // namespace

CameraRays::CameraRays(const Camera& camera, int width_, int height_)
    : width(width_), height(height_) {
    origin = camera.position;
    forward = peer_normalize(camera.look_at - camera.position);
    right = peer_normalize(cross(forward, camera.up));
    up = cross(right, forward);
    tan_half_fov = std::tan(camera.fov_y * 0.5f * static_cast<float>(std::numbers::pi) / 180.0f);
    aspect = static_cast<float>(width) / static_cast<float>(height);
    view_ = KdView{};
    for (int a = 0; a < 3; ++a) {
        view_.origin[a] = origin[a];
        view_.forward[a] = forward[a];
        view_.right[a] = right[a];
        view_.up[a] = up[a];
    }
    view_.tan_half_fov = tan_half_fov;
    view_.aspect = aspect;
    view_.width = static_cast<kd_u32>(width);
    view_.height = static_cast<kd_u32>(height);
}

KdRay CameraRays::ray(float px, float py) const {
    KdRay ray;
    kd_camera_ray(&view_, px, py, &ray);
    return ray;
}

Camera frame_bounds(const Aabb& bounds, float fov_y) {
    Camera camera;
    camera.fov_y = fov_y;
    if (bounds.empty() || !is_finite(bounds.lo) || !is_finite(bounds.hi)) return camera;
    const Vec3 centre = (bounds.lo + bounds.hi) * 0.5f;
    // The box's bounding sphere fills the vertical field of view at this distance; the wider
    // horizontal view of a landscape image then shows all of it too.
    float radius = 0.5f * length(bounds.extent());
    if (!(radius > 0.0f)) radius = 1.0f;  // a single point: any distance will do
    const float half = 0.5f * fov_y * static_cast<float>(std::numbers::pi) / 180.0f;
    const float distance = radius / std::sin(half);
    camera.look_at = centre;
    camera.position = {centre.x, centre.y, centre.z + distance};
    camera.up = {0, 1, 0};
    return camera;
}

}  // namespace kdray
