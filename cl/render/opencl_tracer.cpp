#include "cl/render/opencl_tracer.h"

#include "cl/build/opencl_tree_builder.h"

namespace kdray {

OpenClRenderPlan& OpenClTracer::plan_for(const RenderInputs& inputs) {
    const OpenClRenderChoice choice = choose_opencl_render(device_, inputs);
    auto found = plans_.find(choice);
    if (found != plans_.end()) return found->second;
    OpenClRenderPlan plan = plan_opencl_render(device_, choice);
    warm_up_opencl_render(device_, plan);
    return plans_.emplace(choice, std::move(plan)).first->second;
}

FrameResult OpenClTracer::trace(const BuiltTree& built, const Scene& scene,
                                const RenderInputs& inputs) {
    // The OpenCL builder's buffers when it built this tree (on this run's one device).
    const auto* resident = dynamic_cast<const OpenClResidentTree*>(built.on_device.get());
    return render_opencl(device_, plan_for(inputs), built.tree, scene, inputs,
                         resident ? &resident->buffers : nullptr);
}

}  // namespace kdray
