// test_bad_input.cpp — bad input as a user of the command line meets it: broken OBJ and render
// files, impossible cameras, a missing file or device, a missing argument. Each case runs the
// kdray binary and checks what the user sees: the exit status (1 for bad input, 2 for usage),
// exactly one `kdray: error: ...` line on stderr that names the file and the problem, and no image
// or stats.json left behind. Warnings (a missing MTL file) are the exception: the run succeeds,
// says so on stderr and records the warning in stats.json.
#include <doctest/doctest.h>

#include <algorithm>
#include <cstdlib>
#include <filesystem>
#include <fstream>
#include <initializer_list>
#include <string>
#include <vector>

#include <nlohmann/json.hpp>

#include "tests/support.h"

namespace fs = std::filesystem;
using namespace kdray::test;

namespace {

const char* kTriangleObj = "v 0 0 0\nv 1 0 0\nv 0 1 0\nf 1 2 3\n";

/// A render file with a valid camera, light and size; cases replace one field of it.
std::string render_json(
    const std::string& image = R"({"width": 16, "height": 12})",
    const std::string& camera =
        R"({"position": [0.3, 0.3, 3], "look_at": [0.3, 0.3, 0], "up": [0, 1, 0], "fov_y": 45})") {
    return R"({"image": )" + image + R"(, "camera": )" + camera +
           R"(, "lights": [{"type": "point", "position": [0, 2, 2], "intensity": [5, 5, 5]}]})";
}

/// The output folder holds no image, AOV or stats.json (it may not exist at all).
void check_nothing_written(const fs::path& out) {
    CHECK_FALSE(fs::exists(out / "stats.json"));
    if (!fs::exists(out)) return;
    for (const auto& entry : fs::directory_iterator(out))
        CHECK_MESSAGE(false, "left behind: " << entry.path().string());
}

/// Exit status `status` and stderr exactly one line "kdray: error: ..." holding every one of
/// `mentions` (the file, the field, the problem).
/// `kdray render OBJ -o OUT [--camera RENDER] ...` with the reference builder and tracer.
CommandResult render(const fs::path& obj, const fs::path& out, const fs::path& camera = {},
                     std::vector<std::string> extra = {}) {
    std::vector<std::string> args = {"render",     obj.string(), "-o",
                                     out.string(), "--builder",  "reference",
                                     "--tracer",   "reference",  "-q"};
    if (!camera.empty()) args.insert(args.end(), {"--camera", camera.string()});
    args.insert(args.end(), extra.begin(), extra.end());
    return run_kdray(args);
}

}  // namespace

TEST_CASE("bad OBJ files: one error line naming the file and the problem, nothing written") {
    const fs::path dir = fresh_temp_dir("bad-input-obj");
    const fs::path out = dir / "out";

    SUBCASE("garbage bytes (a binary file given as OBJ)") {
        const fs::path obj =
            write_text_file(dir / "garbage.obj", std::string("v 0 0 0\n\x7f"
                                                             "ELF\x02\x01\x01\x00\xff\xfe",
                                                             18));
        const CommandResult r = render(obj, out);
        check_error(r, 1, {"garbage.obj:2", "not a text OBJ file"});
        // The byte is shown escaped (\x7f), never raw on the user's terminal.
        CHECK(std::none_of(r.err.begin(), r.err.end() - 1, [](char c) {
            return static_cast<unsigned char>(c) < 0x20 || static_cast<unsigned char>(c) >= 0x7f;
        }));
    }
    SUBCASE("an empty file") {
        const fs::path obj = write_text_file(dir / "empty.obj", "");
        check_error(render(obj, out), 1, {"empty.obj", "no triangles"});
    }
    SUBCASE("vertices but no faces") {
        const fs::path obj = write_text_file(dir / "points.obj", "v 0 0 0\nv 1 0 0\nv 0 1 0\n");
        check_error(render(obj, out), 1, {"points.obj", "no triangles"});
    }
    SUBCASE("a face index past the last vertex") {
        const fs::path obj = write_text_file(dir / "range.obj", "v 0 0 0\nv 1 0 0\nf 1 2 3\n");
        check_error(render(obj, out), 1, {"range.obj:3", "out of range"});
    }
    SUBCASE("a missing OBJ file") {
        check_error(render(dir / "missing.obj", out), 1, {"missing.obj", "no such file"});
    }
    SUBCASE("a folder given as the OBJ file") {
        fs::create_directories(dir / "folder.obj");
        check_error(render(dir / "folder.obj", out), 1, {"folder.obj", "folder"});
    }
    SUBCASE("a glob that matches nothing") {
        check_error(render(dir / "frame_*.obj", out), 1, {"frame_*.obj", "no file matches"});
    }
    SUBCASE("kdray build on garbage") {
        const fs::path obj = write_text_file(dir / "garbage.obj", "\x01\x02\x03");
        check_error(run_kdray({"build", obj.string(), "--builder", "reference"}), 1,
                    {"garbage.obj:1", "unexpected byte"});
    }
    check_nothing_written(out);
    fs::remove_all(dir);
}

TEST_CASE("a missing MTL file is one warning line, exit 0, and recorded in stats.json") {
    const fs::path dir = fresh_temp_dir("bad-input-mtl");
    const fs::path obj = write_text_file(
        dir / "scene.obj", std::string("mtllib nowhere.mtl\nusemtl red\n") + kTriangleObj);
    const fs::path out = dir / "out";
    const CommandResult r = render(obj, out);
    INFO("stderr: " << r.err);
    REQUIRE(r.status == 0);
    CHECK(r.err.rfind("kdray: warning: ", 0) == 0);
    CHECK(r.err.find("nowhere.mtl") != std::string::npos);
    CHECK(r.err.find("error") == std::string::npos);
    CHECK(fs::exists(out / "scene.png"));
    const nlohmann::json stats = read_json(out / "stats.json");
    const nlohmann::json warnings = stats["frames"][0]["scene"]["warnings"];
    REQUIRE(warnings.size() >= 1);
    CHECK(warnings[0].get<std::string>().find("nowhere.mtl") != std::string::npos);
    fs::remove_all(dir);
}

TEST_CASE("a texture the MTL file names but that does not exist does not stop the render") {
    // A missing map_Kd is a warning naming the material, the statement, the file and where it
    // was looked for; the material renders with its Kd.
    const fs::path dir = fresh_temp_dir("bad-input-texture");
    write_text_file(dir / "scene.mtl",
                    "newmtl red\nKd 1 0 0\nmap_Kd no_such_texture.png\n"
                    "newmtl cased\nKd 1 1 1\nmap_Kd CHECKER.png\n");
    // Found though its case differs (Sponza's MTL names 00_SKAP.JPG for 00_skap.JPG).
    kdray::Image checker;
    checker.width = checker.height = 2;
    checker.rgb.assign(12, 0.5f);
    kdray::write_image(dir / "checker.png", checker);
    const fs::path obj = write_text_file(
        dir / "scene.obj", std::string("mtllib scene.mtl\nusemtl red\n") + kTriangleObj +
                               "usemtl cased\nv 0 0 1\nv 1 0 1\nv 0 1 1\nf 4 5 6\n");
    const fs::path out = dir / "out";
    const CommandResult r = render(obj, out);
    INFO("stderr: " << r.err);
    CHECK(r.status == 0);
    CHECK(r.err.find("kdray: error") == std::string::npos);
    CHECK(std::count(r.err.begin(), r.err.end(), '\n') == 1);
    CHECK(r.err.find("kdray: warning: " + obj.string() +
                     ": material 'red': map_Kd 'no_such_texture.png' not found in " + dir.string() +
                     "; it renders untextured") != std::string::npos);
    CHECK(fs::exists(out / "scene.png"));
    CHECK(fs::exists(out / "stats.json"));
    // The same scene named without its folder, from inside it: the textures are looked up in
    // the current directory, and the warning says so.
    const std::string command = "cd '" + dir.string() + "' && '" + KDRAY_BINARY +
                                "' render scene.obj -o here --builder reference --tracer "
                                "reference -q 2>here.err";
    CHECK(std::system(command.c_str()) == 0);
    const std::string here = read_file(dir / "here.err");
    INFO("stderr from the folder: " << here);
    CHECK(std::count(here.begin(), here.end(), '\n') == 1);
    CHECK(here.find("map_Kd 'no_such_texture.png' not found in the current directory;") !=
          std::string::npos);
    fs::remove_all(dir);
}

TEST_CASE("bad render files: one error line naming the file and the field, nothing written") {
    const fs::path dir = fresh_temp_dir("bad-input-render");
    const fs::path obj = write_text_file(dir / "scene.obj", kTriangleObj);
    const fs::path out = dir / "out";
    auto run = [&](const std::string& text) {
        return render(obj, out, write_text_file(dir / "render.json", text));
    };

    SUBCASE("truncated JSON") {
        check_error(run(render_json().substr(0, 40)), 1, {"render.json", "invalid JSON"});
    }
    SUBCASE("an empty file") {
        check_error(run(""), 1, {"render.json", "invalid JSON"});
    }
    SUBCASE("not an object") {
        check_error(run("[1, 2, 3]"), 1, {"render.json", "must be a JSON object"});
    }
    SUBCASE("a string where a number belongs") {
        check_error(run(render_json(R"({"width": "16", "height": 12})")), 1,
                    {"render.json", "image.width", "must be an integer"});
    }
    SUBCASE("a float where an integer belongs") {
        check_error(run(render_json(R"({"width": 16.5, "height": 12})")), 1,
                    {"render.json", "image.width", "must be an integer"});
    }
    SUBCASE("a vector of two numbers") {
        check_error(run(render_json(R"({"width": 16, "height": 12})",
                                    R"({"position": [0, 0], "look_at": [0, 0, -1]})")),
                    1, {"render.json", "camera.position", "array of 3 numbers"});
    }
    SUBCASE("an unknown field at the top") {
        check_error(run(R"({"imag": {"width": 16}})"), 1, {"render.json", "unknown field 'imag'"});
    }
    SUBCASE("an unknown field inside the camera") {
        check_error(run(render_json(R"({"width": 16, "height": 12})",
                                    R"({"position": [0, 0, 3], "fov": 45})")),
                    1, {"render.json", "unknown field 'camera.fov'"});
    }
    SUBCASE("zero width") {
        check_error(run(render_json(R"({"width": 0, "height": 12})")), 1,
                    {"render.json", "image.width", "between 1 and"});
    }
    SUBCASE("negative height") {
        check_error(run(render_json(R"({"width": 16, "height": -12})")), 1,
                    {"render.json", "image.height", "between 1 and"});
    }
    SUBCASE("an absurd size") {
        check_error(run(render_json(R"({"width": 16, "height": 100000000000})")), 1,
                    {"render.json", "image.height", "between 1 and"});
    }
    SUBCASE("up parallel to the view direction") {
        check_error(
            run(render_json(R"({"width": 16, "height": 12})",
                            R"({"position": [0, 0, 3], "look_at": [0, 0, 0], "up": [0, 0, -2]})")),
            1, {"render.json", "camera.up", "parallel to the view direction"});
    }
    SUBCASE("look_at at the camera position") {
        check_error(run(render_json(R"({"width": 16, "height": 12})",
                                    R"({"position": [1, 1, 1], "look_at": [1, 1, 1]})")),
                    1, {"render.json", "camera.look_at", "must differ"});
    }
    SUBCASE("fov 0") {
        check_error(run(render_json(R"({"width": 16, "height": 12})",
                                    R"({"position": [0, 0, 3], "fov_y": 0})")),
                    1, {"render.json", "camera.fov_y", "between 0 and 180"});
    }
    SUBCASE("fov 180") {
        check_error(run(render_json(R"({"width": 16, "height": 12})",
                                    R"({"position": [0, 0, 3], "fov_y": 180})")),
                    1, {"render.json", "camera.fov_y", "between 0 and 180"});
    }
    SUBCASE("a keyframe without a frame number") {
        check_error(
            run(render_json(R"({"width": 16, "height": 12})", R"([{"position": [0, 0, 3]}])")), 1,
            {"render.json", "camera[0].frame", "is missing"});
    }
    SUBCASE("a number too large for a float") {
        check_error(run(R"({"background": [1e39, 0, 0]})"), 1,
                    {"render.json", "background[0]", "finite number"});
    }
    SUBCASE("a missing --camera file") {
        check_error(render(obj, out, dir / "no_such_render.json"), 1,
                    {"no_such_render.json", "cannot open"});
    }
    SUBCASE("a folder given as the --camera file") {
        fs::create_directories(dir / "folder.json");
        check_error(render(obj, out, dir / "folder.json"), 1, {"folder.json", "cannot open"});
    }
    check_nothing_written(out);
    fs::remove_all(dir);
}

TEST_CASE("an OpenCL device that does not exist: exit 1 and the devices listed") {
    const fs::path dir = fresh_temp_dir("bad-input-device");
    const fs::path obj = write_text_file(dir / "scene.obj", kTriangleObj);
    const fs::path out = dir / "out";
    SUBCASE("kdray build") {
        const CommandResult r = run_kdray({"build", obj.string(), "--device", "99"});
        INFO("stderr: " << r.err);
        CHECK(r.status == 1);
        CHECK(r.err.rfind("kdray: error: ", 0) == 0);
        CHECK(r.err.find("'99'") != std::string::npos);
        // The message lists the devices there are ("0: NAME (...)"), so the user can pick one.
        CHECK(r.err.find("0: ") != std::string::npos);
    }
    SUBCASE("kdray render") {
        const CommandResult r = run_kdray({"render", obj.string(), "-o", out.string(), "--device",
                                           "99", "--builder", "opencl", "-q"});
        INFO("stderr: " << r.err);
        CHECK(r.status == 1);
        CHECK(r.err.rfind("kdray: error: ", 0) == 0);
        CHECK(r.err.find("'99'") != std::string::npos);
        CHECK(r.err.find("0: ") != std::string::npos);
    }
    check_nothing_written(out);
    fs::remove_all(dir);
}

// The device list once came one device per line, with a trailing newline: every other error is
// one line, which scripts that grep `kdray: error:` rely on. The devices now share the line.
TEST_CASE("an OpenCL device that does not exist is one error line") {
    const fs::path dir = fresh_temp_dir("bad-input-device-line");
    const fs::path obj = write_text_file(dir / "scene.obj", kTriangleObj);
    check_error(run_kdray({"build", obj.string(), "--device", "99"}), 1, {"'99'", "0: "});
    fs::remove_all(dir);
}

TEST_CASE("missing arguments are usage errors: exit 2, one line, nothing written") {
    const fs::path dir = fresh_temp_dir("bad-input-usage");
    const fs::path obj = write_text_file(dir / "scene.obj", kTriangleObj);
    const fs::path out = dir / "out";
    SUBCASE("render without frames") {
        check_error(run_kdray({"render", "-o", out.string()}), 2, {"frames"});
    }
    SUBCASE("render without an output folder") {
        check_error(run_kdray({"render", obj.string()}), 2, {"--output"});
    }
    SUBCASE("build without a scene") {
        check_error(run_kdray({"build"}), 2, {"scene"});
    }
    SUBCASE("no command") {
        check_error(run_kdray({}), 2, {"subcommand"});
    }
    SUBCASE("--camera without its value") {
        check_error(run_kdray({"render", obj.string(), "-o", out.string(), "--camera"}), 2,
                    {"--camera"});
    }
    check_nothing_written(out);
    fs::remove_all(dir);
}
