// small_subtrees.h — the small-node stage of the OpenCL builder (Zhou et al. 2008, §4.2): every
// small root's subtree by the full SAH over 64-bit triangle masks (internal to cl/builder/; the
// kernels are build_small.cl's), by batch of roots, in either shape (per root, or per level:
// small_levels.h), and the records the output stage reads.
#pragma once

#include <vector>

#include "cl/builder/bounds.h"
#include "cl/builder/build_context.h"
#include "cl/builder/small_roots.h"

namespace kdray::build_detail {

/// Small roots whose split-candidate masks and node records the small stage holds at once: roots
/// root_begin.. and their references ref_begin.. (a root's references are contiguous, and so are
/// consecutive roots'). A batch's records stay until the output stage has moved them into place.
struct SmallBatch {
    cl_uint root_begin = 0, roots = 0, ref_begin = 0, refs = 0;
    cl_uint first_scale = 0;
    // [0] the first pass's records (KdSmallNode), first_scale * (n + 1) per root of n references;
    // [1] the second's, exactly the node counts of the subtrees that outgrew the first (empty
    // when none did).
    DeviceArray records[2];
    // Where each root's second-pass records start (roots + 1 entries; read only for the roots
    // that outgrew the first pass).
    DeviceArray second_offset;

    /// The kernels' view of the batch (second_pass: 1 for the second pass).
    KdSmallBatchArgs args(const BuildParams& params, cl_uint second_pass) const;
};

/// The small stage's result: the subtrees, by batch, with each root's node and leaf reference
/// counts (one entry per root, at least one: the output stage reads them even without roots).
struct SmallSubtrees {
    std::vector<SmallBatch> batches;
    DeviceArray node_count, leaf_refs;
    // The split-candidate masks of the last batch, held to the end of the build (see
    // run_small_stage).
    DeviceArray side_masks;
    cl_uint nodes = 0;
    int levels = 0;
};

/// Small-node stage (§4.2): every small root's subtree, in batches of roots whose masks and first
/// records take at most batch_bytes each. first_scale: the first pass's records per reference
/// and root (detail::SmallStageLimits). per_level: built level by level, a work-group per node
/// (small_levels.h), else a work-item per root (build_small.cl); the records are the same.
SmallSubtrees run_small_stage(BuildContext& ctx, const SmallRoots& small,
                              const TriangleBounds& triangles, cl_uint first_scale,
                              std::size_t batch_bytes, bool per_level);

/// The second pass's places of the batch's subtrees that outgrew their first records (by
/// out.node_count): batch.second_offset, one entry per root and the total, which it returns.
cl_uint place_second_pass(BuildContext& ctx, const SmallRoots& small, const SmallSubtrees& out,
                          SmallBatch& batch);

}  // namespace kdray::build_detail
