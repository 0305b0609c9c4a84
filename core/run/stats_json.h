// stats_json.h — the JSON records kdray writes and prints: a scene, a built tree (the keys
// scripts rely on: nodes, leaves, sah_cost, build_ms, timings_ms, ...), and the summary over a
// run's frame records, the one summary both stats.json and `kdray stats` over folders give.
#pragma once

#include <cstddef>
#include <string>
#include <vector>

#include <nlohmann/json.hpp>

#include "core/scene/scene.h"
#include "core/tree/tree_builder.h"

namespace kdray {

nlohmann::json scene_json(const Scene& scene);
/// Tree statistics (SAH cost with the tree's own C_t and C_i), build parameters and timings.
nlohmann::json tree_json(const BuiltTree& built, std::size_t triangle_count);
/// The parameters `tree` was built with, under their option names (docs/names.md): what
/// tree_json's "params" holds, and what `kdray stats TREE.kdt` reads back from a tree file.
nlohmann::json params_json(const KdTree& tree);
/// Summary of the frame records of one run (stats.json's "frames") or of several (the folders
/// of an animation's shards), each in the order it rendered them: frames, mean and worst
/// frame_ms, the mean of each part of a frame (load wait, compile, build, trace, write), frames
/// per second (1000 / mean frame_ms) over every frame and over all but each run's first (the one
/// that built the programs; 0 when no frame is left), the frame numbers sorted, and a warning when
/// one appears twice.
nlohmann::json summarise_runs(const std::vector<nlohmann::json>& runs);
nlohmann::json summarise_frames(const nlohmann::json& frames);

/// `json` as kdray prints and writes it (indented by 2). Text that is not UTF-8 (a file name of
/// Latin-1 bytes, say) is written with U+FFFD in place of the bad bytes instead of failing.
std::string json_text(const nlohmann::json& json);

}  // namespace kdray
