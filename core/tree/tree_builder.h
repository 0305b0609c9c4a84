// tree_builder.h — the builder interface every frame, `kdray build` and `kdray stats` go through:
// build(scene) gives the host tree, its BuildReport and whatever the builder left on a device for
// a tracer there. The CPU reference builder lives in core/tree/reference_builder.h, the OpenCL
// builder of Zhou et al. (2008) in cl/builder/opencl_tree_builder.h; cl/backends.h picks one.
#pragma once

#include <memory>
#include <string>

#include "core/scene/scene.h"
#include "core/tree/tree.h"

namespace kdray {

/// What a builder leaves on a device for a tracer on that device (the OpenCL builder: the
/// nodes, leaf indices and triangles as it wrote them). Opaque outside the backend that made it:
/// only that backend's tracer knows the derived type and looks for it.
class DeviceResidentTree {
  public:
    virtual ~DeviceResidentTree() = default;
};

struct BuiltTree {
    KdTree tree;
    BuildReport report;
    /// The tree where the builder left it; null for a builder on the host.
    std::shared_ptr<const DeviceResidentTree> on_device;
};

class TreeBuilder {
  public:
    virtual ~TreeBuilder() = default;

    /// Does now what would otherwise land in the first build's time (opening the device,
    /// compiling programs).
    virtual void prepare() {}
    /// The triangle count of the scene the next build will be given, before prepare(): a
    /// builder may then make the first build's memory ready while it prepares (build_prewarm.h).
    virtual void expect_triangles(std::size_t /*triangles*/) {}
    /// The tree of `scene`, with build_ms the whole build as the caller sees it.
    virtual BuiltTree build(const Scene& scene) = 0;
    /// A tree the caller is done with: a builder may keep its host memory for a later build, whose
    /// tree then fills pages already mapped (a fresh page costs about 2 us on this project's
    /// 2-core VM: 1.8 of the Robots' 2.2 ms download in a first build).
    virtual void recycle(KdTree&& /*tree*/) {}
    /// For stats.json: "reference (CPU, full SAH)" or "opencl on <device name>".
    virtual std::string description() = 0;
    /// For the log: the quality its parameters make (build_quality_of: low, medium, high or
    /// custom) for the OpenCL builder, "exact (reference)" for the reference builder.
    virtual std::string quality() = 0;
    /// Whether builds run on the host's own cores (the reference builder, a CPU device), where a
    /// loader thread beside them only preempts their workers.
    virtual bool computes_on_host() = 0;
};

}  // namespace kdray
