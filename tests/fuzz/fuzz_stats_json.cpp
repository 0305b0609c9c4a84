// fuzz_stats_json.cpp — libFuzzer target for a render folder's stats.json as kdray reads it back
// (issue #29, problems 2, 8 and 10): the bytes are the folder's stats.json, read by
// read_folder_stats (what `kdray render -o` does before it renders: parse_json's depth budget and
// duplicate keys, read_render_stats's field types), then summarised as `kdray stats FOLDER` does
// (frames_by_run, summarise_runs, the builder and tracer it prints), asked for what
// --skip-existing skips (completed_images), and merged with a run's records as a run ends
// (merge_render_stats). kdray::Error from the read is the expected outcome of a bad file. A
// sanitizer report, any other exception, an Error after the file was accepted (the run would
// have rendered every frame and then failed to record them), a merged file that kdray cannot read
// back or that lost the run's frame, or a summary that is not finite numbers is a bug.
#include <unistd.h>

#include <cmath>
#include <cstdint>
#include <cstdio>
#include <cstdlib>
#include <filesystem>
#include <fstream>
#include <string>

#include <nlohmann/json.hpp>

#include "core/error.h"
#include "core/run/render_stats.h"
#include "core/run/stats_json.h"
#include "tests/fuzz/fuzz_scratch.h"

namespace fs = std::filesystem;
using nlohmann::json;

namespace {

[[noreturn]] void bug(const char* what, const std::string& detail = "") {
    std::fprintf(stderr, "fuzz_stats_json: invariant broken: %s %s\n", what, detail.c_str());
    std::abort();
}

/// This process's scratch folder (fuzz_scratch.h).
const fs::path& scratch() {
    return kdray::fuzz::scratch_folder("fuzz-stats");
}

void write(const fs::path& path, const char* data, std::size_t size) {
    std::ofstream out(path, std::ios::binary | std::ios::trunc);
    out.write(data, std::streamsize(size));
}

/// Every number in a summary finite: `kdray stats` prints it, and JSON writes inf as null.
void check_summary(const json& summary) {
    if (!summary.is_object()) bug("a summary that is not an object");
    for (const auto& [key, value] : summary.items())
        if (value.is_number_float() && !std::isfinite(value.get<double>()))
            bug("a summary with a non-finite number:", key);
}

}  // namespace

extern "C" int LLVMFuzzerTestOneInput(const std::uint8_t* data, std::size_t size) {
    const fs::path file = scratch() / "stats.json";
    write(file, reinterpret_cast<const char*>(data), size);
    json previous;
    try {
        previous = kdray::read_folder_stats(scratch());
    } catch (const kdray::Error&) {
        return 0;  // a bad file, refused before anything renders
    }
    if (previous.is_null()) bug("a stats.json that is there read as none");
    try {
        // `kdray stats FOLDER`.
        check_summary(kdray::summarise_runs(kdray::frames_by_run(previous["frames"])));
        if (previous.value("builder", "").size() > size ||
            previous.value("tracer", "").size() > size)
            bug("a builder or tracer longer than the file");
        // `kdray render --skip-existing`.
        kdray::completed_images(previous);
        // The end of a run: frame 3 rendered, frame 4 failed.
        const json run = {{"builder", "reference"},
                          {"tracer", "reference"},
                          {"frames",
                           {{{"frame", 3},
                             {"image", "frame_0003.png"},
                             {"input", "scene.obj"},
                             {"frame_ms", 2.5},
                             {"build_ms", 1.0},
                             {"trace_ms", 1.5}}}},
                          {"failed_frames",
                           {{{"frame", 4},
                             {"image", "frame_0004.png"},
                             {"input", "scene.obj"},
                             {"error", "scene.obj: no triangles"}}}}};
        const json merged = kdray::merge_render_stats(std::move(previous), run);
        check_summary(merged.at("summary"));
        const std::string text = kdray::json_text(merged) + "\n";
        write(file, text.data(), text.size());
        const json back = kdray::read_render_stats(file);
        const auto done = kdray::completed_images(back);
        if (done.count("frame_0003.png") == 0) bug("the merged file lost the run's frame");
        if (done.count("frame_0004.png") != 0) bug("the merged file counts a failed frame as done");
    } catch (const kdray::Error& e) {
        bug("an accepted stats.json failed after the read:", e.what());
    }
    return 0;
}
