#include "core/run/stats_json.h"

#include <algorithm>
#include <map>
#include <string>
#include <vector>

#include "core/tree/build_quality.h"
#include "core/tree/tree_stats.h"

namespace kdray {

nlohmann::json scene_json(const Scene& scene) {
    return {{"path", scene.path.string()},
            {"triangles", scene.triangle_count()},
            {"zero_area_triangles", scene.zero_area_triangles},
            // Whether the frame shades smooth (the OBJ's vn) or flat.
            {"vertex_normals", scene.has_vertex_normals()},
            {"materials", scene.materials.size()},
            // The texel atlas of map_Kd and map_Ka, on the device when the frame is textured.
            {"texture_bytes", scene.texture_bytes()},
            // Where kdray traced it: frame = (scene - offset) * scale (scene_frame.h).
            {"frame",
             {{"offset", {scene.frame.offset.x, scene.frame.offset.y, scene.frame.offset.z}},
              {"scale", scene.frame.scale}}},
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
    j["params"] = params_json(tree);
    if (tree.builder == "opencl") {
        j["quality"] = build_quality_of(p);
        // What was asked for (params: auto too), and the shape that ran (per-root or per-level).
        if (!built.report.small_stage.empty()) j["small_stage"] = built.report.small_stage;
        if (!built.report.large_stage.empty()) j["large_stage"] = built.report.large_stage;
        j["large_node_levels"] = built.report.large_node_levels;
        if (built.report.large_stage == "depth-first") {
            j["depth_first_subtrees"] = built.report.depth_first_subtrees;
            j["depth_first_rounds"] = built.report.depth_first_rounds;
            j["depth_first_rebuilt"] = built.report.depth_first_rebuilt;
        }
        j["small_node_levels"] = built.report.small_node_levels;
        j["budget_leaves"] = built.report.budget_leaves;
        j["device_bytes"] = built.report.device_bytes;
        // Round trips: each sync idles the device for a host round trip (DeviceTraffic).
        j["device_syncs"] = built.report.device_syncs;
        j["kernel_launches"] = built.report.kernel_launches;
        j["device_transfers"] = built.report.device_transfers;
        if (triangle_count > 0)
            j["device_bytes_per_triangle"] =
                double(built.report.device_bytes) / double(triangle_count);
    }
    if (!built.report.warnings.empty()) j["warnings"] = built.report.warnings;
    return j;
}

nlohmann::json params_json(const KdTree& tree) {
    const BuildParams& p = tree.params;
    nlohmann::json j = {{"cost_traversal", p.costs.traversal},
                        {"cost_intersection", p.costs.intersection},
                        {"tree_depth", p.max_depth}};
    if (tree.builder == "opencl") {
        j["large_node_threshold"] = p.large_node_threshold;
        j["empty_space_ratio"] = p.empty_space_ratio;
        j["large_split_bins"] = p.large_split_bins;
        j["small_reclip_refs"] = p.small_reclip_refs;
        j["small_leaf_refs"] = p.small_leaf_refs;
        j["small_split_bins"] = p.small_split_bins;
        j["small_stage"] = small_stage_name(p.small_stage);
        j["large_stage"] = large_stage_name(p.large_stage);
    }
    j["empty_bonus"] = p.empty_bonus;
    return j;
}

nlohmann::json summarise_runs(const std::vector<nlohmann::json>& runs) {
    // Totals over every frame, and frame_ms over the frames after each run's first.
    const char* parts[] = {"load_wait_ms", "compile_ms", "build_ms", "trace_ms", "write_ms"};
    std::map<std::string, double> part_totals;
    double total_ms = 0, worst_ms = 0, after_first_ms = 0;
    std::size_t after_first = 0;
    std::vector<std::size_t> numbers;
    for (const nlohmann::json& frames : runs)
        for (std::size_t k = 0; k < frames.size(); ++k) {
            const nlohmann::json& frame = frames[k];
            const double ms = frame.value("frame_ms", 0.0);
            total_ms += ms;
            worst_ms = std::max(worst_ms, ms);
            if (k > 0) {
                after_first_ms += ms;
                ++after_first;
            }
            for (const char* part : parts) part_totals[part] += frame.value(part, 0.0);
            numbers.push_back(frame.value("frame", std::size_t(0)));
        }
    std::sort(numbers.begin(), numbers.end());
    auto mean = [](double total, std::size_t count) { return count > 0 ? total / count : 0.0; };
    auto per_second = [](double mean_ms) { return mean_ms > 0 ? 1000.0 / mean_ms : 0.0; };
    const double mean_ms = mean(total_ms, numbers.size());
    nlohmann::json j = {
        {"frames", numbers.size()}, {"mean_frame_ms", mean_ms}, {"worst_frame_ms", worst_ms}};
    for (const char* part : parts)
        j["mean_" + std::string(part)] = mean(part_totals[part], numbers.size());
    j["frames_per_second"] = per_second(mean_ms);
    // No frame after a first: no rate, rather than a rate of 0 that reads as "stalled".
    j["frames_per_second_after_first"] =
        after_first > 0 ? nlohmann::json(per_second(mean(after_first_ms, after_first)))
                        : nlohmann::json(nullptr);
    j["frame_numbers"] = numbers;
    if (std::adjacent_find(numbers.begin(), numbers.end()) != numbers.end())
        j["warning"] = "some frame numbers appear in more than one folder";
    return j;
}

nlohmann::json summarise_frames(const nlohmann::json& frames) {
    return summarise_runs({frames});
}

std::string json_text(const nlohmann::json& json) {
    return json.dump(2, ' ', false, nlohmann::json::error_handler_t::replace);
}

}  // namespace kdray
