// test_render_file.cpp — the render file of conventions.md: defaults, every field, keyframed
// cameras against closed-form interpolation, and every error message, each of which must name
// the file and the field's path.
#include <doctest/doctest.h>

#include <algorithm>
#include <cmath>
#include <filesystem>
#include <string>
#include <utility>

#include "core/error.h"
#include "core/render/render_file.h"
#include "tests/support.h"

using namespace kdray;
namespace fs = std::filesystem;

namespace {

/// The message parse_render_json throws for `text` (named "scene/render.json"), or "".
std::string parse_error(const std::string& text) {
    try {
        parse_render_json(text, "scene/render.json");
    } catch (const Error& e) {
        return e.what();
    }
    return "";
}

}  // namespace

TEST_CASE("an empty render file gives the defaults") {
    const RenderSettings s = parse_render_json("{}", "r.json");
    CHECK(s.path == fs::path("r.json"));
    CHECK(s.width == 640);
    CHECK(s.height == 480);
    CHECK(s.spp == 1);
    CHECK(s.max_depth == 4);
    CHECK_FALSE(s.camera_given);
    REQUIRE(s.camera_keys.size() == 1);
    CHECK(s.camera_at(7).position == Vec3{0, 0, 1});
    CHECK(s.camera_at(7).fov_y == 45.0f);
    CHECK(s.lights.empty());
    CHECK(s.background == Vec3{0.05f, 0.05f, 0.08f});
    CHECK(s.ambient == Vec3{0, 0, 0});
    CHECK(s.exposure == 0.0f);
}

TEST_CASE("ambient is RGB or a grey; exposure is in stops") {
    const RenderSettings rgb =
        parse_render_json(R"({"ambient": [0.1, 0.2, 0.3], "exposure": -1.5})", "r.json");
    CHECK(rgb.ambient == Vec3{0.1f, 0.2f, 0.3f});
    CHECK(rgb.exposure == -1.5f);
    const RenderSettings grey = parse_render_json(R"({"ambient": 0.25, "exposure": 2})", "r.json");
    CHECK(grey.ambient == Vec3{0.25f, 0.25f, 0.25f});
    CHECK(grey.exposure == 2.0f);
}

TEST_CASE("display: filmic by default, clamp on request, nothing else") {
    CHECK(parse_render_json("{}", "r.json").display == DisplayTransform::filmic);
    CHECK(parse_render_json(R"({"display": "clamp"})", "r.json").display ==
          DisplayTransform::clamp);
    CHECK(parse_render_json(R"({"display": "filmic"})", "r.json").display ==
          DisplayTransform::filmic);
    CHECK(parse_error(R"({"display": "aces"})") ==
          "scene/render.json: field 'display' must be \"clamp\" or \"filmic\"");
    CHECK(parse_error(R"({"display": 1})") ==
          "scene/render.json: field 'display' must be \"clamp\" or \"filmic\"");
}

TEST_CASE("integrator: Whitted by default; path with its own depth, unbounded by default") {
    const RenderSettings whitted = parse_render_json("{}", "r.json");
    CHECK(whitted.integrator == Integrator::whitted);
    CHECK(whitted.max_depth == 4);
    const RenderSettings path = parse_render_json(R"({"integrator": "path"})", "r.json");
    CHECK(path.integrator == Integrator::path);
    CHECK(path.max_depth == -1);
    // A path's max_depth counts segments and is not bound by Whitted's stack of 16.
    CHECK(parse_render_json(R"({"integrator": "path", "max_depth": 100})", "r.json").max_depth ==
          100);
    CHECK(parse_render_json(R"({"max_depth": 7, "integrator": "path"})", "r.json").max_depth == 7);
    CHECK(parse_render_json(R"({"integrator": null})", "r.json").integrator == Integrator::whitted);
    CHECK(parse_error(R"({"integrator": "bdpt"})") ==
          "scene/render.json: field 'integrator' must be \"whitted\" or \"path\"");
    CHECK(parse_error(R"({"integrator": "path", "max_depth": 0})") ==
          "scene/render.json: field 'max_depth' must be -1 (unbounded) or at least 1 with the "
          "path integrator (1 sees emitters only)");
    CHECK(parse_error(R"({"integrator": "path", "max_depth": -2})")
              .find("field 'max_depth' must be between -1 and 65536") != std::string::npos);
    CHECK(parse_error(R"({"max_depth": -1})").find("field 'max_depth' must be between 1 and 16") !=
          std::string::npos);
    CHECK(parse_error(R"({"max_depth": 17})").find("field 'max_depth' must be between 1 and 16") !=
          std::string::npos);
}

TEST_CASE("display transforms against their closed forms") {
    // Narkowicz's fit y = x (2.51 x + 0.03) / (x (2.43 x + 0.59) + 0.14), evaluated apart (in
    // Python, double) at a few points; above about 7.25 it exceeds 1 and is clamped.
    const std::pair<float, double> filmic[] = {{0.01f, 0.003770279794447903},
                                               {0.18f, 0.2668989203894968},
                                               {0.5f, 0.6163069544364508},
                                               {1.0f, 0.8037974683544302},
                                               {2.0f, 0.914855072463768},
                                               {7.0f, 0.9988649262202043},
                                               {7.3f, 1.0},
                                               {100.0f, 1.0}};
    for (const auto& [x, y] : filmic) {
        CAPTURE(x);
        CHECK(display_transform(x, DisplayTransform::filmic) == doctest::Approx(y).epsilon(1e-6));
    }
    // Clamp is min(x, 1): today's images.
    for (const float x : {0.0f, 0.001f, 0.25f, 0.999f, 1.0f, 1.5f, 1e30f})
        CHECK(display_transform(x, DisplayTransform::clamp) == std::min(x, 1.0f));
    for (const DisplayTransform t : {DisplayTransform::clamp, DisplayTransform::filmic}) {
        CHECK(display_transform(-1.0f, t) == 0.0f);
        CHECK(display_transform(NAN, t) == 0.0f);
        CHECK(display_transform(INFINITY, t) == 1.0f);
    }
    CHECK(std::string(display_name(DisplayTransform::clamp)) == "clamp");
    CHECK(std::string(display_name(DisplayTransform::filmic)) == "filmic");
}

TEST_CASE("the example of conventions.md reads field by field") {
    const RenderSettings s = parse_render_json(R"({
      "image":  { "width": 320, "height": 200, "spp": 4 },
      "camera": { "position": [0, 1, 3], "look_at": [0, 0, 0], "up": [0, 1, 0], "fov_y": 50 },
      "lights": [
        { "type": "point", "position": [2, 4, 2], "intensity": [30, 30, 30] },
        { "type": "directional", "direction": [-1, -1, -1], "irradiance": [1, 2, 3] }
      ],
      "background": [0.1, 0.2, 0.3],
      "ambient": [0, 0, 0],
      "exposure": 0,
      "max_depth": 7
    })",
                                               "r.json");
    CHECK(s.width == 320);
    CHECK(s.height == 200);
    CHECK(s.spp == 4);
    CHECK(s.camera_given);
    const Camera c = s.camera_at(0);
    CHECK(c.position == Vec3{0, 1, 3});
    CHECK(c.fov_y == 50.0f);
    REQUIRE(s.lights.size() == 2);
    CHECK(s.lights[0].type == Light::Type::point);
    CHECK(s.lights[0].position == Vec3{2, 4, 2});
    CHECK(s.lights[0].intensity == Vec3{30, 30, 30});
    CHECK(s.lights[1].type == Light::Type::directional);
    CHECK(s.lights[1].direction == Vec3{-1, -1, -1});
    CHECK(s.lights[1].intensity == Vec3{1, 2, 3});
    CHECK(s.background == Vec3{0.1f, 0.2f, 0.3f});
    CHECK(s.max_depth == 7);
}

TEST_CASE("null means the default (BART's robots render file has a null background)") {
    const RenderSettings s =
        parse_render_json(R"({"background": null, "image": {"spp": null}})", "r.json");
    CHECK(s.background == Vec3{0.05f, 0.05f, 0.08f});
    CHECK(s.spp == 1);
}

// Editors find docs/render-file.schema.json through a top-level "$schema"; an unknown field is
// an error everywhere else, so kdray must take this one (and only check that it is a string).
TEST_CASE("a $schema string is accepted and ignored") {
    const RenderSettings s = parse_render_json(
        R"({"$schema": "../docs/render-file.schema.json", "max_depth": 2})", "r.json");
    CHECK(s.max_depth == 2);
    CHECK_THROWS_WITH_AS(parse_render_json(R"({"$schema": 1})", "r.json"),
                         doctest::Contains("field '$schema' must be a string"), Error);
    CHECK_THROWS_WITH_AS(parse_render_json(R"({"image": {"$schema": "x"}})", "r.json"),
                         doctest::Contains("unknown field 'image.$schema'"), Error);
}

TEST_CASE("keyframed cameras: sorted, interpolated linearly, held outside the keys") {
    // Keys given out of order; between frames 0 and 10 the closed form is a + (b - a) * f / 10.
    const RenderSettings s = parse_render_json(R"({"camera": [
        {"frame": 10, "position": [10, 0, 20], "look_at": [0, 5, 0], "up": [0, 1, 0], "fov_y": 60},
        {"frame": 0,  "position": [0, 0, 10],  "look_at": [0, 0, 0], "up": [0, 1, 0], "fov_y": 40},
        {"frame": 14, "position": [14, 0, 20], "look_at": [0, 5, 0], "up": [1, 1, 0], "fov_y": 20}
    ]})",
                                               "r.json");
    CHECK(s.camera_given);
    REQUIRE(s.camera_keys.size() == 3);
    CHECK(s.camera_keys[0].frame == 0);
    CHECK(s.camera_keys[1].frame == 10);
    CHECK(s.camera_keys[2].frame == 14);

    const Camera mid = s.camera_at(5);
    CHECK(mid.position.x == doctest::Approx(5));
    CHECK(mid.position.z == doctest::Approx(15));
    CHECK(mid.look_at.y == doctest::Approx(2.5));
    CHECK(mid.fov_y == doctest::Approx(50));
    const Camera q = s.camera_at(3);
    CHECK(q.position.x == doctest::Approx(3));
    CHECK(q.position.z == doctest::Approx(13));
    CHECK(q.fov_y == doctest::Approx(46));
    const Camera late = s.camera_at(11);  // a quarter of the way from frame 10 to 14
    CHECK(late.position.x == doctest::Approx(11));
    CHECK(late.up.x == doctest::Approx(0.25));
    CHECK(late.fov_y == doctest::Approx(50));
    // Exactly on a key, and the nearest key before the first and after the last.
    CHECK(s.camera_at(10).position == Vec3{10, 0, 20});
    CHECK(s.camera_at(-5).position == Vec3{0, 0, 10});
    CHECK(s.camera_at(100).position == Vec3{14, 0, 20});
    CHECK(s.camera_at(100).fov_y == 20.0f);
}

TEST_CASE("every error names the file and the field") {
    struct Case {
        const char* text;
        const char* message;  // after "scene/render.json: "
    };
    const Case cases[] = {
        {R"({"imagee": {}})", "unknown field 'imagee'"},
        {R"({"image": {"widht": 10}})", "unknown field 'image.widht'"},
        {R"({"camera": [{"frame": 0}, {"frame": 1}, {"frame": 2, "fov_y": "wide"}]})",
         "field 'camera[2].fov_y' must be a number"},
        {R"({"camera": {"position": [0, 0]}})",
         "field 'camera.position' must be an array of 3 numbers"},
        {R"({"camera": {"up": [0, "1", 0]}})", "field 'camera.up[1]' must be a number"},
        {R"({"camera": {"frame": 3}})", "unknown field 'camera.frame'"},
        {R"({"camera": [{"fov_y": 30}]})", "field 'camera[0].frame' is missing"},
        {R"({"camera": [{"frame": 1.5}]})", "field 'camera[0].frame' must be an integer"},
        {R"({"camera": [{"frame": 4}, {"frame": 2}, {"frame": 4}]})",
         "field 'camera[2].frame' repeats frame 4 of camera[0]"},
        {R"({"camera": []})", "field 'camera' must have at least one keyframe"},
        {R"({"camera": 3})", "field 'camera' must be an object or an array of keyframes"},
        {R"({"image": {"width": "640"}})", "field 'image.width' must be an integer"},
        {R"({"image": {"width": 0}})", "field 'image.width' must be between 1 and 65536 (is 0)"},
        {R"({"image": {"height": -480}})", "field 'image.height' must be between 1 and 65536"},
        {R"({"image": {"spp": 0}})", "field 'image.spp' must be between 1 and"},
        {R"({"image": {"width": 100000}})", "field 'image.width' must be between 1 and 65536"},
        {R"({"image": []})", "field 'image' must be an object"},
        {R"({"max_depth": 0})", "field 'max_depth' must be between 1 and"},
        {R"({"camera": {"fov_y": 0}})", "field 'camera.fov_y' must be between 0 and 180"},
        {R"({"camera": {"fov_y": 180}})", "field 'camera.fov_y' must be between 0 and 180"},
        {R"({"camera": {"position": [0, 5, 0], "look_at": [0, 0, 0]}})",
         "field 'camera.up' is parallel to the view direction"},
        {R"({"camera": {"position": [1, 1, 1], "look_at": [1, 1, 1]}})",
         "field 'camera.look_at' must differ from the camera position"},
        {R"({"camera": {"up": [0, 0, 0]}})", "field 'camera.up' must not be the zero vector"},
        {R"({"camera": {"fov_y": 1e300}})", "field 'camera.fov_y' must be a finite number"},
        {R"({"lights": [{"type": "spot"}]})",
         "field 'lights[0].type' must be \"point\" or \"directional\" (is \"spot\")"},
        {R"({"lights": [{"type": "directional", "position": [0, 1, 0]}]})",
         "unknown field 'lights[0].position'"},
        {R"({"lights": [{"type": "point", "intensity": [1, -1, 1]}]})",
         "field 'lights[0].intensity' must not be negative"},
        {R"({"lights": {"type": "point"}})", "field 'lights' must be an array"},
        {R"({"background": [1, 1]})", "field 'background' must be an array of 3 numbers"},
        {R"({"ambient": [0.1, -0.1, 0]})", "field 'ambient' must not be negative"},
        {R"({"ambient": -1})", "field 'ambient' must not be negative"},
        {R"({"ambient": "grey"})", "field 'ambient' must be a number (a grey) or an array"},
        {R"({"ambient": [0, 0]})", "field 'ambient' must be an array of 3 numbers"},
        {R"({"exposure": "1"})", "field 'exposure' must be a number"},
        {R"({"exposure": 65})", "field 'exposure' must be between -64 and 64 stops"},
        {R"({"exposure": -1e300})", "field 'exposure' must be a finite number"},
        {R"([1, 2, 3])", "the render file must be a JSON object"},
        {R"({"image": {"width": 640,)", "invalid JSON at byte 25"},
        {"", "invalid JSON at byte 1"},
    };
    for (const Case& c : cases) {
        CAPTURE(c.text);
        CHECK(parse_error(c.text).find(std::string("scene/render.json: ") + c.message) == 0);
    }
}

TEST_CASE("cameras are read in double; the traced camera must have a basis in the scene's frame") {
    // The render file's numbers are the scene's units, read in double, where each of these has a
    // basis. What is traced is the camera in the scene's frame (scene_frame.h), in float: there
    // a view 1e-30 long is fine for a scene 1e-30 across and has no direction for a unit scene.
    const auto settings = [](const std::string& text) {
        return parse_render_json(text, "scene/render.json");
    };
    const SceneFrame unit;  // a scene of about unit extent at the origin
    SceneFrame tiny;        // a scene about 1e-30 across
    tiny.scale = std::ldexp(1.0, 100);
    const std::string tiny_view =
        R"({"camera": {"position": [0, 0, 1e-30], "look_at": [0, 0, 0]}})";
    CHECK(parse_error(tiny_view).empty());
    CHECK_THROWS_WITH_AS(
        settings(tiny_view).camera_at(0, unit),
        doctest::Contains("scene/render.json: the camera of frame 0: its look_at is "
                          "too far from or too close to the camera position"),
        Error);
    const Camera traced = settings(tiny_view).camera_at(0, tiny);
    CHECK(traced.position.z == float(1e-30 * std::ldexp(1.0, 100)));
    CHECK_THROWS_WITH_AS(
        settings(R"({"camera": {"position": [-3e38, 0, 0], "look_at": [3e38, 0, 0]}})")
            .camera_at(0, unit),
        doctest::Contains("its look_at is too far from or too close to the camera position"),
        Error);
    // In a keyframe, the frame and its keys are named.
    CHECK_THROWS_WITH_AS(
        settings(
            R"({"camera": [{"frame": 0}, {"frame": 4, "position": [0, 0, 1e-30], "look_at": [0, 0, 0]}]})")
            .camera_at(5, unit),
        doctest::Contains("the camera of frame 5: its look_at"), Error);

    // Up is a direction: any length that has a square in double will do, in any frame.
    for (const char* up : {"[0, 1e30, 0]", "[0, 1e-30, 0]"}) {
        CAPTURE(up);
        const std::string text = std::string(R"({"camera": {"up": )") + up + "}}";
        REQUIRE(parse_error(text).empty());
        const Camera c = settings(text).camera_at(0, unit);
        CHECK(c.up.y > 0.0f);
        CHECK(std::isfinite(c.up.y));
    }
    // So is a directional light's direction (render_setup normalises it in double).
    CHECK(
        parse_error(R"({"lights": [{"type": "directional", "direction": [1e30, 0, 0]}]})").empty());
    CHECK(parse_error(R"({"lights": [{"type": "directional", "direction": [1e-200, 0, 0]}]})")
              .find("field 'lights[0].direction' is too short to give a direction") !=
          std::string::npos);
    // A point light's intensity may be any finite double: the frame scales it by scale^2.
    CHECK(parse_error(R"({"lights": [{"position": [0, 0, 0], "intensity": [1e-60, 1e60, 1]}]})")
              .empty());
    // What has no basis in double is an error as the file is read.
    CHECK(parse_error(R"({"camera": {"up": [0, 0, 1]}})").find("field 'camera.up' is parallel") !=
          std::string::npos);
}

TEST_CASE("load_render_file reads files and names the missing one") {
    const fs::path missing = fs::temp_directory_path() / "kdray_no_such_render.json";
    CHECK_THROWS_WITH_AS(load_render_file(missing),
                         (missing.string() + ": cannot open: No such file or directory").c_str(),
                         Error);

    const fs::path root = test::source_dir() / "testdata";
    const RenderSettings cornell = load_render_file(root / "cornell" / "render.json");
    CHECK(cornell.path == root / "cornell" / "render.json");
    CHECK(cornell.width == 640);
    CHECK(cornell.height == 480);
    CHECK(cornell.lights.size() == 1);
    const RenderSettings anim = load_render_file(root / "anim" / "render.json");
    CHECK(anim.camera_keys.size() == 2);
    CHECK(anim.camera_keys.back().frame == 11);

    const fs::path scenes = test::shared_dir() / "scenes";
    if (!fs::exists(scenes)) {
        MESSAGE("skipped the shared render files: " << scenes.string() << " is absent");
        return;
    }
    for (const auto& entry : fs::directory_iterator(scenes)) {
        const fs::path file = entry.path() / "render.json";
        if (!fs::exists(file)) continue;
        CAPTURE(file.string());
        CHECK_NOTHROW(load_render_file(file));
    }
    CHECK(load_render_file(scenes / "bart-kitchen" / "render.json").camera_keys.size() == 8);
}
