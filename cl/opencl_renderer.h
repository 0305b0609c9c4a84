// opencl_renderer.h — traces and shades a frame on the OpenCL device with the shared code of
// core/kd_render.h: the same rays and the same arithmetic as the reference renderer, so the
// reference image is this one's oracle.
#pragma once

#include "cl/device.h"
#include "core/frame.h"
#include "core/kd_tree.h"
#include "core/render_setup.h"
#include "core/scene.h"

namespace kdray {

/// Renders one frame. The render program is built once per effects combination and reused.
FrameResult render_opencl(ClDevice& device, const KdTree& tree, const Scene& scene,
                          const RenderInputs& inputs);

}  // namespace kdray
