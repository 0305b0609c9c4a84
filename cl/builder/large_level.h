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
/// The nodes the large stage's depth-first schedule builds (deep roots,
/// build_large_depth_first.cl): the levels append every child of more than T and at most deep_refs
/// references here instead of to the next level. Node i (a KdLargeNode) has references ref_start[i]
/// .. + ref_count[i] of ref_tri and ref_box (triangle id, box clipped to the node), in the order
/// the level had them.
struct DeepRoots {
    cl_uint count = 0, refs = 0;
    /// The most references of a deep root; 0: the schedule is off (every large node stays in the
    /// levels).
    cl_uint deep_refs = 0;
    DeviceArray node, ref_start, ref_count, ref_tri, ref_box;

    /// Room for `roots` roots and `refs` references in all, keeping those there are.
    void reserve(BuildContext& ctx, std::size_t roots, std::size_t refs);
    /// The whole scene as the one deep root, node 0 (a scene of at most deep_refs triangles):
    /// its references are the triangles' own boxes.
    void make_scene_root(BuildContext& ctx, TriangleBounds& triangles, const Aabb& bounds);
};

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
    /// references to `small`, those of at most deep.deep_refs to `deep` and the leaves'
    /// references to the leaf store, and returns the next level: the children that stay large.
    /// `force_leaf`: every node becomes a leaf. The next level takes this one's chunk starts
    /// (ParentBoxes).
    LargeLevel next(BuildContext& ctx, const TriangleBounds& triangles, bool force_leaf,
                    BuildOutput& output, SmallRoots& small, DeepRoots& deep, LargeScratch& scratch);
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
    std::size_t depth_first_subtrees = 0;  // deep roots (large_depth_first.h)
    int depth_first_rounds = 0;            // runs of the depth-first kernel
    std::size_t depth_first_rebuilt = 0;   // subtrees built again after the first run
};

/// Large-node stage (§4.1): levels until no large node is left, then with the depth-first
/// schedule the deep roots the levels made (large_depth_first.h); a scene of at most T triangles
/// is one small root from the start, one of at most deep_refs one deep root.
/// `arena_shift`: the depth-first arenas start that many halvings small (tests).
LargeStageResult run_large_stage(BuildContext& ctx, TriangleBounds& triangles, const Aabb& bounds,
                                 BuildOutput& output, SmallRoots& small, unsigned arena_shift = 0);

}  // namespace kdray::build_detail
