// test_cli_warnings.cpp — issue #31, item 3: a run prints each warning's cause once however many
// frames repeat it, ends with a summary, lists the causes in stats.json's run record, and
// --strict makes any warning an error before the frame builds. Each runs the binary.
#include <doctest/doctest.h>

#include <filesystem>
#include <string>

#include "tests/support.h"

namespace fs = std::filesystem;
using namespace kdray::test;

namespace {

constexpr int kNoHang = 120;

/// How often `needle` occurs in `text`.
std::size_t occurrences(const std::string& text, const std::string& needle) {
    std::size_t n = 0;
    for (std::size_t at = text.find(needle); at != std::string::npos;
         at = text.find(needle, at + needle.size()))
        ++n;
    return n;
}

/// `frames` OBJ frames sharing one MTL whose material 'skin' names the missing 'gone.png' by both
/// map_Kd and map_Ka, and a map_Ks that kdray does not simulate: two causes a frame, as
/// Sponza's frames share their MTL's warnings.
fs::path write_animation(const fs::path& dir, int frames) {
    write_text_file(dir / "shared.mtl",
                    "newmtl skin\nKd 0.5 0.5 0.5\nKa 0.1 0.1 0.1\nmap_Kd gone.png\n"
                    "map_Ka gone.png\nmap_Ks shine.png\n");
    for (int i = 0; i < frames; ++i)
        write_text_file(dir / ("frame_" + std::to_string(i) + ".obj"),
                        "mtllib shared.mtl\nv 0 0 0\nv 1 0 " + std::to_string(0.1 * i) +
                            "\nv 0 1 0\nvt 0 0\nvt 1 0\nvt 0 1\nusemtl skin\nf 1/1 2/2 3/3\n");
    return write_text_file(dir / "cam.json", kSmallRender);
}

std::vector<std::string> render_args(const fs::path& dir, const fs::path& out) {
    return {"render",    (dir / "frame_*.obj").string(),
            "-o",        out.string(),
            "--camera",  (dir / "cam.json").string(),
            "--builder", "reference",
            "--tracer",  "reference"};
}

}  // namespace

TEST_CASE("a warning that every frame repeats is printed once, summarised and counted") {
    const fs::path dir = fresh_temp_dir("warnings-once");
    write_animation(dir, 3);
    const fs::path out = dir / "out";
    const CommandResult r = run_kdray(render_args(dir, out), kNoHang);
    INFO("stderr: " << r.err);
    REQUIRE(r.status == 0);
    // Two causes, each on one line, naming the first frame that gave it.
    CHECK(occurrences(r.err, "kdray: warning: ") == 2);
    CHECK(occurrences(r.err, "'gone.png' not found") == 1);
    CHECK(occurrences(r.err, "map_Ks 'shine.png' is not simulated") == 1);
    // The texture named by map_Kd and map_Ka is one warning naming both statements.
    CHECK(r.err.find((dir / "frame_0.obj").string() +
                     ": material 'skin': map_Kd and map_Ka 'gone.png' not found in ") !=
          std::string::npos);
    CHECK(r.err.find("kdray: 6 warnings (2 kinds) in 3 frames; each printed once\n") !=
          std::string::npos);

    // The run's record lists each cause with the frames that gave it; the folder's top level,
    // which speaks for every run, does not.
    const nlohmann::json stats = read_json(out / "stats.json");
    REQUIRE(stats["runs"].size() == 1);
    const nlohmann::json& warnings = stats["runs"][0]["warnings"];
    REQUIRE(warnings.size() == 2);
    for (const nlohmann::json& w : warnings) {
        CHECK(w["count"] == 3);
        CHECK(w["first_frame"] == 0);
    }
    CHECK_FALSE(stats.contains("warnings"));
    // Each frame's record keeps its own scene's warnings, as before.
    REQUIRE(stats["frames"].size() == 3);
    CHECK(stats["frames"][2]["scene"]["warnings"].size() == 2);
    fs::remove_all(dir);
}

TEST_CASE("a run without warnings prints no summary and records none") {
    const fs::path dir = fresh_temp_dir("warnings-none");
    write_text_file(dir / "frame_0.obj", "v 0 0 0\nv 1 0 0\nv 0 1 0\nf 1 2 3\n");
    write_text_file(dir / "cam.json", kSmallRender);
    const fs::path out = dir / "out";
    const CommandResult r = run_kdray(render_args(dir, out), kNoHang);
    INFO("stderr: " << r.err);
    REQUIRE(r.status == 0);
    CHECK(r.err.find("kdray: warning") == std::string::npos);
    CHECK(r.err.find(" warnings (") == std::string::npos);
    CHECK_FALSE(read_json(out / "stats.json")["runs"][0].contains("warnings"));
    fs::remove_all(dir);
}

TEST_CASE("--strict: a scene's warning fails render and build with exit 1 before any output") {
    const fs::path dir = fresh_temp_dir("warnings-strict");
    write_animation(dir, 2);
    const fs::path out = dir / "out";
    std::vector<std::string> args = render_args(dir, out);
    args.push_back("--strict");
    const CommandResult r = run_kdray(args, kNoHang);
    INFO("stderr: " << r.err);
    CHECK(r.status == 1);
    CHECK(r.err.find("kdray: error: --strict: ") != std::string::npos);
    CHECK(r.err.find("(and 1 more warning(s))") != std::string::npos);
    // The first frame's scene failed before it was built: nothing rendered, nothing recorded.
    CHECK_FALSE(fs::exists(out / "frame_0.png"));
    CHECK_FALSE(fs::exists(out / "stats.json"));

    const fs::path tree = dir / "frame_0.kdt";
    const CommandResult b = run_kdray({"build", (dir / "frame_0.obj").string(), "--builder",
                                       "reference", "-o", tree.string(), "--strict"},
                                      kNoHang);
    INFO("build stderr: " << b.err);
    CHECK(b.status == 1);
    CHECK(b.err.find("kdray: error: --strict: ") != std::string::npos);
    CHECK(occurrences(b.err, "kdray: warning: ") == 2);
    CHECK_FALSE(fs::exists(tree));

    // Without --strict the same build succeeds and writes the tree.
    const CommandResult ok = run_kdray(
        {"build", (dir / "frame_0.obj").string(), "--builder", "reference", "-o", tree.string()},
        kNoHang);
    CHECK(ok.status == 0);
    CHECK(fs::exists(tree));
    fs::remove_all(dir);
}
