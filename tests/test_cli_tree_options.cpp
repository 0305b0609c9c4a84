// test_cli_tree_options.cpp — the kd-tree's options through the binary: --quality's ladder of
// parameters and each command's default, options set apart winning over the level, and
// --tree-depth bounding the depth of the tree both builders save, walked from the node layout.
#include <doctest/doctest.h>

#include <algorithm>
#include <filesystem>
#include <string>
#include <vector>

#include <nlohmann/json.hpp>

#include "core/device/kd_shared.h"
#include "core/tree/build_quality.h"
#include "core/tree/reference_builder.h"
#include "core/tree/tree_check.h"
#include "core/tree/tree_file.h"
#include "tests/support.h"

namespace fs = std::filesystem;
using namespace kdray;
using namespace kdray::test;

TEST_CASE("--quality: the ladder's parameters, each command's default, options set apart win") {
    fs::path dir = fresh_temp_dir("cli-quality");
    Scene scene = random_triangles(500, 13);
    const fs::path obj = write_obj(dir / "in" / "frame_1.obj", scene);
    write_obj(dir / "in" / "frame_2.obj", scene);
    const fs::path render = write_text_file(dir / "render.json", kSmallRender);
    auto ladder = [](const nlohmann::json& params) {
        return std::vector<int>{
            params["large_split_bins"].get<int>(), params["small_reclip_refs"].get<int>(),
            params["small_leaf_refs"].get<int>(), params["small_split_bins"].get<int>()};
    };
    auto level = [](BuildQuality q) {
        const BuildParams p = with_build_quality({}, q);
        return std::vector<int>{p.large_split_bins, p.small_reclip_refs, p.small_leaf_refs,
                                p.small_split_bins};
    };
    auto build_json = [&](std::vector<std::string> extra) {
        std::vector<std::string> args = {"build", obj.string(), "--json"};
        args.insert(args.end(), extra.begin(), extra.end());
        const CommandResult r = run_kdray(args);
        REQUIRE_MESSAGE(r.status == 0, r.err);
        return nlohmann::json::parse(r.out);
    };
    // build: the static default; each named level; an option set apart makes it custom.
    nlohmann::json j = build_json({});
    CHECK(j["quality"] == build_quality_name(kStaticBuildQuality));
    CHECK(ladder(j["params"]) == level(kStaticBuildQuality));
    std::size_t previous_nodes = std::size_t(-1);
    for (BuildQuality q : {BuildQuality::High, BuildQuality::Medium, BuildQuality::Low}) {
        j = build_json({"--quality", build_quality_name(q)});
        CHECK(j["quality"] == build_quality_name(q));
        CHECK(ladder(j["params"]) == level(q));
        CHECK(j["nodes"].get<std::size_t>() < previous_nodes);
        previous_nodes = j["nodes"].get<std::size_t>();
    }
    j = build_json({"--quality", "low", "--leaf-refs", "2"});
    CHECK(j["quality"] == "custom");
    CHECK(j["params"]["small_leaf_refs"] == 2);
    CHECK(j["params"]["large_split_bins"] == level(BuildQuality::Low)[0]);
    // Binned small nodes: off the ladder, saved in the tree file and read back from it.
    const CommandResult saved =
        run_kdray({"build", obj.string(), "--json", "--quality", "low", "--small-bins", "8", "-o",
                   (dir / "binned.kdt").string()});
    REQUIRE_MESSAGE(saved.status == 0, saved.err);
    CHECK(nlohmann::json::parse(saved.out)["quality"] == "custom");
    CHECK(read_tree_file(dir / "binned.kdt").tree.params.small_split_bins == 8);
    const CommandResult read_back = run_kdray({"stats", (dir / "binned.kdt").string(), "--json"});
    REQUIRE_MESSAGE(read_back.status == 0, read_back.err);
    CHECK(nlohmann::json::parse(read_back.out)["tree"]["params"]["small_split_bins"] == 8);
    // render: several frames get the animation default, one frame the static one.
    const fs::path out = dir / "out";
    CommandResult r = run_kdray({"render", (dir / "in" / "frame_1.obj").string(),
                                 (dir / "in" / "frame_2.obj").string(), "-o", out.string(),
                                 "--camera", render.string(), "--tracer", "reference", "-q"});
    REQUIRE_MESSAGE(r.status == 0, r.err);
    // Held in a variable: a range-for over read_json(...)["frames"] walks a destroyed temporary.
    const nlohmann::json animation = read_json(out / "stats.json");
    for (const nlohmann::json& frame : animation["frames"])
        CHECK(frame["tree"]["quality"] == build_quality_name(kAnimationBuildQuality));
    r = run_kdray({"render", obj.string(), "-o", (dir / "one").string(), "--camera",
                   render.string(), "--tracer", "reference", "-q"});
    REQUIRE_MESSAGE(r.status == 0, r.err);
    CHECK(read_json(dir / "one" / "stats.json")["frames"][0]["tree"]["quality"] ==
          build_quality_name(kStaticBuildQuality));
    // A name off the ladder is a usage error.
    r = run_kdray({"build", obj.string(), "--quality", "ultra"});
    CHECK(r.status == 2);
    CHECK(r.err.find("--quality") != std::string::npos);
    fs::remove_all(dir);
}

namespace {

/// The depth of the deepest node under `index` (the root's depth is 0), walked from the layout
/// of kd_shared.h alone: the below child follows its parent, the above child's index is stored.
int deepest_level(const KdTree& tree, std::size_t index, int depth) {
    REQUIRE(index < tree.nodes.size());
    REQUIRE(depth <= KDRAY_MAX_DEPTH);
    const KdNode node = tree.nodes[index];
    if (kd_node_is_leaf(node)) return depth;
    return std::max(deepest_level(tree, index + 1, depth + 1),
                    deepest_level(tree, kd_node_above_child(node), depth + 1));
}

}  // namespace

TEST_CASE("--tree-depth limits the depth of the tree both builders save; the tree stays sound") {
    // The room's 2130 triangles build deeper than 3 levels by the SAH; at --tree-depth 3 every
    // path from the root ends within 3 splits, and every triangle is still in each leaf it
    // overlaps.
    const fs::path room = source_dir() / "testdata" / "cornell" / "room.obj";
    const Scene scene = load_obj(room);
    for (const std::string builder : {"opencl", "reference"}) {
        CAPTURE(builder);
        const fs::path dir = fresh_temp_dir("cli-tree-depth-" + builder);
        auto build = [&](const fs::path& tree_file, std::vector<std::string> extra) {
            std::vector<std::string> args = {
                "build", room.string(), "--json", "-o", tree_file.string(), "--builder", builder};
            args.insert(args.end(), extra.begin(), extra.end());
            const CommandResult r = run_kdray(args, 300);
            REQUIRE_MESSAGE(r.status == 0, r.err);
            return nlohmann::json::parse(r.out);
        };
        const nlohmann::json limited = build(dir / "limited.kdt", {"--tree-depth", "3"});
        const nlohmann::json free = build(dir / "free.kdt", {});
        const KdTree limited_tree = read_tree_file(dir / "limited.kdt").tree;
        const KdTree free_tree = read_tree_file(dir / "free.kdt").tree;
        const int limited_depth = deepest_level(limited_tree, 0, 0);
        const int free_depth = deepest_level(free_tree, 0, 0);
        CHECK(limited_depth <= 3);
        CHECK(limited_depth >= 1);  // the room is split at all
        CHECK(free_depth > 3);
        CHECK(limited["params"]["tree_depth"] == 3);
        CHECK(limited["tree_depth_reached"] == limited_depth);
        CHECK(free["tree_depth_reached"] == free_depth);
        // One name per depth: the limit, the depth reached, never "max_depth".
        CHECK_FALSE(limited.contains("max_depth"));
        CHECK_FALSE(limited["params"].contains("max_depth"));
        CHECK(check_tree(limited_tree, scene).empty());
        fs::remove_all(dir);
    }
}
