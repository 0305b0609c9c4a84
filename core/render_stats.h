// render_stats.h — a render folder's stats.json across runs. A folder can be rendered by several
// runs (an interrupted run resumed with --skip-existing or --frames, the shards of a job array):
// its stats.json keeps every frame's newest record, each tagged with the run that rendered it,
// and one summary over them all.
//
// The file: the newest run's settings at the top level (builder, tracer, render_file, image, ...
// as one run always wrote them), "runs" (every run's settings and the frame numbers it rendered,
// oldest first), "frames" (one record per frame number, in frame order; "run" is an index into
// "runs"), "failed_frames" (frames whose newest attempt failed) and "summary".
#pragma once

#include <filesystem>
#include <vector>

#include <nlohmann/json.hpp>

namespace kdray {

/// `file` (a stats.json) read and checked as the summary reads it: an object with "frames" (each
/// an object, its frame number a count, its times numbers) and "summary". Throws Error naming the
/// file and the problem.
nlohmann::json read_render_stats(const std::filesystem::path& file);

/// `frames` (a stats.json's frame records) grouped by the run that rendered them ("run"; none:
/// run 0), each group in frame order: summarise_runs's input for one folder.
std::vector<nlohmann::json> frames_by_run(const nlohmann::json& frames);

/// The folder's stats.json after a run: `previous` (the file as it was; null when there was none)
/// with `run`'s frame records (run["frames"]) in place of its records of the same frame numbers
/// and its failures (run["failed_frames"], optional) in place of theirs, and the summary
/// recomputed over every frame, each run's first frame counted as a first (summarise_runs).
/// `run`'s other keys are its settings.
nlohmann::json merge_render_stats(const nlohmann::json& previous, nlohmann::json run);

}  // namespace kdray
