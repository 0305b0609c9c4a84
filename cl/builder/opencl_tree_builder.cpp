#include "cl/builder/opencl_tree_builder.h"

#include <memory>

#include "cl/builder/build_prewarm.h"
#include "core/tree/build_quality.h"

namespace kdray {

void OpenClTreeBuilder::prepare() {
    // The first build's memory is made ready once: a run prepares before every frame, and later
    // frames take the buffers the frame before gave back.
    if (!prewarmed_ && expected_triangles_ > 0)
        spare_ = build_detail::prewarm_host_tree(expected_triangles_);
    prepare_opencl_builder(session_.device(), params_, prewarmed_ ? 0 : expected_triangles_);
    prewarmed_ = prewarmed_ || expected_triangles_ > 0;
}

void OpenClTreeBuilder::recycle(KdTree&& tree) {
    spare_ = std::move(tree);
}

BuiltTree OpenClTreeBuilder::build(const Scene& scene) {
    BuiltTree built;
    auto on_device = std::make_shared<OpenClResidentTree>();
    built.tree = build_opencl(session_.device(), scene, params_, &built.report, &on_device->buffers,
                              &spare_);
    // Its vectors are the tree's now; the rest of it (params, builder) is stale.
    spare_ = KdTree{};
    built.on_device = std::move(on_device);
    return built;
}

std::string OpenClTreeBuilder::description() {
    return "opencl on " + session_.device().info().name;
}

std::string OpenClTreeBuilder::quality() {
    return build_quality_of(params_);
}

bool OpenClTreeBuilder::computes_on_host() {
    return session_.device().is_cpu();
}

}  // namespace kdray
