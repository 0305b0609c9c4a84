// test_cli_messages.cpp — issue #31, item 8: errors that say what to do. A usage error names its
// command's help, a mistyped render-file field the nearest name, a light's strength under the
// other light's name the right one, a render file or another scene format given as a frame what
// kdray reads; --device takes a device type; a CPU run for want of a GPU is said once; --frames
// takes N and START-END, and says which frames of a range lie past the inputs. Each runs the
// binary. A scene whose materials have Ka, rendered without ambient light, is told why its
// shadows are black (#30).
#include <doctest/doctest.h>

#include <filesystem>
#include <string>
#include <vector>

#include "tests/support.h"

namespace fs = std::filesystem;
using namespace kdray::test;

namespace {

constexpr int kNoHang = 300;

const char* const kTriangle = "v 0 0 0\nv 1 0 0\nv 0 1 0\nf 1 2 3\n";

/// `kdray render OBJ -o OUT` on the reference path with `extra`.
CommandResult render(const fs::path& obj, const fs::path& out, std::vector<std::string> extra) {
    std::vector<std::string> args = {"render",    obj.string(), "-o",       out.string(),
                                     "--builder", "reference",  "--tracer", "reference",
                                     "--size",    "8x6"};
    args.insert(args.end(), extra.begin(), extra.end());
    return run_kdray(args, kNoHang);
}

/// The frame numbers stats.json in `out` records.
std::vector<int> recorded_frames(const fs::path& out) {
    std::vector<int> frames;
    const nlohmann::json stats = read_json(out / "stats.json");
    for (const nlohmann::json& f : stats["frames"]) frames.push_back(f["frame"].get<int>());
    return frames;
}

}  // namespace

TEST_CASE("a usage error points at the help of the command it was given to") {
    const fs::path dir = fresh_temp_dir("messages-help");
    const fs::path obj = write_text_file(dir / "tri.obj", kTriangle);
    check_error(run_kdray({"render", obj.string()}, kNoHang), 2, {"(see kdray render --help)"});
    check_error(
        run_kdray({"render", obj.string(), "-o", (dir / "o").string(), "--sizee", "8x6"}, kNoHang),
        2, {"unknown option '--sizee'; did you mean '--size'?", "(see kdray render --help)"});
    // Errors found after parsing, in the command itself, too.
    check_error(
        run_kdray({"render", obj.string(), "-o", (dir / "o").string(), "--size", "8"}, kNoHang), 2,
        {"--size 8", "(see kdray render --help)"});
    check_error(run_kdray({"build", obj.string(), "--ct", "-1"}, kNoHang), 2,
                {"(see kdray build --help)"});
    check_error(run_kdray({"compare", obj.string()}, kNoHang), 2, {"(see kdray compare --help)"});
    check_error(run_kdray({"rendr"}, kNoHang), 2, {"did you mean 'render'?", "(see kdray --help)"});
    fs::remove_all(dir);
}

TEST_CASE("a render file's mistyped field gets the nearest name; a light's strength its own") {
    const fs::path dir = fresh_temp_dir("messages-render-file");
    const fs::path obj = write_text_file(dir / "tri.obj", kTriangle);
    struct Case {
        const char* json;
        std::vector<std::string> mentions;
    };
    const std::vector<Case> cases = {
        {R"({"max_dpeth": 3})", {"unknown field 'max_dpeth'; did you mean 'max_depth'?"}},
        {R"({"image": {"widht": 8}})", {"unknown field 'image.widht'; did you mean 'width'?"}},
        {R"({"camera": {"fovy": 40}})", {"unknown field 'camera.fovy'; did you mean 'fov_y'?"}},
        {R"({"lights": [{"type": "directional", "direction": [0, -1, 0], "intensity": [1, 1, 1]}]})",
         {"unknown field 'lights[0].intensity'",
          "a directional light's strength is its "
          "'irradiance'"}},
        {R"({"lights": [{"type": "point", "irradiance": [1, 1, 1]}]})",
         {"unknown field 'lights[0].irradiance'", "a point light's strength is its 'intensity'"}},
    };
    for (const Case& c : cases) {
        CAPTURE(c.json);
        const fs::path file = write_text_file(dir / "r.json", c.json);
        const CommandResult r = render(obj, dir / "o", {"--camera", file.string()});
        check_error(r, 1, {});
        for (const std::string& m : c.mentions)
            CHECK_MESSAGE(r.err.find(m) != std::string::npos, m);
    }
    // A name near none of the allowed ones gets no guess.
    const fs::path far = write_text_file(dir / "far.json", R"({"zzzzzzzzzz": 1})");
    const CommandResult r = render(obj, dir / "o", {"--camera", far.string()});
    check_error(r, 1, {"unknown field 'zzzzzzzzzz'"});
    CHECK(r.err.find("did you mean") == std::string::npos);
    fs::remove_all(dir);
}

TEST_CASE("a render file or another scene format given as a scene is told what kdray reads") {
    const fs::path dir = fresh_temp_dir("messages-formats");
    const fs::path json = write_text_file(dir / "shot.json", kSmallRender);
    check_error(render(json, dir / "o", {}), 2,
                {json.string() + " is a render file, not a scene: pass it with --render-file"});
    // Also inside a glob's matches, and for build.
    write_text_file(dir / "frames" / "f_0.obj", kTriangle);
    write_text_file(dir / "frames" / "cam.json", kSmallRender);
    check_error(render(dir / "frames" / "*", dir / "o", {}), 2, {"is a render file"});
    for (const char* name : {"bunny.ply", "car.glb", "car.GLTF", "rig.fbx", "part.stl"}) {
        CAPTURE(name);
        const fs::path scene = write_text_file(dir / name, "not an OBJ\n");
        check_error(render(scene, dir / "o", {}), 2,
                    {"kdray reads Wavefront OBJ (.obj) files; convert it first"});
        check_error(run_kdray({"build", scene.string()}, kNoHang), 2,
                    {"kdray reads Wavefront OBJ (.obj) files"});
    }
    const fs::path packed = write_text_file(dir / "scene.obj.gz", "not gzip\n");
    check_error(render(packed, dir / "o", {}), 2, {"uncompressed; decompress it first"});
    CHECK_FALSE(fs::exists(dir / "o"));
    fs::remove_all(dir);
}

TEST_CASE("--frames takes N and START-END; a range past the inputs says what it renders") {
    const fs::path dir = fresh_temp_dir("messages-frames");
    for (int i = 0; i < 10; ++i)
        write_text_file(dir / "in" / ("f_" + std::to_string(i) + ".obj"), kTriangle);
    const fs::path frames = dir / "in" / "f_*.obj";

    CommandResult r = render(frames, dir / "one", {"--frames", "5", "-q"});
    INFO("stderr: " << r.err);
    REQUIRE(r.status == 0);
    CHECK(r.err.empty());
    CHECK(recorded_frames(dir / "one") == std::vector<int>{5});

    r = render(frames, dir / "dash", {"--frames", "2-4", "-q"});
    REQUIRE(r.status == 0);
    CHECK(recorded_frames(dir / "dash") == std::vector<int>{2, 3, 4});

    // 9:12 on 10 inputs (0 to 9): one frame rendered, three missing, said in one warning.
    r = render(frames, dir / "past", {"--frames", "9:12", "-q"});
    REQUIRE(r.status == 0);
    CHECK(r.err ==
          "kdray: warning: --frames 9:12: frames 10 to 12 are past the 10 inputs; rendering "
          "frame 9\n");
    CHECK(recorded_frames(dir / "past") == std::vector<int>{9});
    // With a step: 6, 8 rendered; 10 and 12 past, 14 beyond the range's end.
    r = render(frames, dir / "step", {"--frames", "6:13:2", "-q"});
    REQUIRE(r.status == 0);
    CHECK(r.err.find("frames 10 to 12 are past the 10 inputs; rendering frames 6 to 8\n") !=
          std::string::npos);
    CHECK(recorded_frames(dir / "step") == std::vector<int>{6, 8});
    r = render(frames, dir / "last", {"--frames", "8-10", "-q"});
    CHECK(r.err.find("frame 10 is past the 10 inputs; rendering frames 8 to 9") !=
          std::string::npos);
    // Within the inputs, or with the end left open, nothing is said.
    r = render(frames, dir / "open", {"--frames", "8:", "-q"});
    CHECK(r.err.empty());

    // --strict makes it an error before anything renders.
    r = render(frames, dir / "strict", {"--frames", "9:12", "--strict"});
    check_error(r, 1, {"--strict: --frames 9:12: frames 10 to 12 are past"});
    CHECK_FALSE(fs::exists(dir / "strict"));

    for (const char* bad : {"2-", "-4", "2-4-6", "a", "2-4:1", "5:"}) {
        CAPTURE(bad);
        const CommandResult b = render(frames, dir / "bad", {"--frames", bad});
        if (std::string(bad) == "5:") {
            CHECK(b.status == 0);  // START: is kdray's own form, to the last input
            continue;
        }
        check_error(b, 2, {std::string("--frames ") + bad, "N (one frame) or START-END"});
    }
    fs::remove_all(dir);
}

TEST_CASE("--device gpu and cpu choose by type; a CPU chosen for want of a GPU is said") {
    // What the OpenCL runtime offers, as `kdray stats --json` lists it: the first device of
    // each type.
    const CommandResult listed = run_kdray({"stats", "--json"}, kNoHang);
    REQUIRE(listed.status == 0);
    std::string first_gpu, first_cpu;
    const nlohmann::json stats = nlohmann::json::parse(listed.out);
    for (const nlohmann::json& d : stats["devices"]) {
        const std::string type = d.value("type", ""), name = d.value("name", "");
        if (type == "GPU" && first_gpu.empty()) first_gpu = name;
        if (type == "CPU" && first_cpu.empty()) first_cpu = name;
    }
    if (first_gpu.empty() && first_cpu.empty()) {
        MESSAGE("skipped: no OpenCL device here");
        return;
    }
    const fs::path dir = fresh_temp_dir("messages-device");
    const fs::path obj = write_text_file(dir / "tri.obj", kTriangle);
    const std::string said = "no OpenCL GPU found: kdray runs on the CPU device";
    // The OpenCL builder (the reference tracer: one kernel set to compile) on each device.
    auto run_on = [&](const std::string& out, std::vector<std::string> device) {
        std::vector<std::string> args = {"render", obj.string(), "-o",       (dir / out).string(),
                                         "--size", "8x6",        "--tracer", "reference"};
        args.insert(args.end(), device.begin(), device.end());
        return run_kdray(args, kNoHang);
    };
    for (const char* type : {"gpu", "GPU", "cpu"}) {
        CAPTURE(type);
        const std::string expected = std::string(type) == "cpu" ? first_cpu : first_gpu;
        const CommandResult r = run_on(type, {"--device", type});
        INFO("stderr: " << r.err);
        if (!expected.empty()) {
            REQUIRE(r.status == 0);
            CHECK(read_json(dir / type / "stats.json")["builder"].get<std::string>() ==
                  "opencl on " + expected);
        } else {
            check_error(r, 1, {"no OpenCL device of type GPU here; the devices are"});
        }
        // A device asked for is not announced as a fallback.
        CHECK(r.err.find(said) == std::string::npos);
    }
    const CommandResult chosen = run_on("default", {});
    INFO("stderr: " << chosen.err);
    REQUIRE(chosen.status == 0);
    CHECK((chosen.err.find(said + " '" + first_cpu + "'") != std::string::npos) ==
          first_gpu.empty());
    fs::remove_all(dir);
}

TEST_CASE("a scene whose materials reflect ambient light, rendered without any, is told so") {
    const fs::path dir = fresh_temp_dir("messages-ambient");
    write_text_file(dir / "m.mtl", "newmtl lit\nKd 0.5 0.5 0.5\nKa 0.3 0.3 0.3\n");
    const fs::path obj =
        write_text_file(dir / "tri.obj", std::string("mtllib m.mtl\nusemtl lit\n") + kTriangle);
    const CommandResult none = render(obj, dir / "none", {});
    REQUIRE(none.status == 0);
    CHECK(none.err.find("no ambient term: the render file has no ambient light, though material "
                        "'lit' reflects it (Ka > 0)") != std::string::npos);
    CHECK(read_json(dir / "none" / "stats.json")["frames"][0]["effects"]["ambient_unlit"] == true);
    // With ambient light there is nothing to say, and the term is simulated.
    const fs::path render_file =
        write_text_file(dir / "render.json", "{\"ambient\": [0.2, 0.2, 0.2]}");
    const CommandResult lit = render(obj, dir / "lit", {"--render-file", render_file.string()});
    REQUIRE(lit.status == 0);
    CHECK(lit.err.find("no ambient term") == std::string::npos);
    CHECK(read_json(dir / "lit" / "stats.json")["frames"][0]["effects"]["ambient"] == true);
    CHECK(read_json(dir / "lit" / "stats.json")["frames"][0]["effects"]["ambient_unlit"] == false);
    fs::remove_all(dir);
}
