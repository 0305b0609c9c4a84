#include "cli/report.h"

#include <iomanip>
#include <ostream>

#include "core/tree_stats.h"

namespace kdray::cli {

nlohmann::json scene_json(const Scene& scene) {
    return {{"path", scene.path.string()},
            {"triangles", scene.triangle_count()},
            {"zero_area_triangles", scene.zero_area_triangles},
            // Whether the frame shades smooth (the OBJ's vn) or flat.
            {"vertex_normals", scene.has_vertex_normals()},
            {"materials", scene.materials.size()},
            {"warnings", scene.warnings}};
}

nlohmann::json tree_json(const BuiltTree& built, std::size_t triangle_count) {
    const KdTree& tree = built.tree;
    nlohmann::json j = to_json(compute_tree_stats(tree, triangle_count, tree.params.costs));
    j["builder"] = tree.builder;
    j["build_ms"] = built.report.build_ms;
    nlohmann::json stages = nlohmann::json::object();
    for (const auto& [stage, ms] : built.report.timings_ms) stages[stage] = ms;
    j["timings_ms"] = stages;
    const BuildParams& p = tree.params;
    j["params"] = {{"cost_traversal", p.costs.traversal},
                   {"cost_intersection", p.costs.intersection},
                   {"max_depth", p.max_depth}};
    if (tree.builder == "opencl") {
        j["params"]["large_node_threshold"] = p.large_node_threshold;
        j["params"]["empty_space_ratio"] = p.empty_space_ratio;
        j["params"]["large_split_bins"] = p.large_split_bins;
        j["params"]["empty_bonus"] = p.empty_bonus;
        j["large_node_levels"] = built.report.large_node_levels;
        j["small_node_levels"] = built.report.small_node_levels;
        j["device_bytes"] = built.report.device_bytes;
        if (triangle_count > 0)
            j["device_bytes_per_triangle"] =
                double(built.report.device_bytes) / double(triangle_count);
    } else {
        j["params"]["empty_bonus"] = p.empty_bonus;
    }
    return j;
}

namespace {

void print_rows(std::ostream& out, const nlohmann::json& object, const std::string& prefix) {
    for (const auto& [key, value] : object.items()) {
        if (value.is_object()) {
            print_rows(out, value, prefix + key + ".");
            continue;
        }
        out << "  " << std::left << std::setw(34) << (prefix + key) << ' ';
        if (value.is_number_float())
            out << std::setprecision(6) << value.get<double>();
        else if (value.is_string())
            out << value.get<std::string>();
        else if (value.is_array() && value.empty())
            out << "none";
        else
            out << value.dump();
        out << '\n';
    }
}

}  // namespace

void print_table(std::ostream& out, const nlohmann::json& report) {
    for (const auto& [section, value] : report.items()) {
        out << section << '\n';
        if (value.is_object()) {
            print_rows(out, value, "");
        } else if (value.is_array() && !value.empty() && value[0].is_object()) {
            // A list of records (devices, say): one block each, numbered.
            for (std::size_t i = 0; i < value.size(); ++i)
                print_rows(out, value[i], "[" + std::to_string(i) + "].");
        } else {
            out << "  " << value.dump() << '\n';
        }
    }
}

}  // namespace kdray::cli
