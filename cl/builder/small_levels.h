// small_levels.h — the small-node stage in the level-parallel shape of Zhou et al. (2008), §4.2
// (internal to cl/builder/; the kernels are build_small_level.cl's): a batch's small nodes level
// by level, one work-group per node, into the records the per-root shape writes.
#pragma once

#include "cl/builder/bounds.h"
#include "cl/builder/build_context.h"
#include "cl/builder/small_roots.h"
#include "cl/builder/small_subtrees.h"

namespace kdray::build_detail {

/// Every subtree of `batch`, level by level (its split-candidate masks already in
/// out.side_masks): batch.records (and second_offset) as kd_build_small_subtrees lays them out,
/// the roots' out.node_count and out.leaf_refs, and out.nodes and out.levels counted.
void build_batch_levels(BuildContext& ctx, const SmallRoots& small, const TriangleBounds& triangles,
                        SmallSubtrees& out, SmallBatch& batch);

}  // namespace kdray::build_detail
