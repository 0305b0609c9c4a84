// small_roots.cpp — the small roots' arrays (small_roots.h).
#include "cl/builder/small_roots.h"

#include <vector>

namespace kdray::build_detail {

void SmallRoots::reserve(BuildContext& ctx, std::size_t new_roots, std::size_t new_refs) {
    ctx.reserve<cl_uint>(ref_tri, new_refs, refs, "small root triangle ids");
    ctx.reserve<KdBuildBox>(ref_box, new_refs, refs, "small root triangle boxes");
    ctx.reserve<cl_uint>(ref_root, new_refs, refs, "small root of each reference");
    ctx.reserve<KdSmallRoot>(roots, new_roots, count, "small roots");
}

void SmallRoots::make_scene_root(BuildContext& ctx, const TriangleBounds& triangles,
                                 const Aabb& bounds, BuildOutput& output) {
    const cl_uint n = triangles.count;
    reserve(ctx, 1, n);
    ctx.primitives.copy(triangles.ref_tri.buffer(), ref_tri.buffer(), n * sizeof(cl_uint));
    ctx.primitives.copy(triangles.ref_box.buffer(), ref_box.buffer(), n * sizeof(KdBuildBox));
    ctx.primitives.fill(ref_root.buffer(), 0, n);
    ctx.write(roots, std::vector<KdSmallRoot>{{build_box(bounds), 0, n, 0, 0}});
    ctx.write(output.records,
              std::vector<KdBuildNode>{{KDRAY_SMALL_ROOT_AXIS, 0.0f, {0, 0}, 0, 0}});
    count = 1;
    refs = n;
}

}  // namespace kdray::build_detail
