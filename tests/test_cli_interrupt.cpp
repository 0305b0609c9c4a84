// test_cli_interrupt.cpp — Ctrl-C on `kdray render` through the binary, as a user meets it: the
// first signal said at once and the run stopped after its frame, with the command that resumes
// it; that command pasted back finishing the run; a second signal said and ending the process
// before stats.json, leaving no image that is not whole.
#include <doctest/doctest.h>

#include <sys/wait.h>

#include <csignal>
#include <cstdlib>
#include <filesystem>
#include <sstream>
#include <string>
#include <vector>

#include <nlohmann/json.hpp>

#include "tests/support.h"

namespace fs = std::filesystem;
using namespace kdray;
using namespace kdray::test;

namespace {

constexpr int kFrames = 4;

/// kFrames scenes of 3000 random triangles in `dir`/in, traced on one thread at 128 spp so that a
/// frame lasts long enough (about 0.6 s on an EPYC core) for the signals to land inside the run.
std::vector<std::string> slow_frames(const fs::path& dir) {
    std::vector<std::string> frames;
    for (int f = 0; f < kFrames; ++f)
        frames.push_back(write_obj(dir / "in" / ("f_" + std::to_string(f) + ".obj"),
                                   random_triangles(3000, std::uint32_t(300 + f)))
                             .string());
    return frames;
}

std::vector<std::string> render_args(const std::vector<std::string>& frames, const fs::path& out) {
    std::vector<std::string> args = {"render"};
    args.insert(args.end(), frames.begin(), frames.end());
    for (const char* a : {"--size", "256x192", "--spp", "128", "--builder", "reference", "--tracer",
                          "reference", "--threads", "1"})
        args.emplace_back(a);
    args.emplace_back("-o");
    args.push_back(out.string());
    return args;
}

struct SignalledRun {
    int status = -1;  // the shell's $? of kdray: 128 + signal when a signal ended it
    std::string err;
};

/// Runs kdray with `args` in the background, stderr to a file; once its log says the first frame
/// is rendering, sends SIGINT; with `twice`, a second SIGINT once the first is acknowledged.
SignalledRun run_and_interrupt(const std::vector<std::string>& args, const fs::path& dir,
                               bool twice) {
    const fs::path err = dir / "err.txt", status = dir / "status.txt";
    std::ostringstream script;
    script << shell_quoted(KDRAY_BINARY);
    for (const std::string& a : args) script << ' ' << shell_quoted(a);
    const std::string wait_for = "while ! grep -q %s " + shell_quoted(err.string()) +
                                 " && kill -0 $pid 2>/dev/null; do sleep 0.02; done; ";
    auto waiting = [&](const std::string& text) {
        std::string w = wait_for;
        return w.replace(w.find("%s"), 2, shell_quoted(text));
    };
    script << " 2>" << shell_quoted(err.string()) << " </dev/null & pid=$!; "
           << waiting("^kdray: rendering ") << "kill -INT $pid 2>/dev/null; ";
    if (twice) script << waiting("stopping after this frame") << "kill -INT $pid 2>/dev/null; ";
    script << "wait $pid; echo $? >" << shell_quoted(status.string());
    REQUIRE(std::system(script.str().c_str()) == 0);
    SignalledRun run;
    run.status = std::atoi(read_file(status).c_str());
    run.err = read_file(err);
    return run;
}

/// The line of `text` that starts with `prefix`, without its newline; "" when none does.
std::string line_starting(const std::string& text, const std::string& prefix) {
    std::istringstream lines(text);
    for (std::string line; std::getline(lines, line);)
        if (line.rfind(prefix, 0) == 0) return line;
    return {};
}

}  // namespace

TEST_CASE("Ctrl-C is said at once, stops after the frame, and prints the command that resumes") {
    const fs::path dir = fresh_temp_dir("cli-ctrl-c");
    const std::vector<std::string> frames = slow_frames(dir);
    // A space and an apostrophe in the folder: the resume command must quote it for the shell.
    const fs::path out = dir / "out dir's";
    const SignalledRun run = run_and_interrupt(render_args(frames, out), dir, false);
    INFO("stderr: " << run.err);
    CHECK(run.status == 130);
    CHECK(line_starting(run.err, "kdray: stopping after this frame") ==
          "kdray: stopping after this frame; Ctrl-C again to abort now");
    const nlohmann::json stats = read_json(out / "stats.json");
    const std::size_t done = stats["frames"].size();
    CHECK(done >= 1);
    CHECK(done < std::size_t(kFrames));
    CHECK(stats["interrupted_after_frames"] == done);

    // "kdray: interrupted: N frame(s) complete in OUT; resume with: COMMAND"
    const std::string interrupted = line_starting(run.err, "kdray: interrupted: ");
    const std::string marker = "; resume with: ";
    REQUIRE(interrupted.find(marker) != std::string::npos);
    CHECK(interrupted.rfind("kdray: interrupted: " + std::to_string(done) + " frame(s) complete",
                            0) == 0);
    const std::string resume = interrupted.substr(interrupted.find(marker) + marker.size());
    std::vector<std::string> expected = render_args(frames, out);
    expected.insert(expected.begin() + 1, "--skip-existing");
    std::string command = shell_quoted(KDRAY_BINARY);
    for (const std::string& a : expected) command += ' ' + shell_quoted(a);
    // The same words, whichever quoting: the shell's own reading of both.
    const fs::path said = dir / "said.txt", meant = dir / "meant.txt";
    REQUIRE(std::system(
                ("printf '%s\\n' " + resume + " >" + shell_quoted(said.string())).c_str()) == 0);
    REQUIRE(std::system(
                ("printf '%s\\n' " + command + " >" + shell_quoted(meant.string())).c_str()) == 0);
    CHECK(read_file(said) == read_file(meant));

    // Pasted back, it renders the rest and only the rest.
    REQUIRE(std::system((resume + " -q 2>/dev/null").c_str()) == 0);
    const nlohmann::json resumed = read_json(out / "stats.json");
    CHECK(resumed["frames"].size() == std::size_t(kFrames));
    REQUIRE(resumed["runs"].size() == 2);
    CHECK(resumed["runs"][1]["frames_rendered"].size() == std::size_t(kFrames) - done);
    fs::remove_all(dir);
}

TEST_CASE("a second Ctrl-C is said and ends the process before stats.json; images stay whole") {
    const fs::path dir = fresh_temp_dir("cli-ctrl-c-twice");
    const fs::path out = dir / "out";
    const SignalledRun run = run_and_interrupt(render_args(slow_frames(dir), out), dir, true);
    INFO("stderr: " << run.err);
    CHECK(run.status == 128 + SIGINT);  // the shell says so for a process the signal ended
    CHECK(run.err.find("kdray: stopping after this frame; Ctrl-C again to abort now\n") !=
          std::string::npos);
    CHECK(line_starting(run.err, "kdray: aborted") == "kdray: aborted");
    CHECK(line_starting(run.err, "kdray: interrupted").empty());
    CHECK(!fs::exists(out / "stats.json"));
    // Whatever image is under its final name is whole: a PNG ends with its IEND chunk.
    if (fs::exists(out))
        for (const auto& entry : fs::directory_iterator(out))
            if (entry.path().extension() == ".png") {
                const std::string png = read_file(entry.path());
                CHECK_MESSAGE(png.size() > 12, entry.path());
                CHECK_MESSAGE(png.find("IEND") == png.size() - 8, entry.path());
            }
    fs::remove_all(dir);
}
