// test_shading_normals.cpp — smooth shading from the OBJ's vertex normals: the shared shading
// functions on hand-made cases, and whole frames of one triangle under a directional light against
// Lambert's law in closed form, by the reference renderer and by the OpenCL renderer with and
// without packets.
#include <doctest/doctest.h>

#include <cmath>
#include <vector>

#include "cl/renderer/opencl_renderer.h"
#include "core/device/kd_render.h"
#include "core/render/camera.h"
#include "core/render/reference_tracer.h"
#include "core/render/render_file.h"
#include "core/render/render_setup.h"
#include "core/scene/scene.h"
#include "core/tree/reference_builder.h"
#include "tests/test_opencl_fixture.h"

using namespace kdray;

namespace {

void put(std::vector<float>& out, Vec3 v) {
    out.insert(out.end(), {v.x, v.y, v.z});
}

/// A scene view holding nothing but vertex normals (all kd_shading_normal reads).
KdSceneView normals_view(const std::vector<float>& normals) {
    KdSceneView view{};
    view.vertex_normals = normals.data();
    return view;
}

/// One triangle in z = 0, wound counter-clockwise seen from +z, covering the camera's view of
/// [-1.2, 1.2]^2 except a corner; its corners' normals lean apart, the second one so far that a
/// region near it faces away from the light of lit_triangle_settings.
Scene smooth_triangle() {
    Scene scene = make_scene({-1.5f, -1.5f, 0, 3.5f, -1.5f, 0, -1.5f, 3.5f, 0});
    put(scene.vertex_normals, {0, 0, 1});
    put(scene.vertex_normals, normalize(Vec3{-4, 0, 1}));
    put(scene.vertex_normals, normalize(Vec3{0, 1, 1}));
    return scene;
}

const Vec3 kToLight = normalize(Vec3{0.3f, 0.2f, 1.0f});

RenderSettings lit_triangle_settings() {
    RenderSettings s;
    s.width = 24;
    s.height = 24;
    s.camera_keys[0].camera = Camera{{0, 0, 4}, {0, 0, 0}, {0, 1, 0}, 34.0f};
    s.camera_given = true;
    s.lights.push_back(Light{Light::Type::directional, {}, -kToLight, {2, 2, 2}});
    return s;
}

/// Lambert's law in double at each pixel's hit: Kd / pi * E * max(0, n . l), with n the corners'
/// normals interpolated at the hit's barycentrics (u, v: the second and third corners') and
/// normalised (the light is in front of the triangle's plane everywhere); the background where
/// the ray missed. Returns the largest difference from the
/// frame's image, after checking that most rays hit.
double largest_lambert_error(const Scene& scene, const FrameResult& frame) {
    const Vec3 kd = scene.materials[0].diffuse, background = RenderSettings{}.background;
    double worst = 0;
    std::size_t hits = 0;
    for (std::size_t i = 0; i < frame.hits.hits.size(); ++i) {
        const KdHit& hit = frame.hits.hits[i];
        double expected[3] = {background.x, background.y, background.z};
        if (hit.prim != KDRAY_NO_HIT) {
            ++hits;
            const double u = hit.u, v = hit.v, w = 1.0 - u - v;
            double n[3], length2 = 0;
            for (int a = 0; a < 3; ++a) {
                n[a] = w * scene.vertex_normals[a] + u * scene.vertex_normals[3 + a] +
                       v * scene.vertex_normals[6 + a];
                length2 += n[a] * n[a];
            }
            const double cos_l =
                (n[0] * kToLight.x + n[1] * kToLight.y + n[2] * kToLight.z) / std::sqrt(length2);
            const double shade = 2.0 * std::max(0.0, cos_l) / M_PI;
            expected[0] = kd.x * shade, expected[1] = kd.y * shade, expected[2] = kd.z * shade;
        }
        for (int c = 0; c < 3; ++c)
            worst = std::max(worst, std::fabs(frame.image.rgb[3 * i + c] - expected[c]));
    }
    CHECK(hits > frame.hits.hits.size() / 2);
    return worst;
}

}  // namespace

TEST_CASE("shading normal: interpolated, unit length, on the geometric normal's side") {
    const float ng[3] = {0, 0, 1};
    float ns[3];
    SUBCASE("the corners' normals weighted by the barycentrics") {
        std::vector<float> normals;
        put(normals, {0, 0, 1});
        put(normals, {1, 0, 0});
        put(normals, {0, 1, 0});
        const KdSceneView view = normals_view(normals);
        kd_shading_normal(&view, KdHit{1.0f, 0, 0.5f, 0.0f}, ng, ns);
        CHECK(ns[0] == doctest::Approx(std::sqrt(0.5)));
        CHECK(ns[1] == 0.0f);
        CHECK(ns[2] == doctest::Approx(std::sqrt(0.5)));
    }
    SUBCASE("normals against the winding are turned to the side the ray sees") {
        std::vector<float> normals;
        for (int k = 0; k < 3; ++k) put(normals, normalize(Vec3{0.2f, 0, -1}));
        const KdSceneView view = normals_view(normals);
        kd_shading_normal(&view, KdHit{1.0f, 0, 0.2f, 0.3f}, ng, ns);
        CHECK(ns[0] == doctest::Approx(-normalize(Vec3{0.2f, 0, -1}).x));
        CHECK(ns[2] == doctest::Approx(-normalize(Vec3{0.2f, 0, -1}).z));
    }
    SUBCASE("normals that cancel, or none at all, leave the geometric normal") {
        std::vector<float> normals;
        put(normals, {0, 1, 0});
        put(normals, {0, -1, 0});
        put(normals, {0, 0, 1});
        KdSceneView view = normals_view(normals);
        kd_shading_normal(&view, KdHit{1.0f, 0, 0.5f, 0.0f}, ng, ns);
        CHECK(ns[0] == 0.0f);
        CHECK(ns[1] == 0.0f);
        CHECK(ns[2] == 1.0f);
        view.vertex_normals = nullptr;
        kd_shading_normal(&view, KdHit{1.0f, 0, 0.2f, 0.2f}, ng, ns);
        CHECK(ns[2] == 1.0f);
    }
}

TEST_CASE("shading normal bends secondary rays only to the right side of the surface") {
    const float ng[3] = {0, 0, 1};
    const Vec3 d = normalize(Vec3{0.98f, 0, -0.196f});  // a grazing ray onto z = 0
    const float dir[3] = {d.x, d.y, d.z};
    const float mild[3] = {-0.6f, 0, 0.8f};
    // The mirror ray about this normal would go into the surface: z = -0.003.
    const float steep[3] = {0.1f, 0, std::sqrt(1.0f - 0.01f)};
    // Facing away from the ray: no incidence at all.
    const float away[3] = {0.6f, 0, 0.8f};
    CHECK(kd_shading_normal_bends(dir, ng, ng, 0.0f));
    CHECK(kd_shading_normal_bends(dir, ng, ng, 1.0f / 1.5f));
    CHECK(kd_shading_normal_bends(dir, ng, mild, 0.0f));
    CHECK_FALSE(kd_shading_normal_bends(dir, ng, steep, 0.0f));
    CHECK_FALSE(kd_shading_normal_bends(dir, ng, away, 0.0f));
    // Leaving glass (eta 1.5) near total internal reflection about a tilted normal: the mirror
    // ray is fine (z = 0.91), the refracted ray would come back out on the ray's side (z = 0.15).
    const Vec3 inside = normalize(Vec3{1.6f, 0, -1});
    const float exit_dir[3] = {inside.x, inside.y, inside.z};
    const Vec3 tilt = normalize(Vec3{-0.3f, 0, 1});
    const float tilted[3] = {tilt.x, tilt.y, tilt.z};
    CHECK(kd_shading_normal_bends(exit_dir, ng, tilted, 0.0f));
    CHECK_FALSE(kd_shading_normal_bends(exit_dir, ng, tilted, 1.5f));
}

TEST_CASE("smooth shading follows Lambert's law at the interpolated normal") {
    const Scene scene = smooth_triangle();
    const KdTree tree = build_reference(scene);
    const RenderSettings settings = lit_triangle_settings();
    RenderInputs inputs = prepare_render(scene, settings, settings.camera_at(0), 0);
    REQUIRE(inputs.effects.shadows);

    SUBCASE("the reference renderer") {
        CHECK(largest_lambert_error(scene, render_reference(tree, scene, inputs, 2)) < 1e-5);
    }
    SUBCASE("the OpenCL renderer, with and without packets") {
        for (auto packets : {RenderInputs::Packets::On, RenderInputs::Packets::Off}) {
            inputs.packets = packets;
            const FrameResult frame =
                render_opencl(test::opencl_test_device(), tree, scene, inputs);
            CHECK(largest_lambert_error(scene, frame) < 1e-5);
        }
    }

    SUBCASE("the check tells smooth from flat shading") {
        Scene flat = scene;
        flat.vertex_normals.clear();
        const FrameResult frame = render_reference(tree, flat, inputs, 2);
        CHECK(largest_lambert_error(scene, frame) > 0.1);
    }
}

TEST_CASE("a smooth mirror reflects about the interpolated normal") {
    // A mirror square in z = 0 whose normals all lean toward +x, seen from above: its mirror
    // rays lean toward +x too and find an emitting wall at x = 2 that the camera cannot see;
    // about the flat normal they would go straight up, into the background. The wall's winding
    // faces -x, toward the mirror: an emitter emits from its front side only (conventions.md).
    Scene scene = make_scene({-1, -1,   0, 1, -1, 0, 1, 1,    0, -1, -1,   0, 1,  1, 0, -1, 1, 0, 2,
                              -3, 0.5f, 2, 3, 5,  2, 3, 0.5f, 2, -3, 0.5f, 2, -3, 5, 2, 3,  5});
    const Vec3 lean = normalize(Vec3{0.3f, 0, 1});
    for (int c = 0; c < 6; ++c) put(scene.vertex_normals, lean);
    for (int c = 0; c < 6; ++c) put(scene.vertex_normals, {-1, 0, 0});
    const Vec3 glow{1.0f, 0.5f, 0.25f};
    scene.materials = {
        Material{.name = "mirror", .diffuse = {0, 0, 0}, .specular = {1, 1, 1}, .illum = 3},
        Material{.name = "wall", .diffuse = {0, 0, 0}, .emission = glow}};
    scene.material_ids = {0, 0, 1, 1};
    const KdTree tree = build_reference(scene);
    RenderSettings settings;
    settings.width = settings.height = 20;
    const Camera camera{{0, 0, 3}, {0, 0, 0}, {0, 1, 0}, 30.0f};
    const RenderInputs inputs = prepare_render(scene, settings, camera, 0);
    REQUIRE(inputs.effects.reflection);

    // The expected colour of each pixel, in double: the wall's emission where the mirror ray
    // about `lean` meets it, else the background; pixels whose rays pass within 1e-3 of an edge
    // are left out.
    auto check_frame = [&](const FrameResult& frame) {
        const CameraRays rays(camera, settings.width, settings.height);
        const Vec3 bg = settings.background;
        int on_wall = 0, checked = 0;
        double worst = 0;
        for (int y = 0; y < settings.height; ++y)
            for (int x = 0; x < settings.width; ++x) {
                const KdRay ray = rays.ray(x + 0.5f, y + 0.5f);
                const double o[3] = {ray.org[0], ray.org[1], ray.org[2]};
                const double d[3] = {ray.dir[0], ray.dir[1], ray.dir[2]};
                const double t = -o[2] / d[2], px = o[0] + t * d[0], py = o[1] + t * d[1];
                if (std::fabs(std::fabs(px) - 1) < 1e-3 || std::fabs(std::fabs(py) - 1) < 1e-3)
                    continue;
                Vec3 expected = bg;
                if (std::fabs(px) < 1 && std::fabs(py) < 1) {
                    const double n[3] = {lean.x, lean.y, lean.z};
                    const double dn = d[0] * n[0] + d[1] * n[1] + d[2] * n[2];
                    const double r[3] = {d[0] - 2 * dn * n[0], d[1] - 2 * dn * n[1],
                                         d[2] - 2 * dn * n[2]};
                    const double s = (2 - px) / r[0], qy = py + s * r[1], qz = s * r[2];
                    if (std::fabs(std::fabs(qy) - 3) < 1e-3 || std::fabs(qz - 0.5) < 1e-3 ||
                        std::fabs(qz - 5) < 1e-3)
                        continue;
                    if (r[0] > 0 && std::fabs(qy) < 3 && qz > 0.5 && qz < 5) {
                        expected = glow;
                        ++on_wall;
                    }
                }
                const float* rgb = &frame.image.rgb[3 * (std::size_t(y) * settings.width + x)];
                const float want[3] = {expected.x, expected.y, expected.z};
                for (int c = 0; c < 3; ++c)
                    worst = std::max(worst, double(std::fabs(rgb[c] - want[c])));
                ++checked;
            }
        CHECK(checked > settings.width * settings.height * 3 / 4);
        CHECK(on_wall > 50);
        return worst;
    };
    SUBCASE("the reference renderer") {
        CHECK(check_frame(render_reference(tree, scene, inputs, 2)) < 1e-5);
    }
    SUBCASE("the OpenCL renderer") {
        CHECK(check_frame(render_opencl(test::opencl_test_device(), tree, scene, inputs)) < 1e-5);
    }
    SUBCASE("the check tells the leaning normals from the flat one") {
        Scene flat = scene;
        flat.vertex_normals.clear();
        CHECK(check_frame(render_reference(tree, flat, inputs, 2)) > 0.5);
    }
}
