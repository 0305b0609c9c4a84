// test_cli_effects.cpp — the effects `kdray render` decides for a scene, and the reasons it gives,
// as stats.json records them, on the default (OpenCL) path: a matte scene, a mirror, a glass and
// a lit scene, each a head-on quad whose MTL calls for exactly one thing (README, "What is
// simulated: only what the scene calls for"); and the rays the frame cast follow the decision.
#include <doctest/doctest.h>

#include <filesystem>
#include <fstream>
#include <string>

#include <nlohmann/json.hpp>

#include "tests/support.h"

namespace fs = std::filesystem;
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
    const fs::path dir = fresh_temp_dir(std::string("cli-effects-") + c.name);
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
