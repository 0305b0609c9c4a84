// tracer.h — the tracer interface every frame goes through: prepare(inputs) once per effects
// combination, outside trace_ms (programs, kernels, first launches: a frame's compile_ms and
// other_ms), then trace(built tree, scene, inputs) per frame. The CPU reference is
// core/render/reference_tracer.h, the OpenCL tracer cl/renderer/opencl_tracer.h; cl/backends.h
// picks one.
#pragma once

#include <string>

#include "core/render/frame.h"
#include "core/render/render_setup.h"
#include "core/scene/scene.h"
#include "core/tree/tree_builder.h"

namespace kdray {

class Tracer {
  public:
    virtual ~Tracer() = default;

    /// Readies frames with these inputs (their effects, triangle test and packets); later calls
    /// with the same combination do nothing.
    virtual void prepare(const RenderInputs& inputs) = 0;
    /// One frame of `scene` through `built` (its device-resident tree where this tracer can use
    /// it, else the host tree).
    virtual FrameResult trace(const BuiltTree& built, const Scene& scene,
                              const RenderInputs& inputs) = 0;
    /// For stats.json: "opencl" or "reference".
    virtual std::string name() const = 0;
    /// For stats.json: the arithmetic of the triangle test's exact steps (the watertight edge
    /// fallback, the refined distance), "fp64" or "float-float" (a device without double).
    virtual std::string exact_arithmetic() const = 0;
    /// Whether traces run on the host's own cores (see TreeBuilder::computes_on_host).
    virtual bool computes_on_host() const = 0;
};

}  // namespace kdray
