// opencl_tracer.h — the OpenCL renderer behind core's Tracer interface. It holds a run's render
// plans: prepare() decides a frame's kernels (opencl_renderer.h's choice) and creates and warms
// them once per combination; trace() reuses them, and traces the OpenCL builder's tree where the
// builder left it on the device.
#pragma once

#include <cstddef>
#include <map>
#include <string>

#include "cl/renderer/opencl_renderer.h"
#include "cl/runtime/device.h"
#include "core/render/tracer.h"

namespace kdray {

class OpenClTracer final : public Tracer {
  public:
    explicit OpenClTracer(ClDevice& device) : device_(device) {}

    void prepare(const RenderInputs& inputs) override { plan_for(inputs); }
    FrameResult trace(const BuiltTree& built, const Scene& scene,
                      const RenderInputs& inputs) override;
    std::string name() const override { return "opencl"; }
    std::string exact_arithmetic() const override {
        return exact_arithmetic_name(render_uses_fp64(device_));
    }
    bool computes_on_host() const override { return device_.is_cpu(); }
    /// The combinations planned so far.
    std::size_t plan_count() const { return plans_.size(); }

  private:
    /// The plan of frames with these inputs, made and warmed up on first need.
    OpenClRenderPlan& plan_for(const RenderInputs& inputs);

    ClDevice& device_;
    std::map<OpenClRenderChoice, OpenClRenderPlan> plans_;
};

}  // namespace kdray
