// large_level.h — the large-node stage of the OpenCL builder (Zhou et al. 2008, §4.1): one level
// of active large nodes at a time, every node of the level at once (internal to cl/builder/; the
// kernels are build_large.cl's).
#pragma once

#include <cstddef>

#include "cl/builder/bounds.h"
#include "cl/builder/build_context.h"
#include "cl/builder/small_roots.h"

namespace kdray::build_detail {

/// What a level's split writes per reference and the next level no longer reads (each
/// reference's sides, its boxes clipped to the children): one set for the whole stage, replaced
/// only when a level outgrows it.
struct LargeScratch {
    DeviceArray ref_sides, child_box;
};

/// What a level below the root keeps of the level before, to bound its nodes without reading its
/// references: the parent level's chunk starts and, per chunk and side, the union of the boxes
/// it sent there (kd_distribute_chunks' side_box), 2 * chunks boxes.
struct ParentBoxes {
    cl_uint chunks = 0;
    DeviceArray chunk_start, side_box;
};

/// The active large nodes of one level (KdLargeNode each) and their references. Node i's
/// references are ref_start[i] .. + ref_count[i], in reduction chunks chunk_start[i] ..
/// chunk_start[i + 1] (nodes + 1 entries, the last the total): the segments of primitives.cl's
/// reduction. References: triangle id and box clipped to the node (KdBuildBox). Below the root,
/// parent[i] is node i's slot in the level before (2 * its parent + side), and from_parent what
/// that level left for the nodes' bounds.
struct LargeLevel {
    cl_uint nodes = 0, refs = 0, chunks = 0;
    DeviceArray node, ref_start, ref_count, chunk_start;
    DeviceArray ref_tri, ref_box;
    DeviceArray parent;
    ParentBoxes from_parent;

    /// Level 0: the root (node 0, the scene's bounds) holding every triangle's reference.
    static LargeLevel root(BuildContext& ctx, TriangleBounds& triangles, const Aabb& bounds);
    /// A level of `nodes` nodes and `refs` references in `chunks` chunks, not yet written.
    static LargeLevel allocate(BuildContext& ctx, cl_uint nodes, cl_uint refs, cl_uint chunks);

    /// Splits every node of this level: writes their node records (with their chains of
    /// empty-space cuts and their empty leaves) to `output`, appends the children of at most T
    /// references to `small` and the leaves' references to the leaf store, and returns the
    /// next level: the children that stay large. `force_leaf`: every node becomes a leaf. The
    /// next level takes this one's chunk starts (ParentBoxes).
    LargeLevel next(BuildContext& ctx, const TriangleBounds& triangles, bool force_leaf,
                    BuildOutput& output, SmallRoots& small, LargeScratch& scratch);
};

/// A large-stage level holding more references than this many per triangle splits no further: its
/// nodes become leaves. Real scenes stay well below it; it bounds memory on pathological input
/// where every plane cuts most triangles.
constexpr std::size_t kReferenceBudgetPerTriangle = 4;

/// What the large-node stage did: its levels, and the nodes it made leaves unsplit because their
/// level outgrew the reference budget (kReferenceBudgetPerTriangle in large_level.cpp).
struct LargeStageResult {
    int levels = 0;
    std::size_t budget_leaves = 0;
};

/// Large-node stage (§4.1): levels until no large node is left; a scene of at most T triangles
/// is one small root from the start.
LargeStageResult run_large_stage(BuildContext& ctx, TriangleBounds& triangles, const Aabb& bounds,
                                 BuildOutput& output, SmallRoots& small);

}  // namespace kdray::build_detail
