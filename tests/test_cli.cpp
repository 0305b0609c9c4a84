// The kdray command line, run as a user runs it: what it prints, the files it writes (and does not
// write on bad input), and its exit status. Results are checked against the library run
// in-process and against brute force, never against the command's own earlier output.
#include <doctest/doctest.h>

#include <sys/wait.h>

#include <algorithm>
#include <filesystem>
#include <fstream>
#include <iterator>
#include <map>
#include <sstream>

#include <nlohmann/json.hpp>

#include "core/device/kd_render.h"
#include "core/io/image.h"
#include "core/io/image_codec.h"
#include "core/io/natural_order.h"
#include "core/render/camera.h"
#include "core/render/render_setup.h"
#include "core/tree/build_quality.h"
#include "core/tree/reference_builder.h"
#include "core/tree/tree_check.h"
#include "core/tree/tree_file.h"
#include "core/tree/tree_stats.h"
#include "tests/support.h"

namespace fs = std::filesystem;
using namespace kdray;
using namespace kdray::test;

namespace {

/// The parts of every frame's time in `stats` add up to its frame_ms (the remainder, other_ms,
/// small), none negative; and the summary's rates are those of the frames' own frame_ms:
/// frames_per_second_after_first over frames 2..n only.
void check_frame_times(const nlohmann::json& stats) {
    const nlohmann::json& frames = stats["frames"];
    REQUIRE(frames.size() >= 2);
    double total_ms = 0, after_first_ms = 0, compile_ms = 0, write_ms = 0;
    for (std::size_t k = 0; k < frames.size(); ++k) {
        const nlohmann::json& f = frames[k];
        INFO("frame record " << k << ": " << f.dump());
        for (const char* key : {"load_ms", "load_wait_ms", "compile_ms", "build_ms", "trace_ms",
                                "write_ms", "frame_ms"}) {
            REQUIRE_MESSAGE(f.contains(key), key);
            CHECK_MESSAGE(f[key].get<double>() >= 0.0, key);
        }
        const double named = f["load_wait_ms"].get<double>() + f["compile_ms"].get<double>() +
                             f["build_ms"].get<double>() + f["trace_ms"].get<double>() +
                             f["write_ms"].get<double>();
        const double frame_ms = f["frame_ms"].get<double>();
        // The named parts are separate stretches of the frame: they cannot exceed it, and what
        // they leave (render inputs, kernels made on first use) is a few milliseconds.
        CHECK(named <= frame_ms + 1e-6);
        CHECK(frame_ms - named <= 5.0 + 0.1 * frame_ms);
        CHECK(f["other_ms"].get<double>() == doctest::Approx(frame_ms - named).epsilon(1e-6));
        CHECK(f["write_ms"].get<double>() > 0.0);  // a PNG written
        total_ms += frame_ms;
        if (k > 0) after_first_ms += frame_ms;
        compile_ms += f["compile_ms"].get<double>();
        write_ms += f["write_ms"].get<double>();
    }
    const double n = double(frames.size());
    const nlohmann::json& s = stats["summary"];
    CHECK(s["frames_per_second"].get<double>() == doctest::Approx(1000.0 * n / total_ms));
    CHECK(s["frames_per_second_after_first"].get<double>() ==
          doctest::Approx(1000.0 * (n - 1) / after_first_ms));
    CHECK(s["mean_compile_ms"].get<double>() == doctest::Approx(compile_ms / n));
    CHECK(s["mean_write_ms"].get<double>() == doctest::Approx(write_ms / n));
}

}  // namespace

TEST_CASE("natural order puts frame_2 before frame_10") {
    CHECK(natural_less("frame_2.obj", "frame_10.obj"));
    CHECK_FALSE(natural_less("frame_10.obj", "frame_2.obj"));
    CHECK(natural_less("a/frame_009.obj", "a/frame_010.obj"));
    CHECK(natural_less("frame.obj", "frame_1.obj"));
}

TEST_CASE("kdray build --json reports the tree the reference builder makes in-process") {
    fs::path dir = fresh_temp_dir("cli-build");
    Scene scene = random_triangles(300, 11);
    fs::path obj = write_obj(dir / "scene.obj", scene);
    CommandResult r = run_kdray({"build", obj.string(), "--builder", "reference", "--json", "-o",
                                 (dir / "scene.kdt").string()});
    REQUIRE_MESSAGE(r.status == 0, r.err);
    nlohmann::json j = nlohmann::json::parse(r.out);
    for (const char* key :
         {"nodes", "leaves", "sah_cost", "build_ms", "timings_ms", "tree_depth_reached"})
        CHECK_MESSAGE(j.contains(key), key);
    // Beside the build: the load, and a preparation that builds no program (the reference).
    CHECK(j["load_ms"].get<double>() > 0.0);
    CHECK(j["prepare_ms"].get<double>() >= 0.0);
    CHECK(j["compile_ms"] == 0.0);

    KdTree expected = build_reference(load_obj(obj));
    CHECK(j["nodes"].get<std::size_t>() == expected.nodes.size());
    TreeStats stats = compute_tree_stats(expected, scene.triangle_count(), expected.params.costs);
    CHECK(j["sah_cost"].get<double>() == doctest::Approx(stats.sah_cost).epsilon(1e-9));
    CHECK(j["scene"]["triangles"].get<std::size_t>() == 300);
    CHECK(j["scene"]["vertex_normals"] == false);  // write_obj writes no vn
    CommandResult smooth =
        run_kdray({"build", (source_dir() / "testdata/cornell/room.obj").string(), "--builder",
                   "reference", "--json"});
    REQUIRE_MESSAGE(smooth.status == 0, smooth.err);
    CHECK(nlohmann::json::parse(smooth.out)["scene"]["vertex_normals"] == true);

    // The saved tree is the same tree, and `kdray stats` reads it back.
    TreeFile file = read_tree_file(dir / "scene.kdt");
    REQUIRE(file.tree.nodes.size() == expected.nodes.size());
    for (std::size_t i = 0; i < expected.nodes.size(); ++i) {
        CHECK(file.tree.nodes[i].split_or_count == expected.nodes[i].split_or_count);
        CHECK(file.tree.nodes[i].axis_and_offset == expected.nodes[i].axis_and_offset);
    }
    CHECK(file.scene_triangles == 300);
    CommandResult s = run_kdray({"stats", (dir / "scene.kdt").string(), "--json"});
    REQUIRE_MESSAGE(s.status == 0, s.err);
    CHECK(nlohmann::json::parse(s.out)["tree"]["nodes"].get<std::size_t>() ==
          expected.nodes.size());
    fs::remove_all(dir);
}

TEST_CASE("a mistyped command or option is answered with the nearest valid name") {
    struct Case {
        std::vector<std::string> args;
        const char* hint;
    };
    for (const Case& c :
         {Case{{"rendr", "x.obj"}, "'rendr' is not a command; did you mean 'render'?"},
          Case{{"biuld", "x.obj"}, "did you mean 'build'?"},
          Case{{"render", "x.obj", "-o", "y", "--sp", "3"}, "did you mean '--spp'?"},
          Case{{"build", "x.obj", "--qualty", "low"}, "did you mean '--quality'?"}}) {
        CAPTURE(c.hint);
        const CommandResult r = run_kdray(c.args);
        CHECK(r.status == 2);
        CHECK(r.err.find(c.hint) != std::string::npos);
    }
    // Nothing near: no guess.
    const CommandResult far = run_kdray({"frobnicate"});
    CHECK(far.status == 2);
    CHECK(far.err.find("did you mean") == std::string::npos);
}

TEST_CASE("render overrides --spp, --size and --ray-depth; --max-depth is refused by name") {
    fs::path dir = fresh_temp_dir("cli-overrides");
    const fs::path obj = write_obj(dir / "scene.obj", random_triangles(200, 14));
    const fs::path render = write_text_file(dir / "render.json", kSmallRender);  // 48x32, spp 1
    CommandResult r =
        run_kdray({"render", obj.string(), "-o", (dir / "out").string(), "--camera",
                   render.string(), "--aov", "--spp", "2", "--size", "16x8", "--ray-depth", "1",
                   "--builder", "reference", "--tracer", "reference", "-q"});
    REQUIRE_MESSAGE(r.status == 0, r.err);
    const nlohmann::json stats = read_json(dir / "out" / "stats.json");
    CHECK(stats["image"]["width"] == 16);
    CHECK(stats["image"]["height"] == 8);
    CHECK(stats["image"]["spp"] == 2);
    CHECK(stats["ray_depth"] == 1);
    CHECK_FALSE(stats.contains("max_depth"));  // one name per depth
    CHECK(stats["overrides"]["size"] == "16x8");
    CHECK(stats["overrides"]["spp"] == 2);
    CHECK(stats["overrides"]["ray_depth"] == 1);
    const HitBuffer aov = read_aov(dir / "out" / "scene.aov.exr");
    CHECK(aov.width == 16);
    CHECK(aov.height == 8);
    for (const char* size : {"16", "16x", "0x8", "16x8x2", "axb"}) {
        CAPTURE(size);
        r = run_kdray({"render", obj.string(), "-o", (dir / "bad").string(), "--size", size});
        CHECK(r.status == 2);
        CHECK(r.err.find("--size") != std::string::npos);
    }
    for (const char* command : {"build", "render"}) {
        r = run_kdray({command, obj.string(), "-o", (dir / "x").string(), "--max-depth", "3"});
        CHECK(r.status == 2);
        CHECK(r.err.find("--tree-depth") != std::string::npos);
        CHECK(r.err.find("--ray-depth") != std::string::npos);
    }
    CHECK(!fs::exists(dir / "bad"));
    fs::remove_all(dir);
}

TEST_CASE(
    "--ray-depth 1 stops every bounce, on both paths; --spp and --size set the primary rays") {
    // The Cornell room has a mirror sphere (illum 3) and a glass one (illum 7): with its render
    // file's max_depth of 6 some camera rays reflect and refract; with --ray-depth 1 a path ends
    // at its first hit, so none does. Primary rays are one per sample of every pixel, and with
    // spp > 1 one more, the pixel's centre ray (conventions.md: AOVs use the centre ray).
    const fs::path room = source_dir() / "testdata" / "cornell" / "room.obj";
    const fs::path render = source_dir() / "testdata" / "cornell" / "render.json";
    for (const std::string path : {"opencl", "reference"}) {
        CAPTURE(path);
        const fs::path dir = fresh_temp_dir("cli-ray-depth-" + path);
        auto run = [&](const fs::path& out, std::vector<std::string> extra) {
            std::vector<std::string> args = {
                "render",        room.string(), "-o",       out.string(), "--camera",
                render.string(), "--spp",       "2",        "--size",     "16x12",
                "--builder",     path,          "--tracer", path,         "-q"};
            args.insert(args.end(), extra.begin(), extra.end());
            return run_kdray(args, 300);
        };
        const CommandResult shallow = run(dir / "shallow", {"--ray-depth", "1"});
        REQUIRE_MESSAGE(shallow.status == 0, shallow.err);
        const CommandResult deep = run(dir / "deep", {});
        REQUIRE_MESSAGE(deep.status == 0, deep.err);

        const nlohmann::json one = read_json(dir / "shallow" / "stats.json");
        CHECK(one["ray_depth"] == 1);
        CHECK(one["overrides"]["ray_depth"] == 1);
        const nlohmann::json& one_rays = one["frames"][0]["rays"];
        CHECK(one_rays["reflection"] == 0);
        CHECK(one_rays["refraction"] == 0);
        CHECK(one_rays["primary"] == (2 + 1) * 16 * 12);

        const nlohmann::json six = read_json(dir / "deep" / "stats.json");
        CHECK(six["ray_depth"] == 6);  // the render file's
        CHECK_FALSE(six["overrides"].contains("ray_depth"));
        const nlohmann::json& six_rays = six["frames"][0]["rays"];
        CHECK(six_rays["reflection"].get<long long>() > 0);
        CHECK(six_rays["refraction"].get<long long>() > 0);
        CHECK(six_rays["primary"] == (2 + 1) * 16 * 12);
        for (const char* out : {"shallow", "deep"}) {
            const DecodedImage image = read_image(dir / out / "room.png");
            CHECK(image.width == 16);
            CHECK(image.height == 12);
        }
        fs::remove_all(dir);
    }
}

TEST_CASE("render --help lists its options under their groups, each group once") {
    const CommandResult r = run_kdray({"render", "--help"});
    REQUIRE(r.status == 0);
    // CLI11 prints a group as its name and a colon on a line of its own, then its options, one
    // per line, indented: the group of an option is the last heading above it.
    std::map<std::string, std::string> group_of;
    std::map<std::string, int> headings;
    std::string group;
    std::istringstream help(r.out);
    for (std::string line; std::getline(help, line);) {
        if (!line.empty() && line[0] != ' ' && line.back() == ':') {
            group = line.substr(0, line.size() - 1);
            ++headings[group];
            continue;
        }
        std::istringstream words(line);
        std::string first;
        words >> first;
        if (first.rfind("--", 0) == 0 || first.rfind("-o,", 0) == 0 || first.rfind("-q,", 0) == 0)
            for (std::size_t at = 0; at != std::string::npos;) {
                const std::size_t comma = first.find(',', at);
                group_of[first.substr(at, comma - at)] = group;
                at = comma == std::string::npos ? comma : comma + 1;
            }
    }
    for (const auto& [name, count] : headings) CHECK_MESSAGE(count == 1, name);
    const std::map<std::string, std::vector<std::string>> expected = {
        {"Image", {"--render-file", "--camera", "--spp", "--size", "--ray-depth", "--exposure"}},
        {"Output",
         {"--output", "--name", "--skip-existing", "--aov", "--format", "--stats-json", "--quiet"}},
        {"Tracer", {"--tracer", "--threads", "--intersect", "--packets"}},
        {"Frames", {"--frames", "--shard"}},
        {"Device", {"--device"}},
        {"Tree",
         {"--builder", "--cost-traversal", "--ct", "--cost-intersection", "--ci", "--quality",
          "--large-node-threshold", "--large-threshold", "--empty-space-ratio", "--empty-bonus",
          "--small-leaf-refs", "--leaf-refs", "--small-stage", "--large-stage", "--tree-depth"}}};
    for (const auto& [name, options] : expected)
        for (const std::string& option : options) {
            CAPTURE(option);
            CHECK(group_of[option] == name);
        }
    // The retired --max-depth is refused, not offered.
    CHECK(group_of.count("--max-depth") == 0);
}

TEST_CASE("kdray render writes images, AOVs that agree with brute force, and stats.json") {
    fs::path dir = fresh_temp_dir("cli-render");
    Scene scene = random_triangles(400, 12);
    // Frames given out of order: the run must put frame_2 before frame_10.
    write_obj(dir / "in" / "frame_10.obj", scene);
    write_obj(dir / "in" / "frame_2.obj", scene);
    fs::path render = write_text_file(dir / "render.json", kSmallRender);
    fs::path out = dir / "out";
    CommandResult r = run_kdray({"render", (dir / "in" / "frame_10.obj").string(),
                                 (dir / "in" / "frame_2.obj").string(), "-o", out.string(),
                                 "--camera", render.string(), "--aov", "--builder", "reference",
                                 "--tracer", "reference", "-q"});
    REQUIRE_MESSAGE(r.status == 0, r.err);
    CHECK(fs::exists(out / "frame_2.png"));
    CHECK(fs::exists(out / "frame_10.png"));
    REQUIRE(fs::exists(out / "frame_2.aov.exr"));

    nlohmann::json stats = read_json(out / "stats.json");
    REQUIRE(stats["frames"].size() == 2);
    CHECK(fs::path(stats["frames"][0]["input"].get<std::string>()).filename() == "frame_2.obj");
    CHECK(stats["frames"][0]["rays"]["primary"].get<std::size_t>() == 48 * 32);
    CHECK(stats["summary"]["frames"].get<int>() == 2);
    check_frame_times(stats);
    // The reference builder and tracer compile nothing.
    for (const auto& frame : stats["frames"]) CHECK(frame["compile_ms"] == 0.0);

    // Every pixel's hit equals brute force along the camera ray of conventions.md.
    HitBuffer aov = read_aov(out / "frame_2.aov.exr");
    RenderSettings settings = load_render_file(render);
    Scene loaded = load_obj(dir / "in" / "frame_2.obj");
    RenderInputs inputs = prepare_render(loaded, settings, settings.camera_at(0, loaded.frame), 0);
    REQUIRE(aov.width == 48);
    REQUIRE(aov.height == 32);
    const AovAgreement agreement = aov_against_brute_force(aov, loaded, inputs.view);
    CHECK(agreement.hits > 100);
    CHECK(agreement.mismatches == 0);
    fs::remove_all(dir);
}

TEST_CASE("kdray render --frames and --shard pick frames by their number in the whole sequence") {
    fs::path dir = fresh_temp_dir("cli-frames");
    Scene scene = random_triangles(50, 13);
    for (int f = 0; f < 12; ++f) write_obj(dir / "in" / ("f_" + std::to_string(f) + ".obj"), scene);
    auto rendered = [&](const std::string& frames, const std::string& shard) {
        fs::path out = dir / ("out" + frames + shard);
        std::vector<std::string> args = {"render",    (dir / "in" / "f_*.obj").string(),
                                         "-o",        out.string(),
                                         "--builder", "reference",
                                         "-q"};
        if (!frames.empty()) args.insert(args.end(), {"--frames", frames});
        if (!shard.empty()) args.insert(args.end(), {"--shard", shard});
        CommandResult r = run_kdray(args);
        REQUIRE_MESSAGE(r.status == 0, r.err);
        std::vector<int> numbers;
        const nlohmann::json stats = read_json(out / "stats.json");
        for (const auto& f : stats["frames"]) numbers.push_back(f["frame"].get<int>());
        return numbers;
    };
    CHECK(rendered("2:9:3", "") == std::vector<int>{2, 5, 8});
    CHECK(rendered("10:", "") == std::vector<int>{10, 11});
    CHECK(rendered("", "1/4") == std::vector<int>{1, 5, 9});
    CHECK(rendered("0:7", "0/2") == std::vector<int>{0, 2, 4, 6});
    CHECK(run_kdray({"render", (dir / "in" / "f_0.obj").string(), "-o", (dir / "x").string(),
                     "--shard", "2/2"})
              .status == 2);
    CHECK(run_kdray({"render", (dir / "in" / "f_0.obj").string(), "-o", (dir / "x").string(),
                     "--frames", "a:b"})
              .status == 2);
    fs::remove_all(dir);
}

TEST_CASE("kdray render --warm-up renders the first frame through the run's pipeline, unwritten") {
    // The warm-up is the run's own render_frame with nothing written: the files and the frames
    // of stats.json are those of a run without it, and a bad first frame fails the warm-up with
    // the frame's own error, before anything is written. Both runs are fresh processes on the
    // OpenCL backends: without the warm-up the first frame builds every program (compile_ms) and
    // the later ones none; with it, no frame of the run builds one.
    fs::path dir = fresh_temp_dir("cli-warm-up");
    write_obj(dir / "in" / "f_0.obj", random_triangles(60, 15));
    write_obj(dir / "in" / "f_1.obj", random_triangles(60, 16));
    write_obj(dir / "in" / "f_2.obj", random_triangles(60, 17));
    fs::path render = write_text_file(dir / "render.json", kSmallRender);
    auto run = [&](const fs::path& out, const std::string& frames, bool warm_up) {
        std::vector<std::string> args = {"render",   frames,          "-o", out.string(),
                                         "--camera", render.string(), "-q"};
        if (warm_up) args.push_back("--warm-up");
        return run_kdray(args);
    };
    const std::string frames = (dir / "in" / "f_*.obj").string();
    CommandResult cold = run(dir / "cold", frames, false);
    REQUIRE_MESSAGE(cold.status == 0, cold.err);
    CommandResult warm = run(dir / "warm", frames, true);
    REQUIRE_MESSAGE(warm.status == 0, warm.err);
    for (const char* image : {"f_0.png", "f_1.png", "f_2.png"})
        CHECK(read_file(dir / "warm" / image) == read_file(dir / "cold" / image));
    std::size_t files = 0;
    for (const auto& entry : fs::directory_iterator(dir / "warm"))
        files += entry.path().filename().string()[0] != '.';  // not the stats.json lock
    CHECK(files == 4);                                        // three images and stats.json
    const nlohmann::json stats = read_json(dir / "warm" / "stats.json");
    REQUIRE(stats["frames"].size() == 3);
    CHECK(stats["frames"][0]["frame"] == 0);
    CHECK(stats["summary"]["frame_numbers"] == nlohmann::json::array({0, 1, 2}));
    check_frame_times(stats);
    CHECK(stats["warm_up_ms"].get<double>() > 0.0);
    for (const auto& frame : stats["frames"]) CHECK(frame["compile_ms"] == 0.0);
    // The warm-up's scene is the first frame's: it waited for no load.
    CHECK(stats["frames"][0]["load_wait_ms"].get<double>() < 1.0);

    const nlohmann::json cold_stats = read_json(dir / "cold" / "stats.json");
    REQUIRE(cold_stats["frames"].size() == 3);
    check_frame_times(cold_stats);
    CHECK(cold_stats["frames"][0]["compile_ms"].get<double>() > 0.0);
    CHECK(cold_stats["frames"][1]["compile_ms"] == 0.0);
    CHECK(cold_stats["frames"][2]["compile_ms"] == 0.0);
    CHECK(cold_stats["summary"]["mean_compile_ms"].get<double>() > 0.0);

    write_text_file(dir / "bad" / "f_0.obj", "v 0 0 0\nv 1 0 0\nv 0 1 inf\nf 1 2 3\n");
    CommandResult bad = run(dir / "bad-out", (dir / "bad" / "f_0.obj").string(), true);
    CHECK(bad.status == 1);
    CHECK(bad.err.find("f_0.obj:3") != std::string::npos);
    CHECK_FALSE(fs::exists(dir / "bad-out" / "stats.json"));
    fs::remove_all(dir);
}

TEST_CASE("an animation with a bad frame: stop at it, or --keep-going past it") {
    fs::path dir = fresh_temp_dir("cli-keep-going");
    Scene scene = random_triangles(50, 14);
    write_obj(dir / "in" / "f_0.obj", scene);
    write_text_file(dir / "in" / "f_1.obj", "v 0 0 0\nv 1 0 0\nv 0 1 inf\nf 1 2 3\n");
    write_obj(dir / "in" / "f_2.obj", scene);
    auto render = [&](const fs::path& out, bool keep_going) {
        std::vector<std::string> args = {"render",    (dir / "in" / "f_*.obj").string(),
                                         "-o",        out.string(),
                                         "--builder", "reference",
                                         "-q"};
        if (keep_going) args.push_back("--keep-going");
        return run_kdray(args);
    };
    SUBCASE("by default the run stops at the bad frame; earlier frames stay valid") {
        CommandResult r = render(dir / "stop", false);
        CHECK(r.status == 1);
        CHECK(r.err.find("f_1.obj:3") != std::string::npos);
        CHECK(fs::exists(dir / "stop" / "f_0.png"));
        CHECK_FALSE(fs::exists(dir / "stop" / "f_1.png"));
        CHECK_FALSE(fs::exists(dir / "stop" / "f_2.png"));
        nlohmann::json stats = read_json(dir / "stop" / "stats.json");
        CHECK(stats["frames"].size() == 1);
        CHECK(stats["failed_frames"].size() == 1);
    }
    SUBCASE("--keep-going renders the rest and lists the failure") {
        CommandResult r = render(dir / "keep", true);
        CHECK(r.status == 1);
        CHECK(fs::exists(dir / "keep" / "f_0.png"));
        CHECK_FALSE(fs::exists(dir / "keep" / "f_1.png"));
        CHECK(fs::exists(dir / "keep" / "f_2.png"));
        nlohmann::json stats = read_json(dir / "keep" / "stats.json");
        CHECK(stats["frames"].size() == 2);
        REQUIRE(stats["failed_frames"].size() == 1);
        CHECK(stats["failed_frames"][0]["frame"].get<int>() == 1);
    }
    fs::remove_all(dir);
}

TEST_CASE("Ctrl-C (or a closed terminal's SIGHUP) mid-run leaves complete images and their stats") {
    // SIGINT is Ctrl-C; SIGHUP comes from a closed terminal or a killed ssh session.
    for (const char* signal : {"INT", "HUP"}) {
        INFO("SIG" << std::string(signal));
        fs::path dir = fresh_temp_dir("cli-interrupt");
        Scene scene = random_triangles(3000, 15);
        for (int f = 0; f < 60; ++f)
            write_obj(dir / "in" / ("f_" + std::to_string(f) + ".obj"), scene);
        fs::path out = dir / "out";
        // The signal once the first image exists (polled, so a slow machine does not matter).
        // Built with a stream: GCC 12's -Wrestrict misreads a chain of string operator+ here.
        std::ostringstream script_text;
        script_text << "'" << KDRAY_BINARY << "' render '" << (dir / "in").string()
                    << "'/f_*.obj -o '" << out.string()
                    << "' --builder reference --tracer reference -q 2>/dev/null & pid=$!; "
                    << "while ! ls '" << out.string() << "'/*.png >/dev/null 2>&1 && "
                    << "kill -0 $pid 2>/dev/null; do sleep 0.02; done; "
                    << "kill -" << signal << " $pid 2>/dev/null; wait $pid; exit $?";
        const std::string script = script_text.str();
        // std::system runs the script with sh -c itself: wrapping it in another "sh -c \"...\""
        // let the outer shell expand $! and $pid to nothing, so no signal was ever sent.
        int status = std::system(script.c_str());
        int code = WIFEXITED(status) ? WEXITSTATUS(status) : -1;
        std::size_t images = 0;
        for (const auto& entry : fs::directory_iterator(out)) {
            const std::string name = entry.path().filename().string();
            CHECK_MESSAGE(name.find(".tmp") == std::string::npos,
                          "a temporary file remains: " << name);
            if (entry.path().extension() == ".png") ++images;
        }
        // The run was stopped mid-way (60 frames of 3000 triangles take seconds), with 130.
        CHECK(code == 130);
        CHECK(images >= 1);
        CHECK(images < 60);
        nlohmann::json stats = read_json(out / "stats.json");
        CHECK(stats["frames"].size() == images);
        CHECK(stats["interrupted_after_frames"] == images);
        fs::remove_all(dir);
    }
}

TEST_CASE("bad input: one error line naming the file, exit status 1, no output written") {
    fs::path dir = fresh_temp_dir("cli-bad");
    fs::path out = dir / "out";

    SUBCASE("a missing scene") {
        CommandResult r = run_kdray({"render", (dir / "missing.obj").string(), "-o", out.string(),
                                     "--builder", "reference", "-q"});
        CHECK(r.status == 1);
        CHECK(r.err.find("missing.obj") != std::string::npos);
        CHECK(r.err.rfind("kdray: error: ", 0) == 0);
        CHECK(std::count(r.err.begin(), r.err.end(), '\n') == 1);
    }
    SUBCASE("a NaN vertex names the file and the line") {
        fs::path obj = write_text_file(dir / "nan.obj", "v 0 0 0\nv 1 0 0\nv 0 nan 0\nf 1 2 3\n");
        CommandResult r =
            run_kdray({"render", obj.string(), "-o", out.string(), "--builder", "reference", "-q"});
        CHECK(r.status == 1);
        CHECK(r.err.find("nan.obj:3") != std::string::npos);
        CHECK(std::count(r.err.begin(), r.err.end(), '\n') == 1);
    }
    SUBCASE("a malformed render file names the file") {
        fs::path obj = write_obj(dir / "ok.obj", random_triangles(10, 1));
        fs::path json = write_text_file(dir / "bad.json", "{\"image\": {\"width\": 64,");
        CommandResult r = run_kdray({"render", obj.string(), "-o", out.string(), "--camera",
                                     json.string(), "--builder", "reference", "-q"});
        CHECK(r.status == 1);
        CHECK(r.err.find("bad.json") != std::string::npos);
    }
    SUBCASE("an output folder that cannot be created") {
        fs::path obj = write_obj(dir / "ok.obj", random_triangles(10, 1));
        fs::path blocker = write_text_file(dir / "file", "not a folder");
        CommandResult r = run_kdray({"render", obj.string(), "-o", (blocker / "out").string(),
                                     "--builder", "reference", "-q"});
        CHECK(r.status == 1);
        CHECK(r.err.find("file/out") != std::string::npos);
    }
    SUBCASE("an unknown option is a usage error") {
        CommandResult r = run_kdray({"build", "x.obj", "--no-such-option"});
        CHECK(r.status == 2);
    }
    // Exactly one line on stderr, and nothing written for the failed run.
    CHECK_FALSE(fs::exists(out / "stats.json"));
    if (fs::exists(out)) CHECK(fs::is_empty(out));
    fs::remove_all(dir);
}
