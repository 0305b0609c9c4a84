// opencl_tree_builder.h — build_opencl (Zhou et al. 2008) behind core's TreeBuilder interface,
// on the run's DeviceSession (opened on first need, shared with the tracer). The tree's device
// buffers cross to the tracer as an OpenClResidentTree, opaque to everything outside cl/.
#pragma once

#include <string>

#include "cl/builder/opencl_builder.h"
#include "cl/runtime/device_session.h"
#include "core/tree/tree_builder.h"

namespace kdray {

/// The OpenCL builder's tree as it lies on its device, for an OpenCL tracer on that device.
struct OpenClResidentTree final : DeviceResidentTree {
    DeviceTree buffers;
};

class OpenClTreeBuilder final : public TreeBuilder {
  public:
    OpenClTreeBuilder(DeviceSession& session, const BuildParams& params)
        : session_(session), params_(params) {}

    /// Opens the device and builds the builder's programs (prepare_opencl_builder); the first
    /// time after expect_triangles, also makes the first build's buffers and warms its launches.
    void prepare() override;
    void expect_triangles(std::size_t triangles) override { expected_triangles_ = triangles; }
    BuiltTree build(const Scene& scene) override;
    void recycle(KdTree&& tree) override;
    std::string description() override;
    std::string quality() override;
    bool computes_on_host() override;

  private:
    DeviceSession& session_;
    BuildParams params_;
    std::size_t expected_triangles_ = 0;
    bool prewarmed_ = false;
    /// Host memory for the next build's tree: prewarm_host_tree's, or a recycled tree's.
    KdTree spare_;
};

}  // namespace kdray
