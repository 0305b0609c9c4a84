// reference_tracer.h — the CPU reference tracer: the shared kd-tree walk of kd_traverse.h run over
// all pixels on std::threads, and the shared shading of kd_render.h over a frame's pixels.
#pragma once

#include <vector>

#include "core/device/kd_shared.h"
#include "core/io/image.h"
#include "core/render/frame.h"
#include "core/render/render_file.h"
#include "core/render/render_setup.h"
#include "core/render/tracer.h"
#include "core/scene/scene.h"
#include "core/tree/tree.h"

namespace kdray {

/// Nearest hits of a batch of rays, in parallel over `threads` (0: all cores).
std::vector<KdHit> trace_closest(const KdTree& tree, const Scene& scene,
                                 const std::vector<KdRay>& rays, int threads = 0);

/// One frame (the centre-ray hits for the AOV, the shaded image, the rays cast), shaded by
/// kd_render_pixel exactly as the OpenCL render kernel shades it.
FrameResult render_reference(const KdTree& tree, const Scene& scene, const RenderInputs& inputs,
                             int threads = 0);

/// render_reference behind the Tracer interface: the host tree, on `threads` threads (0: all).
class ReferenceTracer final : public Tracer {
  public:
    explicit ReferenceTracer(int threads) : threads_(threads) {}

    void prepare(const RenderInputs&) override {}
    FrameResult trace(const BuiltTree& built, const Scene& scene,
                      const RenderInputs& inputs) override {
        return render_reference(built.tree, scene, inputs, threads_);
    }
    std::string name() const override { return "reference"; }
    std::string exact_arithmetic() const override { return "fp64"; }
    bool computes_on_host() const override { return true; }

  private:
    int threads_;
};

}  // namespace kdray
