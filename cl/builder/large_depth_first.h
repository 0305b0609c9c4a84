// large_depth_first.h — the large-node stage's depth-first schedule (CPU devices): the levels
// hand it every node of at most deep_root_refs references, and one work-item builds each such
// node's whole large subtree (internal to cl/builder/; the kernels are
// build_large_depth_first.cl's).
#pragma once

#include <cstddef>

#include "cl/builder/large_level.h"

namespace kdray::build_detail {

/// The most references of a deep root on this device for a scene of `triangles`: small enough
/// for a subtree's workspace to stay in a core's cache, and for the scene to make a few
/// subtrees per compute unit.
cl_uint deep_root_refs(const BuildContext& ctx, std::size_t triangles);

/// What build_depth_first did: the nodes that became leaves because a subtree's workspace
/// (kReferenceBudgetPerTriangle references per reference of its root) was full, and the runs of
/// its kernel (more than one when arenas ran out: each run after the first builds only the
/// subtrees whose arenas ran out in the one before).
struct DepthFirstResult {
    std::size_t budget_leaves = 0;
    int rounds = 0;
    std::size_t rebuilt = 0;  // subtrees built again, in the runs after the first
};

/// Builds every deep root's large subtree depth first, down to its small roots and leaves:
/// records (outside the batches, listed in output.regions for the output stage), small roots and
/// leaf references appended like a level's. The output arenas start `arena_shift` halvings
/// smaller than usual (tests).
DepthFirstResult build_depth_first(BuildContext& ctx, const TriangleBounds& triangles,
                                   const DeepRoots& deep, BuildOutput& output, SmallRoots& small,
                                   unsigned arena_shift = 0);

}  // namespace kdray::build_detail
