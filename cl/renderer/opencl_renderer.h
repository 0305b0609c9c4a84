// opencl_renderer.h — traces and shades a frame on the OpenCL device with the shared code of
// core/device/kd_render.h: the same rays and the same arithmetic as the reference renderer, so the
// reference image is this one's oracle. A frame runs the kernels of a plan, decided and created
// once per combination of effects, triangle test and packets (cl/renderer/opencl_tracer.h keeps
// them for a run).
#pragma once

#include <compare>
#include <string>

#include <CL/opencl.hpp>

#include "cl/builder/opencl_builder.h"
#include "cl/runtime/device.h"
#include "cl/runtime/work_group.h"
#include "core/render/frame.h"
#include "core/render/render_setup.h"
#include "core/scene/scene.h"
#include "core/tree/tree.h"

namespace kdray {

/// Which kernels frames with given inputs run on a device: the render program (effects and
/// triangle test compiled in), whether packets trace the primary rays (kd_trace_camera_packets)
/// and their shadow rays (kd_trace_shadow_packets) and in how many lanes, and the pixel kernel
/// that shades.
struct OpenClRenderChoice {
    kd_u32 effects = 0, intersect = KDRAY_INTERSECT_WATERTIGHT;
    bool packets = false, shadow_packets = false;
    /// Rays per packet, 8 or 16 (render_packet_lanes); 0 without packets.
    kd_u32 packet_lanes = 0;
    /// The triangle test's exact steps in double (true) or float-float
    /// (core/device/kd_float_float.h).
    bool fp64 = true;
    /// kd_render_pixels, kd_shade_traced_pixels, or kd_trace_shade_camera_packets (which traces
    /// the packets' primary rays itself)
    std::string pixel_kernel;
    bool cost = false;  // kd_trace_costs after the pixels (the cost AOV)

    auto operator<=>(const OpenClRenderChoice&) const = default;
};
OpenClRenderChoice choose_opencl_render(const ClDevice& device, const RenderInputs& inputs);

/// Whether render programs on `device` do the triangle test's exact steps (the watertight edge
/// fallback, the refined distance) in double: the device has fp64 and the environment does not
/// set KDRAY_FORCE_NO_FP64 (to anything but "" or "0"), which makes them take the float-float
/// path a device without fp64 takes, for tests.
bool render_uses_fp64(const ClDevice& device);
/// Rays per packet on `device`: 16 (a float16, 4x4 pixels) where its native float vector width is
/// 16 or more (PoCL on AVX-512), else 8 (a float8, 4x2 pixels: AVX2, where a float16 takes two
/// registers per operation). KDRAY_PACKET_LANES=8 or 16 in the environment overrides it, for tests
/// and benchmarks; any other value set there is an Error.
kd_u32 render_packet_lanes(const ClDevice& device);
/// "fp64" or "float-float", as stats.json and the log name the path.
const char* exact_arithmetic_name(bool fp64);

/// The pixel kernel's work-group before the device's limits: 8x8 pixels, one pixel for a path
/// program on a CPU device.
Tile preferred_pixel_tile(bool cpu_device, const OpenClRenderChoice& choice);

/// A choice's kernels, created from its render program (built once per effects combination and
/// triangle test by cl/runtime/program_cache); packet and shadow only where the choice uses them.
struct OpenClRenderPlan {
    OpenClRenderChoice choice;
    cl::Kernel pixel, packet, shadow, cost;
    /// The pixel kernel's tile and the packet kernels' tiles per group, from the device's limits
    /// (cl/runtime/work_group.h): preferred_pixel_tile and 4 where allowed.
    Tile tile;
    std::size_t packet_group = 0;
};
OpenClRenderPlan plan_opencl_render(ClDevice& device, const OpenClRenderChoice& choice);

/// The -D and -cl options of the render program (render.cl) for `choice` on a device that does
/// or does not offer correctly rounded single-precision divide and sqrt
/// (CL_FP_CORRECTLY_ROUNDED_DIVIDE_SQRT); cl/program_catalogue.cpp lists them all from here.
std::string render_program_defines(const OpenClRenderChoice& choice,
                                   bool correctly_rounded_divide_sqrt);

/// Runs each of the plan's kernels once on an empty image, so that the device compiler's
/// first-launch work (PoCL compiles a kernel per work-group size on its first launch) is done
/// before the first frame is timed.
void warm_up_opencl_render(ClDevice& device, OpenClRenderPlan& plan);

/// Renders one frame with a plan made for these inputs (choose_opencl_render(device, inputs)).
/// `on_device`, when given, is `tree` and the scene's triangles as build_opencl left them on this
/// device: they are traced where they lie instead of being uploaded again.
FrameResult render_opencl(ClDevice& device, OpenClRenderPlan& plan, const KdTree& tree,
                          const Scene& scene, const RenderInputs& inputs,
                          const DeviceTree* on_device = nullptr);

/// One frame with a plan of its own (one-off frames, tests); the program cache still builds each
/// program once.
FrameResult render_opencl(ClDevice& device, const KdTree& tree, const Scene& scene,
                          const RenderInputs& inputs, const DeviceTree* on_device = nullptr);

}  // namespace kdray
