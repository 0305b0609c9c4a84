#include "cli/tree_builder.h"

#include <chrono>

#include "core/error.h"
#include "core/reference_builder.h"

namespace kdray::cli {

struct TreeBuilder::OpenCl {};

TreeBuilder::TreeBuilder(BuilderOptions options) : options_(std::move(options)) {}
TreeBuilder::~TreeBuilder() = default;

TreeBuilder::OpenCl& TreeBuilder::opencl() {
    throw Error("the OpenCL builder is not available in this build yet; use --builder reference");
}

std::string TreeBuilder::description() {
    if (options_.builder == "reference") return "reference (CPU, full SAH)";
    opencl();
    return "opencl";
}

BuiltTree TreeBuilder::build(const Scene& scene) {
    BuiltTree built;
    auto start = std::chrono::steady_clock::now();
    if (options_.builder == "reference") {
        built.tree = build_reference(scene, options_.params);
    } else {
        opencl();
    }
    built.report.build_ms =
        std::chrono::duration<double, std::milli>(std::chrono::steady_clock::now() - start).count();
    if (built.report.timings_ms.empty())
        built.report.timings_ms.push_back({"build", built.report.build_ms});
    return built;
}

}  // namespace kdray::cli
