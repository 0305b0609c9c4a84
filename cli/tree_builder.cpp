#include "cli/tree_builder.h"

#include <chrono>

#include "cl/build/opencl_builder.h"
#include "core/reference_builder.h"

namespace kdray::cli {

TreeBuilder::TreeBuilder(BuilderOptions options, DeviceSession& session)
    : options_(std::move(options)), session_(session) {}

void TreeBuilder::prepare() {
    if (options_.builder == "opencl") prepare_opencl_builder(session_.device(), options_.params);
}

std::string TreeBuilder::description() {
    if (options_.builder == "reference") return "reference (CPU, full SAH)";
    return "opencl on " + session_.device().info().name;
}

BuiltTree TreeBuilder::build(const Scene& scene) {
    BuiltTree built;
    if (options_.builder == "reference") {
        auto start = std::chrono::steady_clock::now();
        built.tree = build_reference(scene, options_.params);
        built.report.build_ms =
            std::chrono::duration<double, std::milli>(std::chrono::steady_clock::now() - start)
                .count();
        built.report.timings_ms.push_back({"build", built.report.build_ms});
    } else {
        built.tree = build_opencl(session_.device(), scene, options_.params, &built.report,
                                  &built.on_device);
    }
    return built;
}

}  // namespace kdray::cli
