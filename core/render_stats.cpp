#include "core/render_stats.h"

#include <algorithm>
#include <map>
#include <set>
#include <string>
#include <vector>

#include "core/error.h"
#include "core/input_file.h"
#include "core/stats_json.h"

namespace kdray {
namespace {

/// The keys of the file that are not a run's settings.
bool is_folder_key(const std::string& key) {
    return key == "frames" || key == "summary" || key == "runs" || key == "failed_frames";
}

/// A run's settings: `record`'s keys but the folder's.
nlohmann::json settings_of(const nlohmann::json& record) {
    nlohmann::json settings = nlohmann::json::object();
    for (const auto& [key, value] : record.items())
        if (!is_folder_key(key)) settings[key] = value;
    return settings;
}

std::size_t frame_number(const nlohmann::json& record) {
    return record.value("frame", std::size_t(0));
}

}  // namespace

nlohmann::json read_render_stats(const std::filesystem::path& file) {
    nlohmann::json stats;
    try {
        stats = nlohmann::json::parse(read_input_file(file, "stats.json file"));
    } catch (const nlohmann::json::exception& e) {
        throw Error(file.string() + ": malformed JSON: " + e.what());
    }
    if (!stats.is_object() || !stats.contains("summary") || !stats.contains("frames") ||
        !stats["frames"].is_array())
        throw Error(file.string() + ": not a kdray stats file (no summary or frames)");
    // What the summary reads must be what kdray writes: a frame number that is a count, times
    // that are numbers.
    for (std::size_t k = 0; k < stats["frames"].size(); ++k) {
        const nlohmann::json& frame = stats["frames"][k];
        const std::string where = file.string() + ": frames[" + std::to_string(k) + "]";
        if (!frame.is_object()) throw Error(where + " is not an object");
        if (frame.contains("frame") && !frame["frame"].is_number_unsigned())
            throw Error(where + ".frame is " + frame["frame"].dump() + ", not a frame number");
        for (const char* key : {"frame_ms", "load_ms", "load_wait_ms", "compile_ms", "build_ms",
                                "trace_ms", "write_ms", "other_ms"})
            if (frame.contains(key) && !frame[key].is_number())
                throw Error(where + "." + key + " is " + frame[key].dump() + ", not a number");
        if (frame.contains("run") && !frame["run"].is_number_unsigned())
            throw Error(where + ".run is " + frame["run"].dump() + ", not a run index");
    }
    if (stats.contains("runs") && !stats["runs"].is_array())
        throw Error(file.string() + ": runs is not a list");
    if (stats.contains("failed_frames") && !stats["failed_frames"].is_array())
        throw Error(file.string() + ": failed_frames is not a list");
    return stats;
}

std::vector<nlohmann::json> frames_by_run(const nlohmann::json& frames) {
    // Each run's frames in frame order: its first is the one that built the programs.
    std::map<std::size_t, nlohmann::json> by_run;
    for (const nlohmann::json& frame : frames) {
        nlohmann::json& group = by_run[frame.value("run", std::size_t(0))];
        if (group.is_null()) group = nlohmann::json::array();
        group.push_back(frame);
    }
    std::vector<nlohmann::json> groups;
    for (auto& [index, group] : by_run) {
        std::stable_sort(group.begin(), group.end(), [](const auto& a, const auto& b) {
            return frame_number(a) < frame_number(b);
        });
        groups.push_back(std::move(group));
    }
    return groups;
}

nlohmann::json merge_render_stats(const nlohmann::json& previous, nlohmann::json run) {
    // The earlier runs: a file written before runs were recorded is one run.
    nlohmann::json runs = nlohmann::json::array();
    std::vector<nlohmann::json> frames;
    nlohmann::json failures = nlohmann::json::array();
    if (previous.is_object()) {
        runs = previous.contains("runs") ? previous["runs"]
                                         : nlohmann::json::array({settings_of(previous)});
        for (nlohmann::json frame : previous.value("frames", nlohmann::json::array())) {
            if (!frame.contains("run")) frame["run"] = 0;
            frames.push_back(std::move(frame));
        }
        failures = previous.value("failed_frames", nlohmann::json::array());
    }

    // This run's frames (rendered or failed) replace the earlier records of their numbers.
    const std::size_t run_index = runs.size();
    nlohmann::json run_frames = run.value("frames", nlohmann::json::array());
    nlohmann::json run_failures = run.value("failed_frames", nlohmann::json::array());
    std::set<std::size_t> replaced;
    for (const nlohmann::json& f : run_frames) replaced.insert(frame_number(f));
    for (const nlohmann::json& f : run_failures) replaced.insert(frame_number(f));
    auto is_replaced = [&](const nlohmann::json& f) { return replaced.count(frame_number(f)) > 0; };
    frames.erase(std::remove_if(frames.begin(), frames.end(), is_replaced), frames.end());
    nlohmann::json kept_failures = nlohmann::json::array();
    for (const nlohmann::json& f : failures)
        if (!is_replaced(f)) kept_failures.push_back(f);
    std::vector<std::size_t> rendered;
    for (nlohmann::json& frame : run_frames) {
        rendered.push_back(frame_number(frame));
        frame["run"] = run_index;
        frames.push_back(std::move(frame));
    }
    for (nlohmann::json& f : run_failures) {
        f["run"] = run_index;
        kept_failures.push_back(std::move(f));
    }
    std::stable_sort(frames.begin(), frames.end(), [](const auto& a, const auto& b) {
        return frame_number(a) < frame_number(b);
    });

    nlohmann::json settings = settings_of(run);
    nlohmann::json run_record = settings;
    run_record["frames_rendered"] = rendered;
    runs.push_back(std::move(run_record));

    nlohmann::json merged = std::move(settings);
    merged["runs"] = std::move(runs);
    merged["frames"] = frames;
    merged["summary"] = summarise_runs(frames_by_run(merged["frames"]));
    if (!kept_failures.empty()) merged["failed_frames"] = std::move(kept_failures);
    return merged;
}

}  // namespace kdray
