// small_roots.h — the small roots (Zhou et al. 2008, §4.2: nodes of at most T triangles), which
// the large stage appends level by level and the small stage turns into subtrees (internal to
// cl/builder/).
#pragma once

#include "cl/builder/bounds.h"
#include "cl/builder/build_context.h"

namespace kdray::build_detail {

/// The small roots (KdSmallRoot each) and their reference lists: triangle id, box clipped to the
/// root (KdBuildBox) and the root's index, per reference; a root's references are contiguous,
/// and so are consecutive roots'.
struct SmallRoots {
    cl_uint count = 0, refs = 0;
    DeviceArray roots;
    DeviceArray ref_tri, ref_box, ref_root;

    /// Room for `roots` roots and `refs` references in all, keeping those there are.
    void reserve(BuildContext& ctx, std::size_t roots, std::size_t refs);
    /// The whole scene as the one small root, node 0 (a scene of at most T triangles): its
    /// references are the triangles' own boxes.
    void make_scene_root(BuildContext& ctx, const TriangleBounds& triangles, const Aabb& bounds,
                         BuildOutput& output);
};

}  // namespace kdray::build_detail
