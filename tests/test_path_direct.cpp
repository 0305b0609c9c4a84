// test_path_direct.cpp — the path integrator's direct light (core/device/kd_path.h, max_depth 2:
// the camera ray and a light sample) against a closed form and against Whitted's estimators, which
// share none of its sampling code: delta lights (deterministic, so equal within rounding), and an
// emissive lamp over Lambertian and Blinn-Phong floors, where multiple importance sampling weighs
// the light sample against the lobes' directions.
#include <doctest/doctest.h>

#include <algorithm>
#include <cmath>
#include <filesystem>
#include <string>
#include <vector>

#include "core/device/kd_render.h"
#include "core/render/reference_tracer.h"
#include "core/render/render_file.h"
#include "core/render/render_setup.h"
#include "core/scene/scene.h"
#include "core/tree/reference_builder.h"
#include "tests/support.h"

using namespace kdray;

namespace {

/// The two estimators of direct light these tests compare, over one image and camera with a black
/// background: Whitted's first generation, and the path integrator at max_depth 2 (the camera ray
/// and one light sample). The path's background lights the scene as a sky would
/// (docs/path-tracing.md); black, it adds nothing Whitted's first generation lacks.
struct DirectLight {
    RenderSettings whitted, path;
};

DirectLight direct_light(int width, int height, int spp, const Camera& camera) {
    DirectLight d;
    d.whitted.width = width;
    d.whitted.height = height;
    d.whitted.spp = spp;
    d.whitted.max_depth = 1;
    d.whitted.background = {0, 0, 0};
    d.whitted.camera_keys = {CameraKey{0, SceneCamera(camera)}};
    d.whitted.camera_given = true;
    d.path = d.whitted;
    d.path.integrator = Integrator::path;
    d.path.max_depth = 2;
    return d;
}

/// The floor (4 x 4 at y = 0, material `floor`) under a lamp facing down 1.2 above it (its
/// winding normal -y), in dir/scene.obj with `mtl` as dir/m.mtl; the lamp's corners in `lamp`.
Scene floor_under_lamp(const std::filesystem::path& dir, const std::string& mtl) {
    test::write_text_file(dir / "m.mtl", mtl);
    test::write_text_file(dir / "scene.obj",
                          "mtllib m.mtl\nv -2 0 -2\nv 2 0 -2\nv 2 0 2\nv -2 0 2\n"
                          "v -0.4 1.2 -0.6\nv 0.4 1.2 -0.6\nv 0.4 1.2 0.2\nv -0.4 1.2 0.2\n"
                          "usemtl floor\nf 1 3 2\nf 1 4 3\nusemtl lamp\nf 5 6 7\nf 5 7 8\n");
    return load_obj(dir / "scene.obj");
}

/// A Lambertian floor (Kd 0.6 0.5 0.4) and the lamp (Ke 6 5 4), for floor_under_lamp.
const char* const kLambertFloorMtl =
    "newmtl floor\nKd 0.6 0.5 0.4\nillum 1\nnewmtl lamp\nKd 0 0 0\nKe 6 5 4\n";

/// Looking down at the floor past the lamp, so that the lamp's mirror image lights a highlight.
const Camera kFloorCamera{{0.0f, 1.0f, 2.2f}, {0, 0, -0.3f}, {0, 1, 0}, 60.0f};

/// E / Le at floor point p (in the scene's frame) under floor_under_lamp's lamp: Le / 2 sum_i
/// theta_i (n . u_i) (Lambert 1760; Arvo 1995), theta_i the angle the edge (v_i, v_i+1) subtends
/// at p, u_i the unit normal of the plane through p and the edge.
double lamp_irradiance_factor(const Scene& scene, const Vec3& p) {
    const Vec3 lamp[4] = {
        {-0.4f, 1.2f, -0.6f}, {0.4f, 1.2f, -0.6f}, {0.4f, 1.2f, 0.2f}, {-0.4f, 1.2f, 0.2f}};
    double sum = 0;
    for (int i = 0; i < 4; ++i) {
        // The lamp's corners in the scene's frame, where the hits are (the form factor is the
        // same at any scale).
        const DVec3 a = DVec3(scene.frame.point(DVec3(lamp[i]))) - DVec3(p);
        const DVec3 b = DVec3(scene.frame.point(DVec3(lamp[(i + 1) % 4]))) - DVec3(p);
        const double theta = std::acos(std::clamp(dot(a, b) / (length(a) * length(b)), -1.0, 1.0));
        const DVec3 u = cross(a, b);
        sum += theta * u.y / length(u);
    }
    return std::fabs(sum) / 2;
}

}  // namespace

TEST_CASE("path: at max_depth 2 a scene under point lights is Whitted's direct light") {
    // Two segments are the camera ray and a light sample: with only delta lights (nothing emits)
    // the path integrator's estimate is deterministic, and it is Whitted's first generation:
    // Lambert and the Blinn-Phong highlight under each light, behind shadow rays.
    const auto dir = test::fresh_temp_dir("path_direct");
    test::write_text_file(dir / "m.mtl",
                          "newmtl matte\nKd 0.6 0.5 0.4\nillum 1\n"
                          "newmtl shiny\nKd 0.2 0.3 0.4\nKs 0.5 0.5 0.5\nNs 40\nillum 2\n");
    test::write_text_file(dir / "scene.obj",
                          "mtllib m.mtl\nv -2 0 -2\nv 2 0 -2\nv 2 0 2\nv -2 0 2\n"
                          "v -0.5 0.2 0\nv 0.5 0.2 0\nv 0 1 0.3\n"
                          "usemtl matte\nf 1 3 2\nf 1 4 3\nusemtl shiny\nf 5 6 7\n");
    const Scene scene = load_obj(dir / "scene.obj");
    const KdTree tree = build_reference(scene);
    auto [whitted, path] =
        direct_light(48, 36, 2, Camera{{0.5f, 2.0f, 3.0f}, {0, 0.2f, 0}, {0, 1, 0}, 50.0f});
    whitted.lights = path.lights = {
        Light{Light::Type::point, {1, 2, 1}, {}, {5, 5, 5}},
        Light{Light::Type::directional, {}, {-1, -2, -0.5}, {0.5, 0.4, 0.3}}};
    const Camera camera = whitted.camera_at(0, scene.frame);
    const FrameResult a =
        render_reference(tree, scene, prepare_render(scene, whitted, camera, 3), 2);
    const FrameResult b = render_reference(tree, scene, prepare_render(scene, path, camera, 3), 2);
    double largest = 0;
    for (std::size_t i = 0; i < a.image.rgb.size(); ++i) {
        CAPTURE(i);
        largest = std::max(largest, double(a.image.rgb[i]));
        // The same terms summed in another order: a few float roundings apart.
        CHECK(b.image.rgb[i] == doctest::Approx(a.image.rgb[i]).epsilon(1e-5).scale(1e-6));
    }
    CHECK(largest > 0.1);  // the lights do reach what the camera sees
    CHECK(b.rays.shadow == a.rays.shadow);
    CHECK(b.rays.primary == a.rays.primary);
}

TEST_CASE("path: direct light from an emitter on a glossy floor is Whitted's light sampling") {
    // Two independent estimators of one integral: Whitted's first generation samples the emitter
    // only; the path integrator at max_depth 2 weighs that light sample against a direction drawn
    // from the Lambert and Blinn-Phong lobes (MIS). A density of the lobes that is not the one
    // they draw with (the half vector's 1 / (4 wi.h), the cosine's 1 / pi) biases the second
    // only, most in the highlight.
    const auto dir = test::fresh_temp_dir("path_gloss");
    const Scene scene = floor_under_lamp(
        dir, "newmtl floor\nKd 0.2 0.25 0.3\nKs 0.6 0.5 0.4\nNs 30\nillum 2\n"
             "newmtl lamp\nKd 0 0 0\nKe 6 5 4\n");
    const KdTree tree = build_reference(scene);
    auto [whitted, path] = direct_light(32, 24, 512, kFloorCamera);
    // The 2% bound below was sized from independent samples' spread: both sides draw independent
    // samples (with the R2 sampler both would be stratified, each in its own way).
    whitted.independent_samples = path.independent_samples = true;
    const Camera camera = whitted.camera_at(0, scene.frame);
    const FrameResult a =
        render_reference(tree, scene, prepare_render(scene, whitted, camera, 5), 2);
    const FrameResult b = render_reference(tree, scene, prepare_render(scene, path, camera, 6), 2);
    // Per channel, over the floor's pixels: the mean difference within 4 standard errors (the
    // differences' spread over sqrt(pixels)) and within 2% of the mean radiance; and so in the
    // brightest tenth of them, the highlight.
    const kd_u32 floor_triangles = 2;
    std::vector<std::size_t> floor;
    for (std::size_t i = 0; i < a.hits.hits.size(); ++i)
        if (a.hits.hits[i].prim < floor_triangles) floor.push_back(i);
    REQUIRE(floor.size() > 400);
    std::vector<std::size_t> bright = floor;
    std::sort(bright.begin(), bright.end(), [&](std::size_t i, std::size_t j) {
        return a.image.rgb[3 * i] > a.image.rgb[3 * j];
    });
    bright.resize(bright.size() / 10);
    for (const std::vector<std::size_t>* pixels : {&floor, &bright})
        for (int c = 0; c < 3; ++c) {
            CAPTURE(c);
            CAPTURE(pixels->size());
            double mean = 0, diff = 0, spread = 0;
            for (std::size_t i : *pixels) {
                mean += a.image.rgb[3 * i + c];
                diff += b.image.rgb[3 * i + c] - a.image.rgb[3 * i + c];
            }
            const double n = double(pixels->size());
            mean /= n;
            diff /= n;
            for (std::size_t i : *pixels) {
                const double d = b.image.rgb[3 * i + c] - a.image.rgb[3 * i + c] - diff;
                spread += d * d;
            }
            const double standard_error = std::sqrt(spread / (n - 1) / n);
            CAPTURE(mean);
            CAPTURE(diff);
            CAPTURE(standard_error);
            CHECK(mean > 0.05);
            CHECK(std::fabs(diff) <= 4 * standard_error);
            CHECK(std::fabs(diff) <= 0.02 * mean);
        }
}

TEST_CASE("path: a Lambertian floor under a square lamp has the polygon's closed-form irradiance") {
    // The irradiance at p from a polygon of uniform radiance Le above it is
    // Le / 2 sum_i theta_i (n . u_i) (Lambert 1760; Arvo 1995): theta_i the angle the edge
    // (v_i, v_i+1) subtends at p, u_i the unit normal of the plane through p and the edge. So
    // each floor pixel's radiance is Kd / pi times that, for Whitted's light sampling and for the
    // path integrator's MIS at max_depth 2 alike.
    const auto dir = test::fresh_temp_dir("path_lamp");
    const Scene scene = floor_under_lamp(dir, kLambertFloorMtl);
    const KdTree tree = build_reference(scene);
    // One sample, the centre ray: the hit, and so the closed form, is the pixel's.
    const auto [whitted, path] = direct_light(128, 96, 1, kFloorCamera);
    const Camera camera = whitted.camera_at(0, scene.frame);
    const RenderInputs inputs = prepare_render(scene, whitted, camera, 9);
    auto irradiance_factor = [&](const Vec3& p) { return lamp_irradiance_factor(scene, p); };
    const float kd[3] = {0.6f, 0.5f, 0.4f}, le[3] = {6, 5, 4};
    for (const RenderSettings* settings : {&whitted, &path}) {
        CAPTURE(integrator_name(settings->integrator));
        const FrameResult r =
            render_reference(tree, scene, prepare_render(scene, *settings, camera, 9), 2);
        for (int c = 0; c < 3; ++c) {
            CAPTURE(c);
            double n = 0, mean = 0, diff = 0, spread = 0;
            std::vector<double> d;
            for (std::size_t i = 0; i < r.hits.hits.size(); ++i) {
                if (r.hits.hits[i].prim >= 2) continue;  // the floor's two triangles only
                KdRay ray;
                kd_camera_ray(&inputs.view, float(i % whitted.width) + 0.5f,
                              float(i / whitted.width) + 0.5f, &ray);
                const Vec3 p{ray.org[0] + r.hits.hits[i].t * ray.dir[0],
                             ray.org[1] + r.hits.hits[i].t * ray.dir[1],
                             ray.org[2] + r.hits.hits[i].t * ray.dir[2]};
                const double expected = kd[c] / M_PI * le[c] * irradiance_factor(p);
                d.push_back(r.image.rgb[3 * i + c] - expected);
                mean += expected;
                diff += d.back();
                n += 1;
            }
            REQUIRE(n > 5000);
            mean /= n;
            diff /= n;
            for (double x : d) spread += (x - diff) * (x - diff);
            const double standard_error = std::sqrt(spread / (n - 1) / n);
            CAPTURE(mean);
            CAPTURE(diff);
            CAPTURE(standard_error);
            CHECK(std::fabs(diff) <= 4 * standard_error);
            CHECK(std::fabs(diff) <= 0.01 * mean);
        }
    }
}

TEST_CASE("whitted: a pixel's area-light samples are stratified, nearer the closed form") {
    // One pixel seeing one point of a Lambertian floor under the lamp, 256 samples, in 48 frames
    // (each its own seed, so its own rotation of the pixel's sequence): the samples' choices of a
    // lamp triangle and points on it follow one pair of the pixel's R2 sequence (kd_area_light.h),
    // whose error against the closed form falls faster than independent samples' 1 / sqrt(256)
    // (measured: 0.27x). Hashed per shading point, as before, or drawn from two dimensions that
    // move in lockstep (a pair's first coordinate, unpermuted, beside another pair's: 0.9x on the
    // glass room's walls), the errors are alike.
    const auto dir = test::fresh_temp_dir("whitted_strata");
    const Scene scene = floor_under_lamp(dir, kLambertFloorMtl);
    const KdTree tree = build_reference(scene);
    // A narrow view of the floor point (0.1, 0, -0.1), off the lamp's centre.
    auto [whitted, path] =
        direct_light(1, 1, 256, {{0.1f, 0.6f, 1.0f}, {0.1f, 0, -0.1f}, {0, 1, 0}, 0.05f});
    const Camera camera = whitted.camera_at(0, scene.frame);
    double squared[2] = {0, 0};
    for (const bool independent : {false, true}) {
        whitted.independent_samples = independent;
        for (kd_u32 seed = 0; seed < 48; ++seed) {
            const RenderInputs inputs = prepare_render(scene, whitted, camera, seed);
            const FrameResult r = render_reference(tree, scene, inputs, 1);
            REQUIRE(r.hits.hits[0].prim < 2u);
            KdRay ray;
            kd_camera_ray(&inputs.view, 0.5f, 0.5f, &ray);
            const Vec3 p{ray.org[0] + r.hits.hits[0].t * ray.dir[0],
                         ray.org[1] + r.hits.hits[0].t * ray.dir[1],
                         ray.org[2] + r.hits.hits[0].t * ray.dir[2]};
            const double expected = 0.6 / M_PI * 6 * lamp_irradiance_factor(scene, p);
            const double relative = r.image.rgb[0] / expected - 1;
            squared[independent] += relative * relative;
        }
    }
    const double stratified = std::sqrt(squared[0] / 48), independent = std::sqrt(squared[1] / 48);
    CAPTURE(stratified);
    CAPTURE(independent);
    CHECK(independent > 0.005);  // the independent estimate's spread is there to be beaten
    CHECK(stratified < 0.4 * independent);
}
