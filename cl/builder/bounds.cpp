// bounds.cpp — upload and triangle bounding boxes (Zhou et al. 2008, §4, step 1; bounds.h).
#include "cl/builder/bounds.h"

#include "cl/runtime/launch.h"

namespace kdray::build_detail {

TriangleBounds upload_triangles(BuildContext& ctx, const Scene& scene) {
    TriangleBounds b;
    b.count = static_cast<cl_uint>(scene.triangle_count());
    b.triangles = ctx.allocate<float>(scene.triangles.size(), "triangles");
    // The scene outlives the build, and the upload stage's wait comes next.
    ctx.upload(b.triangles, scene.triangles.data(), scene.triangles.size() * sizeof(float));
    return b;
}

void compute_triangle_boxes(BuildContext& ctx, TriangleBounds& b) {
    b.ref_box = ctx.allocate<KdBuildBox>(b.count, "triangle boxes");
    b.ref_tri = ctx.allocate<cl_uint>(b.count, "triangle references");
    enqueue_kernel(ctx.device, ctx.kernels.compute_aabbs, b.count, b.triangles.buffer(), b.count,
                   b.ref_box.buffer(), b.ref_tri.buffer());
}

}  // namespace kdray::build_detail
