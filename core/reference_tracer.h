// reference_tracer.h — the CPU reference tracer: the shared kd-tree walk of kd_traverse.h run over
// all pixels on std::threads, and simple shading (Lambert under the render file's lights, or a
// headlight when there are none) so that the reference path produces a picture.
#pragma once

#include <vector>

#include "core/frame.h"
#include "core/image.h"
#include "core/kd_shared.h"
#include "core/kd_tree.h"
#include "core/render_file.h"
#include "core/scene.h"

namespace kdray {

/// Nearest hits of a batch of rays, in parallel over `threads` (0: all cores).
std::vector<KdHit> trace_closest(const KdTree& tree, const Scene& scene,
                                 const std::vector<KdRay>& rays, int threads = 0);

/// One frame: the centre-ray hits (the AOV) and the shaded image.
FrameResult render_reference(const KdTree& tree, const Scene& scene, const RenderSettings& settings,
                             const Camera& camera, int threads = 0);

}  // namespace kdray
