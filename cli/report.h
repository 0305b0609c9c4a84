// report.h — readable text made from kdray's JSON reports (core/run/stats_json.h): a tree and its
// scene grouped (scene, tree, quality, parameters, timing, device, file) with units, a render
// folder as a per-frame table and its summary, the devices and defaults as a plain table.
#pragma once

#include <nlohmann/json.hpp>
#include <ostream>

namespace kdray::cli {

/// Every section of `report` as `key value` rows (devices, defaults).
void print_table(std::ostream& out, const nlohmann::json& report);

/// A report of sections "scene", "tree", "tree_file" and "render" (any of them), grouped by what
/// a reader asks (what was built, how good, with which parameters, how fast, on what), with
/// units. Keys no group claims are printed under "other", so that nothing a report holds is lost.
void print_grouped(std::ostream& out, const nlohmann::json& report);

/// A render folder's stats.json as one line per frame: frame, input, size, build ms, trace ms,
/// nodes and SAH cost.
void print_frame_table(std::ostream& out, const nlohmann::json& folder_stats);

}  // namespace kdray::cli
