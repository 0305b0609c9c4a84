// `kdray build SCENE.obj`: load, build (--repeat: again, timed), print its statistics, save it.
#include <algorithm>
#include <iostream>
#include <memory>
#include <vector>

#include "cl/backends.h"
#include "cl/runtime/program_cache.h"
#include "cli/commands.h"
#include "cli/devices.h"
#include "cli/inputs.h"
#include "cli/log.h"
#include "cli/report.h"
#include "core/run/frame_pipeline.h"
#include "core/run/stats_json.h"
#include "core/run/warning_tally.h"
#include "core/scene/scene.h"
#include "core/tree/tree_file.h"

namespace kdray::cli {

int run_build(const BuildCommand& command) {
    // What the process does beside the build, timed so that a cold figure adds up: the OBJ
    // loaded, then the device opened and the builder prepared (its programs built). Loading on a
    // thread beside the preparation gained nothing on 2 cores (each slowed the other: Kitchen
    // process 994 -> 1010 ms, dragon res2 1217 -> 1266, medians of 8 alternating runs).
    check_scene_input(command.scene);
    const auto load_start = FrameClock::now();
    Scene scene = load_obj(command.scene);
    const double load_ms = ms_since(load_start);
    // --strict: the scene's warnings fail the build before the device opens.
    if (command.strict) {
        for (const std::string& warning : scene.warnings) print_warning(warning);
        throw_if_strict(true, scene.warnings);
    }
    const auto prepare_start = FrameClock::now();
    DeviceSession session(command.builder.device);
    say_when_no_gpu(session, command.builder.device);
    const std::unique_ptr<TreeBuilder> builder = make_tree_builder(
        command.builder.builder, command.builder.build_params(kStaticBuildQuality), session);
    builder->expect_triangles(scene.triangle_count());
    builder->prepare();
    const double prepare_ms = ms_since(prepare_start);
    BuiltTree built = builder->build(scene);
    std::vector<double> samples;
    if (command.repeat > 1) {
        // The first build above was the warm-up (device opened, programs built, caches filled).
        for (int i = 0; i < command.repeat; ++i) {
            builder->recycle(std::move(built.tree));
            built = builder->build(scene);
            samples.push_back(built.report.build_ms);
        }
        std::vector<double> sorted = samples;
        std::sort(sorted.begin(), sorted.end());
        built.report.build_ms = sorted[sorted.size() / 2];
    }
    if (command.strict) {
        for (const std::string& warning : built.report.warnings) print_warning(warning);
        throw_if_strict(true, built.report.warnings);
    }
    if (!command.output.empty()) write_tree_file(command.output, built.tree, scene);

    nlohmann::json report = tree_json(built, scene.triangle_count());
    report["scene"] = scene_json(scene);
    report["load_ms"] = load_ms;
    report["prepare_ms"] = prepare_ms;
    report["compile_ms"] = compile_ms_total();  // of prepare_ms: the programs built
    if (!samples.empty()) report["build_ms_samples"] = samples;
    if (!command.output.empty()) report["tree_file"] = command.output;
    if (command.json) {
        std::cout << json_text(report) << "\n";
    } else {
        for (const std::string& warning : scene.warnings) print_warning(warning);
        for (const std::string& warning : built.report.warnings) print_warning(warning);
        nlohmann::json table = {{"scene", report["scene"]}, {"tree", report}};
        table["tree"].erase("scene");
        print_grouped(std::cout, table);
    }
    return 0;
}

}  // namespace kdray::cli
