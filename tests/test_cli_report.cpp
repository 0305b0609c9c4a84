// test_cli_report.cpp — what `kdray build` and `kdray stats` print for a reader: the tree grouped
// (scene, tree, quality, parameters, timing, device) with units, every figure of --json present
// and equal to it; a render folder as a per-frame table equal to its stats.json; one frame's
// summary without a rate after the first (null, not 0).
#include <doctest/doctest.h>

#include <filesystem>
#include <map>
#include <sstream>
#include <string>
#include <vector>

#include "tests/support.h"

namespace fs = std::filesystem;
using namespace kdray::test;

namespace {

/// The lines of `text`.
std::vector<std::string> lines_of(const std::string& text) {
    std::vector<std::string> lines;
    std::istringstream in(text);
    for (std::string line; std::getline(in, line);) lines.push_back(line);
    return lines;
}

/// label -> value of the rows under `group` (a heading line) in a grouped report.
std::map<std::string, std::string> group_rows(const std::string& text, const std::string& group) {
    std::map<std::string, std::string> rows;
    bool inside = false;
    for (const std::string& line : lines_of(text)) {
        if (!line.empty() && line[0] != ' ') {
            inside = line == group;
            continue;
        }
        if (!inside || line.size() < 33) continue;
        std::string label = line.substr(2, 30);
        label.erase(label.find_last_not_of(' ') + 1);
        rows[label] = line.substr(33);
    }
    return rows;
}

}  // namespace

TEST_CASE("kdray build prints its figures grouped, with units, the same as --json") {
    const std::string room = (source_dir() / "testdata" / "cornell" / "room.obj").string();
    // The reference builder makes the same tree every time: the text and the JSON agree.
    const CommandResult text = run_kdray({"build", room, "--builder", "reference"}, 300);
    REQUIRE_MESSAGE(text.status == 0, text.err);
    const CommandResult json_run =
        run_kdray({"build", room, "--builder", "reference", "--json"}, 300);
    REQUIRE_MESSAGE(json_run.status == 0, json_run.err);
    const nlohmann::json j = nlohmann::json::parse(json_run.out);

    // The groups, in this order, each once; nothing left over.
    std::vector<std::string> headings;
    for (const std::string& line : lines_of(text.out))
        if (!line.empty() && line[0] != ' ') headings.push_back(line);
    CHECK(headings ==
          std::vector<std::string>{"scene", "tree", "quality", "parameters", "timing", "warnings"});
    const auto tree = group_rows(text.out, "tree");
    CHECK(tree.at("nodes") == j["nodes"].dump());
    CHECK(tree.at("tree depth reached") == j["tree_depth_reached"].dump());
    CHECK(tree.at("bytes").find(" B (") != std::string::npos);
    const auto quality = group_rows(text.out, "quality");
    CHECK(std::stod(quality.at("sah cost")) ==
          doctest::Approx(j["sah_cost"].get<double>()).epsilon(1e-3));
    const auto parameters = group_rows(text.out, "parameters");
    CHECK(parameters.at("tree depth") == j["params"]["tree_depth"].dump());
    const auto timing = group_rows(text.out, "timing");
    for (const char* label : {"build", "load", "prepare"}) {
        CAPTURE(label);
        REQUIRE(timing.count(label) == 1);
        CHECK(timing.at(label).size() > 3);
        CHECK(timing.at(label).substr(timing.at(label).size() - 3) == " ms");
    }
    // Far fewer lines than one per key, and no flat "params." rows.
    CHECK(text.out.find("params.") == std::string::npos);
}

TEST_CASE(
    "kdray stats FOLDER prints a frame per line, equal to stats.json; one frame has no rate "
    "after the first") {
    const fs::path dir = fresh_temp_dir("cli-report-folder");
    std::vector<std::string> args = {"render"};
    for (int i = 0; i < 3; ++i)
        args.push_back(
            (source_dir() / "testdata" / "anim" / ("frame_00" + std::to_string(i) + ".obj"))
                .string());
    for (const std::string& a :
         {std::string("-o"), (dir / "three").string(), std::string("--size"), std::string("16x12"),
          std::string("--builder"), std::string("reference"), std::string("--tracer"),
          std::string("reference"), std::string("-q")})
        args.push_back(a);
    const CommandResult r = run_kdray(args, 300);
    REQUIRE_MESSAGE(r.status == 0, r.err);
    const nlohmann::json stats = read_json(dir / "three" / "stats.json");
    const CommandResult shown = run_kdray({"stats", (dir / "three").string()}, 120);
    REQUIRE_MESSAGE(shown.status == 0, shown.err);
    const std::vector<std::string> lines = lines_of(shown.out);
    REQUIRE(lines.size() > 4);
    CHECK(lines[0].find("frame") != std::string::npos);
    CHECK(lines[0].find("SAH") != std::string::npos);
    for (std::size_t k = 0; k < 3; ++k) {
        CAPTURE(k);
        std::istringstream row(lines[1 + k]);
        std::size_t frame = 0, nodes = 0;
        std::string input, size;
        double build_ms = 0, trace_ms = 0, sah = 0;
        row >> frame >> input >> size >> build_ms >> trace_ms >> nodes >> sah;
        const nlohmann::json& record = stats["frames"][k];
        CHECK(frame == record["frame"].get<std::size_t>());
        CHECK(input == fs::path(record["input"].get<std::string>()).filename().string());
        CHECK(size == "16x12");
        CHECK(build_ms == doctest::Approx(record["build_ms"].get<double>()).epsilon(0.01));
        CHECK(nodes == record["tree"]["nodes"].get<std::size_t>());
        CHECK(sah == doctest::Approx(record["tree"]["sah_cost"].get<double>()).epsilon(1e-3));
    }
    CHECK(stats["summary"]["frames_per_second_after_first"].get<double>() > 0);

    // One frame: no rate after the first, in the file and in the JSON stats prints.
    args.insert(args.end(), {"--frames", "1:1"});
    args[5] = (dir / "one").string();
    REQUIRE(args[4] == "-o");
    const CommandResult one = run_kdray(args, 300);
    REQUIRE_MESSAGE(one.status == 0, one.err);
    CHECK(read_json(dir / "one" / "stats.json")["summary"]["frames_per_second_after_first"]
              .is_null());
    const CommandResult one_json = run_kdray({"stats", "--json", (dir / "one").string()}, 120);
    REQUIRE_MESSAGE(one_json.status == 0, one_json.err);
    CHECK(nlohmann::json::parse(one_json.out)["render"]["frames_per_second_after_first"].is_null());
    const CommandResult one_text = run_kdray({"stats", (dir / "one").string()}, 120);
    CHECK(one_text.out.find("none (one frame)") != std::string::npos);
    fs::remove_all(dir);
}

TEST_CASE("kdray stats TREE.kdt shows the parameters and quality the tree was built with") {
    const fs::path dir = fresh_temp_dir("cli-report-tree");
    const std::string room = (source_dir() / "testdata" / "cornell" / "room.obj").string();
    const fs::path tree_file = dir / "room.kdt";
    const CommandResult built =
        run_kdray({"build", room, "--json", "-o", tree_file.string(), "--quality", "medium",
                   "--empty-bonus", "0.3", "--tree-depth", "40"},
                  300);
    REQUIRE_MESSAGE(built.status == 0, built.err);
    const nlohmann::json at_build = nlohmann::json::parse(built.out);
    const CommandResult read = run_kdray({"stats", "--json", tree_file.string()}, 120);
    REQUIRE_MESSAGE(read.status == 0, read.err);
    const nlohmann::json tree = nlohmann::json::parse(read.out)["tree"];
    CHECK(tree["quality"] == "medium");
    CHECK(tree["quality"] == at_build["quality"]);
    nlohmann::json params = at_build["params"];
    params.erase("small_stage");  // not kept: they shape the build, not the tree
    params.erase("large_stage");
    CHECK(tree["params"] == params);
    CHECK(tree["params"]["tree_depth"] == 40);
    CHECK(tree["sah_cost"].get<double>() == doctest::Approx(at_build["sah_cost"].get<double>()));
    // And in the text, under its group.
    const CommandResult text = run_kdray({"stats", tree_file.string()}, 120);
    REQUIRE(text.status == 0);
    CHECK(group_rows(text.out, "parameters").at("empty bonus") == "0.3");
    CHECK(group_rows(text.out, "tree").at("quality") == "medium");
    fs::remove_all(dir);
}
