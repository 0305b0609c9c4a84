// test_cli_batch.cpp — `kdray render` as a batch user runs it: --exposure against the render
// file's own exposure, --name patterns, a folder's stats.json merged across runs (an interrupted
// run resumed, --skip-existing) against one whole run, and the log a run writes when stderr is
// not a terminal. Every case that renders runs on the default OpenCL path and on the reference.
#include <doctest/doctest.h>

#include <fcntl.h>
#include <poll.h>
#include <pty.h>
#include <sys/file.h>
#include <sys/wait.h>
#include <unistd.h>

#include <algorithm>
#include <cerrno>
#include <chrono>
#include <csignal>
#include <filesystem>
#include <future>
#include <set>
#include <sstream>
#include <string>
#include <thread>
#include <vector>

#include <nlohmann/json.hpp>

#include "core/error.h"
#include "core/io/output_name.h"
#include "core/run/render_stats.h"
#include "tests/support.h"

namespace fs = std::filesystem;
using namespace kdray;
using namespace kdray::test;

namespace {

/// `kdray render FRAMES -o OUT --size 48x36 EXTRA...` on `path` ("opencl" or "reference").
CommandResult render(const std::vector<std::string>& frames, const fs::path& out,
                     const std::string& path, std::vector<std::string> extra = {}) {
    std::vector<std::string> args = {"render"};
    args.insert(args.end(), frames.begin(), frames.end());
    for (const std::string& a :
         {std::string("-o"), out.string(), std::string("--size"), std::string("48x36"),
          std::string("--builder"), path, std::string("--tracer"), path})
        args.push_back(a);
    args.insert(args.end(), extra.begin(), extra.end());
    return run_kdray(args, 300);
}

std::size_t count_lines_with(const std::string& text, const std::string& part) {
    std::size_t n = 0;
    for (std::size_t at = text.find(part); at != std::string::npos; at = text.find(part, at + 1))
        ++n;
    return n;
}

/// The parts of a frame's record that do not depend on when or how fast it ran.
nlohmann::json timeless(const nlohmann::json& frame) {
    return {{"frame", frame["frame"]},
            {"input", frame["input"]},
            {"image", frame["image"]},
            {"nodes", frame["tree"]["nodes"]},
            {"sah_cost", frame["tree"]["sah_cost"]},
            {"hit_pixels", frame["hit_pixels"]},
            {"rays", frame["rays"]}};
}

/// What kdray wrote to a terminal: `started` is false when no pseudo-terminal could be had.
struct TerminalRun {
    bool started = false;
    int status = -1;
    std::string bytes;  // everything written to the terminal, stdout and stderr, as sent
};

/// Runs the kdray binary with `args` on a pseudo-terminal (its stdin, stdout and stderr), 200
/// columns wide, as a user at a terminal runs it; killed after `timeout_s` seconds.
TerminalRun run_kdray_on_terminal(const std::vector<std::string>& args, int timeout_s) {
    TerminalRun run;
    std::vector<std::string> argv_strings = {KDRAY_BINARY};
    argv_strings.insert(argv_strings.end(), args.begin(), args.end());
    std::vector<char*> argv;
    for (std::string& a : argv_strings) argv.push_back(a.data());
    argv.push_back(nullptr);
    struct winsize size {};
    size.ws_col = 200;
    size.ws_row = 50;
    int terminal = -1;
    const pid_t pid = ::forkpty(&terminal, nullptr, nullptr, &size);
    if (pid < 0) return run;
    if (pid == 0) {
        ::execv(KDRAY_BINARY, argv.data());
        ::_exit(127);
    }
    run.started = true;
    const auto deadline = std::chrono::steady_clock::now() + std::chrono::seconds(timeout_s);
    char buffer[4096];
    for (;;) {
        const auto left = std::chrono::duration_cast<std::chrono::milliseconds>(
                              deadline - std::chrono::steady_clock::now())
                              .count();
        if (left <= 0) {
            ::kill(pid, SIGKILL);
            break;
        }
        pollfd ready{terminal, POLLIN, 0};
        const int n = ::poll(&ready, 1, int(left));
        if (n == 0 || (n < 0 && errno == EINTR)) continue;
        const ssize_t got = n > 0 ? ::read(terminal, buffer, sizeof buffer) : -1;
        if (got > 0) {
            run.bytes.append(buffer, std::size_t(got));
            continue;
        }
        if (got < 0 && errno == EINTR) continue;
        break;  // EIO: the process ended and closed the terminal
    }
    int status = 0;
    ::waitpid(pid, &status, 0);
    ::close(terminal);
    run.status = WIFEXITED(status) ? WEXITSTATUS(status) : 128 + WTERMSIG(status);
    return run;
}

/// The lines a terminal shows after `bytes`: '\r' moves to the start of the line, "\033[K"
/// clears from there to its end, '\n' starts a new line, any other byte is drawn at the cursor.
/// `other_escapes` counts escape sequences it does not know (the picture would be wrong).
std::vector<std::string> terminal_lines(const std::string& bytes, int& other_escapes) {
    std::vector<std::string> lines(1);
    std::size_t column = 0;
    other_escapes = 0;
    for (std::size_t i = 0; i < bytes.size(); ++i) {
        std::string& line = lines.back();
        if (bytes[i] == '\r') {
            column = 0;
        } else if (bytes[i] == '\n') {
            lines.emplace_back();
            column = 0;
        } else if (bytes.compare(i, 3, "\033[K") == 0) {
            line.resize(std::min(line.size(), column));
            i += 2;
        } else {
            other_escapes += bytes[i] == '\033';
            if (column < line.size())
                line[column] = bytes[i];
            else
                line.push_back(bytes[i]);
            ++column;
        }
    }
    return lines;
}
}  // namespace

TEST_CASE("--name: placeholders expand, bad patterns are usage errors naming the pattern") {
    CHECK(OutputName()("dir/frame_7.obj", 7) == "frame_7");
    CHECK(OutputName("f_{frame:04}")("a/b.obj", 12) == "f_0012");
    CHECK(OutputName("{stem}_{frame}")("x.obj", 3) == "x_3");
    CHECK(OutputName("f_{frame:02}")("x.obj", 1234) == "f_1234");
    for (const char* bad : {"{frame", "a}b", "{nope}", "a/{stem}", "", "{frame:0}", "{frame:4}"})
        CHECK_THROWS_AS(OutputName{bad}, UsageError);
    try {
        OutputName{"x_{fram}"};
        FAIL("an unknown placeholder was accepted");
    } catch (const UsageError& e) {
        CHECK(std::string(e.what()).find("x_{fram}") != std::string::npos);
        CHECK(std::string(e.what()).find("{fram}") != std::string::npos);
    }
    CHECK_THROWS_AS(OutputName{".hidden_{frame}"}, UsageError);
}

TEST_CASE("merge_render_stats: a run replaces its frames' records and keeps the others") {
    auto image = [](std::size_t frame) { return "f" + std::to_string(frame) + ".png"; };
    auto record = [&](std::size_t frame, double ms) {
        return nlohmann::json{
            {"frame", frame}, {"image", image(frame)}, {"frame_ms", ms}, {"build_ms", ms / 2}};
    };
    // A stats.json of one run, as kdray wrote it before runs were recorded: frames 0..3.
    nlohmann::json old = {
        {"builder", "old"},
        {"frames", {record(0, 100), record(1, 10), record(2, 10), record(3, 10)}},
        {"failed_frames", {{{"frame", 5}, {"image", image(5)}, {"error", "bad"}}}},
        {"summary", nlohmann::json::object()}};
    // A second run re-renders frames 2 and 5 and fails frame 3.
    nlohmann::json run = {
        {"builder", "new"},
        {"frames", {record(2, 200), record(5, 20)}},
        {"failed_frames", {{{"frame", 3}, {"image", image(3)}, {"error", "worse"}}}}};
    const nlohmann::json merged = merge_render_stats(old, run);
    CHECK(merged["builder"] == "new");
    REQUIRE(merged["runs"].size() == 2);
    CHECK(merged["runs"][0]["builder"] == "old");
    CHECK(merged["runs"][1]["frames_rendered"] == nlohmann::json({2, 5}));
    std::vector<std::size_t> numbers, runs;
    for (const auto& f : merged["frames"]) {
        numbers.push_back(f["frame"]);
        runs.push_back(f["run"]);
    }
    // Frame 3 failed now: its earlier record stays, with its image.
    CHECK(numbers == std::vector<std::size_t>{0, 1, 2, 3, 5});
    CHECK(runs == std::vector<std::size_t>{0, 0, 1, 0, 1});
    CHECK(merged["runs"][0]["frames_rendered"] == nlohmann::json({0, 1, 2, 3}));
    CHECK(merged["frames"][2]["frame_ms"] == 200.0);
    REQUIRE(merged["failed_frames"].size() == 1);
    CHECK(merged["failed_frames"][0]["frame"] == 3);
    // completed_images: rendered, and not failed since.
    CHECK(completed_images(merged) ==
          std::set<std::string>{image(0), image(1), image(2), image(5)});
    // The summary by hand: 5 frames of 100, 10, 200, 10, 20 ms; each run's first (0 and 2) left
    // out of the rate after the first: 10, 10 and 20 ms.
    const nlohmann::json& summary = merged["summary"];
    CHECK(summary["frames"] == 5);
    CHECK(summary["mean_frame_ms"].get<double>() == doctest::Approx(68));
    CHECK(summary["worst_frame_ms"].get<double>() == doctest::Approx(200));
    CHECK(summary["frames_per_second_after_first"].get<double>() ==
          doctest::Approx(1000.0 / (40.0 / 3)));
    CHECK(summary["mean_build_ms"].get<double>() == doctest::Approx(34));
    // Merging into nothing is the run alone.
    const nlohmann::json alone = merge_render_stats(nullptr, run);
    CHECK(alone["frames"].size() == 2);
    CHECK(alone["runs"].size() == 1);
}

TEST_CASE("--exposure overrides the render file's exposure, recorded in stats.json") {
    const fs::path dir = fresh_temp_dir("cli-exposure");
    const fs::path obj = source_dir() / "testdata" / "cornell" / "room.obj";
    REQUIRE(fs::exists(obj));
    const fs::path base_json = source_dir() / "testdata" / "cornell" / "render.json";
    nlohmann::json with_exposure = read_json(base_json);
    with_exposure["exposure"] = 1.5;
    const fs::path exposed_json = write_text_file(dir / "exposed.json", with_exposure.dump());
    for (const std::string path : {"opencl", "reference"}) {
        CAPTURE(path);
        const CommandResult a = render({obj.string()}, dir / (path + "-file"), path,
                                       {"--camera", exposed_json.string(), "-q"});
        const CommandResult b = render({obj.string()}, dir / (path + "-flag"), path,
                                       {"--camera", base_json.string(), "--exposure", "1.5", "-q"});
        REQUIRE(a.status == 0);
        REQUIRE(b.status == 0);
        const std::string image_a = read_file(dir / (path + "-file") / "room.png");
        CHECK(!image_a.empty());
        CHECK(image_a == read_file(dir / (path + "-flag") / "room.png"));
        // Not the unexposed image: the override did something.
        const CommandResult c = render({obj.string()}, dir / (path + "-none"), path,
                                       {"--camera", base_json.string(), "-q"});
        REQUIRE(c.status == 0);
        CHECK(image_a != read_file(dir / (path + "-none") / "room.png"));
        CHECK(read_json(dir / (path + "-flag") / "stats.json")["overrides"]["exposure"] == 1.5);
    }
    const CommandResult bad =
        render({obj.string()}, dir / "bad", "reference", {"--exposure", "65"});
    CHECK(bad.status == 2);
    CHECK(bad.err.find("--exposure") != std::string::npos);
    CHECK(!fs::exists(dir / "bad"));
}

TEST_CASE("--name writes numbered files; a pattern that makes two frames one name is refused") {
    const fs::path dir = fresh_temp_dir("cli-name");
    const std::vector<std::string> frames = anim_frames(3);
    const CommandResult r =
        render(frames, dir / "out", "reference", {"--name", "shot_{frame:04}", "--aov", "-q"});
    REQUIRE(r.status == 0);
    for (const char* name :
         {"shot_0000.png", "shot_0001.png", "shot_0002.png", "shot_0002.aov.exr"})
        CHECK_MESSAGE(fs::exists(dir / "out" / name), name);
    CHECK(!fs::exists(dir / "out" / "frame_000.png"));
    CHECK(read_json(dir / "out" / "stats.json")["frames"][1]["image"] == "shot_0001.png");

    const CommandResult same = render(frames, dir / "same", "reference", {"--name", "shot"});
    CHECK(same.status == 2);
    CHECK(same.err.find("frame_000.obj") != std::string::npos);
    CHECK(same.err.find("frame_001.obj") != std::string::npos);
    CHECK(!fs::exists(dir / "same"));
    const CommandResult bad = render(frames, dir / "bad", "reference", {"--name", "a/{stem}"});
    CHECK(bad.status == 2);
    CHECK(bad.err.find("a/{stem}") != std::string::npos);
}

TEST_CASE("runs into one folder add up: an interrupted run resumed equals one whole run") {
    for (const std::string path : {"opencl", "reference"}) {
        CAPTURE(path);
        const fs::path dir = fresh_temp_dir("cli-merge-" + path);
        const std::vector<std::string> frames = anim_frames(4);
        // No render file: every run frames the first input's scene, wherever it starts.
        REQUIRE(render(frames, dir / "whole", path, {"-q"}).status == 0);
        REQUIRE(render(frames, dir / "parts", path, {"--frames", "0:1", "-q"}).status == 0);
        REQUIRE(render(frames, dir / "parts", path, {"--frames", "2:3", "-q"}).status == 0);
        const nlohmann::json whole = read_json(dir / "whole" / "stats.json");
        const nlohmann::json parts = read_json(dir / "parts" / "stats.json");
        REQUIRE(parts["frames"].size() == 4);
        CHECK(parts["runs"].size() == 2);
        CHECK(parts["summary"]["frames"] == 4);
        CHECK(parts["summary"]["frame_numbers"] == nlohmann::json({0, 1, 2, 3}));
        for (std::size_t k = 0; k < 4; ++k) {
            CHECK(timeless(parts["frames"][k]) == timeless(whole["frames"][k]));
            CHECK(parts["frames"][k]["run"] == (k < 2 ? 0 : 1));
            const std::string image = whole["frames"][k]["image"];
            CHECK_MESSAGE(read_file(dir / "whole" / image) == read_file(dir / "parts" / image),
                          image);
        }

        // --skip-existing renders only the frame whose image is gone, and keeps the others'
        // records.
        fs::remove(dir / "parts" / "frame_002.png");
        const CommandResult skip =
            render(frames, dir / "parts", path, {"--skip-existing", "--log-level", "info", "-q"});
        REQUIRE(skip.status == 0);
        CHECK(skip.err.find("skipping 3 of 4 frame(s)") != std::string::npos);
        const nlohmann::json resumed = read_json(dir / "parts" / "stats.json");
        REQUIRE(resumed["runs"].size() == 3);
        CHECK(resumed["runs"][2]["frames_rendered"] == nlohmann::json({2}));
        REQUIRE(resumed["frames"].size() == 4);
        CHECK(resumed["frames"][2]["run"] == 2);
        CHECK(resumed["frames"][1]["run"] == 0);
        CHECK(timeless(resumed["frames"][2]) == timeless(whole["frames"][2]));
        CHECK(read_file(dir / "parts" / "frame_002.png") ==
              read_file(dir / "whole" / "frame_002.png"));
        // Nothing left to render: the folder stays as it was.
        const CommandResult none = render(frames, dir / "parts", path, {"--skip-existing", "-q"});
        CHECK(none.status == 0);
        CHECK(read_json(dir / "parts" / "stats.json")["runs"].size() == 3);
    }
}

TEST_CASE("on a terminal a later frame's warning gets a line of its own, above the progress line") {
    // The progress line is drawn only when stderr is a terminal, so the pipes of run_kdray never
    // reach the code that clears it for a message. Frame 1 of 3 names a missing MTL file: its
    // warning comes while the progress line shows frame 1/3.
    const fs::path dir = fresh_temp_dir("cli-terminal");
    for (int f = 0; f < 3; ++f) {
        const fs::path obj =
            write_obj(dir / "in" / ("f_" + std::to_string(f) + ".obj"), random_triangles(200, f));
        if (f == 1) write_text_file(obj, "mtllib nowhere.mtl\n" + read_file(obj));
    }
    const TerminalRun run = run_kdray_on_terminal(
        {"render", (dir / "in" / "f_*.obj").string(), "-o", (dir / "out").string(), "--size",
         "16x12", "--builder", "reference", "--tracer", "reference"},
        120);
    if (!run.started) {
        MESSAGE("skipped: no pseudo-terminal could be opened here (forkpty failed)");
        return;
    }
    INFO("terminal bytes: " << nlohmann::json(run.bytes).dump());
    REQUIRE(run.status == 0);
    // The terminal path ran: the progress line was drawn in place, and the warning came after
    // it was showing.
    CHECK(run.bytes.find("\r\033[Kkdray: frame 1/3") != std::string::npos);
    CHECK(run.bytes.find("kdray: frame 1/3") < run.bytes.find("kdray: warning: "));
    int other_escapes = 0;
    const std::vector<std::string> lines = terminal_lines(run.bytes, other_escapes);
    CHECK(other_escapes == 0);
    std::size_t warning_lines = 0;
    for (const std::string& line : lines) {
        // The run's closing summary ("1 warning (1 kind) in 1 frame") is no warning of its own.
        const bool warning = line.find("warning") != std::string::npos &&
                             line.find(" warning (") == std::string::npos;
        const bool progress = line.find("kdray: frame ") != std::string::npos;
        CHECK_MESSAGE(!(warning && progress), "a warning shares a line with progress: " << line);
        if (!warning) continue;
        ++warning_lines;
        CHECK(line.rfind("kdray: warning: ", 0) == 0);
        CHECK(line.find("f_1.obj:1: material library 'nowhere.mtl' not found") !=
              std::string::npos);
    }
    CHECK(warning_lines == 1);
    // The last progress line stays, ended by a newline.
    CHECK(std::any_of(lines.begin(), lines.end(), [](const std::string& line) {
        return line.rfind("kdray: frame 3/3", 0) == 0;
    }));
    fs::remove_all(dir);
}

TEST_CASE("Ctrl-C, then --skip-existing into the same folder: every frame once, as one run") {
    // The first run is interrupted once its first image exists; the second renders only what
    // the first did not finish. Each frame is a different scene, so that an image written for
    // the wrong frame, or a frame framed otherwise than in one whole run, shows.
    const fs::path dir = fresh_temp_dir("cli-interrupt-resume");
    constexpr int kFrames = 16;
    for (int f = 0; f < kFrames; ++f)
        write_obj(dir / "in" / ("f_" + std::to_string(f) + ".obj"),
                  random_triangles(2000, std::uint32_t(100 + f)));
    const std::string frames = (dir / "in" / "f_*.obj").string();
    const fs::path out = dir / "out";
    auto args = [&](const fs::path& folder) {
        return std::vector<std::string>{"render",   frames,      "-o",        folder.string(),
                                        "--size",   "24x16",     "--builder", "reference",
                                        "--tracer", "reference", "-q"};
    };
    // SIGINT once the first image exists (polled, so a slow machine does not matter).
    std::ostringstream script;
    script << "'" << KDRAY_BINARY << "'";
    for (const std::string& a : args(out)) script << " '" << a << "'";
    script << " 2>/dev/null & pid=$!; while ! ls '" << out.string()
           << "'/*.png >/dev/null 2>&1 && kill -0 $pid 2>/dev/null; do sleep 0.02; done; "
           << "kill -INT $pid 2>/dev/null; wait $pid; exit $?";
    const int status = std::system(script.str().c_str());
    REQUIRE(WIFEXITED(status));
    REQUIRE(WEXITSTATUS(status) == 130);
    std::vector<int> first_run;
    const nlohmann::json interrupted = read_json(out / "stats.json");
    for (const auto& f : interrupted["frames"]) first_run.push_back(f["frame"].get<int>());
    REQUIRE(!first_run.empty());
    REQUIRE(first_run.size() < std::size_t(kFrames));

    CommandResult resumed = run_kdray(
        [&] {
            std::vector<std::string> a = args(out);
            a.push_back("--skip-existing");
            return a;
        }(),
        300);
    REQUIRE_MESSAGE(resumed.status == 0, resumed.err);
    const nlohmann::json stats = read_json(out / "stats.json");
    std::vector<int> listed, second_run;
    for (const auto& f : stats["frames"]) listed.push_back(f["frame"].get<int>());
    std::vector<int> all(kFrames);
    for (int f = 0; f < kFrames; ++f) all[std::size_t(f)] = f;
    std::sort(listed.begin(), listed.end());
    CHECK(listed == all);  // each exactly once
    REQUIRE(stats["runs"].size() == 2);
    CHECK(stats["runs"][0]["frames_rendered"] == nlohmann::json(first_run));
    std::set_difference(all.begin(), all.end(), first_run.begin(), first_run.end(),
                        std::back_inserter(second_run));
    CHECK(stats["runs"][1]["frames_rendered"] == nlohmann::json(second_run));

    REQUIRE(run_kdray(args(dir / "whole"), 300).status == 0);
    for (int f = 0; f < kFrames; ++f) {
        const std::string image = "f_" + std::to_string(f) + ".png";
        CAPTURE(image);
        const std::string whole = read_file(dir / "whole" / image);
        CHECK(!whole.empty());
        CHECK(read_file(out / image) == whole);
    }
    for (const auto& entry : fs::directory_iterator(out))
        CHECK_MESSAGE(entry.path().filename().string().find(".tmp") == std::string::npos,
                      entry.path().filename().string());
    fs::remove_all(dir);
}

TEST_CASE("a run merges into the folder under its lock: it waits while another holds it") {
    // Shards of a job array may finish into one folder at once; each merges under an exclusive
    // flock of OUT/.kdray-stats.lock. Held here, the run renders every frame, then waits.
    const fs::path dir = fresh_temp_dir("cli-merge-lock");
    const fs::path out = dir / "out";
    fs::create_directories(out);
    // O_CLOEXEC: a kdray started while it is open must not inherit the lock.
    const int lock =
        ::open((out / ".kdray-stats.lock").c_str(), O_RDWR | O_CREAT | O_CLOEXEC, 0644);
    REQUIRE(lock >= 0);
    REQUIRE(::flock(lock, LOCK_EX) == 0);
    auto run = std::async(std::launch::async,
                          [&] { return render(anim_frames(3), out, "reference", {"-q"}); });
    for (int i = 0; i < 600 && !fs::exists(out / "frame_002.png"); ++i)
        std::this_thread::sleep_for(std::chrono::milliseconds(100));
    REQUIRE(fs::exists(out / "frame_002.png"));
    std::this_thread::sleep_for(std::chrono::milliseconds(1500));
    CHECK(!fs::exists(out / "stats.json"));
    ::close(lock);
    REQUIRE(run.get().status == 0);
    CHECK(read_json(out / "stats.json")["frames"].size() == 3);
}

TEST_CASE("--skip-existing skips only frames with a record and all their files") {
    const fs::path dir = fresh_temp_dir("cli-skip");
    const fs::path out = dir / "out";
    const std::vector<std::string> frames = anim_frames(3);
    REQUIRE(render(frames, out, "reference", {"--aov", "-q"}).status == 0);
    // Frame 1's AOV is gone; frame 2's image stays but its record is gone, as after a run
    // killed (SIGKILL) between its image and its stats.json.
    fs::remove(out / "frame_001.aov.exr");
    nlohmann::json stats = read_json(out / "stats.json");
    stats["frames"].erase(2);
    write_text_file(out / "stats.json", stats.dump());
    const CommandResult r =
        render(frames, out, "reference", {"--aov", "--skip-existing", "--log-level", "info", "-q"});
    REQUIRE(r.status == 0);
    CHECK(r.err.find("skipping 1 of 3 frame(s)") != std::string::npos);
    const nlohmann::json merged = read_json(out / "stats.json");
    CHECK(merged["runs"].back()["frames_rendered"] == nlohmann::json({1, 2}));
    CHECK(fs::exists(out / "frame_001.aov.exr"));
    CHECK(merged["frames"].size() == 3);
}

TEST_CASE("scenes rendered one by one into a folder each keep their record") {
    // A folder's stats.json holds a record per image: two scenes at frame 0, side by side, and a
    // scene rendered again replaces its own.
    const fs::path dir = fresh_temp_dir("cli-scenes-one-by-one");
    const fs::path out = dir / "out";
    const fs::path a = write_obj(dir / "a.obj", random_triangles(40, 1));
    const fs::path b = write_obj(dir / "b.obj", random_triangles(50, 2));
    for (const fs::path& scene : {a, b, a})
        REQUIRE(render({scene.string()}, out, "reference", {"-q"}).status == 0);
    const nlohmann::json stats = read_json(out / "stats.json");
    REQUIRE(stats["frames"].size() == 2);
    CHECK(stats["runs"].size() == 3);
    CHECK(stats["frames"][0]["image"] == "a.png");
    CHECK(stats["frames"][0]["run"] == 2);
    CHECK(stats["frames"][0]["scene"]["triangles"] == 40);
    CHECK(stats["frames"][1]["image"] == "b.png");
    CHECK(stats["frames"][1]["run"] == 1);
    CHECK(stats["summary"]["frames"] == 2);
    CHECK(!stats["summary"].contains("warning"));
}

TEST_CASE("a bad first input: a later range frames its own first frame, with a warning") {
    const fs::path dir = fresh_temp_dir("cli-bad-first");
    // All three in one folder: kdray sorts its inputs by path, and the bad frame must sort first
    // wherever the temporary folder lies beside the source tree.
    std::vector<std::string> frames = anim_frames(3);
    write_text_file(dir / "in" / "frame_000.obj", "v 0 0 nan\n");
    for (std::size_t i = 0; i < frames.size(); ++i) {
        const fs::path copy = dir / "in" / fs::path(frames[i]).filename();
        if (i > 0) fs::copy_file(frames[i], copy);
        frames[i] = copy.string();
    }
    const CommandResult r = render(frames, dir / "out", "reference", {"--frames", "1:2", "-q"});
    CHECK(r.status == 0);
    CHECK(r.err.find("kdray: warning: ") != std::string::npos);
    CHECK(r.err.find("frame_000.obj:1") != std::string::npos);
    CHECK(r.err.find("frames its own first frame, 1") != std::string::npos);
    // Framed on frame 1, exactly as a run that starts there would be.
    const std::vector<std::string> good = {frames[1], frames[2]};
    REQUIRE(render(good, dir / "alone", "reference", {"-q"}).status == 0);
    CHECK(read_file(dir / "out" / "frame_001.png") == read_file(dir / "alone" / "frame_001.png"));
}

TEST_CASE("a folder whose stats.json cannot be merged into fails the run before it renders") {
    const fs::path dir = fresh_temp_dir("cli-merge-bad");
    write_text_file(dir / "out" / "stats.json", "{\"frames\": 3");
    const CommandResult r = render(anim_frames(2), dir / "out", "reference", {"-q"});
    CHECK(r.status == 1);
    CHECK(r.err.rfind("kdray: error: ", 0) == 0);
    CHECK(r.err.find("stats.json") != std::string::npos);
    CHECK(std::count(r.err.begin(), r.err.end(), '\n') == 1);
    CHECK(!fs::exists(dir / "out" / "frame_000.png"));
}

TEST_CASE("off a terminal a run logs its device, its compiles and one plain line per frame") {
    for (const std::string path : {"opencl", "reference"}) {
        CAPTURE(path);
        const fs::path dir = fresh_temp_dir("cli-log-" + path);
        const CommandResult r = render(anim_frames(3), dir / "out", path);
        REQUIRE(r.status == 0);
        INFO("stderr: " << r.err);
        // run_kdray's stderr is a pipe: no progress line, no carriage returns.
        CHECK(r.err.find('\r') == std::string::npos);
        CHECK(count_lines_with(r.err, "kdray: rendering 3 frame(s) into ") == 1);
        CHECK(r.err.find("effects: ") != std::string::npos);
        for (const char* line :
             {"kdray: frame 0 (1/3, ", "kdray: frame 1 (2/3, ", "kdray: frame 2 (3/3, "})
            CHECK_MESSAGE(count_lines_with(r.err, line) == 1, line);
        CHECK(count_lines_with(r.err, " fps)") == 3);
        if (path == "opencl") {
            // The device is named, and why the first frame waits.
            const nlohmann::json stats = read_json(dir / "out" / "stats.json");
            const std::string builder = stats["builder"];
            CHECK(r.err.find(builder) != std::string::npos);
            CHECK(count_lines_with(r.err, "kdray: compiling OpenCL kernels for '") == 1);
            CHECK(stats["frames"][0]["compile_ms"].get<double>() > 0);
        } else {
            CHECK(r.err.find("compiling") == std::string::npos);
        }
        // quiet: nothing but warnings and errors; debug: each program's build.
        const CommandResult quiet =
            render(anim_frames(2), dir / "quiet", path, {"--log-level", "quiet"});
        CHECK(quiet.status == 0);
        CHECK(quiet.err.empty());
        const CommandResult q = render(anim_frames(2), dir / "q", path, {"-q"});
        CHECK(q.err.empty());
        if (path == "opencl") {
            const CommandResult debug =
                render(anim_frames(2), dir / "debug", path, {"--log-level", "debug"});
            CHECK(debug.status == 0);
            CHECK(debug.err.find("kdray: debug: built ") != std::string::npos);
        }
    }
    const CommandResult bad = run_kdray({"render", "x.obj", "-o", "o", "--log-level", "loud"});
    CHECK(bad.status == 2);
    CHECK(bad.err.find("--log-level") != std::string::npos);
}
