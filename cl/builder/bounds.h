// bounds.h — the first stage of the OpenCL builder (Zhou et al. 2008, §4, step 1): the scene's
// triangles uploaded, each triangle's bounding box, and the root's reference list (internal to
// cl/builder/).
#pragma once

#include "cl/builder/build_context.h"
#include "core/scene/scene.h"

namespace kdray::build_detail {

/// The triangles on the device (KDRAY_FLOATS_PER_TRIANGLE floats each) and the root's
/// references: triangle i's id and box (KdBuildBox) at index i.
struct TriangleBounds {
    cl_uint count = 0;
    DeviceArray triangles;
    DeviceArray ref_tri, ref_box;
};

/// Uploads `scene`'s triangles (the references are not made yet).
TriangleBounds upload_triangles(BuildContext& ctx, const Scene& scene);
/// The root's references: every triangle's id and bounding box.
void compute_triangle_boxes(BuildContext& ctx, TriangleBounds& bounds);

}  // namespace kdray::build_detail
