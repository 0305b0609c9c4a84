// tree_builder.h — runs the builder the user chose (OpenCL by default, or the CPU reference) and
// times it. The OpenCL device and its programs are set up once, on first use, and reused for
// every frame of a run.
#pragma once

#include <memory>
#include <string>

#include "cli/commands.h"
#include "core/kd_tree.h"
#include "core/scene.h"

namespace kdray::cli {

struct BuiltTree {
    KdTree tree;
    BuildReport report;
};

class TreeBuilder {
  public:
    explicit TreeBuilder(BuilderOptions options);
    ~TreeBuilder();
    TreeBuilder(const TreeBuilder&) = delete;
    TreeBuilder& operator=(const TreeBuilder&) = delete;

    BuiltTree build(const Scene& scene);
    /// "reference (CPU)" or "opencl on <device name>"; opens the device if not yet open.
    std::string description();

  private:
    struct OpenCl;
    OpenCl& opencl();

    BuilderOptions options_;
    std::unique_ptr<OpenCl> opencl_;
};

}  // namespace kdray::cli
