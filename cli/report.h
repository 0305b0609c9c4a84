// report.h — a readable table made from one of kdray's JSON reports (core/run/stats_json.h): a
// tree, a scene, a render folder, the devices.
#pragma once

#include <iosfwd>

#include <nlohmann/json.hpp>

namespace kdray::cli {

void print_table(std::ostream& out, const nlohmann::json& report);

}  // namespace kdray::cli
