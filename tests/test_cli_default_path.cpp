// test_cli_default_path.cpp — the kdray binary on its default path, the OpenCL builder and
// tracer (test_cli.cpp runs most cases on the CPU reference): `build` saves a tree that passes
// the invariant checker, `render` writes AOVs whose every hit is brute force's; and the effects
// `render` decides for a scene, with the reasons stats.json gives, for a matte scene, a mirror,
// a glass and a lit scene, each a head-on quad whose MTL calls for one thing (docs/effects.md,
// "What is simulated: only what the scene calls for"), and the rays the frame cast follow the
// decision.
#include <doctest/doctest.h>

#include <filesystem>
#include <fstream>
#include <sstream>
#include <string>
#include <vector>

#include <nlohmann/json.hpp>

#include "core/device/kd_render.h"
#include "core/io/image.h"
#include "core/render/camera.h"
#include "core/render/render_file.h"
#include "core/render/render_setup.h"
#include "core/scene/scene.h"
#include "core/tree/tree_check.h"
#include "core/tree/tree_file.h"
#include "core/tree/tree_stats.h"
#include "tests/support.h"

namespace fs = std::filesystem;
using namespace kdray;
using namespace kdray::test;

namespace {

struct Case {
    const char* name;
    const char* mtl;     // the quad's material
    const char* lights;  // the render file's "lights"
};

/// Renders the quad with `c`'s material and lights through the binary's default path and returns
/// its frame record.
nlohmann::json rendered_frame(const Case& c) {
    const fs::path dir = fresh_temp_dir(std::string("cli-default-effects-") + c.name);
    write_text_file(dir / "quad.mtl", std::string("newmtl m\n") + c.mtl);
    write_text_file(dir / "quad.obj",
                    "mtllib quad.mtl\nusemtl m\nv -1 -1 0\nv 1 -1 0\nv 1 1 0\nv -1 1 0\n"
                    "f 1 2 3\nf 1 3 4\n");
    write_text_file(
        dir / "render.json", std::string(R"({"image": {"width": 24, "height": 16}, "max_depth": 4,
  "camera": {"position": [0, 0, 3], "look_at": [0, 0, 0], "up": [0, 1, 0], "fov_y": 40},
  "lights": )") + c.lights + "}");
    const CommandResult run =
        run_kdray({"render", (dir / "quad.obj").string(), "--camera",
                   (dir / "render.json").string(), "-o", (dir / "out").string(), "-q"});
    REQUIRE_MESSAGE(run.status == 0, run.err);
    std::ifstream in(dir / "out" / "stats.json");
    const nlohmann::json frame = nlohmann::json::parse(in)["frames"].at(0);
    fs::remove_all(dir);
    return frame;
}

}  // namespace

TEST_CASE("kdray build, default path: the OpenCL tree it saves passes the checker, as reported") {
    const fs::path dir = fresh_temp_dir("cli-default-build");
    const Scene scene = random_triangles(600, 31);
    const fs::path obj = write_obj(dir / "scene.obj", scene);
    const CommandResult r =
        run_kdray({"build", obj.string(), "--json", "-o", (dir / "scene.kdt").string()});
    REQUIRE_MESSAGE(r.status == 0, r.err);
    const nlohmann::json j = nlohmann::json::parse(r.out);
    CHECK(j["builder"] == "opencl");
    const TreeFile file = read_tree_file(dir / "scene.kdt");
    const Scene loaded = load_obj(obj);
    const std::vector<std::string> errors = check_tree(file.tree, loaded);
    CHECK_MESSAGE(errors.empty(), (errors.empty() ? std::string() : errors.front()));
    CHECK(j["nodes"].get<std::size_t>() == file.tree.nodes.size());
    const TreeStats stats =
        compute_tree_stats(file.tree, loaded.triangle_count(), file.tree.params.costs);
    CHECK(j["sah_cost"].get<double>() == doctest::Approx(stats.sah_cost).epsilon(1e-9));
    fs::remove_all(dir);
}

TEST_CASE("kdray render, default path: every AOV hit is brute force's, the tracer is OpenCL") {
    const fs::path dir = fresh_temp_dir("cli-default-render");
    const Scene scene = random_triangles(400, 32);
    write_obj(dir / "in" / "frame_1.obj", scene);
    write_obj(dir / "in" / "frame_2.obj", scene);
    const fs::path render = write_text_file(dir / "render.json", R"({
  "image": {"width": 48, "height": 32},
  "camera": {"position": [0.5, 0.5, 3], "look_at": [0.5, 0.5, 0.5], "up": [0, 1, 0], "fov_y": 50},
  "lights": [{"type": "point", "position": [0.5, 3, 2], "intensity": [10, 10, 10]}]
})");
    const fs::path out = dir / "out";
    const CommandResult r = run_kdray({"render", (dir / "in" / "frame_1.obj").string(),
                                       (dir / "in" / "frame_2.obj").string(), "-o", out.string(),
                                       "--camera", render.string(), "--aov", "-q"});
    REQUIRE_MESSAGE(r.status == 0, r.err);
    std::ifstream in(out / "stats.json");
    const nlohmann::json stats = nlohmann::json::parse(in);
    REQUIRE(stats["frames"].size() == 2);
    for (const auto& frame : stats["frames"]) {
        CHECK(frame["tracer"] == "opencl");
        CHECK(frame["tree"]["builder"] == "opencl");
        CHECK(frame["rays"]["primary"] == 48 * 32);
    }
    const RenderSettings settings = load_render_file(render);
    for (const char* stem : {"frame_1", "frame_2"}) {
        INFO(stem);
        CHECK(fs::exists(out / (std::string(stem) + ".png")));
        const HitBuffer aov = read_aov(out / (std::string(stem) + ".aov.exr"));
        const Scene loaded = load_obj(dir / "in" / (std::string(stem) + ".obj"));
        const RenderInputs inputs =
            prepare_render(loaded, settings, settings.camera_at(0, loaded.frame), 0);
        REQUIRE(aov.width == 48);
        REQUIRE(aov.height == 32);
        const AovAgreement agreement = aov_against_brute_force(aov, loaded, inputs.view);
        CHECK(agreement.hits > 100);
        CHECK(agreement.mismatches == 0);
    }
    fs::remove_all(dir);
}

TEST_CASE("stats.json's effects and their reasons: matte, mirror, glass and a lit scene") {
    const char* none = "[]";
    const char* point = R"([{"type": "point", "position": [0, 0, 2], "intensity": [5, 5, 5]}])";

    SUBCASE("matte: no secondary rays, no shadows, a headlight") {
        const nlohmann::json f = rendered_frame({"matte", "Kd 0.5 0.5 0.5\nillum 1\n", none});
        const nlohmann::json& e = f["effects"];
        CHECK(f["tracer"] == "opencl");
        CHECK_FALSE(e["shadows"].get<bool>());
        CHECK_FALSE(e["reflection"].get<bool>());
        CHECK_FALSE(e["refraction"].get<bool>());
        CHECK_FALSE(e["area_lights"].get<bool>());
        CHECK(e["reasons"]["shadows"].get<std::string>().find("no lights") != std::string::npos);
        CHECK(e["reasons"]["reflection"] == "no material reflects");
        CHECK(e["reasons"]["refraction"] == "no material transmits");
        CHECK(e["reasons"]["area_lights"] == "no triangle emits");
        CHECK(f["rays"]["primary"] == 24 * 16);
        CHECK(f["rays"].value("shadow", 0) == 0);
        CHECK(f["rays"].value("reflection", 0) == 0);
        CHECK(f["rays"].value("refraction", 0) == 0);
    }
    SUBCASE("mirror: reflection rays, named after the mirror") {
        const nlohmann::json f =
            rendered_frame({"mirror", "Kd 0.1 0.1 0.1\nKs 0.9 0.9 0.9\nillum 3\n", none});
        const nlohmann::json& e = f["effects"];
        CHECK(e["reflection"].get<bool>());
        CHECK_FALSE(e["refraction"].get<bool>());
        CHECK(e["reasons"]["reflection"] == "material 'm' is a mirror");
        CHECK(f["rays"]["reflection"].get<int>() > 0);
        CHECK(f["rays"].value("refraction", 0) == 0);
    }
    SUBCASE("glass: refraction and reflection rays, named after the dielectric") {
        const nlohmann::json f =
            rendered_frame({"glass", "Kd 0 0 0\nKs 1 1 1\nNi 1.5\nillum 7\n", none});
        const nlohmann::json& e = f["effects"];
        CHECK(e["reflection"].get<bool>());
        CHECK(e["refraction"].get<bool>());
        CHECK(e["reasons"]["refraction"] == "material 'm' transmits");
        CHECK(e["reasons"]["reflection"] == "material 'm' reflects as a dielectric");
        CHECK(f["rays"]["refraction"].get<int>() > 0);
        CHECK(f["rays"]["reflection"].get<int>() > 0);
    }
    SUBCASE("lit: shadow rays for the render file's light") {
        const nlohmann::json f = rendered_frame({"lit", "Kd 0.5 0.5 0.5\nillum 1\n", point});
        const nlohmann::json& e = f["effects"];
        CHECK(e["shadows"].get<bool>());
        CHECK_FALSE(e["reflection"].get<bool>());
        CHECK(e["reasons"]["shadows"] == "1 light(s)");
        CHECK(f["rays"]["shadow"].get<int>() > 0);
    }
}

TEST_CASE("stats.json records whether packets traced, not only what --packets asked for") {
    const fs::path dir = fresh_temp_dir("cli-default-packets");
    const Scene scene = random_triangles(200, 33);
    const fs::path obj = write_obj(dir / "scene.obj", scene);
    const fs::path render = write_text_file(dir / "render.json", R"({
  "image": {"width": 16, "height": 16},
  "camera": {"position": [0.5, 0.5, 3], "look_at": [0.5, 0.5, 0.5], "up": [0, 1, 0], "fov_y": 50},
  "lights": [{"type": "point", "position": [0.5, 3, 2], "intensity": [10, 10, 10]}]
})");
    struct Run {
        std::vector<std::string> options;
        bool primary, shadow;
    };
    // Packets exist for the watertight test and the OpenCL tracer only: `on` with Möller–Trumbore
    // or the reference tracer traces one ray at a time.
    for (const Run& run :
         {Run{{"--packets", "on"}, true, true}, Run{{"--packets", "off"}, false, false},
          Run{{"--packets", "on", "--intersect", "moller"}, false, false},
          Run{{"--packets", "on", "--tracer", "reference"}, false, false}}) {
        std::vector<std::string> args = {
            "render", obj.string(), "--camera", render.string(), "-o", (dir / "out").string(), "-q",
            // One folder for all: each run replaces the one before, whose settings differ.
            "--overwrite"};
        args.insert(args.end(), run.options.begin(), run.options.end());
        std::string options;
        for (const std::string& o : run.options) options += o + " ";
        INFO(options);
        const CommandResult r = run_kdray(args);
        REQUIRE_MESSAGE(r.status == 0, r.err);
        std::ifstream in(dir / "out" / "stats.json");
        const nlohmann::json stats = nlohmann::json::parse(in);
        CHECK(stats["packets_requested"] == run.options[1]);
        const nlohmann::json& packets = stats["frames"][0]["packets"];
        CHECK(packets["primary"] == run.primary);
        CHECK(packets["shadow"] == run.shadow);
    }
    fs::remove_all(dir);
}

TEST_CASE("packets at 8 and 16 lanes write the AOV and image of one ray at a time, bit for bit") {
    // 37 x 29 pixels under a light: 4x2 and 4x4 tiles cut by the right and bottom edges, shadow
    // packets too. KDRAY_PACKET_LANES picks the width; stats.json says which ran.
    const fs::path dir = fresh_temp_dir("cli-default-packet-lanes");
    const Scene scene = random_triangles(300, 35);
    const fs::path obj = write_obj(dir / "scene.obj", scene);
    const fs::path render = write_text_file(dir / "render.json", R"({
  "image": {"width": 37, "height": 29},
  "camera": {"position": [0.5, 0.5, 3], "look_at": [0.5, 0.5, 0.5], "up": [0, 1, 0], "fov_y": 50},
  "lights": [{"type": "point", "position": [0.5, 3, 2], "intensity": [10, 10, 10]}]
})");
    struct Output {
        std::string aov, image;
    };
    auto run = [&](const std::string& lanes, const std::string& packets) {
        const ScopedEnv width("KDRAY_PACKET_LANES", lanes);
        const fs::path out = dir / ("out-" + packets + lanes);
        const CommandResult r =
            run_kdray({"render", obj.string(), "--camera", render.string(), "-o", out.string(),
                       "--aov", "--packets", packets, "-q"});
        REQUIRE_MESSAGE(r.status == 0, r.err);
        std::ifstream in(out / "stats.json");
        const nlohmann::json packets_ran = nlohmann::json::parse(in)["frames"][0]["packets"];
        CHECK(packets_ran["primary"] == (packets == "on"));
        CHECK(packets_ran["shadow"] == (packets == "on"));
        CHECK(packets_ran["lanes"] == (packets == "on" ? std::stoi(lanes) : 0));
        return Output{read_file(out / "scene.aov.exr"), read_file(out / "scene.png")};
    };
    const Output scalar = run("", "off");
    REQUIRE(!scalar.aov.empty());
    for (const char* lanes : {"8", "16"}) {
        CAPTURE(lanes);
        const Output packets = run(lanes, "on");
        CHECK(packets.aov == scalar.aov);
        CHECK(packets.image == scalar.image);
    }
    // Any other width is refused, with the variable named.
    {
        const ScopedEnv width("KDRAY_PACKET_LANES", "12");
        check_error(run_kdray({"render", obj.string(), "--camera", render.string(), "-o",
                               (dir / "out-12").string(), "--packets", "on", "-q"}),
                    1, {"KDRAY_PACKET_LANES", "8 or 16"});
    }
    fs::remove_all(dir);
}
