// opencl_builder.h — kd-tree construction on an OpenCL device with the algorithm of Zhou, Hou,
// Wang and Guo, "Real-time kd-tree construction on graphics hardware" (ACM TOG 27(5), 2008):
// a large-node stage (empty-space cutting, then binned-SAH or spatial-median splits of every
// large node of a level at once), a small-node stage (exact SAH with 64-bit triangle masks) and a
// preorder output stage, all on the device; the host only launches kernels and reads back the
// counts that size the next launch.
#pragma once

#include <cstddef>

#include <CL/opencl.hpp>

#include "cl/runtime/device.h"
#include "core/scene/scene.h"
#include "core/tree/tree.h"

namespace kdray {

/// Builds the kd-tree of `scene` on `device`. The tree's bounds are scene.bounds(), its builder
/// "opencl", its params a copy of `params`, which validate_build_params must accept (Error
/// otherwise: max_depth at most KDRAY_MAX_DEPTH, large_node_threshold in [1, 64], the width of
/// the small stage's masks). When `report` is given
/// it receives the per-stage times (upload, aabbs, large_nodes, small_nodes, output, download),
/// build_ms, the level counts of both stages and the peak device memory. Throws Error on any
/// OpenCL failure, naming the step. An empty scene gives a single empty leaf.
/// Builds (through cl/program_cache) every OpenCL program build_opencl uses on `device`, so that a
/// caller can keep program compilation out of its first build's time; a later build_opencl on the
/// device with the same `params` then builds no program (large_split_bins is compiled in).
/// `triangles`: the size of the scene the first build will be given, when known (0: unknown),
/// whose largest buffers are then made and written while the programs build
/// (build_prewarm.h), so that the first build touches no more fresh pages than a later one.
void prepare_opencl_builder(ClDevice& device, const BuildParams& params = {},
                            std::size_t triangles = 0);

/// The tree as it already lies on the device after a build: the preorder nodes, the leaf
/// indices and the scene's triangles (9 floats each), so that a renderer on the same device need
/// not upload them again. The buffers stay valid as long as this object holds them.
struct DeviceTree {
    cl::Buffer nodes, leaf_indices, triangles;
};

/// When `on_device` is given it receives the built tree's device buffers. `host_storage`, when
/// given, lends the result its vectors' memory (they are moved from): a tree the caller is done
/// with, or prewarm_host_tree's, so that the download writes pages already mapped instead of
/// fresh ones (about 2 us a page on the PoCL CPU device's host; 1.1k pages for the BART Robots).
KdTree build_opencl(ClDevice& device, const Scene& scene, const BuildParams& params = {},
                    BuildReport* report = nullptr, DeviceTree* on_device = nullptr,
                    KdTree* host_storage = nullptr);

namespace detail {
/// Limits of build_opencl's small stage, which tests set to reach its rarer paths.
struct SmallStageLimits {
    /// Node records first set aside per small root of n references: this times n + 1. Subtrees
    /// average 2.8 nodes per reference on the BART Kitchen and 5.2 on the bunny, and need a
    /// scale of at most 7 and 10; the few that outgrow the first budget are built again in a
    /// second pass. With 6, the bunny's second pass cost 20% of its build's CPU time (perf stat)
    /// and the kitchen's peak device memory was higher (113 MB against 102: both passes' records
    /// at once). Tests pass 1 so that most subtrees take the second pass.
    unsigned subtree_budget_scale = 10;
    /// The most bytes of one batch's split-candidate masks, and of its first node records; 0:
    /// the device's largest allocation. Tests pass a few kilobytes so that a small scene is
    /// built in many batches.
    std::size_t batch_bytes = 0;
    /// The large stage's depth-first arenas start this many halvings smaller than their usual
    /// size (large_depth_first.cpp). Tests pass a few so that the arenas run out and the subtrees
    /// are built again with larger ones.
    unsigned depth_first_arena_shift = 0;
};

KdTree build_opencl_with_limits(ClDevice& device, const Scene& scene, const BuildParams& params,
                                const SmallStageLimits& limits, BuildReport* report = nullptr,
                                DeviceTree* on_device = nullptr, KdTree* host_storage = nullptr);
}  // namespace detail

}  // namespace kdray
