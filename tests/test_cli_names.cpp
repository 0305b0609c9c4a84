// test_cli_names.cpp — one name per thing (docs/names.md): every build parameter's option is its
// stats key with dashes, the old short spellings still set the same parameter, and the three
// depths (ray depth, tree depth limit, tree depth reached) have a key each, none "max_depth".
#include <doctest/doctest.h>

#include <algorithm>
#include <filesystem>
#include <string>
#include <vector>

#include "tests/support.h"

namespace fs = std::filesystem;
using namespace kdray::test;

namespace {

/// "--large-node-threshold" for "large_node_threshold".
std::string option_of(std::string key) {
    std::replace(key.begin(), key.end(), '_', '-');
    return "--" + key;
}

/// `kdray stats --json ARGS...`'s defaults.
nlohmann::json defaults_with(const std::vector<std::string>& extra) {
    std::vector<std::string> args = {"stats", "--json"};
    args.insert(args.end(), extra.begin(), extra.end());
    const CommandResult r = run_kdray(args, 120);
    REQUIRE_MESSAGE(r.status == 0, r.err);
    return nlohmann::json::parse(r.out)["defaults"];
}

}  // namespace

TEST_CASE("every tree parameter in stats.json has the option of its name, and old names alias") {
    // Every key of an OpenCL tree's "params" is an option of build, render and stats.
    const fs::path room = source_dir() / "testdata" / "cornell" / "room.obj";
    const CommandResult built = run_kdray({"build", room.string(), "--json"}, 300);
    REQUIRE_MESSAGE(built.status == 0, built.err);
    const nlohmann::json params = nlohmann::json::parse(built.out)["params"];
    REQUIRE(params.size() >= 10);
    for (const char* command : {"build", "render", "stats"}) {
        const std::string help = run_kdray({command, "--help"}).out;
        for (const auto& [key, value] : params.items()) {
            CAPTURE(command);
            CAPTURE(key);
            // "  --name" at a line's start, followed by an alias or a type.
            const std::string option = option_of(key);
            CHECK((help.find("  " + option + " ") != std::string::npos ||
                   help.find("  " + option + ",") != std::string::npos));
        }
    }

    // The value given under the new name and under the old one lands on that key.
    struct Case {
        std::string key, old_option, value;
    };
    for (const Case& c : std::vector<Case>{{"cost_traversal", "--ct", "7"},
                                           {"cost_intersection", "--ci", "9"},
                                           {"large_node_threshold", "--large-threshold", "17"},
                                           {"empty_space_ratio", "--empty-ratio", "0.5"},
                                           {"large_split_bins", "--large-bins", "5"},
                                           {"small_reclip_refs", "--reclip-refs", "3"},
                                           {"small_leaf_refs", "--leaf-refs", "2"},
                                           {"small_split_bins", "--small-bins", "4"},
                                           {"empty_bonus", "", "0.375"},
                                           {"tree_depth", "", "11"}}) {
        CAPTURE(c.key);
        std::vector<std::string> spellings = {option_of(c.key)};
        if (!c.old_option.empty()) spellings.push_back(c.old_option);
        for (const std::string& option : spellings) {
            CAPTURE(option);
            const nlohmann::json defaults = defaults_with({option, c.value});
            REQUIRE(defaults.contains(c.key));
            CHECK(defaults[c.key].get<double>() == doctest::Approx(std::stod(c.value)));
        }
    }
    check_error(run_kdray({"stats", "--empty-bonus", "1"}), 2, {"--empty-bonus", "[0, 1)"});
}

TEST_CASE("--empty-bonus changes the tree both builders make, and is recorded") {
    const fs::path room = source_dir() / "testdata" / "cornell" / "room.obj";
    for (const std::string builder : {"reference", "opencl"}) {
        CAPTURE(builder);
        auto build = [&](const std::string& bonus) {
            const CommandResult r = run_kdray(
                {"build", room.string(), "--json", "--builder", builder, "--empty-bonus", bonus},
                300);
            REQUIRE_MESSAGE(r.status == 0, r.err);
            return nlohmann::json::parse(r.out);
        };
        const nlohmann::json none = build("0"), strong = build("0.9");
        CHECK(none["params"]["empty_bonus"] == 0.0);
        CHECK(strong["params"]["empty_bonus"].get<double>() == doctest::Approx(0.9));
        // A large bonus buys empty leaves: more of them than without.
        CHECK(strong["empty_leaves"].get<int>() > none["empty_leaves"].get<int>());
    }
}

TEST_CASE("the three depths have three names in stats.json, none of them max_depth") {
    const fs::path dir = fresh_temp_dir("cli-names-depths");
    const fs::path render_file = write_text_file(dir / "render.json", kSmallRender);
    const CommandResult r = run_kdray(
        {"render", (source_dir() / "testdata" / "cornell" / "room.obj").string(), "-o",
         (dir / "out").string(), "--render-file", render_file.string(), "--ray-depth", "3",
         "--tree-depth", "9", "--builder", "reference", "--tracer", "reference", "-q"},
        300);
    REQUIRE_MESSAGE(r.status == 0, r.err);
    const nlohmann::json stats = read_json(dir / "out" / "stats.json");
    CHECK(stats["ray_depth"] == 3);
    const nlohmann::json& tree = stats["frames"][0]["tree"];
    CHECK(tree["params"]["tree_depth"] == 9);
    CHECK(tree["tree_depth_reached"].get<int>() <= 9);
    CHECK(tree["tree_depth_reached"].get<int>() >= 1);
    CHECK(stats.dump().find("max_depth") == std::string::npos);
    fs::remove_all(dir);
}
