// stats_json.h — the JSON records kdray writes and prints: a scene, a built tree (the keys
// scripts rely on: nodes, leaves, sah_cost, build_ms, timings_ms, ...), and the summary over a
// run's frame records, the one summary both stats.json and `kdray stats` over folders give.
#pragma once

#include <cstddef>
#include <string>

#include <nlohmann/json.hpp>

#include "core/scene.h"
#include "core/tree_builder.h"

namespace kdray {

nlohmann::json scene_json(const Scene& scene);
/// Tree statistics (SAH cost with the tree's own C_t and C_i), build parameters and timings.
nlohmann::json tree_json(const BuiltTree& built, std::size_t triangle_count);
/// Summary of an array of frame records (stats.json's "frames", or the frames of several
/// folders, the shards of one animation): frames, mean and worst frame_ms, mean build_ms and
/// trace_ms, frames per second, the frame numbers sorted, and a warning when one appears twice.
nlohmann::json summarise_frames(const nlohmann::json& frames);

/// `json` as kdray prints and writes it (indented by 2). Text that is not UTF-8 (a file name of
/// Latin-1 bytes, say) is written with U+FFFD in place of the bad bytes instead of failing.
std::string json_text(const nlohmann::json& json);

}  // namespace kdray
