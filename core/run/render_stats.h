// render_stats.h — a render folder's stats.json across runs. A folder can be rendered by several
// runs (an interrupted run resumed with --skip-existing or --frames, the shards of a job array):
// its stats.json keeps the newest record of every image in the folder (a frame of an
// animation, or a scene rendered on its own), each tagged with the run that rendered it, and one
// summary over them all.
//
// The file: the newest run's settings at the top level (builder, tracer, render_file, image, ...
// as one run always wrote them), "runs" (every run's settings and the frame numbers it rendered,
// oldest first), "frames" (one record per image, in frame order; "run" is an index into "runs"),
// "failed_frames" (images whose newest attempt failed) and "summary".
#pragma once

#include <cstddef>
#include <cstdint>
#include <filesystem>
#include <set>
#include <string>
#include <vector>

#include <nlohmann/json.hpp>

namespace kdray {

/// The largest stats.json kdray reads: 256 MiB, or an eighth of the input budget
/// (input_size_limit(), a quarter of the machine's memory) where that is less. A parsed file
/// takes about 7 to 9 times its size in memory (a 54 MB file of 16,000 records: 0.37 GB for
/// `kdray stats`, 0.45 GB for a run merging into it), so an unbounded one ran out of memory
/// (std::bad_alloc, exit 134) before the run rendered. A frame's record takes about 3.4 KB, so
/// 256 MiB holds some 80,000 frames.
inline constexpr std::uint64_t kMaxStatsBytes = std::uint64_t(256) << 20;
std::uint64_t stats_size_limit();

/// `file` (a stats.json) read and checked as the summary reads it: an object with "frames" (each
/// an object, its frame number a count, its times numbers) and "summary". Throws Error naming the
/// file and the problem.
nlohmann::json read_render_stats(const std::filesystem::path& file);

/// `dir`/stats.json read and checked; null when there is none. Throws Error naming the file when
/// it is not one kdray can merge into (not a regular file, not kdray's, malformed).
nlohmann::json read_folder_stats(const std::filesystem::path& dir);

/// The images (file names) that `previous` holds a record of and whose newest attempt did not
/// fail: with their files in the folder, what --skip-existing skips.
std::set<std::string> completed_images(const nlohmann::json& previous);

/// How merge_into_folder went: whether the folder's lock was taken (a file system without locks,
/// NFS without lockd say, is merged without one), and why not.
struct FolderMerge {
    bool locked = true;
    std::string lock_problem;
};

/// Merges `run` into `dir`/stats.json (merge_render_stats) under an exclusive lock on
/// `dir`/.kdray-stats.lock, so that shards finishing at once add up; written atomically.
FolderMerge merge_into_folder(const std::filesystem::path& dir, nlohmann::json run,
                              bool replace_other_settings = false);

/// `frames` (a stats.json's frame records) grouped by the run that rendered them ("run"; none:
/// run 0), each group in frame order: summarise_runs's input for one folder (each record cut to
/// the keys it reads).
std::vector<nlohmann::json> frames_by_run(const nlohmann::json& frames);

/// The folder's stats.json after a run: `previous` (the file as it was; null when there was none)
/// with `run`'s frame records (run["frames"]) in place of its records of the same images, and
/// its failures (run["failed_frames"], optional; each naming the image it would have written) in
/// place of the earlier failures of theirs (a failure leaves an earlier record of its image,
/// which it did not replace), and the
/// summary recomputed over every frame, each run's first frame counted as a first
/// (summarise_runs). `run`'s other keys are its settings. With `replace_other_settings`
/// (--overwrite), the earlier records whose image settings differ from the run's are dropped
/// (core/run/image_settings.h); the top-level "image" says when the records still differ.
nlohmann::json merge_render_stats(nlohmann::json previous, nlohmann::json run,
                                  bool replace_other_settings = false);

}  // namespace kdray
