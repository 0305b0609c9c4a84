// The OpenCL builder's stage shapes on the command line (--small-stage, --large-stage): each
// shape of a stage builds the same tree as the other, says which ran in build --json and
// stats.json, and a name that is not a shape is refused. The trees are compared node count for
// node count and SAH, across shapes; tests/test_opencl_small_level.cpp and
// test_opencl_large_stage.cpp compare them node for node in-process.
#include <doctest/doctest.h>

#include <filesystem>
#include <string>

#include <nlohmann/json.hpp>

#include "tests/support.h"

namespace fs = std::filesystem;
using namespace kdray;
using namespace kdray::test;

TEST_CASE(
    "--small-stage, --large-stage: each stage's shapes build the same tree, say which ran; "
    "a bad name is refused") {
    fs::path dir = fresh_temp_dir("cli-small-stage");
    const fs::path obj = write_obj(dir / "in" / "frame_1.obj", random_triangles(2000, 17));
    auto build_json = [&](const std::string& stage, const std::string& option = "--small-stage") {
        const CommandResult r = run_kdray({"build", obj.string(), "--json", option, stage});
        REQUIRE_MESSAGE(r.status == 0, r.err);
        return nlohmann::json::parse(r.out);
    };
    const nlohmann::json per_root = build_json("per-root"), per_level = build_json("per-level");
    CHECK(per_root["small_stage"] == "per-root");
    CHECK(per_root["params"]["small_stage"] == "per-root");
    CHECK(per_level["small_stage"] == "per-level");
    CHECK(per_level["nodes"] == per_root["nodes"]);
    CHECK(per_level["leaves"] == per_root["leaves"]);
    CHECK(per_level["sah_cost"] == per_root["sah_cost"]);
    // auto: the chosen shape is recorded, the request beside it.
    const nlohmann::json automatic = build_json("auto");
    CHECK(automatic["params"]["small_stage"] == "auto");
    CHECK((automatic["small_stage"] == "per-root" || automatic["small_stage"] == "per-level"));
    // A render's stats.json records it per frame.
    const fs::path render = write_text_file(dir / "render.json", kSmallRender);
    CommandResult r =
        run_kdray({"render", obj.string(), "-o", (dir / "out").string(), "--camera",
                   render.string(), "--tracer", "reference", "-q", "--small-stage", "per-level"});
    REQUIRE_MESSAGE(r.status == 0, r.err);
    CHECK(read_json(dir / "out" / "stats.json")["frames"][0]["tree"]["small_stage"] == "per-level");
    r = run_kdray({"build", obj.string(), "--small-stage", "bogus"});
    CHECK(r.status == 2);
    CHECK(r.err.find("--small-stage") != std::string::npos);
    // The large stage: the same, with its own names.
    const nlohmann::json chunked = build_json("chunked", "--large-stage");
    const nlohmann::json level = build_json("level", "--large-stage");
    const nlohmann::json depth_first = build_json("depth-first", "--large-stage");
    CHECK(chunked["large_stage"] == "chunked");
    CHECK(level["large_stage"] == "level");
    CHECK(depth_first["large_stage"] == "depth-first");
    CHECK(level["params"]["large_stage"] == "level");
    CHECK(depth_first["params"]["large_stage"] == "depth-first");
    CHECK(level["nodes"] == chunked["nodes"]);
    CHECK(level["sah_cost"] == chunked["sah_cost"]);
    CHECK(depth_first["nodes"] == chunked["nodes"]);
    CHECK(depth_first["sah_cost"] == chunked["sah_cost"]);
    // Its own figures, only for the shape that has them.
    CHECK(depth_first["depth_first_subtrees"].get<int>() > 0);
    CHECK(depth_first["depth_first_rounds"].get<int>() >= 1);
    CHECK(!chunked.contains("depth_first_subtrees"));
    // Auto: level on a GPU, depth-first on a CPU.
    CHECK((automatic["large_stage"] == "depth-first" || automatic["large_stage"] == "level"));
    r = run_kdray({"build", obj.string(), "--large-stage", "depth"});
    CHECK(r.status == 2);
    CHECK(r.err.find("--large-stage") != std::string::npos);
    fs::remove_all(dir);
}
