#include "core/run/render_stats.h"

#include <fcntl.h>
#include <sys/file.h>
#include <unistd.h>

#include <cerrno>
#include <cstring>

#include <algorithm>
#include <map>
#include <set>
#include <string>
#include <vector>

#include "core/error.h"
#include "core/io/atomic_file.h"
#include "core/io/input_file.h"
#include "core/run/image_settings.h"
#include "core/run/stats_json.h"

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

/// `value` as a message quotes it: its JSON text, cut to 40 bytes (a 30 MB string is one field).
std::string excerpt(const nlohmann::json& value) {
    std::string text = value.dump(-1, ' ', true, nlohmann::json::error_handler_t::replace);
    if (text.size() > 40) text = text.substr(0, 40) + "...";
    return text;
}

/// The names a frame's record (or failure) is matched by across runs: strings where present.
void check_names(const nlohmann::json& record, const std::string& where) {
    for (const char* key : {"input", "image"})
        if (record.contains(key) && !record[key].is_string())
            throw Error(where + "." + key + " is " + excerpt(record[key]) + ", not a file name");
}

/// A frame's time as kdray writes it: a number of milliseconds, >= 0, and at most 10^12 (31
/// years), so that the summary's sums over every record a stats.json can hold stay finite: two
/// records of 1e308 ms summed to inf, which `kdray stats` printed and JSON writes as null.
bool is_time_ms(const nlohmann::json& value) {
    return value.is_number() && value.get<double>() >= 0.0 && value.get<double>() <= 1e12;
}

/// What a record is of: its image's file name (a record per image in the folder), or, for a
/// failure recorded before failures named their image, its frame and input.
std::string record_key(const nlohmann::json& record) {
    if (record.contains("image") && record["image"].is_string()) return record["image"];
    return std::to_string(frame_number(record)) + "|" + record.value("input", std::string());
}

/// Records in frame order, then by image: the order of an animation, of scenes at frame 0.
bool record_before(const nlohmann::json& a, const nlohmann::json& b) {
    const std::size_t fa = frame_number(a), fb = frame_number(b);
    return fa != fb ? fa < fb : record_key(a) < record_key(b);
}

}  // namespace

std::uint64_t stats_size_limit() {
    return std::min(kMaxStatsBytes, input_size_limit() / 8);
}

nlohmann::json read_render_stats(const std::filesystem::path& file) {
    nlohmann::json parsed =
        parse_json(read_input_file(file, "stats.json file", stats_size_limit()), file.string());
    // Checked through a const view: operator[] on the object itself would add missing keys.
    const nlohmann::json& stats = parsed;
    if (!stats.is_object() || !stats.contains("summary") || !stats.contains("frames") ||
        !stats["frames"].is_array())
        throw Error(file.string() + ": not a kdray stats file (no summary or frames)");
    // Every field kdray reads back must be what kdray writes: a frame number that is a count,
    // times that are numbers, names that are strings; checked here, before a run renders
    // anything into the folder, and named with the file and the field.
    for (const char* key : {"builder", "tracer"})
        if (stats.contains(key) && !stats[key].is_string())
            throw Error(file.string() + ": " + key + " is " + excerpt(stats[key]) +
                        ", not a string");
    for (std::size_t k = 0; k < stats["frames"].size(); ++k) {
        const nlohmann::json& frame = stats["frames"][k];
        const std::string where = file.string() + ": frames[" + std::to_string(k) + "]";
        if (!frame.is_object()) throw Error(where + " is not an object");
        if (frame.contains("frame") && !frame["frame"].is_number_unsigned())
            throw Error(where + ".frame is " + excerpt(frame["frame"]) + ", not a frame number");
        for (const char* key : {"frame_ms", "load_ms", "load_wait_ms", "compile_ms", "build_ms",
                                "trace_ms", "write_ms", "other_ms"})
            if (frame.contains(key) && !is_time_ms(frame[key]))
                throw Error(where + "." + key + " is " + excerpt(frame[key]) +
                            ", not a time in milliseconds (a number from 0 to 1e12)");
        if (frame.contains("run") && !frame["run"].is_number_unsigned())
            throw Error(where + ".run is " + excerpt(frame["run"]) + ", not a run index");
        check_names(frame, where);
    }
    if (stats.contains("runs")) {
        if (!stats["runs"].is_array()) throw Error(file.string() + ": runs is not a list");
        for (std::size_t k = 0; k < stats["runs"].size(); ++k)
            if (!stats["runs"][k].is_object())
                throw Error(file.string() + ": runs[" + std::to_string(k) +
                            "] is not an object (a run's settings)");
    }
    if (stats.contains("failed_frames")) {
        if (!stats["failed_frames"].is_array())
            throw Error(file.string() + ": failed_frames is not a list");
        for (std::size_t k = 0; k < stats["failed_frames"].size(); ++k) {
            const nlohmann::json& failure = stats["failed_frames"][k];
            const std::string where = file.string() + ": failed_frames[" + std::to_string(k) + "]";
            if (!failure.is_object() || !failure.contains("frame") ||
                !failure["frame"].is_number_unsigned())
                throw Error(where +
                            " is not a failed frame's record (an object with its frame number)");
            check_names(failure, where);
        }
    }
    return parsed;
}

nlohmann::json read_folder_stats(const std::filesystem::path& dir) {
    const std::filesystem::path file = dir / "stats.json";
    std::error_code ec;
    const auto status = std::filesystem::symlink_status(file, ec);
    if (!std::filesystem::exists(status)) return nullptr;
    if (std::filesystem::is_directory(status))
        throw Error(file.string() + ": exists and is a directory, where the run writes its stats");
    // The merged file replaces the link, not what it names: refused before the run renders, not
    // after.
    if (std::filesystem::is_symlink(status))
        throw Error(file.string() +
                    ": is a symbolic link, where the run writes its stats; move it away, or "
                    "render into another folder");
    try {
        return read_render_stats(file);
    } catch (const Error& e) {
        throw Error(std::string(e.what()) +
                    "; a run merges its frames into the folder's stats.json: move it away, or "
                    "render into another folder");
    }
}

std::set<std::string> completed_images(const nlohmann::json& previous) {
    std::set<std::string> done;
    if (!previous.is_object()) return done;
    for (const nlohmann::json& record : previous.value("frames", nlohmann::json::array()))
        done.insert(record_key(record));
    for (const nlohmann::json& record : previous.value("failed_frames", nlohmann::json::array()))
        done.erase(record_key(record));
    return done;
}

namespace {

/// An exclusive lock (flock) on a lock file in the folder, held while a run reads, merges and
/// writes the folder's stats.json. The file stays: removing it would let a waiting run lock a
/// file that a third has already replaced.
class FolderLock {
  public:
    explicit FolderLock(const std::filesystem::path& dir) {
        const std::filesystem::path path = dir / ".kdray-stats.lock";
        fd_ = ::open(path.c_str(), O_RDWR | O_CREAT | O_CLOEXEC | O_NOFOLLOW, 0644);
        if (fd_ < 0) {
            problem_ = path.string() + ": " + std::strerror(errno);
            return;
        }
        while (::flock(fd_, LOCK_EX) != 0) {
            if (errno == EINTR) continue;
            problem_ = path.string() + ": " + std::strerror(errno);
            break;
        }
    }
    ~FolderLock() {
        if (fd_ >= 0) ::close(fd_);
    }
    FolderLock(const FolderLock&) = delete;
    FolderLock& operator=(const FolderLock&) = delete;

    const std::string& problem() const { return problem_; }

  private:
    int fd_ = -1;
    std::string problem_;
};

}  // namespace

FolderMerge merge_into_folder(const std::filesystem::path& dir, nlohmann::json run,
                              bool replace_other_settings) {
    const FolderLock lock(dir);
    const nlohmann::json merged =
        merge_render_stats(read_folder_stats(dir), std::move(run), replace_other_settings);
    write_file_atomically(dir / "stats.json", json_text(merged) + "\n");
    return {lock.problem().empty(), lock.problem()};
}

std::vector<nlohmann::json> frames_by_run(const nlohmann::json& frames) {
    // Each run's frames in frame order: its first is the one that built the programs. Only what
    // summarise_runs reads is copied: a whole copy of every record doubled the memory a large
    // stats.json took.
    std::map<std::size_t, nlohmann::json> by_run;
    for (const nlohmann::json& frame : frames) {
        nlohmann::json& group = by_run[frame.value("run", std::size_t(0))];
        if (group.is_null()) group = nlohmann::json::array();
        nlohmann::json summary = nlohmann::json::object();
        for (const char* key : {"frame", "image", "input", "frame_ms", "load_wait_ms", "compile_ms",
                                "build_ms", "trace_ms", "write_ms"})
            if (const auto it = frame.find(key); it != frame.end()) summary[key] = *it;
        group.push_back(std::move(summary));
    }
    std::vector<nlohmann::json> groups;
    for (auto& [index, group] : by_run) {
        std::stable_sort(group.begin(), group.end(), record_before);
        groups.push_back(std::move(group));
    }
    return groups;
}

nlohmann::json merge_render_stats(nlohmann::json previous, nlohmann::json run,
                                  bool replace_other_settings) {
    // The earlier runs: a file written before runs were recorded is one run. Their records are
    // moved, not copied, out of `previous`: copies made a large stats.json's merge cost several
    // times its parse.
    nlohmann::json runs = nlohmann::json::array();
    std::vector<nlohmann::json> frames;
    nlohmann::json failures = nlohmann::json::array();
    if (previous.is_object()) {
        if (previous.contains("runs")) {
            runs = std::move(previous["runs"]);
        } else {
            nlohmann::json only = settings_of(previous);
            only["frames_rendered"] = nlohmann::json::array();
            for (const nlohmann::json& f : previous.value("frames", nlohmann::json::array()))
                only["frames_rendered"].push_back(frame_number(f));
            runs.push_back(std::move(only));
        }
        if (previous.contains("frames"))
            for (nlohmann::json& frame : previous["frames"]) {
                if (!frame.contains("run")) frame["run"] = 0;
                frames.push_back(std::move(frame));
            }
        if (previous.contains("failed_frames")) failures = std::move(previous["failed_frames"]);
    }

    if (replace_other_settings) {
        const nlohmann::json own = image_settings(run);
        frames.erase(std::remove_if(frames.begin(), frames.end(),
                                    [&](const nlohmann::json& f) {
                                        const std::size_t r = f.value("run", std::size_t(0));
                                        return r < runs.size() &&
                                               settings_differ(image_settings(runs[r], f), own);
                                    }),
                     frames.end());
    }

    // This run's records replace the earlier records of their frames, and its failures the
    // earlier failures; an earlier record of a frame that failed now stays with its image.
    const std::size_t run_index = runs.size();
    nlohmann::json run_frames = run.value("frames", nlohmann::json::array());
    nlohmann::json run_failures = run.value("failed_frames", nlohmann::json::array());
    std::set<std::string> rendered_now, attempted_now;
    for (const nlohmann::json& f : run_frames) rendered_now.insert(record_key(f));
    attempted_now = rendered_now;
    for (const nlohmann::json& f : run_failures) attempted_now.insert(record_key(f));
    frames.erase(std::remove_if(frames.begin(), frames.end(),
                                [&](const nlohmann::json& f) {
                                    return rendered_now.count(record_key(f)) > 0;
                                }),
                 frames.end());
    nlohmann::json kept_failures = nlohmann::json::array();
    for (const nlohmann::json& f : failures)
        if (attempted_now.count(record_key(f)) == 0) kept_failures.push_back(f);
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
    std::stable_sort(frames.begin(), frames.end(), record_before);

    nlohmann::json settings = settings_of(run);
    nlohmann::json run_record = settings;
    run_record["frames_rendered"] = rendered;
    runs.push_back(std::move(run_record));

    nlohmann::json merged = std::move(settings);
    // A run's warnings are its own record's: the top level speaks for the folder.
    merged.erase("warnings");
    merged["runs"] = std::move(runs);
    merged["frames"] = nlohmann::json::array();
    for (nlohmann::json& frame : frames) merged["frames"].push_back(std::move(frame));
    // Never one size claimed for a folder that holds several (--mixed, or files from before the
    // guard).
    if (nlohmann::json image = folder_image(merged, merged.value("image", nlohmann::json()));
        !image.is_null())
        merged["image"] = std::move(image);
    merged["summary"] = summarise_runs(frames_by_run(merged["frames"]));
    // One folder holds one record per image: scenes rendered one by one into it share frame 0.
    merged["summary"].erase("warning");
    if (!kept_failures.empty()) merged["failed_frames"] = std::move(kept_failures);
    return merged;
}

}  // namespace kdray
