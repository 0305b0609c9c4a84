// opencl_renderer.h — traces and shades a frame on the OpenCL device with the shared code of
// core/kd_render.h: the same rays and the same arithmetic as the reference renderer, so the
// reference image is this one's oracle.
#pragma once

#include "cl/runtime/device.h"
#include "cl/build/opencl_builder.h"
#include "core/frame.h"
#include "core/kd_tree.h"
#include "core/render_setup.h"
#include "core/scene.h"

namespace kdray {

/// Builds the render program of a frame with these inputs (its effects combination and triangle
/// test) and runs the kernels such a frame runs once on an empty image, so that the program build
/// and the device compiler's first-launch work (PoCL compiles a kernel per work-group size on its
/// first launch) are done before the first frame is timed. Later calls, and frames with these
/// effects, reuse what it built.
void prepare_opencl_renderer(ClDevice& device, const RenderInputs& inputs);

/// Renders one frame. The render program is built once per effects combination and triangle
/// test (inputs.intersect) and reused. With packets (inputs.packets), kd_trace_camera_packets
/// traces each launch's primary rays first and the pixel kernel shades from their hits.
/// `on_device`, when given, is `tree` and the scene's triangles as build_opencl left them on this
/// device: they are traced where they lie instead of being uploaded again.
FrameResult render_opencl(ClDevice& device, const KdTree& tree, const Scene& scene,
                          const RenderInputs& inputs, const DeviceTree* on_device = nullptr);

}  // namespace kdray
