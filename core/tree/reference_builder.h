// reference_builder.h — the CPU reference kd-tree builder: full SAH over sorted split events in
// O(N log N) (Wald & Havran 2006, "On building fast kd-trees for ray tracing, and on doing that in
// O(N log N)"), with perfect splits (triangles clipped to the node before their events are made)
// and an empty-space bonus. It is the quality yardstick for the OpenCL builder, not a fast one.
#pragma once

#include "core/scene/scene.h"
#include "core/tree/tree.h"
#include "core/tree/tree_builder.h"

namespace kdray {

KdTree build_reference(const Scene& scene, const BuildParams& params = {});

/// build_reference behind the TreeBuilder interface, timed as one stage ("build").
class ReferenceTreeBuilder final : public TreeBuilder {
  public:
    explicit ReferenceTreeBuilder(const BuildParams& params) : params_(params) {}

    BuiltTree build(const Scene& scene) override;
    std::string description() override { return "reference (CPU, full SAH)"; }
    std::string quality() override { return "exact (reference)"; }
    bool computes_on_host() override { return true; }

  private:
    BuildParams params_;
};

}  // namespace kdray
