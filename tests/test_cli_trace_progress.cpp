// test_cli_trace_progress.cpp — what `kdray render` says while a frame traces, through the binary:
// off a terminal an info line at intervals (KDRAY_PROGRESS_INTERVAL_S, 10 s by default) with the
// share of the frame's primary rays traced, their count checked against the closed form
// width x height x (spp + 1); on a terminal (a pseudo-terminal from script(1)) the progress line
// drawn while the frame traces. Both tracers report between chunks of their work.
#include <doctest/doctest.h>

#include <cstdlib>
#include <filesystem>
#include <regex>
#include <sstream>
#include <string>
#include <vector>

#include "tests/support.h"

namespace fs = std::filesystem;
using namespace kdray;
using namespace kdray::test;

namespace {

/// Arguments that trace one frame of 3000 random triangles for a while: the reference tracer on
/// one thread at 256x192 and 64 spp (about 0.4 s on an EPYC core), or the OpenCL tracer over a
/// wide image that takes several launches.
std::vector<std::string> slow_frame(const fs::path& dir, const std::string& tracer) {
    const fs::path obj = write_obj(dir / "scene.obj", random_triangles(3000, 7));
    std::vector<std::string> args = {"render", obj.string(), "-o", (dir / "out").string()};
    if (tracer == "reference")
        args.insert(args.end(), {"--size", "256x192", "--spp", "64", "--builder", "reference",
                                 "--tracer", "reference", "--threads", "1"});
    else
        args.insert(args.end(), {"--size", "1024x512", "--spp", "16"});
    return args;
}

/// The percentages of the "traced N% of its M primary rays" lines of `err`, each M in `totals`.
std::vector<int> traced_percentages(const std::string& err, std::vector<long long>& totals) {
    static const std::regex line(
        R"(^kdray: frame 0 \(1/1\): traced (\d+)% of its (\d+) primary rays, [0-9.]+ Mrays/s; )"
        R"(about [0-9.]+ s left in the frame, [0-9.]+ s in the run$)");
    std::vector<int> percentages;
    std::istringstream lines(err);
    for (std::string text; std::getline(lines, text);)
        if (std::smatch m; std::regex_match(text, m, line)) {
            percentages.push_back(std::stoi(m[1]));
            totals.push_back(std::stoll(m[2]));
        }
    return percentages;
}

}  // namespace

TEST_CASE("off a terminal a long frame says how far its trace is, at intervals") {
    for (const std::string tracer : {"reference", "opencl"}) {
        CAPTURE(tracer);
        const fs::path dir = fresh_temp_dir("trace-progress-" + tracer);
        const std::vector<std::string> args = slow_frame(dir, tracer);
        const long long rays = tracer == "reference" ? 256LL * 192 * 65 : 1024LL * 512 * 17;
        {
            const ScopedEnv interval("KDRAY_PROGRESS_INTERVAL_S", "0.02");
            const CommandResult r = run_kdray(args, 300);
            INFO("stderr: " << r.err);
            REQUIRE(r.status == 0);
            std::vector<long long> totals;
            const std::vector<int> percentages = traced_percentages(r.err, totals);
            CHECK(!percentages.empty());
            for (std::size_t k = 0; k < percentages.size(); ++k) {
                CHECK(totals[k] == rays);
                CHECK(percentages[k] > 0);
                CHECK(percentages[k] < 100);
                // Whole percents, rounded down: two lines may show the same one.
                if (k > 0) CHECK(percentages[k] >= percentages[k - 1]);
            }
            // Said before the frame's own line.
            CHECK(r.err.find("traced ") < r.err.find("kdray: frame 0 (1/1, "));
        }
        // At the default interval (10 s) a frame this short says nothing while it traces; -q
        // says nothing at all.
        std::vector<long long> totals;
        CHECK(traced_percentages(run_kdray(args, 300).err, totals).empty());
        std::vector<std::string> quiet = args;
        quiet.push_back("-q");
        const ScopedEnv interval("KDRAY_PROGRESS_INTERVAL_S", "0.02");
        CHECK(run_kdray(quiet, 300).err.empty());
        fs::remove_all(dir);
    }
}

TEST_CASE("on a terminal the progress line is drawn while the frame traces") {
    const fs::path dir = fresh_temp_dir("trace-progress-terminal");
    if (std::system("script --version >/dev/null 2>&1") != 0) {
        MESSAGE("skipped: script(1) is not installed");
        return;
    }
    std::string command = shell_quoted(KDRAY_BINARY);
    for (const std::string& a : slow_frame(dir, "reference")) command += ' ' + shell_quoted(a);
    const fs::path typescript = dir / "terminal.txt";
    REQUIRE(std::system(("script -qec " + shell_quoted(command) + " /dev/null >" +
                         shell_quoted(typescript.string()) + " 2>&1 </dev/null")
                            .c_str()) == 0);
    const std::string bytes = read_file(typescript);
    INFO("terminal: " << bytes);
    static const std::regex drawn(
        R"(\r\x1b\[Kkdray: frame 1/1  tracing (\d+)%  [0-9.]+ Mrays/s  ETA \d+ s)");
    std::vector<int> percentages;
    for (auto it = std::sregex_iterator(bytes.begin(), bytes.end(), drawn);
         it != std::sregex_iterator(); ++it)
        percentages.push_back(std::stoi((*it)[1]));
    REQUIRE(!percentages.empty());
    CHECK(percentages.front() > 0);
    CHECK(percentages.back() < 100);
    // Then the frame's own progress line, as before.
    CHECK(bytes.find("kdray: frame 1/1  ") != std::string::npos);
    CHECK(bytes.rfind("tracing") < bytes.rfind("fps"));
    fs::remove_all(dir);
}
