// test_scene_frame.cpp — the frame kdray traces in (core/scene/scene_frame.h): a scene loads in
// double and is traced near the origin at about unit extent, so the same spheres render the same
// hits and the same image at any scale from 1e-30 to 1e30 and at any distance from the origin up to
// 1e9, and what kdray reports (the AOV's Z) is in the scene's own units.
#include <doctest/doctest.h>

#include <cmath>
#include <cstdio>
#include <filesystem>
#include <fstream>
#include <string>

#include <nlohmann/json.hpp>

#include "core/error.h"
#include "core/io/image.h"
#include "core/render/reference_tracer.h"
#include "core/render/render_file.h"
#include "core/render/render_setup.h"
#include "core/scene/scene.h"
#include "core/scene/scene_frame.h"
#include "core/tree/reference_builder.h"
#include "tests/support.h"

namespace fs = std::filesystem;
using namespace kdray;

namespace {

std::string number(double v) {
    char text[40];
    std::snprintf(text, sizeof text, "%.17g", v);
    return text;
}

std::string point(double x, double y, double z, double scale, double offset) {
    return "[" + number(x * scale + offset) + ", " + number(y * scale + offset) + ", " +
           number(z * scale + offset) + "]";
}

/// The render file of spheres_obj's scene at `scale` and `offset`: a camera and a point light
/// whose intensity grows with scale^2, so that the image is the unit scene's.
std::string spheres_render_file(double scale, double offset) {
    return R"({"image": {"width": 96, "height": 72}, "max_depth": 1, "background": [0, 0, 0],
               "camera": {"position": )" +
           point(0.4, 1.0, 5.0, scale, offset) + R"(, "look_at": )" +
           point(0.2, 0.0, 0.0, scale, offset) + R"(, "fov_y": 45},
               "lights": [{"type": "point", "position": )" +
           point(4.0, 6.0, 5.0, scale, offset) + R"(, "intensity": [)" +
           number(30 * scale * scale) + ", " + number(30 * scale * scale) + ", " +
           number(30 * scale * scale) + "]}]}";
}

struct Rendered {
    Scene scene;
    FrameResult frame;
};

/// spheres_obj at `scale` and `offset`, loaded from a file and rendered by the reference builder
/// and tracer; the hits' Z in the scene's units, as the AOV writes them.
Rendered render_spheres(double scale, double offset) {
    const fs::path dir = test::fresh_temp_dir("kdray_scene_frame");
    const fs::path obj =
        test::write_text_file(dir / "spheres.obj", test::spheres_obj(scale, offset));
    Rendered r{load_obj(obj), {}};
    const RenderSettings settings =
        parse_render_json(spheres_render_file(scale, offset), dir / "render.json");
    const RenderInputs inputs =
        prepare_render(r.scene, settings, settings.camera_at(0, r.scene.frame), 0);
    r.frame = render_reference(build_reference(r.scene), r.scene, inputs);
    for (KdHit& hit : r.frame.hits.hits) hit.t = r.scene.frame.scene_length(hit.t);
    return r;
}

/// The share of pixels whose hits disagree (conventions.md), the distances of `scaled` divided
/// by its scale.
double hit_mismatch(const HitBuffer& unit, const HitBuffer& scaled, double scale) {
    REQUIRE(unit.hits.size() == scaled.hits.size());
    std::size_t differ = 0;
    for (std::size_t i = 0; i < unit.hits.size(); ++i) {
        KdHit h = scaled.hits[i];
        h.t = float(double(h.t) / scale);
        differ += !test::hits_agree(h, unit.hits[i]);
    }
    return double(differ) / double(unit.hits.size());
}

/// The share of pixels whose radiance differs by more than 1% of the brightest pixel.
double image_mismatch(const Image& a, const Image& b) {
    REQUIRE(a.rgb.size() == b.rgb.size());
    float brightest = 0;
    for (float v : a.rgb) brightest = std::max(brightest, v);
    std::size_t differ = 0;
    for (std::size_t i = 0; i < a.rgb.size(); i += 3) {
        bool pixel = false;
        for (int c = 0; c < 3; ++c)
            pixel = pixel || std::fabs(a.rgb[i + c] - b.rgb[i + c]) > 0.01f * brightest;
        differ += pixel;
    }
    return double(differ) / double(a.rgb.size() / 3);
}

}  // namespace

TEST_CASE("SceneFrame::fit: a power-of-two scale to an extent in [0.5, 1), whole-cell offsets") {
    const SceneFrame near = SceneFrame::fit({-3, -1, -2}, {5, 2, 1}, "near.obj");
    CHECK(near.scale == 0.0625);  // extent 8 = 2^3 lands in [0.5, 1) at 2^-4
    CHECK(near.offset == DVec3{0, 0, 0});
    CHECK(near.point({5, 2, 1}) == Vec3{0.3125f, 0.125f, 0.0625f});
    CHECK(near.scene_point({0.3125f, 0.125f, 0.0625f}) == DVec3{5, 2, 1});

    const SceneFrame far = SceneFrame::fit({1e7 - 10, -10, -10}, {1e7 + 10, 10, 10}, "far.obj");
    CHECK(far.scale == std::ldexp(1.0, -5));  // extent 20 < 32
    CHECK(far.offset == DVec3{1e7, 0, 0});    // 1e7 is a whole number of 32s
    CHECK(far.point({1e7 + 0.1, 0, 0}).x == float(0.1 / 32));

    const SceneFrame tiny = SceneFrame::fit({0, 0, 0}, {3e-30, 1e-30, 0}, "tiny.obj");
    CHECK(3e-30 * tiny.scale >= 0.5);
    CHECK(3e-30 * tiny.scale < 1.0);

    CHECK(SceneFrame::fit({1, 1, 1}, {1, 1, 1}, "point.obj").is_identity());
    CHECK_THROWS_WITH_AS(SceneFrame::fit({-1.7e308, 0, 0}, {1.7e308, 0, 0}, "huge.obj"),
                         doctest::Contains("huge.obj: the scene's extent overflows a double"),
                         Error);
}

TEST_CASE("a scene too small for the frame's scale is one error naming the file and the extent") {
    // SceneFrame::fit's other error (an extent that overflows a double) is tested above and
    // cannot come from an OBJ: the loader refuses coordinates beyond float range first. This one
    // can: the scale 2^-e of an extent below 2^-1000 would leave double range (a subnormal
    // extent, 1e-310, gives 2^1030 = inf and NaN corners), so fit refuses every extent there.
    // 1e-300 still fits: scaled by 2^996, its extent lies in [0.5, 1).
    const SceneFrame fine = SceneFrame::fit({0, 0, 0}, {1e-300, 0, 0}, "fine.obj");
    CHECK(1e-300 * fine.scale >= 0.5);
    CHECK(1e-300 * fine.scale < 1.0);
    CHECK_THROWS_WITH_AS(SceneFrame::fit({0, 0, 0}, {0, 1e-305, 0}, "speck.obj"),
                         doctest::Contains("speck.obj: the scene's extent (1e-305) is too small "
                                           "for kdray to scale to float precision"),
                         Error);

    // Through load_obj, as kdray render and build meet it: the OBJ names the file.
    const fs::path dir = test::fresh_temp_dir("kdray_scene_frame_small");
    const Scene loaded = load_obj(
        test::write_text_file(dir / "small.obj", "v 0 0 0\nv 1e-300 0 0\nv 0 1e-300 0\nf 1 2 3\n"));
    CHECK(loaded.frame.scale == fine.scale);
    CHECK(loaded.vertex(0, 1).x == float(1e-300 * fine.scale));
    for (const std::string extent : {"1e-305", "1e-310"}) {
        CAPTURE(extent);
        const fs::path obj = test::write_text_file(
            dir / "speck.obj", "v 0 0 0\nv " + extent + " 0 0\nv 0 " + extent + " 0\nf 1 2 3\n");
        const std::string message =
            obj.string() + ": the scene's extent (" + extent + ") is too small for kdray to scale";
        CHECK_THROWS_WITH_AS(load_obj(obj), doctest::Contains(message.c_str()), Error);
    }
    fs::remove_all(dir);
}

TEST_CASE("a scene near the origin is only scaled by a power of two: the same hits, bit for bit") {
    // Power-of-two scaling commutes with every float operation of the build and the trace, so
    // these scenes must give exactly the distances of the unit scene times the scale.
    const Rendered unit = render_spheres(1.0, 0.0);
    CHECK(unit.scene.frame.offset == DVec3{0, 0, 0});
    for (const double scale : {0.25, 1024.0, std::ldexp(1.0, -90), std::ldexp(1.0, 90)}) {
        CAPTURE(scale);
        const Rendered scaled = render_spheres(scale, 0.0);
        CHECK(scaled.scene.triangles == unit.scene.triangles);
        for (std::size_t i = 0; i < unit.frame.hits.hits.size(); ++i) {
            CHECK(scaled.frame.hits.hits[i].prim == unit.frame.hits.hits[i].prim);
            CHECK(double(scaled.frame.hits.hits[i].t) == double(unit.frame.hits.hits[i].t) * scale);
        }
        CHECK(scaled.frame.image.rgb == unit.frame.image.rgb);
    }
}

TEST_CASE("the same hits and image at scales 1e-30 to 1e30 and offsets up to 1e9") {
    const Rendered unit = render_spheres(1.0, 0.0);
    std::size_t hit_pixels = 0;
    for (const KdHit& h : unit.frame.hits.hits) hit_pixels += h.prim != KDRAY_NO_HIT;
    REQUIRE(hit_pixels > unit.frame.hits.hits.size() / 8);  // the spheres fill much of the view
    // Decimal scales and offsets round the vertices differently from the unit scene's: pixels on
    // a silhouette or a shadow's edge may change, nothing else. With the frame fitted as the
    // identity (the loader before the frame), 1e-30 has no camera and 1e15 differs on 28% of the
    // pixels in the test below.
    const struct {
        double scale, offset;
    } cases[] = {{1e-30, 0}, {1e-4, 0}, {1e4, 0}, {1e15, 0},  {1e30, 0},
                 {1, 1e5},   {1, 1e7},  {1, 1e9}, {1e-4, 1e3}};
    for (const auto& c : cases) {
        CAPTURE(c.scale);
        CAPTURE(c.offset);
        const Rendered r = render_spheres(c.scale, c.offset);
        CHECK(hit_mismatch(unit.frame.hits, r.frame.hits, c.scale) <= 2e-3);
        CHECK(image_mismatch(unit.frame.image, r.frame.image) <= 5e-3);
    }
}

TEST_CASE("kdray render: the AOV's Z and stats.json's frame are in the scene's units") {
    // Through the binary and the default OpenCL path: spheres 1e9 from the origin and 1e15 across.
    const fs::path dir = test::fresh_temp_dir("kdray_scene_frame_cli");
    const Rendered unit = render_spheres(1.0, 0.0);
    const struct { double scale, offset; } cases[] = {{1e15, 0}, {1, 1e9}};
    for (const auto& c : cases) {
        CAPTURE(c.scale);
        const fs::path obj =
            test::write_text_file(dir / "spheres.obj", test::spheres_obj(c.scale, c.offset));
        const fs::path render_file =
            test::write_text_file(dir / "render.json", spheres_render_file(c.scale, c.offset));
        const fs::path out = dir / ("out_" + std::to_string(int(std::log10(c.scale + c.offset))));
        const test::CommandResult run =
            test::run_kdray({"render", obj.string(), "--camera", render_file.string(), "-o",
                             out.string(), "--aov"});
        REQUIRE_MESSAGE(run.status == 0, run.err);
        CHECK(hit_mismatch(unit.frame.hits, read_aov(out / "spheres.aov.exr"), c.scale) <= 2e-3);
        std::ifstream in(out / "stats.json");
        const nlohmann::json stats = nlohmann::json::parse(in);
        const nlohmann::json& frame = stats["frames"][0]["scene"]["frame"];
        CHECK(frame["scale"].get<double>() * c.scale * 8 >= 0.5);
        CHECK(frame["scale"].get<double>() * c.scale * 8 < 2.0);
        CHECK(frame["offset"][0].get<double>() == doctest::Approx(c.offset).epsilon(1e-6));
    }
}
