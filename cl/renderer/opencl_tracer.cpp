#include "cl/renderer/opencl_tracer.h"

#include "cl/builder/opencl_tree_builder.h"
#include "core/error.h"
#include "core/io/frame_memory.h"

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
    // A frame whose per-pixel buffers the device cannot hold is refused with the figures before
    // any kernel runs (the device would fail an allocation midway, or not say at all).
    const FrameMemory need =
        estimate_frame_memory(inputs.view.width, inputs.view.height, inputs.normals);
    const ClDeviceInfo& info = device_.info();
    if (need.device_bytes > info.global_mem_bytes ||
        need.largest_device_buffer > info.max_alloc_bytes)
        throw Error("a " + std::to_string(inputs.view.width) + " x " +
                    std::to_string(inputs.view.height) + " frame needs about " +
                    std::to_string(need.device_bytes >> 20) + " MiB of device memory (" +
                    std::to_string(need.largest_device_buffer >> 20) + " MiB in one buffer); " +
                    info.name + " has " + std::to_string(info.global_mem_bytes >> 20) + " MiB (" +
                    std::to_string(info.max_alloc_bytes >> 20) + " MiB in one buffer)");
    return render_opencl(device_, plan_for(inputs), built.tree, scene, inputs,
                         resident ? &resident->buffers : nullptr);
}

}  // namespace kdray
