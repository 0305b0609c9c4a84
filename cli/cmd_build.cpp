// `kdray build SCENE.obj`: load, build, check nothing was lost, print the tree's statistics.
#include <iostream>

#include "cli/commands.h"
#include "cli/report.h"
#include "cli/tree_builder.h"
#include "core/scene.h"
#include "core/tree_file.h"

namespace kdray::cli {

int run_build(const BuildCommand& command) {
    Scene scene = load_obj(command.scene);
    TreeBuilder builder(command.builder);
    BuiltTree built = builder.build(scene);
    if (!command.output.empty()) write_tree_file(command.output, built.tree, scene);

    nlohmann::json report = tree_json(built, scene.triangle_count());
    report["scene"] = scene_json(scene);
    if (!command.output.empty()) report["tree_file"] = command.output;
    if (command.json) {
        std::cout << report.dump(2) << "\n";
    } else {
        for (const std::string& warning : scene.warnings)
            std::cerr << "kdray: warning: " << warning << "\n";
        nlohmann::json table = {{"scene", report["scene"]}, {"tree", report}};
        table["tree"].erase("scene");
        print_table(std::cout, table);
    }
    return 0;
}

}  // namespace kdray::cli
