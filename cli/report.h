// report.h — how kdray shows a built tree: one JSON object (the keys scripts rely on: nodes,
// leaves, sah_cost, build_ms, timings_ms, ...) or a readable table made from that same object.
#pragma once

#include <iosfwd>

#include <nlohmann/json.hpp>

#include "cli/tree_builder.h"
#include "core/scene.h"

namespace kdray::cli {

nlohmann::json scene_json(const Scene& scene);
/// Tree statistics (SAH cost with the tree's own C_t and C_i), build parameters and timings.
nlohmann::json tree_json(const BuiltTree& built, std::size_t triangle_count);
void print_table(std::ostream& out, const nlohmann::json& report);

}  // namespace kdray::cli
