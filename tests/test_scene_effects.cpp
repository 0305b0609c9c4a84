// test_scene_effects.cpp — what a scene calls for beyond lights and mirrors (issue #15): ambient
// light by Ka and the image's exposure, against closed forms on a head-on quad, the OpenCL
// renderer against the reference renderer with them on, and the warnings about what an MTL file
// asks for that kdray does not simulate.
#include <doctest/doctest.h>

#include <OpenImageIO/imageio.h>

#include <cmath>
#include <cstdint>
#include <filesystem>
#include <numbers>
#include <set>
#include <string>
#include <vector>

#include "cl/renderer/opencl_renderer.h"
#include "core/io/image.h"
#include "core/render/reference_tracer.h"
#include "core/render/render_file.h"
#include "core/render/render_setup.h"
#include "core/run/frame_pipeline.h"
#include "core/scene/scene.h"
#include "core/tree/reference_builder.h"
#include "tests/support.h"
#include "tests/test_opencl_fixture.h"

namespace fs = std::filesystem;
using namespace kdray;

namespace {

/// A 20 x 20 quad at z = 0 facing +z (counter-clockwise seen from +z), Kd = 0.5, and a camera at
/// z = 5 looking at it head on: every pixel sees the quad, under the headlight with cos = 1 at
/// the centre.
Scene head_on_quad() {
    const float h = 10.0f;
    Scene scene = make_scene({-h, -h, 0, h, -h, 0, h, h, 0, -h, -h, 0, h, h, 0, -h, h, 0}, "quad");
    scene.materials[0].diffuse = {0.5f, 0.5f, 0.5f};
    return scene;
}

Camera head_on_camera() {
    Camera camera;
    camera.position = {0, 0, 5};
    camera.look_at = {0, 0, 0};
    camera.fov_y = 60.0f;
    return camera;
}

RenderSettings small_settings() {
    RenderSettings settings;
    settings.width = 16;
    settings.height = 12;
    return settings;
}

double max_difference(const Image& a, const Image& b) {
    double worst = 0;
    for (std::size_t i = 0; i < a.rgb.size(); ++i)
        worst = std::max(worst, double(std::fabs(a.rgb[i] - b.rgb[i])));
    return worst;
}

std::vector<float> read_exr(const fs::path& path) {
    auto in = OIIO::ImageInput::open(path.string());
    REQUIRE(in);
    const OIIO::ImageSpec& spec = in->spec();
    std::vector<float> pixels(std::size_t(spec.width) * spec.height * 3);
    REQUIRE(in->read_image(0, 0, 0, 3, OIIO::TypeDesc::FLOAT, pixels.data()));
    return pixels;
}

}  // namespace

TEST_CASE("ambient: a hit adds Ka x ambient, exactly where nothing else lights it") {
    Scene scene = head_on_quad();
    const KdTree tree = build_reference(scene);
    RenderSettings settings = small_settings();
    scene.materials[0].ambient = {0.5f, 0.25f, 0.125f};
    settings.ambient = {0.4f, 0.8f, 1.6f};  // Ka x ambient = 0.2 in every channel

    SUBCASE("Kd 0: the headlight adds nothing, the pixel is Ka x ambient") {
        scene.materials[0].diffuse = {0, 0, 0};
        const RenderInputs inputs = prepare_render(scene, settings, head_on_camera(), 0);
        CHECK(inputs.effects.ambient);
        CHECK(inputs.effects.ambient_reason.find("'default'") != std::string::npos);
        const FrameResult frame = render_reference(tree, scene, inputs, 1);
        for (float v : frame.image.rgb) CHECK(v == doctest::Approx(0.2).epsilon(1e-6));
    }
    SUBCASE("beside a light from behind the quad (lights nothing), Kd 0.5 adds nothing either") {
        settings.lights.push_back(Light{Light::Type::directional, {}, {0, 0, 1}, {9, 9, 9}});
        const RenderInputs inputs = prepare_render(scene, settings, head_on_camera(), 0);
        const FrameResult frame = render_reference(tree, scene, inputs, 1);
        for (float v : frame.image.rgb) CHECK(v == doctest::Approx(0.2).epsilon(1e-6));
    }
    SUBCASE("with the headlight on Kd 0.5: Kd / pi + Ka x ambient at the centre") {
        settings.width = settings.height = 1;  // the one pixel's ray is the view direction
        const RenderInputs inputs = prepare_render(scene, settings, head_on_camera(), 0);
        const FrameResult frame = render_reference(tree, scene, inputs, 1);
        for (float v : frame.image.rgb)
            CHECK(v == doctest::Approx(0.5 / std::numbers::pi + 0.2).epsilon(1e-6));
    }
    SUBCASE("no ambient light, or no Ka: the effect is off and Ka adds nothing") {
        settings.width = settings.height = 1;
        for (int which = 0; which < 2; ++which) {
            CAPTURE(which);
            Scene s = scene;
            RenderSettings r = settings;
            if (which == 0)
                r.ambient = {0, 0, 0};
            else
                s.materials[0].ambient = {0, 0, 0};
            const RenderInputs inputs = prepare_render(s, r, head_on_camera(), 0);
            CHECK_FALSE(inputs.effects.ambient);
            // Ka with no light to reflect is flagged for render to say; no Ka is not.
            CHECK(inputs.effects.ambient_unlit == (which == 0));
            CHECK((inputs.effects.bits() & KDRAY_EFFECT_AMBIENT) == 0u);
            CHECK(inputs.effects.to_json()["reasons"]["ambient"] ==
                  (which == 0 ? "the render file has no ambient light, though material '" +
                                    s.materials[0].name + "' reflects it (Ka > 0)"
                              : "no material reflects ambient light (Ka 0)"));
            const FrameResult frame = render_reference(tree, s, inputs, 1);
            for (float v : frame.image.rgb)
                CHECK(v == doctest::Approx(0.5 / std::numbers::pi).epsilon(1e-6));
        }
    }
}

TEST_CASE("ambient: the OpenCL renderer's image is the reference's") {
    Scene scene = test::random_triangles(400, 5);
    Material tinted;
    tinted.name = "tinted";
    tinted.ambient = {0.3f, 0.6f, 0.9f};
    tinted.diffuse = {0.2f, 0.4f, 0.1f};
    scene.materials.push_back(tinted);
    for (std::size_t t = 0; t < scene.triangle_count(); t += 3) scene.material_ids[t] = 1;
    const KdTree tree = build_reference(scene);
    RenderSettings settings = small_settings();
    settings.width = 40;
    settings.height = 30;
    settings.ambient = {0.25f, 0.5f, 0.125f};
    Camera camera;
    camera.position = {1.8f, 1.6f, 2.4f};
    camera.look_at = {0.5f, 0.5f, 0.5f};
    for (bool lights : {false, true}) {
        CAPTURE(lights);
        if (lights)
            settings.lights.push_back(Light{Light::Type::point, {0.5f, 3, 0.5f}, {}, {4, 4, 4}});
        const RenderInputs inputs = prepare_render(scene, settings, camera, 0);
        REQUIRE(inputs.effects.ambient);
        const FrameResult device = render_opencl(test::opencl_test_device(), tree, scene, inputs);
        const FrameResult host = render_reference(tree, scene, inputs, 2);
        CHECK(max_difference(device.image, host.image) < 1e-4);
        // Ambient light is no ray: the counts are those of the lights alone.
        CHECK(device.rays.shadow == host.rays.shadow);
        CHECK(device.rays.primary == 40u * 30u);
    }
}

TEST_CASE("exposure: each stop doubles the EXR's linear values; PNG clamps 2^e x radiance") {
    const fs::path dir = test::fresh_temp_dir("exposure");
    const Scene scene = head_on_quad();
    ReferenceTreeBuilder builder({});
    ReferenceTracer tracer(1);
    std::vector<std::vector<float>> exr;
    for (int stops : {0, 1, 2, -3}) {
        RenderSettings settings = small_settings();
        settings.width = settings.height = 1;
        settings.camera_keys = {CameraKey{0, head_on_camera()}};
        settings.camera_given = true;
        settings.exposure = float(stops);
        FrameOptions options;
        options.out_dir = dir / std::to_string(stops);
        options.format = "exr";
        fs::create_directories(options.out_dir);
        FramePipeline pipeline(builder, tracer, settings, options);
        pipeline.render_frame({0, (dir / "quad.obj").string(), &scene});
        exr.push_back(read_exr(options.out_dir / "quad.exr"));
    }
    // The headlight on Kd 0.5 at cos 1: 0.5 / pi, times 2^stops exactly (a power of two).
    for (float v : exr[0]) CHECK(v == doctest::Approx(0.5 / std::numbers::pi).epsilon(1e-6));
    for (int c = 0; c < 3; ++c) {
        CHECK(exr[1][c] == 2.0f * exr[0][c]);
        CHECK(exr[2][c] == 4.0f * exr[0][c]);
        CHECK(exr[3][c] == exr[0][c] / 8.0f);
    }

    // PNG: 2^1 x 0.159 = 0.318 encodes as sRGB; 2^3 x 0.159 = 1.27 clamps to white.
    Image grey{1,
               1,
               {0.5f / std::numbers::pi_v<float>, 0.5f / std::numbers::pi_v<float>,
                0.5f / std::numbers::pi_v<float>}};
    const auto png_byte = [&](float stops) {
        write_image(dir / "grey.png", grey, stops);
        auto in = OIIO::ImageInput::open((dir / "grey.png").string());
        REQUIRE(in);
        std::uint8_t rgb[3];
        REQUIRE(in->read_image(0, 0, 0, 3, OIIO::TypeDesc::UINT8, rgb));
        return int(rgb[0]);
    };
    const double linear = 2.0 * 0.5 / std::numbers::pi;
    const double encoded = 1.055 * std::pow(linear, 1.0 / 2.4) - 0.055;  // IEC 61966-2-1
    CHECK(png_byte(1.0f) == int(std::lround(encoded * 255.0)));
    CHECK(png_byte(3.0f) == 255);
    fs::remove_all(dir);
}

TEST_CASE("warnings: one per material and statement read but not simulated, not per face") {
    const fs::path dir = test::fresh_temp_dir("unsimulated");
    test::write_text_file(dir / "scene.mtl", R"(newmtl bumpy
Kd 0.5 0.5 0.5
map_bump -bm 0.5 bump.png
map_Ks spec.png
map_d alpha.png
map_Ns gloss.png
disp height.png
decal sticker.png
refl -type sphere sky.png
Tf 1 0.5 1
newmtl plain
Kd 0.2 0.2 0.2
Tf 1 1 1
newmtl textured
map_Kd wood.png
map_Ka wood_ao.png
bump other.png
)");
    std::string obj = "mtllib scene.mtl\nv 0 0 0\nv 1 0 0\nv 1 1 0\nv 0 1 0\n";
    for (const char* material : {"bumpy", "plain", "textured"}) {
        obj += std::string("usemtl ") + material + "\n";
        for (int face = 0; face < 4; ++face) obj += "f 1 2 3\nf 1 3 4\n";
    }
    const fs::path path = test::write_text_file(dir / "scene.obj", obj);
    const Scene scene = load_obj(path);
    REQUIRE(scene.triangle_count() == 24u);
    std::multiset<std::string> warned;  // "material statement"
    for (const std::string& w : scene.warnings) {
        CAPTURE(w);
        REQUIRE(w.find(path.string() + ": material '") == 0);
        // map_Kd and map_Ka are simulated; their files are missing here, which is one warning
        // each too.
        CHECK((w.find(" is not simulated (") != w.npos || w.find("' not found in ") != w.npos));
        const std::size_t name = w.find('\'') + 1, end = w.find('\'', name);
        const std::string statement = w.substr(end + 3, w.find_first_of(" ", end + 3) - end - 3);
        warned.insert(w.substr(name, end - name) + " " + statement);
    }
    const std::multiset<std::string> expected = {"bumpy map_bump/bump",
                                                 "bumpy map_Ks",
                                                 "bumpy map_d",
                                                 "bumpy map_Ns",
                                                 "bumpy disp",
                                                 "bumpy decal",
                                                 "bumpy refl",
                                                 "bumpy Tf",
                                                 "textured map_Kd",
                                                 "textured map_Ka",
                                                 "textured map_bump/bump"};
    CHECK(warned == expected);
    // The files are named, so that a reader knows which map is missing from the image.
    bool names_file = false;
    for (const std::string& w : scene.warnings) names_file |= w.find("'wood.png'") != w.npos;
    CHECK(names_file);
    fs::remove_all(dir);
}

namespace {

/// The view factor from a differential area to a parallel rectangle a x b at height h, the area
/// lying under one of its corners (the configuration factor of Howell's catalogue):
/// F = 1 / (2 pi) [A / sqrt(1 + A^2) atan(B / sqrt(1 + A^2)) + B / sqrt(1 + B^2) atan(A /
/// sqrt(1 + B^2))], A = a / h, B = b / h.
double corner_view_factor(double a, double b, double h) {
    const double A = a / h, B = b / h, sa = std::sqrt(1 + A * A), sb = std::sqrt(1 + B * B);
    return (A / sa * std::atan(B / sa) + B / sb * std::atan(A / sb)) / (2 * std::numbers::pi);
}

/// A floor (z = 0, facing up, Kd 0.5) under a square emitter of side 1 at z = 1, centred over the
/// origin, emitting Ke = (1, 0.5, 0.25) downwards, or upwards when `facing_up`.
Scene floor_under_panel(bool facing_up) {
    const float f = 10.0f;
    std::vector<float> t = {-f, -f, 0, f, -f, 0, f, f, 0, -f, -f, 0, f, f, 0, -f, f, 0};
    // Clockwise seen from above: the winding normal points down (-z).
    std::vector<float> panel = {-0.5f, -0.5f, 1, -0.5f, 0.5f, 1, 0.5f, 0.5f,  1,
                                -0.5f, -0.5f, 1, 0.5f,  0.5f, 1, 0.5f, -0.5f, 1};
    if (facing_up)
        for (int tri = 0; tri < 2; ++tri)
            for (int a = 0; a < 3; ++a) std::swap(panel[9 * tri + 3 + a], panel[9 * tri + 6 + a]);
    t.insert(t.end(), panel.begin(), panel.end());
    Scene scene = make_scene(t, "panel");
    scene.materials[0].diffuse = {0.5f, 0.5f, 0.5f};
    Material light;
    light.name = "panel";
    light.diffuse = {0, 0, 0};
    light.emission = {1.0f, 0.5f, 0.25f};
    scene.materials.push_back(light);
    scene.material_ids = {0, 0, 1, 1};
    return scene;
}

/// One pixel, a narrow view of the floor's origin from the side, below the panel.
RenderSettings floor_pixel(int spp) {
    RenderSettings settings;
    settings.width = settings.height = 1;
    settings.spp = spp;
    Camera camera;
    camera.position = {0, -3, 0.5f};
    camera.look_at = {0, 0, 0};
    camera.up = {0, 0, 1};
    camera.fov_y = 0.2f;
    settings.camera_keys = {CameraKey{0, camera}};
    settings.camera_given = true;
    return settings;
}

}  // namespace

TEST_CASE("area lights: a floor under a square panel has the closed-form radiance") {
    const Scene scene = floor_under_panel(false);
    const KdTree tree = build_reference(scene);
    const RenderSettings settings = floor_pixel(16384);
    const RenderInputs inputs = prepare_render(scene, settings, settings.camera_at(0), 0);
    REQUIRE(inputs.effects.area_lights);
    CHECK_FALSE(inputs.effects.shadows);
    REQUIRE(inputs.view.emitter_count == 2u);
    // Equal areas and one Ke: each triangle of the panel is chosen half the time.
    CHECK(inputs.emitters[0].probability == 0.5f);
    CHECK(inputs.emitters[1].cdf == 1.0f);
    // E = pi L F, F four times the corner factor of a half-side square; L_floor = Kd / pi E.
    const double view_factor = 4 * corner_view_factor(0.5, 0.5, 1.0);
    const double ke[3] = {1.0, 0.5, 0.25};
    for (const bool device : {false, true}) {
        CAPTURE(device);
        const FrameResult frame =
            device ? render_opencl(test::opencl_test_device(), tree, scene, inputs)
                   : render_reference(tree, scene, inputs, 2);
        REQUIRE(frame.hits.hits[0].prim < 2u);  // the centre ray sees the floor
        // One area-light shadow ray per sample, none toward lights (there are none).
        CHECK(frame.rays.area_shadow == 16384u);
        CHECK(frame.rays.shadow == 0u);
        // The one-sample estimator's relative spread here is about 0.2; 16384 samples: 0.0016.
        for (int c = 0; c < 3; ++c)
            CHECK(frame.image.rgb[c] == doctest::Approx(0.5 * ke[c] * view_factor).epsilon(0.01));
    }
}

TEST_CASE("area lights: an emitter lights and shows only its front side") {
    const Scene away = floor_under_panel(true);
    const KdTree tree = build_reference(away);
    SUBCASE("the floor under a panel that faces away is black: no headlight, no light") {
        const RenderSettings settings = floor_pixel(64);
        const RenderInputs inputs = prepare_render(away, settings, settings.camera_at(0), 0);
        REQUIRE(inputs.effects.area_lights);
        const FrameResult frame = render_reference(tree, away, inputs, 1);
        REQUIRE(frame.hits.hits[0].prim < 2u);
        for (int c = 0; c < 3; ++c) CHECK(frame.image.rgb[c] == 0.0f);
        CHECK(frame.rays.area_shadow == 0u);  // the panel's back: no ray toward it
    }
    SUBCASE("seen from below, the downward panel is Ke; the upward one black") {
        RenderSettings settings = floor_pixel(1);
        Camera camera = settings.camera_at(0);
        camera.position = {0.1f, -0.2f, 0.2f};
        camera.look_at = {0.1f, 0.1f, 1.0f};
        settings.camera_keys = {CameraKey{0, camera}};
        for (const bool facing_up : {false, true}) {
            CAPTURE(facing_up);
            const Scene scene = floor_under_panel(facing_up);
            const KdTree t = build_reference(scene);
            const RenderInputs inputs = prepare_render(scene, settings, camera, 0);
            const FrameResult frame = render_reference(t, scene, inputs, 1);
            REQUIRE(frame.hits.hits[0].prim >= 2u);  // the panel
            const float expected[3] = {1.0f, 0.5f, 0.25f};
            for (int c = 0; c < 3; ++c)
                CHECK(frame.image.rgb[c] == (facing_up ? 0.0f : expected[c]));
        }
    }
}

TEST_CASE("area lights: the OpenCL renderer's image is the reference's") {
    Scene scene = test::random_triangles(600, 17);
    Material light;
    light.name = "light";
    light.emission = {4.0f, 3.0f, 2.0f};
    scene.materials.push_back(light);
    for (std::size_t t = 0; t < scene.triangle_count(); t += 7) scene.material_ids[t] = 1;
    const KdTree tree = build_reference(scene);
    Camera camera;
    camera.position = {1.8f, 1.6f, 2.4f};
    camera.look_at = {0.5f, 0.5f, 0.5f};
    for (const int spp : {1, 4}) {
        for (const bool lights : {false, true}) {
            CAPTURE(spp);
            CAPTURE(lights);
            RenderSettings settings = small_settings();
            settings.width = 40;
            settings.height = 30;
            settings.spp = spp;
            if (lights)
                settings.lights.push_back(
                    Light{Light::Type::point, {0.5f, 3, 0.5f}, {}, {4, 4, 4}});
            const RenderInputs inputs = prepare_render(scene, settings, camera, 0);
            REQUIRE(inputs.effects.area_lights);
            const FrameResult device =
                render_opencl(test::opencl_test_device(), tree, scene, inputs);
            const FrameResult host = render_reference(tree, scene, inputs, 2);
            CHECK(host.rays.area_shadow > 0u);
            CHECK(device.rays.area_shadow == host.rays.area_shadow);
            CHECK(device.rays.shadow == host.rays.shadow);
            CHECK(max_difference(device.image, host.image) < 1e-4);
        }
    }
}

TEST_CASE("area lights: a frame without emitters has no emitter table and a headlight") {
    const Scene scene = head_on_quad();
    RenderSettings settings = small_settings();
    const RenderInputs inputs = prepare_render(scene, settings, head_on_camera(), 0);
    CHECK_FALSE(inputs.effects.area_lights);
    CHECK(inputs.effects.area_lights_reason == "no triangle emits");
    CHECK(inputs.view.emitter_count == 0u);
    CHECK((inputs.effects.bits() & KDRAY_EFFECT_AREA_LIGHTS) == 0u);
}

namespace {

/// The IEC 61966-2-1 decoding of an 8-bit sRGB value, in double.
double srgb_to_linear(int byte) {
    const double e = byte / 255.0;
    return e <= 0.04045 ? e / 12.92 : std::pow((e + 0.055) / 1.055, 2.4);
}

void write_png(const fs::path& path, int width, int height, const std::vector<std::uint8_t>& rgb) {
    auto out = OIIO::ImageOutput::create(path.string());
    REQUIRE(out);
    REQUIRE(out->open(path.string(), OIIO::ImageSpec(width, height, 3, OIIO::TypeDesc::UINT8)));
    REQUIRE(out->write_image(OIIO::TypeDesc::UINT8, rgb.data()));
    REQUIRE(out->close());
}

}  // namespace

TEST_CASE("textures: a head-on quad shows its 2x2 checker at the texel centres, V up") {
    const fs::path dir = test::fresh_temp_dir("checker");
    // The image's rows top first: top-left red, top-right green, bottom-left blue, bottom-right
    // grey; with v = 0 the bottom row, the top of the quad (y = +1, v = 1) shows red and green.
    const std::vector<std::uint8_t> checker = {255, 0, 0, 0, 128, 0, 0, 0, 64, 200, 200, 200};
    write_png(dir / "Checker.png", 2, 2, checker);
    test::write_text_file(dir / "quad.mtl",
                          "newmtl board\nKd 1 1 1\nKa 1 1 1\nmap_Kd checker.png\n"
                          "newmtl missing\nmap_Kd nowhere.png\n");
    // A quad [-1, 1]^2 at z = 0 facing +z, vt (0,0) at the bottom left to (1,1) at the top right
    // (the map_Kd name differs in case from the file: the case-insensitive fallback finds it).
    const fs::path obj = test::write_text_file(
        dir / "quad.obj",
        "mtllib quad.mtl\nv -1 -1 0\nv 1 -1 0\nv 1 1 0\nv -1 1 0\n"
        "vt 0 0\nvt 1 0\nvt 1 1\nvt 0 1\nusemtl board\nf 1/1 2/2 3/3\nf 1/1 3/3 4/4\n"
        "usemtl missing\nf 1 2 3\n");
    const Scene scene = load_obj(obj);
    REQUIRE(scene.texture_table.size() == 1u);
    CHECK(scene.texture_bytes() == 4 * 4 * sizeof(float) + sizeof(KdTexture));
    REQUIRE(scene.warnings.size() == 1u);
    CHECK(scene.warnings[0].find("material 'missing': map_Kd 'nowhere.png' not found") !=
          std::string::npos);
    const KdTree tree = build_reference(scene);
    // A 2 x 2 image whose view is exactly the quad: pixel centres at x, y = +-0.5, i.e. the
    // texel centres u, v = 0.25, 0.75; the headlight at cos 1 gives Kd x texel / pi.
    RenderSettings settings;
    settings.width = settings.height = 2;
    Camera camera;
    camera.position = {0, 0, 2};
    camera.look_at = {0, 0, 0};
    camera.fov_y = float(2 * std::atan(0.5) * 180 / std::numbers::pi);
    // The camera in the scene's units; the loaded quad lies in its frame (scene_frame.h).
    const RenderInputs inputs = prepare_render(scene, settings, in_frame(camera, scene.frame), 0);
    REQUIRE(inputs.effects.textures);
    // The pixels, rows top first, are the image's texels: the top row is v = 0.75, red and green.
    for (const bool device : {false, true}) {
        CAPTURE(device);
        const FrameResult frame =
            device ? render_opencl(test::opencl_test_device(), tree, scene, inputs)
                   : render_reference(tree, scene, inputs, 1);
        for (int i = 0; i < 12; ++i) {
            CAPTURE(i);
            CHECK(frame.image.rgb[i] * std::numbers::pi ==
                  doctest::Approx(srgb_to_linear(checker[i])).epsilon(1e-4));
        }
    }
    // Without vt the same material renders untextured: Kd / pi.
    Scene plain = scene;
    plain.texcoords.clear();
    const RenderInputs untextured =
        prepare_render(plain, settings, in_frame(camera, plain.frame), 0);
    CHECK_FALSE(untextured.effects.textures);
    const FrameResult frame = render_reference(tree, plain, untextured, 1);
    for (float v : frame.image.rgb) CHECK(v * std::numbers::pi == doctest::Approx(1.0));
    fs::remove_all(dir);
}

TEST_CASE("textures: map_Ka multiplies Ka x ambient") {
    const fs::path dir = test::fresh_temp_dir("ambient-map");
    write_png(dir / "ao.png", 1, 1, {51, 102, 204});
    test::write_text_file(dir / "quad.mtl", "newmtl m\nKd 0 0 0\nKa 0.5 0.5 0.5\nmap_Ka ao.png\n");
    const fs::path obj = test::write_text_file(
        dir / "quad.obj",
        "mtllib quad.mtl\nv -1 -1 0\nv 1 -1 0\nv 1 1 0\nvt 0 0\nvt 1 0\nvt 1 1\n"
        "usemtl m\nf 1/1 2/2 3/3\n");
    const Scene scene = load_obj(obj);
    const KdTree tree = build_reference(scene);
    RenderSettings settings;
    settings.width = settings.height = 1;
    settings.ambient = {2, 2, 2};
    Camera camera;
    camera.position = {0.5f, -0.5f, 2};
    camera.look_at = {0.5f, -0.5f, 0};
    const RenderInputs inputs = prepare_render(scene, settings, in_frame(camera, scene.frame), 0);
    REQUIRE(inputs.effects.textures);
    const FrameResult frame = render_reference(tree, scene, inputs, 1);
    const int bytes[3] = {51, 102, 204};
    for (int c = 0; c < 3; ++c)
        CHECK(frame.image.rgb[c] ==
              doctest::Approx(0.5 * 2 * srgb_to_linear(bytes[c])).epsilon(1e-5));
    fs::remove_all(dir);
}
