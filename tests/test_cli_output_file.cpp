// test_cli_output_file.cpp — `kdray render -o FILE.png|.jpg|.tif|.exr` writes one frame's image
// exactly there, in the format its extension picks (`--name shot.jpg` too), and refuses several
// frames; `-o DIR/`, an existing folder and a name without an image extension stay folders. The
// 8-bit images are checked against the linear EXR of the same frame through the sRGB curve, not
// against their own encoder.
#include <doctest/doctest.h>

#include <algorithm>
#include <cmath>
#include <filesystem>
#include <string>
#include <vector>

#include "core/io/image_codec.h"
#include "tests/support.h"

namespace fs = std::filesystem;
using namespace kdray;
using namespace kdray::test;

namespace {

const std::string kRoom = (source_dir() / "testdata" / "cornell" / "room.obj").string();

/// `kdray render ROOM -o OUT` at 40x30 on the reference builder and tracer, with `extra`.
CommandResult render_room(const std::string& out, std::vector<std::string> extra = {}) {
    std::vector<std::string> args = {"render",   kRoom,       "-o",        out,
                                     "--size",   "40x30",     "--builder", "reference",
                                     "--tracer", "reference", "-q"};
    args.insert(args.end(), extra.begin(), extra.end());
    return run_kdray(args, 300);
}

/// The names in `dir`, sorted.
std::vector<std::string> names_in(const fs::path& dir) {
    std::vector<std::string> names;
    for (const auto& entry : fs::directory_iterator(dir))
        names.push_back(entry.path().filename().string());
    std::sort(names.begin(), names.end());
    return names;
}

/// The 8-bit value of a linear one by the default display transform (Narkowicz's ACES fit,
/// conventions.md's "filmic") and the sRGB transfer function (IEC 61966-2-1).
float srgb(float linear) {
    const double x = std::max(linear, 0.0f);
    const double filmic = x >= 8 ? 1.0 : (x * (2.51 * x + 0.03)) / (x * (2.43 * x + 0.59) + 0.14);
    const float v = float(std::min(filmic, 1.0));
    return v <= 0.0031308f ? 12.92f * v : 1.055f * std::pow(v, 1.0f / 2.4f) - 0.055f;
}

}  // namespace

TEST_CASE("render -o FILE writes that one image in its extension's format, and nothing else") {
    const fs::path dir = fresh_temp_dir("cli-output-file");
    // The linear image, from which every 8-bit one must follow by the sRGB curve.
    const CommandResult exr_run = render_room((dir / "exr" / "room.exr").string());
    REQUIRE_MESSAGE(exr_run.status == 0, exr_run.err);
    CHECK(names_in(dir / "exr") == std::vector<std::string>{"room.exr"});
    const DecodedImage linear = read_image(dir / "exr" / "room.exr");
    REQUIRE(linear.width == 40);
    REQUIRE(linear.height == 30);

    for (const std::string name : {"shot.png", "shot.tif", "shot.TIFF", "shot.jpg", "shot.jpeg"}) {
        CAPTURE(name);
        const fs::path out = dir / name / "deeper" / name;  // a folder made on the way
        const CommandResult r = render_room(out.string());
        REQUIRE_MESSAGE(r.status == 0, r.err);
        // No stats.json, no folder named after the file.
        CHECK(names_in(out.parent_path()) == std::vector<std::string>{name});
        REQUIRE(fs::is_regular_file(out));
        const DecodedImage image = read_image(out);
        REQUIRE(image.width == 40);
        REQUIRE(image.height == 30);
        CHECK(image.integer);
        // The file is what its extension says, not a PNG under another name.
        const std::string magic = read_file(out).substr(0, 4);
        const bool jpeg = name.find(".jp") != std::string::npos;
        if (jpeg)
            CHECK(magic.substr(0, 2) == "\xFF\xD8");
        else if (name.find(".png") != std::string::npos)
            CHECK(magic == "\x89PNG");
        else
            CHECK(magic == std::string("II*\0", 4));
        // Lossless ones to the 8-bit step; JPEG on average (block artefacts at the room's edges).
        double worst = 0, sum = 0;
        for (std::size_t p = 0; p < 40 * 30; ++p)
            for (int c = 0; c < 3; ++c) {
                const double d = std::fabs(image.values[p * image.channels + c] -
                                           srgb(linear.values[p * linear.channels + c]));
                worst = std::max(worst, d);
                sum += d;
            }
        if (jpeg)
            CHECK(sum / (40 * 30 * 3) < 0.02);
        else
            CHECK(worst <= 0.5 / 255 + 1e-6);
    }

    // TIFF is the same bytes every time (no time stamp), as PNG is.
    const fs::path again = dir / "again.tif";
    REQUIRE(render_room(again.string()).status == 0);
    CHECK(read_file(again) == read_file(dir / "shot.tif" / "deeper" / "shot.tif"));
    fs::remove_all(dir);
}

TEST_CASE("render -o FILE puts the AOV beside it, and stats.json only with --stats-json") {
    const fs::path dir = fresh_temp_dir("cli-output-file-aov");
    const CommandResult r = render_room((dir / "shot.jpg").string(), {"--aov", "--heatmap"});
    REQUIRE_MESSAGE(r.status == 0, r.err);
    CHECK(names_in(dir) == std::vector<std::string>{"shot.aov.exr", "shot.cost.png", "shot.jpg"});
    CHECK(read_exr(dir / "shot.aov.exr").find("Z") != nullptr);

    // Asked for, the record merges into the folder's stats.json as a folder run's would.
    const CommandResult with_stats = render_room((dir / "b.tif").string(), {"--stats-json"});
    REQUIRE_MESSAGE(with_stats.status == 0, with_stats.err);
    const nlohmann::json stats = read_json(dir / "stats.json");
    REQUIRE(stats["frames"].size() == 1);
    CHECK(stats["frames"][0]["image"] == "b.tif");

    // --skip-existing goes by the file when there is no stats.json.
    const auto written = fs::last_write_time(dir / "shot.jpg");
    const CommandResult skipped =
        render_room((dir / "shot.jpg").string(), {"--skip-existing", "--log-level", "info"});
    REQUIRE_MESSAGE(skipped.status == 0, skipped.err);
    CHECK(skipped.err.find("skipping 1 of 1") != std::string::npos);
    CHECK(fs::last_write_time(dir / "shot.jpg") == written);
    fs::remove_all(dir);
}

TEST_CASE("render -o FILE refuses several frames, naming how many, and writes nothing") {
    const fs::path dir = fresh_temp_dir("cli-output-file-frames");
    std::vector<std::string> args = {"render"};
    for (int i = 0; i < 3; ++i)
        args.push_back(
            (source_dir() / "testdata" / "anim" / ("frame_00" + std::to_string(i) + ".obj"))
                .string());
    for (const char* a : {"-o", "", "--builder", "reference", "--tracer", "reference"})
        args.push_back(a);
    args[5] = (dir / "anim.png").string();
    check_error(run_kdray(args, 120), 2, {"anim.png", "3 of the 3", "-o DIR/"});
    CHECK(names_in(dir).empty());
    // One of them selected is one image.
    args.insert(args.end(), {"--frames", "1:1", "-q"});
    const CommandResult one = run_kdray(args, 300);
    REQUIRE_MESSAGE(one.status == 0, one.err);
    CHECK(names_in(dir) == std::vector<std::string>{"anim.png"});
    fs::remove_all(dir);
}

TEST_CASE("render -o DIR/, an existing folder or a name without an image extension is a folder") {
    const fs::path dir = fresh_temp_dir("cli-output-folder");
    fs::create_directories(dir / "existing.png");
    for (const std::string out : {"slash.png/", "existing.png", "plain", "odd.obj"}) {
        CAPTURE(out);
        const CommandResult r = render_room((dir / out).string());
        REQUIRE_MESSAGE(r.status == 0, r.err);
        CHECK(fs::is_regular_file(dir / out / "room.png"));
        CHECK(fs::is_regular_file(dir / out / "stats.json"));
    }
    fs::remove_all(dir);
}

TEST_CASE("render --name shot.jpg writes shot.jpg, and contradictions are usage errors") {
    const fs::path dir = fresh_temp_dir("cli-output-name");
    const CommandResult r = render_room((dir / "out").string(), {"--name", "shot.jpg"});
    REQUIRE_MESSAGE(r.status == 0, r.err);
    CHECK(fs::is_regular_file(dir / "out" / "shot.jpg"));
    CHECK(!fs::exists(dir / "out" / "shot.jpg.png"));
    CHECK(read_file(dir / "out" / "shot.jpg").substr(0, 2) == "\xFF\xD8");
    CHECK(read_json(dir / "out" / "stats.json")["frames"][0]["image"] == "shot.jpg");
    // --format agrees with the extension, or one of them is wrong.
    CHECK(render_room((dir / "f").string(), {"--name", "a.jpg", "--format", "jpg"}).status == 0);
    check_error(render_room((dir / "g").string(), {"--name", "a.jpg", "--format", "png"}), 2,
                {"--name a.jpg", "jpg", "png"});
    check_error(render_room((dir / "h.png").string(), {"--format", "exr"}), 2, {"h.png", "exr"});
    check_error(render_room((dir / "i.png").string(), {"--name", "x"}), 2, {"i.png", "--name"});
    check_error(render_room((dir / "j").string(), {"--format", "gif"}), 2, {"--format"});
    CHECK(!fs::exists(dir / "g"));
    CHECK(!fs::exists(dir / "h.png"));
    fs::remove_all(dir);
}

TEST_CASE("render --render-file is the render file's option, --camera its old name") {
    const fs::path dir = fresh_temp_dir("cli-render-file");
    const fs::path render_file = write_text_file(dir / "render.json", kSmallRender);
    for (const char* option : {"--render-file", "--camera"}) {
        CAPTURE(option);
        const fs::path out = dir / (option + 2);
        const CommandResult r = render_room(out.string(), {option, render_file.string()});
        REQUIRE_MESSAGE(r.status == 0, r.err);
        CHECK(read_json(out / "stats.json")["render_file"] == render_file.string());
    }
    const CommandResult help = run_kdray({"render", "--help"});
    CHECK(help.out.find("--render-file,--camera") != std::string::npos);
    fs::remove_all(dir);
}
