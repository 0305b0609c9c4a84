// test_cli_resume_guard.cpp — a run into a folder whose stats.json records frames made with other
// image settings, through the binary: refused before the device opens, naming each difference;
// --overwrite replacing those records (and, with --skip-existing, rendering their frames again);
// --mixed rendering beside them, the top-level "image" then listing each group's frames instead of
// claiming one size. The image sizes are read from the PNGs themselves, not from stats.json.
#include <doctest/doctest.h>

#include <cstdint>
#include <filesystem>
#include <string>
#include <utility>
#include <vector>

#include <nlohmann/json.hpp>

#include "tests/support.h"

namespace fs = std::filesystem;
using namespace kdray;
using namespace kdray::test;

namespace {

/// `kdray render FRAMES -o OUT EXTRA... -q` with the reference builder and tracer (fast, and no
/// device to open) unless EXTRA names a builder.
CommandResult render(const std::vector<std::string>& frames, const fs::path& out,
                     const std::vector<std::string>& extra) {
    std::vector<std::string> args = {"render"};
    args.insert(args.end(), frames.begin(), frames.end());
    args.insert(args.end(), {"-o", out.string(), "-q"});
    bool builder = false;
    for (const std::string& a : extra) builder = builder || a == "--builder";
    if (!builder) args.insert(args.end(), {"--builder", "reference", "--tracer", "reference"});
    args.insert(args.end(), extra.begin(), extra.end());
    return run_kdray(args, 300);
}

/// A PNG's width and height, from its IHDR chunk (bytes 16 to 23, big-endian).
std::pair<int, int> png_size(const fs::path& path) {
    const std::string png = read_file(path);
    REQUIRE(png.size() > 24);
    auto word = [&](std::size_t at) {
        std::uint32_t v = 0;
        for (std::size_t k = 0; k < 4; ++k) v = (v << 8) | std::uint8_t(png[at + k]);
        return int(v);
    };
    return {word(16), word(20)};
}

std::vector<int> frame_numbers(const nlohmann::json& stats) {
    std::vector<int> numbers;
    for (const auto& f : stats["frames"]) numbers.push_back(f["frame"].get<int>());
    return numbers;
}

}  // namespace

TEST_CASE("a resume at another size is refused before the device opens, naming the differences") {
    // The case: --frames 0:1 at 64x48, then all four at 128x96 and 4 spp with
    // --skip-existing, which left two sizes side by side.
    const fs::path out = fresh_temp_dir("guard-resume") / "out";
    REQUIRE(
        render(anim_frames(4), out, {"--frames", "0:1", "--size", "64x48", "--builder", "opencl"})
            .status == 0);
    const std::string before = read_file(out / "stats.json");
    // A device that does not exist: the guard must speak before kdray looks for one.
    const CommandResult r =
        render(anim_frames(4), out,
               {"--size", "128x96", "--spp", "4", "--skip-existing", "--builder", "opencl",
                "--tracer", "opencl", "--device", "no-such-device"});
    check_error(r, 2,
                {out.string() + " holds 2 frame(s) rendered at 64x48, spp 1; this run: 128x96, "
                                "spp 4",
                 "--overwrite", "--mixed"});
    CHECK(r.err.find("device") == std::string::npos);
    CHECK(read_file(out / "stats.json") == before);
    CHECK(!fs::exists(out / "frame_002.png"));
    CHECK(png_size(out / "frame_000.png") == std::pair{64, 48});

    // The same settings resume as before.
    REQUIRE(
        render(anim_frames(4), out, {"--size", "64x48", "--skip-existing", "--builder", "opencl"})
            .status == 0);
    CHECK(read_json(out / "stats.json")["frames"].size() == 4);
}

TEST_CASE("one frame re-rendered into an animation's folder at another size is refused") {
    const fs::path out = fresh_temp_dir("guard-one-frame") / "out";
    REQUIRE(render(anim_frames(3), out, {"--size", "40x30"}).status == 0);
    const CommandResult r = render(anim_frames(3), out, {"--frames", "1:1", "--size", "64x48"});
    check_error(r, 2, {"holds 3 frame(s) rendered at 40x30; this run: 64x48"});
    CHECK(png_size(out / "frame_001.png") == std::pair{40, 30});
    // Every setting that changes the image is named, each with both values.
    check_error(
        render(anim_frames(3), out, {"--frames", "1:1", "--size", "40x30", "--ray-depth", "2"}), 2,
        {"rendered with ray depth 4; this run: ray depth 2"});
    check_error(
        render(anim_frames(3), out, {"--frames", "1:1", "--size", "40x30", "--exposure", "1"}), 2,
        {"rendered with exposure 0.0; this run: exposure 1.0"});
    check_error(render(anim_frames(3), out, {"--frames", "1:1", "--size", "40x30", "--spp", "2"}),
                2, {"rendered with spp 1; this run: spp 2"});
}

TEST_CASE("one frame of an animation rendered alone builds at another quality: refused") {
    // The OpenCL builder's default quality follows the inputs: low for an animation, high for
    // one scene. The frame rendered alone into the animation's folder was built at high.
    const fs::path out = fresh_temp_dir("guard-quality") / "out";
    REQUIRE(render(anim_frames(2), out, {"--size", "24x18", "--builder", "opencl"}).status == 0);
    check_error(render({anim_frames(2)[1]}, out, {"--size", "24x18", "--builder", "opencl"}), 2,
                {"holds 2 frame(s) rendered with quality low; this run: quality high"});
    // --frames keeps the whole run's inputs, so its quality: accepted.
    REQUIRE(
        render(anim_frames(2), out, {"--frames", "1:1", "--size", "24x18", "--builder", "opencl"})
            .status == 0);
}

TEST_CASE(
    "--overwrite replaces the other settings' records; with --skip-existing it renders them") {
    const fs::path out = fresh_temp_dir("guard-overwrite") / "out";
    REQUIRE(render(anim_frames(4), out, {"--frames", "0:1", "--size", "64x48"}).status == 0);
    REQUIRE(render(anim_frames(4), out, {"--frames", "2:3", "--size", "32x24", "--mixed"}).status ==
            0);
    // Frames 2 and 3 are at 32x24 already: skipped; 0 and 1 are rendered again.
    const CommandResult r =
        render(anim_frames(4), out,
               {"--size", "32x24", "--skip-existing", "--overwrite", "--log-level", "info"});
    REQUIRE_MESSAGE(r.status == 0, r.err);
    CHECK(r.err.find("skipping 2 of 4 frame(s)") != std::string::npos);
    const nlohmann::json stats = read_json(out / "stats.json");
    CHECK(stats["runs"].back()["frames_rendered"] == nlohmann::json({0, 1}));
    CHECK(frame_numbers(stats) == std::vector<int>{0, 1, 2, 3});
    CHECK(stats["image"] == nlohmann::json({{"width", 32}, {"height", 24}, {"spp", 1}}));
    for (int f = 0; f < 4; ++f)
        CHECK(png_size(out / ("frame_00" + std::to_string(f) + ".png")) == std::pair{32, 24});

    // Without --skip-existing, the records of frames it does not render are dropped too: the
    // file lists only what was made with its settings.
    REQUIRE(
        render(anim_frames(4), out, {"--frames", "3:3", "--size", "16x12", "--overwrite"}).status ==
        0);
    const nlohmann::json replaced = read_json(out / "stats.json");
    CHECK(frame_numbers(replaced) == std::vector<int>{3});
    CHECK(replaced["image"] == nlohmann::json({{"width", 16}, {"height", 12}, {"spp", 1}}));
    CHECK(replaced["summary"]["frames"] == 1);

    check_error(render(anim_frames(4), out, {"--overwrite", "--mixed"}), 2,
                {"--overwrite", "--mixed"});
}

TEST_CASE("--mixed renders beside the others; stats.json's image lists each group's frames") {
    const fs::path out = fresh_temp_dir("guard-mixed") / "out";
    REQUIRE(render(anim_frames(4), out, {"--frames", "0:1", "--size", "64x48"}).status == 0);
    REQUIRE(
        render(anim_frames(4), out, {"--frames", "2:3", "--size", "32x24", "--spp", "2", "--mixed"})
            .status == 0);
    CHECK(png_size(out / "frame_000.png") == std::pair{64, 48});
    CHECK(png_size(out / "frame_003.png") == std::pair{32, 24});
    const nlohmann::json image = read_json(out / "stats.json")["image"];
    INFO(image.dump());
    CHECK(!image.contains("width"));
    CHECK(!image.contains("height"));
    CHECK(!image.contains("spp"));
    CHECK(image["mixed"] == nlohmann::json({"size", "spp"}));
    REQUIRE(image["groups"].size() == 2);
    CHECK(image["groups"][0]["width"] == 64);
    CHECK(image["groups"][0]["spp"] == 1);
    CHECK(image["groups"][0]["frames"] == nlohmann::json({0, 1}));
    CHECK(image["groups"][1]["width"] == 32);
    CHECK(image["groups"][1]["spp"] == 2);
    CHECK(image["groups"][1]["frames"] == nlohmann::json({2, 3}));
    // A run of either group's settings into the mixed folder is refused over the other group.
    check_error(render(anim_frames(4), out, {"--size", "32x24", "--spp", "2", "--skip-existing"}),
                2, {"holds 2 frame(s) rendered at 64x48, spp 1; this run: 32x24, spp 2"});
}

TEST_CASE("a stats.json from before runs stated exposure and quality is held to what it states") {
    const fs::path out = fresh_temp_dir("guard-old-file") / "out";
    REQUIRE(render(anim_frames(2), out, {"--size", "24x18"}).status == 0);
    nlohmann::json stats = read_json(out / "stats.json");
    for (nlohmann::json* run : {&stats, &stats["runs"][0]}) {
        run->erase("exposure");
        run->erase("quality");
    }
    write_text_file(out / "stats.json", stats.dump());
    // What it does not state is not held against it; what it states is.
    CHECK(render(anim_frames(2), out, {"--size", "24x18", "--exposure", "1", "--frames", "1:1"})
              .status == 0);
    check_error(render(anim_frames(2), out, {"--size", "48x36", "--frames", "1:1"}), 2,
                {"rendered at 24x18", "this run: 48x36"});
}
