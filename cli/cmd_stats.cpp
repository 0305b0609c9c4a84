// `kdray stats [PATH...]`: statistics of OBJ scenes (built with the chosen builder), tree files
// or render output folders; with no PATH, the OpenCL devices kdray can use and its defaults.
#include <filesystem>
#include <fstream>
#include <iostream>
#include <memory>
#include <vector>

#include "cl/backends.h"
#include "cli/commands.h"
#include "cli/devices.h"
#include "cli/report.h"
#include "core/error.h"
#include "core/io/input_file.h"
#include "core/run/render_stats.h"
#include "core/run/stats_json.h"
#include "core/scene/scene.h"
#include "core/tree/tree_file.h"
#include "core/tree/tree_stats.h"

namespace kdray::cli {
namespace {

nlohmann::json defaults_json(const BuilderOptions& o) {
    const BuildParams p = o.build_params(kStaticBuildQuality);
    return {{"builder", o.builder},
            {"quality", build_quality_of(p)},
            {"animation_quality", build_quality_name(kAnimationBuildQuality)},
            {"device", o.device.empty() ? "first GPU, else first device" : o.device},
            {"cost_traversal", p.costs.traversal},
            {"cost_intersection", p.costs.intersection},
            {"large_node_threshold", p.large_node_threshold},
            {"empty_space_ratio", p.empty_space_ratio},
            {"large_split_bins", p.large_split_bins},
            {"small_reclip_refs", p.small_reclip_refs},
            {"small_leaf_refs", p.small_leaf_refs},
            {"small_split_bins", p.small_split_bins},
            {"small_stage", small_stage_name(p.small_stage)},
            {"large_stage", large_stage_name(p.large_stage)},
            {"empty_bonus", p.empty_bonus},
            {"tree_depth", p.max_depth}};
}

/// A render folder's stats.json, read and checked.
nlohmann::json folder_stats(const std::filesystem::path& dir) {
    const std::filesystem::path file = dir / "stats.json";
    std::error_code ec;
    if (!std::filesystem::exists(file, ec))
        throw Error(dir.string() + ": not a render output folder (no stats.json)");
    return read_render_stats(file);
}

nlohmann::json render_folder_json(const std::filesystem::path& dir) {
    nlohmann::json stats = folder_stats(dir);
    nlohmann::json j = summarise_runs(frames_by_run(stats["frames"]));
    j["folder"] = dir.string();
    j["builder"] = stats.value("builder", "");
    j["tracer"] = stats.value("tracer", "");
    return j;
}

nlohmann::json path_json(const std::string& path, TreeBuilder& builder) {
    if (std::filesystem::is_directory(path)) return {{"render", render_folder_json(path)}};
    if (!std::filesystem::exists(path)) throw Error(path + ": no such file");
    if (std::filesystem::path(path).extension() == ".obj") {
        Scene scene = load_obj(path);
        BuiltTree built = builder.build(scene);
        return {{"scene", scene_json(scene)}, {"tree", tree_json(built, scene.triangle_count())}};
    }
    TreeFile file = read_tree_file(path);
    nlohmann::json tree = to_json(
        compute_tree_stats(file.tree, std::size_t(file.scene_triangles), file.tree.params.costs));
    tree["builder"] = file.tree.builder;
    // How it was built: the parameters the file keeps, and the ladder's name for them. The
    // stages shape the build, not the tree, and the file does not keep them.
    tree["params"] = params_json(file.tree);
    tree["params"].erase("small_stage");
    tree["params"].erase("large_stage");
    if (file.tree.builder == "opencl") tree["quality"] = build_quality_of(file.tree.params);
    return {{"tree_file", {{"path", path}, {"scene", file.scene_path}}}, {"tree", tree}};
}

}  // namespace

int run_stats(const StatsCommand& command) {
    nlohmann::json out;
    if (command.paths.empty()) {
        out = {{"devices", list_devices_json()}, {"defaults", defaults_json(command.builder)}};
    } else {
        DeviceSession session(command.builder.device);
        const std::unique_ptr<TreeBuilder> builder = make_tree_builder(
            command.builder.builder, command.builder.build_params(kStaticBuildQuality), session);
        nlohmann::json items = nlohmann::json::array();
        for (const std::string& path : command.paths) items.push_back(path_json(path, *builder));
        out = command.paths.size() == 1 ? items[0] : nlohmann::json{{"items", items}};
        // Several render folders are the shards of one animation: one summary over them all,
        // each shard a run of its own (with its own first frame).
        std::vector<nlohmann::json> runs;
        std::size_t folders = 0;
        for (const std::string& path : command.paths)
            if (std::filesystem::is_directory(path)) {
                ++folders;
                for (nlohmann::json& run : frames_by_run(folder_stats(path)["frames"]))
                    runs.push_back(std::move(run));
            }
        if (folders > 1) out["combined"] = summarise_runs(runs);
    }
    if (command.json) {
        std::cout << json_text(out) << "\n";
    } else if (command.paths.empty()) {
        print_table(std::cout, out);
    } else {
        for (std::size_t i = 0; i < command.paths.size(); ++i) {
            const nlohmann::json& item = command.paths.size() == 1 ? out : out["items"][i];
            if (i > 0) std::cout << '\n';
            // A folder's frames one per line, above its summary.
            if (item.contains("render"))
                print_frame_table(std::cout, folder_stats(command.paths[i]));
            print_grouped(std::cout, item);
        }
        if (out.contains("combined")) {
            std::cout << "\nall the folders together\n";
            print_grouped(std::cout, {{"combined", out["combined"]}});
        }
    }
    return 0;
}

}  // namespace kdray::cli
