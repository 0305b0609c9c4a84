// tree_builder.h — runs the builder the user chose (OpenCL by default, or the CPU reference) and
// times it. The OpenCL device is the run's DeviceSession, opened once and shared with the tracer.
#pragma once

#include <string>

#include "cl/build/opencl_builder.h"
#include "cli/commands.h"
#include "cli/device_session.h"
#include "core/kd_tree.h"
#include "core/scene.h"

namespace kdray::cli {

struct BuiltTree {
    KdTree tree;
    BuildReport report;
    DeviceTree on_device;  // the OpenCL builder's tree where it lies (empty for the reference)
};

class TreeBuilder {
  public:
    TreeBuilder(BuilderOptions options, DeviceSession& session);

    /// Opens the device and builds the builder's programs now, so that no build's time includes
    /// their compilation.
    void prepare();
    BuiltTree build(const Scene& scene);
    /// "reference (CPU, full SAH)" or "opencl on <device name>"; opens the device if needed.
    std::string description();

  private:
    BuilderOptions options_;
    DeviceSession& session_;
};

}  // namespace kdray::cli
