// test_hostile_round3_settings.cpp — issue #29, problem 15: settings kdray cannot honour are
// refused or named, never ignored in silence. Each runs the binary. (Beside
// test_hostile_round3.cpp rather than in it: that file is near the size limit.)
#include <doctest/doctest.h>

#include <algorithm>
#include <filesystem>
#include <string>
#include <vector>

#include "core/io/image.h"
#include "tests/support.h"

namespace fs = std::filesystem;
using namespace kdray::test;

namespace {

// Runs that should end at once get 60 s: a hang fails the test instead of stalling CI.
constexpr int kNoHang = 60;

/// A unit quad facing +z with material `t` whose MTL says `map_kd` (a 2x2 tex.png beside it),
/// and a 16x12 camera on it with `render_extra` added to the render file's top level.
struct Quad {
    fs::path dir, obj, camera;
};

Quad quad(const std::string& name, const std::string& map_kd,
          const std::string& render_extra = "") {
    Quad q;
    q.dir = fresh_temp_dir(name);
    write_text_file(q.dir / "quad.mtl", "newmtl t\nKd 1 1 1\n" + map_kd + "\n");
    kdray::Image texture;
    texture.width = texture.height = 2;
    texture.rgb = {0.2f, 0.4f, 0.6f, 0.8f, 0.1f, 0.3f, 0.5f, 0.7f, 0.9f, 0.25f, 0.75f, 0.5f};
    kdray::write_image(q.dir / "tex.png", texture);
    q.obj = write_text_file(q.dir / "quad.obj",
                            "mtllib quad.mtl\nusemtl t\nv 0 0 0\nv 1 0 0\nv 1 1 0\nv 0 1 0\n"
                            "vt 0 0\nvt 1 0\nvt 1 1\nvt 0 1\nf 1/1 2/2 3/3 4/4\n");
    q.camera = write_text_file(q.dir / "cam.json",
                               R"({"image":{"width":16,"height":12},)" + render_extra +
                                   R"("camera":{"position":[0.5,0.5,2],"look_at":[0.5,0.5,0]}})");
    return q;
}

CommandResult render(const Quad& q, std::vector<std::string> extra = {}) {
    std::vector<std::string> args = {
        "render",   q.obj.string(),    "-o",        (q.dir / "out").string(),
        "--camera", q.camera.string(), "--builder", "reference",
        "--tracer", "reference",       "-q"};
    args.insert(args.end(), extra.begin(), extra.end());
    return run_kdray(args, kNoHang);
}

}  // namespace

TEST_CASE("max_depth and --ray-depth above the renderer's 16 bounces are refused") {
    // The renderer clamped them to KDRAY_MAX_BOUNCES (16) without a word while stats.json
    // recorded the value asked for. 16 itself must still render, and be what stats.json says.
    const Quad deep = quad("round3-max-depth", "map_Kd tex.png", R"("max_depth":17,)");
    check_error(render(deep), 1, {"cam.json", "max_depth", "16"});
    CHECK_FALSE(fs::exists(deep.dir / "out" / "quad.png"));

    const Quad q = quad("round3-ray-depth", "map_Kd tex.png", R"("max_depth":16,)");
    check_error(render(q, {"--ray-depth", "17"}), 2, {"--ray-depth", "16"});
    CHECK_FALSE(fs::exists(q.dir / "out" / "quad.png"));
    for (const auto& extra : {std::vector<std::string>{}, {"--ray-depth", "16"}}) {
        const CommandResult r = render(q, extra);
        INFO("stderr: " << r.err);
        REQUIRE(r.status == 0);
        CHECK(read_json(q.dir / "out" / "stats.json")["ray_depth"] == 16);
        fs::remove_all(q.dir / "out");
    }
    fs::remove_all(deep.dir);
    fs::remove_all(q.dir);
}

TEST_CASE("build and render -o with an empty name are usage errors") {
    // `build x.obj -o ""` exited 0 having written no tree file; `render -o ""` blamed a folder
    // named "" (exit 1) for what is a usage error.
    const Quad q = quad("round3-empty-o", "map_Kd tex.png");
    for (const char* command : {"build", "render"})
        for (const char* option : {"-o", "--output"}) {
            CAPTURE(command);
            CAPTURE(option);
            check_error(
                run_kdray({command, q.obj.string(), option, "", "--builder", "reference"}, kNoHang),
                2, {command, "--output", "empty"});
        }
    fs::remove_all(q.dir);
}

TEST_CASE("map_Kd options kdray does not simulate are named in one warning") {
    // `map_Kd -s 4 4 1 tex.png` (a tiled texture) rendered unscaled, and -o unshifted, without a
    // word. The warning names the material, the options and the file; plain map_Kd gives none.
    struct Case {
        const char* statement;
        std::vector<std::string> mentions;
    };
    const Case cases[] = {
        {"map_Kd -s 4 4 1 tex.png", {"material 't'", "map_Kd", "-s 4 4 1", "tex.png"}},
        {"map_Kd -o 0.5 0.25 0 tex.png", {"material 't'", "map_Kd", "-o 0.5 0.25 0", "tex.png"}},
        {"map_Ka -s 2 2 1 -o 0.5 0 0 tex.png",
         {"material 't'", "map_Ka", "-s 2 2 1", "-o 0.5 0 0", "tex.png"}},
    };
    for (const Case& c : cases) {
        CAPTURE(c.statement);
        const Quad q = quad("round3-map-options", c.statement);
        const CommandResult r = render(q);
        INFO("stderr: " << r.err);
        CHECK(r.status == 0);
        CHECK(r.err.rfind("kdray: warning: ", 0) == 0);
        CHECK(line_count(r.err) == 1);
        for (const std::string& m : c.mentions)
            CHECK_MESSAGE(r.err.find(m) != std::string::npos, m);
        fs::remove_all(q.dir);
    }
    const Quad plain = quad("round3-map-plain", "map_Kd tex.png");
    const CommandResult r = render(plain);
    CHECK(r.status == 0);
    CHECK(r.err.empty());
    fs::remove_all(plain.dir);
}

TEST_CASE("a render-file key given twice is refused, naming the file and the key") {
    // nlohmann::json kept the last of two equal keys, Python's json (the schema check) too, and
    // other readers keep the first: `"spp": 1, ..., "spp": 64` rendered at 64 spp while an editor
    // might show 1. Keys inside arrays (a light, a camera key) are named with their index, and
    // the same key in two different objects is no duplicate.
    struct Case {
        const char* extra;
        const char* key;
    };
    const Case cases[] = {
        {R"("max_depth":4,"max_depth":6,)", "'max_depth'"},
        {R"("lights":[{"type":"point"},{"type":"point","position":[0,0,1],"position":[0,1,1]}],)",
         "'lights[1].position'"},
        {R"("ambient":0.1,"lights":[{"type":"point"}],"ambient":0.2,)", "'ambient'"},
    };
    for (const Case& c : cases) {
        CAPTURE(c.extra);
        const Quad q = quad("round3-duplicate-key", "map_Kd tex.png", c.extra);
        check_error(render(q), 1, {"cam.json", c.key, "twice"});
        CHECK_FALSE(fs::exists(q.dir / "out" / "quad.png"));
        fs::remove_all(q.dir);
    }
    const Quad q = quad("round3-distinct-keys", "map_Kd tex.png",
                        R"("lights":[{"type":"point","position":[0,0,3]},)"
                        R"({"type":"point","position":[1,0,3]}],)");
    const CommandResult r = render(q);
    INFO("stderr: " << r.err);
    CHECK(r.status == 0);
    fs::remove_all(q.dir);
}

TEST_CASE("a stats.json key given twice is refused before the run renders") {
    // The folder's stats.json is read back and merged into: a record whose "frame" is given twice
    // means one frame to kdray and another to a script reading the file.
    const Quad q = quad("round3-duplicate-stats", "map_Kd tex.png");
    REQUIRE(render(q).status == 0);
    const fs::path out = q.dir / "out";
    std::string stats = read_file(out / "stats.json");
    const std::size_t frame = stats.find("\"frame\": 0");
    REQUIRE(frame != std::string::npos);
    stats.insert(frame, "\"frame\": 7, ");
    write_text_file(out / "stats.json", stats);
    fs::remove(out / "quad.png");
    check_error(render(q), 1, {"stats.json", "frame", "twice"});
    CHECK_FALSE(fs::exists(out / "quad.png"));
    check_error(run_kdray({"stats", out.string()}, kNoHang), 1, {"stats.json", "frame", "twice"});
    fs::remove_all(q.dir);
}
