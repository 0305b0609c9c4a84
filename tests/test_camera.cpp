// test_camera.cpp — primary rays against conventions.md's closed form, and bit for bit against
// the Embree peer's own expressions (shared/peers/embree/embree_ref.cpp), which the pixel-exact
// AOV comparison with the peer depends on.
#include <doctest/doctest.h>

#include <cmath>
#include <cstring>

#include "core/render/camera.h"

using namespace kdray;

namespace {

Vec3 dir(const KdRay& r) {
    return {r.dir[0], r.dir[1], r.dir[2]};
}

/// conventions.md's formulas in double precision, for pixel centre (px, py).
Vec3 closed_form(const Camera& c, int w, int h, double px, double py) {
    auto norm = [](double v[3]) {
        const double l = std::sqrt(v[0] * v[0] + v[1] * v[1] + v[2] * v[2]);
        for (int k = 0; k < 3; ++k) v[k] /= l;
    };
    double f[3] = {c.look_at.x - c.position.x, c.look_at.y - c.position.y,
                   c.look_at.z - c.position.z};
    norm(f);
    double r[3] = {f[1] * c.up.z - f[2] * c.up.y, f[2] * c.up.x - f[0] * c.up.z,
                   f[0] * c.up.y - f[1] * c.up.x};
    norm(r);
    const double u[3] = {r[1] * f[2] - r[2] * f[1], r[2] * f[0] - r[0] * f[2],
                         r[0] * f[1] - r[1] * f[0]};
    const double t = std::tan(c.fov_y * M_PI / 360.0), a = double(w) / h;
    const double sx = (2 * px / w - 1) * t * a, sy = (1 - 2 * py / h) * t;
    double d[3];
    for (int k = 0; k < 3; ++k) d[k] = f[k] + sx * r[k] + sy * u[k];
    norm(d);
    return {float(d[0]), float(d[1]), float(d[2])};
}

/// embree_ref.cpp's trace() setup and per-pixel direction, copied expression for expression.
struct PeerV3 {
    float x, y, z;
};
PeerV3 sub(PeerV3 a, PeerV3 b) {
    return {a.x - b.x, a.y - b.y, a.z - b.z};
}
PeerV3 add(PeerV3 a, PeerV3 b) {
    return {a.x + b.x, a.y + b.y, a.z + b.z};
}
PeerV3 mul(PeerV3 a, float s) {
    return {a.x * s, a.y * s, a.z * s};
}
PeerV3 cross(PeerV3 a, PeerV3 b) {
    return {a.y * b.z - a.z * b.y, a.z * b.x - a.x * b.z, a.x * b.y - a.y * b.x};
}
PeerV3 norm(PeerV3 a) {
    float l = std::sqrt(a.x * a.x + a.y * a.y + a.z * a.z);
    return mul(a, 1.0f / l);
}
PeerV3 peer_direction(const Camera& c, int w, int h, int x, int y) {
    PeerV3 pos{c.position.x, c.position.y, c.position.z},
        look{c.look_at.x, c.look_at.y, c.look_at.z}, up{c.up.x, c.up.y, c.up.z};
    PeerV3 f = norm(sub(look, pos)), r = norm(cross(f, up)), u = cross(r, f);
    float th = std::tan(c.fov_y * 0.5f * float(M_PI) / 180.0f), aspect = float(w) / h;
    float px = (2.0f * (x + 0.5f) / w - 1.0f) * th * aspect;
    float py = (1.0f - 2.0f * (y + 0.5f) / h) * th;
    return norm(add(f, add(mul(r, px), mul(u, py))));
}

bool same_bits(float a, float b) {
    return std::memcmp(&a, &b, sizeof a) == 0;
}

const Camera kOblique{{1.5f, 2.25f, 7.0f}, {-0.3f, 0.4f, 0.1f}, {0.1f, 1.0f, 0.05f}, 39.3f};

}  // namespace

TEST_CASE("the centre ray looks along look_at - position, from the camera position") {
    const CameraRays rays(kOblique, 640, 480);
    const KdRay r = rays.ray(320.0f, 240.0f);
    const Vec3 f = normalize(kOblique.look_at - kOblique.position);
    CHECK(r.org[0] == kOblique.position.x);
    CHECK(r.org[1] == kOblique.position.y);
    CHECK(r.org[2] == kOblique.position.z);
    CHECK(r.tmin == 0.0f);
    CHECK(std::isinf(r.tmax));
    CHECK(dir(r).x == doctest::Approx(f.x).epsilon(1e-6));
    CHECK(dir(r).y == doctest::Approx(f.y).epsilon(1e-6));
    CHECK(dir(r).z == doctest::Approx(f.z).epsilon(1e-6));
    CHECK(length(dir(r)) == doctest::Approx(1.0).epsilon(1e-6));
}

TEST_CASE("corner and edge rays match the closed form") {
    for (auto [w, h] : {std::pair{640, 480}, std::pair{101, 333}}) {
        CAPTURE(w);
        const CameraRays rays(kOblique, w, h);
        for (auto [x, y] : {std::pair{0, 0}, std::pair{w - 1, 0}, std::pair{0, h - 1},
                            std::pair{w - 1, h - 1}, std::pair{w / 2, 0}}) {
            CAPTURE(x);
            CAPTURE(y);
            const Vec3 got = dir(rays.ray(x + 0.5f, y + 0.5f));
            const Vec3 want = closed_form(kOblique, w, h, x + 0.5, y + 0.5);
            CHECK(got.x == doctest::Approx(want.x).epsilon(1e-5));
            CHECK(got.y == doctest::Approx(want.y).epsilon(1e-5));
            CHECK(got.z == doctest::Approx(want.z).epsilon(1e-5));
        }
    }
}

TEST_CASE("centre rays are bit-identical with the Embree peer's") {
    const int w = 37, h = 23;
    const CameraRays rays(kOblique, w, h);
    int differing = 0;
    for (int y = 0; y < h; ++y)
        for (int x = 0; x < w; ++x) {
            const KdRay r = rays.ray(x + 0.5f, y + 0.5f);
            const PeerV3 p = peer_direction(kOblique, w, h, x, y);
            differing +=
                !(same_bits(r.dir[0], p.x) && same_bits(r.dir[1], p.y) && same_bits(r.dir[2], p.z));
        }
    CHECK(differing == 0);
}

TEST_CASE("aspect: the horizontal half-angle is the vertical one times width / height") {
    const Camera c{{0, 0, 0}, {0, 0, -1}, {0, 1, 0}, 60.0f};
    const CameraRays rays(c, 800, 400);
    CHECK(rays.aspect == 2.0f);
    // Rays through the middle of the left edge and the top edge of the image.
    const Vec3 left = dir(rays.ray(0.0f, 200.0f)), top = dir(rays.ray(400.0f, 0.0f));
    const double t = std::tan(30.0 * M_PI / 180.0);
    CHECK(-left.x / -left.z == doctest::Approx(2 * t));
    CHECK(top.y / -top.z == doctest::Approx(t));
    CHECK(left.y == doctest::Approx(0.0));
    // Row 0 is the top of the image, column 0 the left.
    CHECK(top.y > 0);
    CHECK(left.x < 0);
}

TEST_CASE("frame_bounds sees the whole box from the +z side") {
    Aabb box;
    box.grow({-2, 1, -1});
    box.grow({4, 3, 0.5f});
    const Camera c = frame_bounds(box, 45.0f);
    CHECK(c.look_at == Vec3{1, 2, -0.25f});
    CHECK(c.position.z > box.hi.z);
    CHECK(c.position.x == 1.0f);
    // Every corner lies inside the vertical field of view (and so the wider horizontal one).
    const CameraRays rays(c, 640, 480);
    for (int k = 0; k < 8; ++k) {
        const Vec3 corner{k & 1 ? box.hi.x : box.lo.x, k & 2 ? box.hi.y : box.lo.y,
                          k & 4 ? box.hi.z : box.lo.z};
        const Vec3 v = corner - c.position;
        const float depth = dot(v, rays.forward);
        CHECK(depth > 0);
        CHECK(std::fabs(dot(v, rays.up)) / depth <= rays.tan_half_fov);
        CHECK(std::fabs(dot(v, rays.right)) / depth <= rays.tan_half_fov * rays.aspect);
    }
    // An empty box still gives a usable camera.
    const Camera fallback = frame_bounds(Aabb{}, 30.0f);
    CHECK_FALSE(fallback.position == fallback.look_at);
}
