// test_opencl_float_float.cpp — the OpenCL tracer on the path a device without fp64 takes (Intel
// Arc, Xe-LP): KDRAY_FORCE_NO_FP64=1 makes PoCL compile its render programs with no double at
// all, so the watertight edge fallback and the refined distance run in float-float arithmetic
// (core/device/kd_float_float.h). Hits must still equal brute force and the host reference (which
// computes in double) on the hard scenes, one ray at a time and in packets; needle distances stay
// within a few ulps of the exact ones; and a run says which path it took, in its log and in
// stats.json.
#include <doctest/doctest.h>

#include <cmath>
#include <cstdlib>
#include <filesystem>
#include <string>

#include <nlohmann/json.hpp>

#include "cl/renderer/opencl_renderer.h"
#include "core/device/kd_render.h"
#include "core/io/image_codec.h"
#include "core/render/camera.h"
#include "core/render/reference_tracer.h"
#include "core/render/render_file.h"
#include "core/render/render_setup.h"
#include "core/tree/reference_builder.h"
#include "tests/needle_distances.h"
#include "tests/support.h"
#include "tests/test_opencl_fixture.h"

using namespace kdray;
namespace fs = std::filesystem;

namespace {

/// KDRAY_FORCE_NO_FP64 set for the guard's life (this process and the kdray it runs).
class ForceNoFp64 {
  public:
    ForceNoFp64() { ::setenv("KDRAY_FORCE_NO_FP64", "1", 1); }
    ~ForceNoFp64() { ::unsetenv("KDRAY_FORCE_NO_FP64"); }
    ForceNoFp64(const ForceNoFp64&) = delete;
    ForceNoFp64& operator=(const ForceNoFp64&) = delete;
};

Camera skew_camera(const Scene& scene) {
    const Aabb b = scene.bounds();
    const Vec3 centre = (b.lo + b.hi) * 0.5f, e = b.extent();
    const float r = std::max({e.x, e.y, e.z, 1e-30f});
    Camera c;
    c.look_at = centre;
    c.position = centre + Vec3{0.9f * r, 0.7f * r, 1.6f * r};
    c.fov_y = 50.0f;
    return c;
}

}  // namespace

TEST_CASE("opencl float-float: the forced path is chosen, and only when forced or without fp64") {
    ClDevice& device = test::opencl_test_device();
    const Scene scene = test::random_triangles(10, 1);
    RenderSettings settings;
    settings.width = 4;
    settings.height = 4;
    const RenderInputs inputs = prepare_render(scene, settings, skew_camera(scene), 0);
    CHECK(render_uses_fp64(device) == device.info().fp64);
    CHECK(choose_opencl_render(device, inputs).fp64 == device.info().fp64);
    ForceNoFp64 force;
    CHECK_FALSE(render_uses_fp64(device));
    CHECK_FALSE(choose_opencl_render(device, inputs).fp64);
    CHECK(std::string(exact_arithmetic_name(false)) == "float-float");
}

TEST_CASE("opencl float-float: hits equal brute force and the reference on the hard scenes") {
    ForceNoFp64 force;
    for (const test::NamedScene& s : test::hard_scenes()) {
        CAPTURE(s.name);
        const KdTree tree = build_reference(s.scene);
        RenderSettings settings;
        settings.width = 40;
        settings.height = 30;
        // One ray at a time, and packets of 8 and 16 lanes (4x2 and 4x4 tiles).
        for (unsigned lanes : {0u, 8u, 16u}) {
            CAPTURE(lanes);
            const test::ScopedEnv width("KDRAY_PACKET_LANES", lanes ? std::to_string(lanes) : "");
            RenderInputs inputs =
                prepare_render(s.scene, settings, s.camera ? *s.camera : skew_camera(s.scene), 0);
            inputs.packets = lanes ? RenderInputs::Packets::On : RenderInputs::Packets::Off;
            const FrameResult device =
                render_opencl(test::opencl_test_device(), tree, s.scene, inputs);
            REQUIRE(device.packet_lanes == lanes);
            const FrameResult host = render_reference(tree, s.scene, inputs, 1);
            int against_brute = 0, against_reference = 0, hits = 0, other_t = 0;
            for (int y = 0; y < settings.height; ++y)
                for (int x = 0; x < settings.width; ++x) {
                    const std::size_t i = std::size_t(y) * settings.width + x;
                    KdRay ray;
                    kd_camera_ray(&inputs.view, float(x) + 0.5f, float(y) + 0.5f, &ray);
                    const KdHit want = test::brute_force_closest(s.scene, ray);
                    hits += want.prim != KDRAY_NO_HIT;
                    against_brute += !test::hits_agree(device.hits.hits[i], want);
                    against_reference += !test::hits_agree(device.hits.hits[i], host.hits.hits[i]);
                    other_t += device.hits.hits[i].t != host.hits.hits[i].t;
                }
            CHECK(hits > 0);
            CHECK(against_brute == 0);
            CHECK(against_reference == 0);
            // Double and float-float round the same near-exact values: equal but at near-ties.
            CAPTURE(other_t);
            CHECK(other_t <= settings.width * settings.height / 100);
        }
    }
}

TEST_CASE("opencl float-float: needle distances within 4 ulps, one ray at a time and in packets") {
    // test_opencl_render.cpp's needle test on the float-float path: with the refinement lost
    // (the float t kept), 18 pixels hit another triangle and distances were off by thousands of
    // ulps.
    ForceNoFp64 force;
    test::check_needle_distances();
}

TEST_CASE("opencl float-float: kdray render says which path ran, in its log and in stats.json") {
    const fs::path dir = test::fresh_temp_dir("cli-float-float");
    const Scene scene = test::random_triangles(400, 12);
    const fs::path obj = test::write_obj(dir / "scene.obj", scene);
    const fs::path render = test::write_text_file(dir / "render.json", test::kSmallRender);
    auto run = [&](const std::string& tracer, const std::string& out) {
        const test::CommandResult r =
            test::run_kdray({"render", obj.string(), "-o", (dir / out).string(), "--camera",
                             render.string(), "--aov", "--tracer", tracer});
        REQUIRE_MESSAGE(r.status == 0, r.err);
        return r;
    };
    const bool device_fp64 = test::opencl_test_device().info().fp64;
    const test::CommandResult plain = run("opencl", "plain");
    const test::CommandResult reference = run("reference", "reference");
    test::CommandResult forced;
    {
        ForceNoFp64 force;
        forced = run("opencl", "forced");
    }
    auto arithmetic = [&](const std::string& out) {
        const nlohmann::json stats = test::read_json(dir / out / "stats.json");
        REQUIRE(stats["runs"].size() == 1);
        return stats["runs"][0]["exact_arithmetic"].get<std::string>();
    };
    CHECK(arithmetic("plain") == (device_fp64 ? "fp64" : "float-float"));
    CHECK(arithmetic("reference") == "fp64");
    CHECK(arithmetic("forced") == "float-float");
    // One info line, only where the path is float-float.
    CHECK(forced.err.find("float-float arithmetic") != std::string::npos);
    CHECK(reference.err.find("float-float arithmetic") == std::string::npos);
    if (device_fp64) CHECK(plain.err.find("float-float arithmetic") == std::string::npos);

    // The forced run's hits agree with brute force along conventions.md's camera rays.
    const HitBuffer aov = read_aov(dir / "forced" / "scene.aov.exr");
    const RenderSettings settings = load_render_file(render);
    const Scene loaded = load_obj(obj);
    const RenderInputs inputs =
        prepare_render(loaded, settings, settings.camera_at(0, loaded.frame), 0);
    const test::AovAgreement agreement = test::aov_against_brute_force(aov, loaded, inputs.view);
    CHECK(agreement.hits > 100);
    CHECK(agreement.mismatches == 0);
    fs::remove_all(dir);
}
