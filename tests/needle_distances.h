// needle_distances.h — the OpenCL tracer's distances on test::needle_bundle against long double,
// shared by the fp64 (test_opencl_render.cpp) and float-float (test_opencl_float_float.cpp) tests.
#pragma once

#include <doctest/doctest.h>

#include <algorithm>
#include <cmath>
#include <string>

#include "cl/renderer/opencl_renderer.h"
#include "core/device/kd_render.h"
#include "core/render/camera.h"
#include "core/render/render_setup.h"
#include "core/tree/reference_builder.h"
#include "tests/support.h"
#include "tests/test_opencl_fixture.h"

namespace kdray::test {

/// The exact distance along `ray` to the plane of triangle `prim`, in long double from the same
/// float corners and ray: n.(p0 - o) / n.d with n from the edges (test_intersect.cpp's needle
/// test does the same).
inline long double exact_plane_distance(const Scene& scene, kd_u32 prim, const KdRay& ray) {
    using L = long double;
    const float* p = &scene.triangles[std::size_t(prim) * KDRAY_FLOATS_PER_TRIANGLE];
    L e1[3], e2[3], n[3], to_plane = 0, along = 0;
    for (int a = 0; a < 3; ++a) e1[a] = L(p[3 + a]) - p[a], e2[a] = L(p[6 + a]) - p[a];
    for (int a = 0; a < 3; ++a) {
        const int b = (a + 1) % 3, c = (a + 2) % 3;
        n[a] = e1[b] * e2[c] - e1[c] * e2[b];
    }
    for (int a = 0; a < 3; ++a) {
        to_plane += n[a] * (L(p[a]) - ray.org[a]);
        along += n[a] * ray.dir[a];
    }
    return to_plane / along;
}

/// |t - exact| in float ulps at `exact`.
inline double ulps_from(float t, long double exact) {
    const float nearest = float(exact);
    const float ulp = std::nextafter(nearest, INFINITY) - nearest;
    return double(std::fabs(static_cast<long double>(t) - exact) / ulp);
}

/// Renders 300 needles (test::needle_bundle, 96x72 pixels) on the OpenCL test device, one ray at
/// a time and in packets of 8 and 16 lanes (which refine lane by lane), with whatever exact
/// arithmetic the program was built for; every pixel must hit brute force's triangle, at a distance
/// within 4 ulps of the exact one.
inline void check_needle_distances() {
    const Scene scene = needle_bundle(300, 6);
    const KdTree tree = build_reference(scene);
    RenderSettings settings;
    settings.width = 96;
    settings.height = 72;
    for (unsigned lanes : {0u, 8u, 16u}) {
        CAPTURE(lanes);
        const ScopedEnv width("KDRAY_PACKET_LANES", lanes ? std::to_string(lanes) : "");
        RenderInputs inputs = prepare_render(scene, settings, needle_bundle_camera(), 0);
        inputs.packets = lanes ? RenderInputs::Packets::On : RenderInputs::Packets::Off;
        const FrameResult device = render_opencl(opencl_test_device(), tree, scene, inputs);
        REQUIRE(device.packet_lanes == lanes);
        int hits = 0, other_triangle = 0;
        double worst_ulps = 0;
        for (int y = 0; y < settings.height; ++y)
            for (int x = 0; x < settings.width; ++x) {
                const KdHit& got = device.hits.hits[std::size_t(y) * settings.width + x];
                KdRay ray;
                kd_camera_ray(&inputs.view, float(x) + 0.5f, float(y) + 0.5f, &ray);
                const KdHit want = brute_force_closest(scene, ray);
                other_triangle += got.prim != want.prim;
                if (want.prim == KDRAY_NO_HIT || got.prim != want.prim) continue;
                ++hits;
                worst_ulps = std::max(worst_ulps,
                                      ulps_from(got.t, exact_plane_distance(scene, got.prim, ray)));
            }
        CAPTURE(hits);
        CHECK(hits > 200);
        CHECK(other_triangle == 0);
        CAPTURE(worst_ulps);
        CHECK(worst_ulps <= 4);
    }
}

}  // namespace kdray::test
