// test_hostile_round3.cpp — the third round of hostile input (issue #29): numbers in files that
// overflow where they are used, JSON nested past any reasonable depth or with fields of the wrong
// type, command-line numbers that overflow or are NaN, outputs that cannot be written, and files
// that look like kdray's temporaries but are the user's. Each runs the binary: one `kdray: error:`
// line naming the file and the problem, exit 1 (2 for usage), no crash, nothing lost.
#include <doctest/doctest.h>
#include <fcntl.h>
#include <sys/file.h>
#include <sys/wait.h>
#include <unistd.h>

#include <csignal>

#include <algorithm>
#include <filesystem>
#include <string>
#include <vector>

#include "core/io/atomic_file.h"
#include "core/io/image.h"
#include "core/io/image_codec.h"
#include "tests/support.h"

namespace fs = std::filesystem;
using namespace kdray::test;

namespace {

// Runs that should end at once get 60 s: a hang fails the test instead of stalling CI.
constexpr int kNoHang = 60;

/// A unit quad facing +z with material `t` (Kd 1, map_Kd tex.png, a 2x2 texture) whose four
/// corners have the texture coordinate `uv` ("" for none), and a 16x12 camera on it.
struct TexturedQuad {
    fs::path dir, obj, camera;
};

TexturedQuad textured_quad(const std::string& name, const std::string& uv) {
    TexturedQuad q;
    q.dir = fresh_temp_dir(name);
    write_text_file(q.dir / "quad.mtl", "newmtl t\nKd 1 1 1\nmap_Kd tex.png\n");
    kdray::Image texture;
    texture.width = texture.height = 2;
    texture.rgb = {0.2f, 0.4f, 0.6f, 0.8f, 0.1f, 0.3f, 0.5f, 0.7f, 0.9f, 0.25f, 0.75f, 0.5f};
    kdray::write_image(q.dir / "tex.png", texture);
    std::string text = "mtllib quad.mtl\nusemtl t\nv 0 0 0\nv 1 0 0\nv 1 1 0\nv 0 1 0\n";
    if (uv.empty()) {
        text += "f 1 2 3 4\n";
    } else {
        for (int i = 0; i < 4; ++i) text += "vt " + uv + "\n";
        text += "f 1/1 2/2 3/3 4/4\n";
    }
    q.obj = write_text_file(q.dir / "quad.obj", text);
    q.camera = write_text_file(
        q.dir / "cam.json",
        R"({"image":{"width":16,"height":12},"camera":{"position":[0.5,0.5,2],"look_at":[0.5,0.5,0]}})");
    return q;
}

CommandResult render(const fs::path& obj, const fs::path& out, const fs::path& camera,
                     const std::string& path, std::vector<std::string> extra = {}) {
    std::vector<std::string> args = {
        "render",    obj.string(), "-o",       out.string(), "--camera", camera.string(),
        "--builder", path,         "--tracer", path,         "-q"};
    args.insert(args.end(), extra.begin(), extra.end());
    return run_kdray(args, kNoHang);
}

/// Runs kdray with `args`, its stdout on `out_fd` and its stderr on `err_fd`, SIGPIPE at its
/// default as a shell leaves it; the wait status.
int run_with_descriptors(const std::vector<std::string>& args, int out_fd, int err_fd) {
    std::vector<char*> argv;
    std::string binary = KDRAY_BINARY;
    argv.push_back(binary.data());
    std::vector<std::string> copies = args;
    for (std::string& a : copies) argv.push_back(a.data());
    argv.push_back(nullptr);
    const pid_t pid = ::fork();
    if (pid == 0) {
        std::signal(SIGPIPE, SIG_DFL);
        ::dup2(out_fd, STDOUT_FILENO);
        ::dup2(err_fd, STDERR_FILENO);
        ::execv(argv[0], argv.data());
        ::_exit(127);
    }
    int status = -1;
    ::waitpid(pid, &status, 0);
    return status;
}

}  // namespace

TEST_CASE("vt values that are not finite floats are refused with the file and line") {
    // tinyobjloader reads `1e39` as inf and `0e725` as 0 * 5^725 = NaN; a NaN u became INT_MIN in
    // the texture lookup and both tracers crashed (exit 139) reading outside the texture.
    for (const char* uv : {"1e39 0", "0 0e725", "nan 0", "0.5 -inf"}) {
        CAPTURE(uv);
        const TexturedQuad q = textured_quad("round3-vt", uv);
        check_error(render(q.obj, q.dir / "out", q.camera, "reference"), 1,
                    {"quad.obj:7", "texture coordinate"});
        CHECK_FALSE(fs::exists(q.dir / "out" / "quad.png"));
        fs::remove_all(q.dir);
    }
}

TEST_CASE("vt corners that overflow when interpolated render untextured on both tracers") {
    // Every corner at FLT_MAX is a finite float, but w*t0 + u*t2 + v*t4 rounds past it to inf at
    // some hits, and inf - floor(inf) is NaN: the lookup must not turn it into a texel index
    // (both tracers crashed). Such a hit is untextured, as the same quad without vt renders; at
    // the other hits the huge finite (u, v) wraps to (0, 0), as a quad whose corners are all
    // (0, 0) renders. Every pixel must be one of the two, and some must be untextured.
    for (const char* path : {"reference", "opencl"}) {
        CAPTURE(path);
        auto rendered = [&](const std::string& uv) {
            const TexturedQuad q = textured_quad("round3-vt-max", uv);
            const CommandResult r = render(q.obj, q.dir / "out", q.camera, path);
            INFO("vt " << uv << ": stderr " << r.err);
            CHECK(r.status == 0);
            kdray::DecodedImage image;
            if (r.status == 0) image = kdray::read_image(q.dir / "out" / "quad.png");
            fs::remove_all(q.dir);
            return image;
        };
        const kdray::DecodedImage image = rendered("3.4028234e38 3.4028234e38");
        const kdray::DecodedImage plain = rendered("");
        const kdray::DecodedImage origin = rendered("0 0");
        REQUIRE(image.values.size() == 16u * 12u * std::size_t(image.channels));
        REQUIRE(plain.values.size() == image.values.size());
        REQUIRE(origin.values.size() == image.values.size());
        const std::size_t c = std::size_t(image.channels);
        int untextured = 0, mismatched = 0;
        for (std::size_t p = 0; p < image.values.size(); p += c) {
            auto same = [&](const kdray::DecodedImage& other) {
                return std::equal(image.values.begin() + p, image.values.begin() + p + c,
                                  other.values.begin() + p);
            };
            if (same(plain) && !same(origin)) ++untextured;
            if (!same(plain) && !same(origin)) ++mismatched;
        }
        CHECK(mismatched == 0);
        CHECK(untextured > 0);
    }
}

TEST_CASE("JSON nested past kdray's depth budget is refused before it is built") {
    // 100,000 nested `[` in 200 KB: every consumer of the parsed value (its message, dump(), its
    // destruction) recursed once a level, and `kdray stats` and every render into the folder
    // overflowed the stack. Refused at depth 64, naming the file.
    const fs::path dir = fresh_temp_dir("round3-deep-json");
    const std::string deep = std::string(100000, '[') + std::string(100000, ']');
    const fs::path obj = write_text_file(dir / "tri.obj", "v 0 0 0\nv 1 0 0\nv 0 1 0\nf 1 2 3\n");
    const fs::path camera = write_text_file(
        dir / "cam.json",
        R"({"image":{"width":16,"height":12},"camera":{"position":[0.3,0.3,3],"look_at":[0.3,0.3,0]}})");
    SUBCASE("a stats.json, read by kdray stats and by a render into its folder") {
        const fs::path out = dir / "out";
        write_text_file(out / "stats.json", R"({"summary":{},"frames":[{"frame":)" + deep + "}]}");
        check_error(run_kdray({"stats", out.string()}, kNoHang), 1,
                    {"stats.json", "nested more than 64 levels"});
        check_error(render(obj, out, camera, "reference"), 1,
                    {"stats.json", "nested more than 64 levels"});
        CHECK_FALSE(fs::exists(out / "tri.png"));
    }
    SUBCASE("a render file") {
        const fs::path deep_camera =
            write_text_file(dir / "deep.json", R"({"camera":)" + deep + "}");
        check_error(render(obj, dir / "out", deep_camera, "reference"), 1,
                    {"deep.json", "nested more than 64 levels"});
    }
    SUBCASE("64 levels are still read: the budget counts the levels a file has") {
        const std::string nested = std::string(63, '[') + "1" + std::string(63, ']');
        const fs::path ok = write_text_file(dir / "ok.json", R"({"camera":)" + nested + "}");
        // Parsed, then refused by the render file's own check of what camera is.
        const CommandResult r = render(obj, dir / "out", ok, "reference");
        check_error(r, 1, {"ok.json", "camera"});
        CHECK(r.err.find("nested") == std::string::npos);
    }
    fs::remove_all(dir);
}

TEST_CASE("stats.json fields of the wrong type are named before anything renders") {
    // A run merges its frames into the folder's stats.json; a field kdray reads back that is not
    // what it writes failed only after every frame had rendered, with a raw
    // `[json.exception.type_error.302]` naming no file.
    const fs::path dir = fresh_temp_dir("round3-stats-types");
    const fs::path obj = write_text_file(dir / "tri.obj", "v 0 0 0\nv 1 0 0\nv 0 1 0\nf 1 2 3\n");
    const fs::path camera = write_text_file(
        dir / "cam.json",
        R"({"image":{"width":16,"height":12},"camera":{"position":[0.3,0.3,3],"look_at":[0.3,0.3,0]}})");
    const fs::path out = dir / "out";
    struct Case {
        std::string stats, field;
    };
    for (
        const Case& c : std::vector<Case>{
            {R"({"summary":{},"frames":[{"frame":0,"input":5}]})", "frames[0].input"},
            {R"({"summary":{},"frames":[{"frame":0,"image":[]}]})", "frames[0].image"},
            {R"({"summary":{},"frames":[],"builder":5})", "builder"},
            {R"({"summary":{},"frames":[],"tracer":{}})", "tracer"},
            {R"({"summary":{},"frames":[],"runs":[3]})", "runs[0]"},
            {R"({"summary":{},"frames":[],"failed_frames":[{"frame":1,"input":false}]})",
             "failed_frames[0].input"},
            // Times kdray never writes: two of 1e308 ms summed to inf in the summary (found by
            // fuzz_stats_json), and a negative one made a negative mean.
            {R"({"summary":{},"frames":[{"frame":0,"frame_ms":1e308},{"frame":1,"frame_ms":1e308}]})",
             "frames[0].frame_ms"},
            {R"({"summary":{},"frames":[{"frame":0,"trace_ms":-1}]})", "frames[0].trace_ms"}}) {
        CAPTURE(c.stats);
        write_text_file(out / "stats.json", c.stats);
        check_error(render(obj, out, camera, "reference"), 1, {"stats.json: " + c.field});
        CHECK_FALSE(fs::exists(out / "tri.png"));
        check_error(run_kdray({"stats", out.string()}, kNoHang), 1, {"stats.json: " + c.field});
    }
    SUBCASE("a message quotes at most 40 bytes of a field") {
        write_text_file(out / "stats.json", R"({"summary":{},"frames":[{"frame":")" +
                                                std::string(100000, 'x') + "\"}]}");
        const CommandResult r = run_kdray({"stats", out.string()}, kNoHang);
        check_error(r, 1, {"frames[0].frame", "not a frame number"});
        CHECK(r.err.size() < 300);
    }
    SUBCASE("a stats.json that is a symbolic link is refused before the run renders") {
        const fs::path elsewhere =
            write_text_file(dir / "elsewhere.json", R"({"summary":{},"frames":[]})");
        fs::remove(out / "stats.json");
        fs::create_symlink(elsewhere, out / "stats.json");
        check_error(render(obj, out, camera, "reference"), 1, {"stats.json", "symbolic link"});
        CHECK_FALSE(fs::exists(out / "tri.png"));
    }
    fs::remove_all(dir);
}

TEST_CASE("--frames steps and ends near 2^63 end the range instead of overflowing") {
    // `f += step` past the last frame overflowed a signed 64-bit integer: 2:2:2^63-2 crashed
    // (exit 139) and other huge steps wrapped to a negative frame, reported as an empty name.
    // Each range below picks exactly the frames listed, out of f_0 .. f_2.
    const fs::path dir = fresh_temp_dir("round3-frames");
    for (int f = 0; f < 3; ++f)
        write_text_file(dir / "in" / ("f_" + std::to_string(f) + ".obj"),
                        "v 0 0 0\nv 1 0 0\nv 0 1 0\nf 1 2 3\n");
    struct Case {
        std::string frames;
        std::vector<int> expected;
    };
    for (const Case& c : std::vector<Case>{{"2:2:9223372036854775806", {2}},
                                           {"0::9223372036854775807", {0}},
                                           {"1:9223372036854775807:9223372036854775807", {1}},
                                           {"0:9223372036854775807:2", {0, 2}}}) {
        CAPTURE(c.frames);
        const fs::path out = dir / "out";
        fs::remove_all(out);
        const CommandResult r =
            run_kdray({"render", (dir / "in" / "f_*.obj").string(), "-o", out.string(), "--builder",
                       "reference", "--tracer", "reference", "-q", "--frames", c.frames},
                      kNoHang);
        INFO("stderr: " << r.err);
        REQUIRE(r.status == 0);
        std::vector<int> numbers;
        const nlohmann::json stats = read_json(out / "stats.json");
        for (const auto& f : stats["frames"])
            numbers.push_back(f["frame"].get<int>());
        CHECK(numbers == c.expected);
    }
    // Past int64 is not a number kdray reads: a usage error naming the option.
    check_error(run_kdray({"render", (dir / "in" / "f_*.obj").string(), "-o", (dir / "x").string(),
                           "--frames", "0:1:9223372036854775808"},
                          kNoHang),
                2, {"--frames"});
    fs::remove_all(dir);
}

TEST_CASE("compare --tolerance and --max-fraction must be finite numbers") {
    // Every comparison with NaN is false, so `--tolerance nan` counted no pixel as over it and an
    // all-0 and an all-1 image agreed (exit 0); `--max-fraction nan` was accepted the same way.
    const fs::path dir = fresh_temp_dir("round3-compare-nan");
    kdray::Image black, white;
    black.width = white.width = 4;
    black.height = white.height = 3;
    black.rgb.assign(36, 0.0f);
    white.rgb.assign(36, 1.0f);
    const fs::path a = dir / "black.png", b = dir / "white.png";
    kdray::write_image(a, black);
    kdray::write_image(b, white);
    for (const std::vector<std::string>& option : {std::vector<std::string>{"--tolerance", "nan"},
                                                   {"--tolerance", "inf"},
                                                   {"--tolerance", "-nan"},
                                                   {"--max-fraction", "nan"}}) {
        CAPTURE(option[0] + " " + option[1]);
        check_error(run_kdray({"compare", a.string(), b.string(), option[0], option[1]}, kNoHang),
                    2, {option[0], "not a finite number"});
    }
    // Finite values still decide: a tolerance of 2 lets every pixel agree, and the default
    // tolerance none.
    CHECK(run_kdray({"compare", a.string(), b.string(), "--tolerance", "2"}, kNoHang).status == 0);
    CHECK(run_kdray({"compare", a.string(), b.string(), "--max-fraction", "1"}, kNoHang).status ==
          0);
    CHECK(run_kdray({"compare", a.string(), b.string()}, kNoHang).status == 1);
    fs::remove_all(dir);
}

TEST_CASE("stdout that cannot be written is an error; a closed stderr pipe ends only the logging") {
    const fs::path dir = fresh_temp_dir("round3-output-streams");
    const fs::path obj = write_text_file(dir / "tri.obj", "v 0 0 0\nv 1 0 0\nv 0 1 0\nf 1 2 3\n");
    SUBCASE("stdout on a full device: exit 1 with one error line, not a silent exit 0") {
        // `kdray build x.obj --json > /dev/full` lost the report and exited 0.
        const int full = ::open("/dev/full", O_WRONLY | O_CLOEXEC);
        REQUIRE(full >= 0);
        const fs::path err_path = dir / "err.txt";
        for (const std::vector<std::string>& args :
             {std::vector<std::string>{"build", obj.string(), "--builder", "reference", "--json"},
              {"build", obj.string(), "--builder", "reference"},
              {"stats", obj.string(), "--builder", "reference", "--json"}}) {
            CAPTURE(args[0] + " " + args.back());
            const int err =
                ::open(err_path.c_str(), O_WRONLY | O_CREAT | O_TRUNC | O_CLOEXEC, 0600);
            REQUIRE(err >= 0);
            const int status = run_with_descriptors(args, full, err);
            ::close(err);
            REQUIRE(WIFEXITED(status));
            CommandResult r;
            r.status = WEXITSTATUS(status);
            r.err = read_file(err_path);
            // build logs its device and compile lines at info: only the last line is the error.
            const std::size_t last = r.err.rfind("kdray: error: ");
            REQUIRE(last != std::string::npos);
            r.err = r.err.substr(last);
            check_error(r, 1, {"standard output", "No space left on device"});
        }
        ::close(full);
    }
    SUBCASE("stderr a pipe whose reader has gone: the run finishes its frames and stats.json") {
        // `kdray render ... 2>&1 | head -3` died of SIGPIPE (exit 141) at its first message after
        // head left, with images written and no stats.json. The reader here is gone before the
        // run starts, so that every message fails, not only those after the third line.
        for (int f = 0; f < 4; ++f)
            write_text_file(dir / "in" / ("f_" + std::to_string(f) + ".obj"),
                            "v 0 0 0\nv 1 0 0\nv 0 1 0\nf 1 2 3\n");
        int fds[2];
        REQUIRE(::pipe2(fds, O_CLOEXEC) == 0);
        ::close(fds[0]);
        const fs::path out = dir / "out";
        const int status = run_with_descriptors(
            {"render", (dir / "in" / "f_*.obj").string(), "-o", out.string(), "--builder",
             "reference", "--tracer", "reference", "--log-level", "info"},
            fds[1], fds[1]);
        ::close(fds[1]);
        CHECK_FALSE(WIFSIGNALED(status));
        REQUIRE(WIFEXITED(status));
        CHECK(WEXITSTATUS(status) == 0);
        const nlohmann::json stats = read_json(out / "stats.json");
        REQUIRE(stats.contains("frames"));
        CHECK(stats["frames"].size() == 4u);
        for (int f = 0; f < 4; ++f) CHECK(fs::exists(out / ("f_" + std::to_string(f) + ".png")));
    }
    fs::remove_all(dir);
}

TEST_CASE("stale-temporary cleanup removes only kdray's own, of this host, of a process gone") {
    // Any `.NAME.tmpN[.ext]` whose process N did not run was taken for a stale temporary: a
    // user's `.holiday.tmp2023.tar` was deleted, an input so named vanished before it loaded, and
    // shards on two nodes rendering into one shared folder deleted each other's live
    // temporaries. kdray's temporaries now carry a marker, the host and a random part, and are
    // locked (flock) while they live: shards in two PID namespaces of one host share the host
    // name, and a process id of one means nothing in the other (tests/slurm_render.py runs that
    // case; here the same as a name whose process runs but that no one locks).
    const fs::path dir = fresh_temp_dir("round3-temporaries");
    const fs::path out = dir / "out";
    const fs::path obj = write_text_file(dir / "tri.obj", "v 0 0 0\nv 1 0 0\nv 0 1 0\nf 1 2 3\n");
    const fs::path camera = write_text_file(
        dir / "cam.json",
        R"({"image":{"width":16,"height":12},"camera":{"position":[0.3,0.3,3],"look_at":[0.3,0.3,0]}})");
    const std::string dead = "2147483600";  // above any pid_max: no process has it
    // This host's and this process's temporary name for out/frame.png, and variants of it.
    const std::string live = kdray::temporary_path(out / "frame.png").filename().string();
    // Appended piece by piece: GCC 12 warns falsely (-Wstringop-overflow) on "@" + std::string.
    std::string pid = "@";
    pid += std::to_string(::getpid());
    pid += '@';
    const std::size_t pid_at = live.find(pid);
    REQUIRE(pid_at != std::string::npos);
    REQUIRE(live.find(".kdray.tmp@") != std::string::npos);
    std::string stale = live, other_host = live, unlocked = live;
    stale.replace(pid_at, pid.size(), "@" + dead + "@");
    // This process runs, but holds no lock on it: in another PID namespace of this host, a
    // kdray killed mid-write may have had this test's process id.
    unlocked.replace(unlocked.size() - 20, 16, "0123456789abcdef");
    other_host.replace(live.find(".kdray.tmp@") + 11, pid_at - live.find(".kdray.tmp@") - 11,
                       "another-node");
    other_host.replace(other_host.find(pid), pid.size(), "@" + dead + "@");
    const std::vector<std::string> kept = {
        ".holiday.tmp2023.tar",            // the reported loss: a user's file
        ".frame.png.tmp" + dead + ".png",  // kdray's old pattern, now a user's name
        ".notes.kdray.tmp@x",              // the marker without the fields after it
        other_host,                        // a dead pid on another node means nothing here
        live,                              // a process (this test) holds its lock
        stale.substr(0, stale.size() - 4) + "Z.png"};  // not 16 hex digits of kdray's
    for (const std::string& name : kept) write_text_file(out / name, "keep " + name);
    // Locked as kdray's writer locks it, for as long as the render below runs.
    const int live_lock = ::open((out / live).c_str(), O_RDONLY | O_CLOEXEC);
    REQUIRE(live_lock >= 0);
    REQUIRE(::flock(live_lock, LOCK_EX) == 0);
    write_text_file(out / stale, "half");
    write_text_file(out / unlocked, "half");
    // An input named like an old temporary, inside the folder: it loads and renders.
    const fs::path input = write_text_file(out / (".scene.tmp" + dead + ".obj"),
                                           "v 0 0 0\nv 1 0 0\nv 0 1 0\nf 1 2 3\n");
    const CommandResult r =
        run_kdray({"render", input.string(), "-o", out.string(), "--camera", camera.string(),
                   "--builder", "reference", "--tracer", "reference", "-q", "--name", "scene"},
                  kNoHang);
    INFO("stderr: " << r.err);
    CHECK(r.status == 0);
    CHECK(fs::exists(out / "scene.png"));
    for (const std::string& name : kept) {
        CAPTURE(name);
        CHECK(read_file(out / name) == "keep " + name);
    }
    CHECK_FALSE(fs::exists(out / stale));
    CHECK_FALSE(fs::exists(out / unlocked));
    ::close(live_lock);
    fs::remove_all(dir);
}
