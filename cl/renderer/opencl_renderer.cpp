#include "cl/renderer/opencl_renderer.h"

#include <algorithm>
#include <chrono>
#include <cstdint>
#include <cstdlib>
#include <iterator>
#include <string>
#include <utility>

#include "cl/renderer/scene_arrays.h"
#include "cl/runtime/cl_error.h"
#include "cl/runtime/launch.h"
#include "cl/runtime/program_cache.h"
#include "core/device/kd_render.h"
#include "core/error.h"

namespace kdray {
namespace {

template <class T>
cl::Buffer upload(ClDevice& device, const std::vector<T>& data, const std::string& what) {
    cl::Buffer buffer = device.allocate(std::max<std::size_t>(1, data.size() * sizeof(T)), what);
    if (!data.empty())
        device.enqueue_write(buffer, 0, data.size() * sizeof(T), data.data(), "uploading " + what);
    return buffer;
}

/// Rows per launch: small enough that no single launch runs for seconds on a slow device (GPU
/// drivers kill long kernels behind a display), large enough to keep every compute unit busy;
/// with packets, the primary hits of a launch's pixels fill a buffer of 2^18 hits (4 MiB).
std::size_t rows_per_launch(const KdView& view, bool packets) {
    const std::size_t rays_per_pixel = packets ? kd_primary_rays_per_pixel(&view) : 1;
    const std::size_t pixels_per_launch =
        std::max<std::size_t>(1, (std::size_t(1) << 18) / rays_per_pixel);
    return std::max<std::size_t>(1, pixels_per_launch / std::max<kd_u32>(1, view.width));
}

/// Packet tiles (KDRAY_PACKET_TILE_WIDTH x KDRAY_PACKET_TILE_HEIGHT(lanes) pixels) per work-group.
constexpr std::size_t kPacketGroup = 4;

/// The pixel kernel that traces its packets too (render.cl).
constexpr const char* kTraceAndShade = "kd_trace_shade_camera_packets";

bool use_packets(const ClDevice& device, kd_u32 intersect, RenderInputs::Packets packets) {
    if (intersect != KDRAY_INTERSECT_WATERTIGHT) return false;
    switch (packets) {
        case RenderInputs::Packets::On:
            return true;
        case RenderInputs::Packets::Off:
            return false;
        case RenderInputs::Packets::Auto:
            break;
    }
    return device.is_cpu();
}

/// Pixels of a work-group. Square tiles keep neighbouring rays, and their paths through the tree,
/// together, which is what a GPU's SIMD lanes want. On PoCL (which runs a work-group as a loop
/// over its work-items) the shape made no measurable difference: process CPU time per frame for
/// 8x8, 16x16, 8x4, 16x1, 32x1 and 64x1 stayed within the noise of one another (kitchen
/// frame_000, 1024x768 primary rays, 2 cores, medians of 5).
constexpr std::size_t kTileWidth = 8, kTileHeight = 8;

}  // namespace

Tile preferred_pixel_tile(bool cpu_device, const OpenClRenderChoice& choice) {
    // A path program on a CPU device runs one pixel per work-group: PoCL then runs the kernel
    // body once per group instead of as a loop over 64 work-items, and a path work-item (its
    // pixel's samples, each a loop of bounces) is work enough per group. 6-10% less trace time
    // than 8x8 on the Cornell boxes (256x256, 64 spp, PoCL EPYC, interleaved runs; 2x1 and 4x1
    // in between); POCL_WORK_GROUP_METHOD=cbs with 8x8 gave the same, so it is the work-item
    // loop that costs.
    if (cpu_device && (choice.effects & KDRAY_EFFECT_PATH) != 0u) return {1, 1};
    return {kTileWidth, kTileHeight};
}

/// Build options of the render program: its effects, its triangle test, and whether it holds the
/// packet kernels (only where the choice uses them: CPU devices). Correctly rounded division and
/// square root, where the device offers them, make the device's camera rays and normals round as
/// the host's do (a GPU's default single-precision divide and sqrt may be off by an ulp or more);
/// a CPU device rounds correctly either way. Nothing that changes float results (fast or relaxed
/// math) is used.
std::string render_program_defines(const OpenClRenderChoice& choice,
                                   bool correctly_rounded_divide_sqrt) {
    std::string options = "-DKDRAY_COMPILED_EFFECTS=" + std::to_string(choice.effects) +
                          " -DKDRAY_COMPILED_INTERSECT=" + std::to_string(choice.intersect) +
                          " -DKDRAY_COMPILED_PACKETS=" + (choice.packets ? "1" : "0");
    if (choice.packets) options += " -DKDRAY_PACKET_LANES=" + std::to_string(choice.packet_lanes);
    // Without it a device with fp64 would take the double path whatever the host decided.
    if (!choice.fp64) options += " -DKDRAY_FORCE_NO_FP64=1";
    if (correctly_rounded_divide_sqrt) options += " -cl-fp32-correctly-rounded-divide-sqrt";
    return options;
}

namespace {

std::string render_options(const ClDevice& device, const OpenClRenderChoice& choice) {
    cl_device_fp_config fp = 0;
    const bool correctly_rounded = clGetDeviceInfo(device.device()(), CL_DEVICE_SINGLE_FP_CONFIG,
                                                   sizeof(fp), &fp, nullptr) == CL_SUCCESS &&
                                   (fp & CL_FP_CORRECTLY_ROUNDED_DIVIDE_SQRT);
    return render_program_defines(choice, correctly_rounded);
}

std::size_t round_up(std::size_t n, std::size_t multiple) {
    return (n + multiple - 1) / multiple * multiple;
}

/// The device buffers a frame's kernels read and write.
struct RenderBuffers {
    /// The tree, where the builder left it or uploaded.
    cl::Buffer nodes, leaf_indices, triangles;
    /// The frame's read-only shading arrays (cl/renderer/scene_arrays.h) and where each lies.
    cl::Buffer scene_data;
    KdSceneLayout layout{};
    cl::Buffer rgb, hits, normals, counts, traced, occluded, costs;
};

/// The image rows of one launch: `count` rows from `first`.
struct LaunchRows {
    std::size_t first = 0, count = 0;
};

// Each launch sets every argument of its kernel in the order of the kernel's signature in
// render.cl: one list per kernel, no argument set by position.

/// kd_render_pixels or kd_shade_traced_pixels (the same arguments) over the launch's rows, in
/// tiles. A width of 0 (the warm-up's empty view) still launches one tile.
void launch_pixels(ClDevice& device, cl::Kernel& kernel, Tile tile, const RenderBuffers& b,
                   const KdRenderLaunch& launch) {
    set_kernel_args(kernel, b.nodes, b.leaf_indices, b.triangles, b.scene_data, b.layout, launch,
                    b.rgb, b.hits, b.normals, b.counts, b.traced, b.occluded);
    device.launch(kernel,
                  cl::NDRange(round_up(std::max<std::size_t>(1, launch.view.width), tile.width),
                              round_up(launch.rows, tile.height)),
                  cl::NDRange(tile.width, tile.height));
}

/// A packet kernel's launch over the launch's rows: a work-item per tile and primary ray of its
/// pixels.
void enqueue_packet_tiles(ClDevice& device, cl::Kernel& kernel, std::size_t group, kd_u32 lanes,
                          const KdRenderLaunch& launch) {
    // At least one tile: the warm-up's empty view would make a global size of 0, which OpenCL
    // 1.2 rejects (each work-item returns at once past the image).
    const std::size_t tile_w = KDRAY_PACKET_TILE_WIDTH, tile_h = KDRAY_PACKET_TILE_HEIGHT(lanes);
    const std::size_t tiles_x = std::max<std::size_t>(1, (launch.view.width + tile_w - 1) / tile_w);
    const std::size_t tiles_y = (launch.rows + tile_h - 1) / tile_h;
    device.launch(
        kernel,
        cl::NDRange(round_up(tiles_x, group), tiles_y, kd_primary_rays_per_pixel(&launch.view)),
        cl::NDRange(group, 1, 1));
}

/// kd_trace_camera_packets over the launch's rows.
void launch_camera_packets(ClDevice& device, cl::Kernel& kernel, std::size_t group, kd_u32 lanes,
                           const RenderBuffers& b, const KdRenderLaunch& launch) {
    set_kernel_args(kernel, b.nodes, b.leaf_indices, b.triangles, launch, b.traced);
    enqueue_packet_tiles(device, kernel, group, lanes, launch);
}

/// kd_trace_shade_camera_packets over the launch's rows: kd_shade_traced_pixels' arguments but the
/// packets' buffers, in the packet kernels' tiles.
void launch_traced_and_shaded(ClDevice& device, cl::Kernel& kernel, std::size_t group, kd_u32 lanes,
                              const RenderBuffers& b, const KdRenderLaunch& launch) {
    set_kernel_args(kernel, b.nodes, b.leaf_indices, b.triangles, b.scene_data, b.layout, launch,
                    b.rgb, b.hits, b.normals, b.counts);
    enqueue_packet_tiles(device, kernel, group, lanes, launch);
}

/// kd_trace_shadow_packets over the launch's rows.
void launch_shadow_packets(ClDevice& device, cl::Kernel& kernel, std::size_t group, kd_u32 lanes,
                           const RenderBuffers& b, const KdRenderLaunch& launch) {
    set_kernel_args(kernel, b.nodes, b.leaf_indices, b.triangles, b.scene_data, b.layout, launch,
                    b.traced, b.occluded);
    enqueue_packet_tiles(device, kernel, group, lanes, launch);
}

/// kd_trace_costs over the launch's rows, in the pixel kernels' tiles.
void launch_costs(ClDevice& device, cl::Kernel& kernel, Tile tile, const RenderBuffers& b,
                  const KdRenderLaunch& launch) {
    set_kernel_args(kernel, b.nodes, b.leaf_indices, b.triangles, launch, b.costs);
    device.launch(kernel,
                  cl::NDRange(round_up(std::max<std::size_t>(1, launch.view.width), tile.width),
                              round_up(launch.rows, tile.height)),
                  cl::NDRange(tile.width, tile.height));
}

/// The launch record of a frame's launches, their rows unset.
KdRenderLaunch frame_launch(const KdView& view, const Aabb& bounds, kd_u32 outputs) {
    KdRenderLaunch launch{};
    launch.view = view;
    const float box[6] = {bounds.lo.x, bounds.lo.y, bounds.lo.z,
                          bounds.hi.x, bounds.hi.y, bounds.hi.z};
    std::copy(std::begin(box), std::end(box), launch.bounds);
    launch.outputs = outputs;
    return launch;
}

/// The launches of `rows` with the frame's launch record: the packets' primary hits and shadows
/// first, then the pixels.
void launch_rows(ClDevice& device, OpenClRenderPlan& plan, const RenderBuffers& b,
                 KdRenderLaunch launch, LaunchRows rows) {
    launch.first_row = kd_u32(rows.first);
    launch.rows = kd_u32(rows.count);
    if (plan.choice.pixel_kernel == kTraceAndShade) {
        launch_traced_and_shaded(device, plan.pixel, plan.packet_group, plan.choice.packet_lanes, b,
                                 launch);
        if (plan.choice.cost) launch_costs(device, plan.cost, plan.tile, b, launch);
        return;
    }
    if (plan.choice.packets)
        launch_camera_packets(device, plan.packet, plan.packet_group, plan.choice.packet_lanes, b,
                              launch);
    if (plan.choice.shadow_packets)
        launch_shadow_packets(device, plan.shadow, plan.packet_group, plan.choice.packet_lanes, b,
                              launch);
    launch_pixels(device, plan.pixel, plan.tile, b, launch);
    if (plan.choice.cost) launch_costs(device, plan.cost, plan.tile, b, launch);
}

}  // namespace

bool render_uses_fp64(const ClDevice& device) {
    const char* force = std::getenv("KDRAY_FORCE_NO_FP64");
    const bool forced = force != nullptr && *force != '\0' && std::string(force) != "0";
    return device.info().fp64 && !forced;
}

kd_u32 render_packet_lanes(const ClDevice& device) {
    if (const char* forced = std::getenv("KDRAY_PACKET_LANES"); forced && *forced != '\0') {
        const std::string lanes = forced;
        if (lanes == "8" || lanes == "16") return kd_u32(std::stoul(lanes));
        throw Error("KDRAY_PACKET_LANES is '" + lanes + "': packets have 8 or 16 lanes");
    }
    // The native width is the SIMD register's (PoCL: 16 on AVX-512, 8 on AVX2); a device that
    // cannot answer gets 8, which no CPU with SIMD splits across registers more than once.
    cl_uint native = 0;
    if (clGetDeviceInfo(device.device()(), CL_DEVICE_NATIVE_VECTOR_WIDTH_FLOAT, sizeof(native),
                        &native, nullptr) != CL_SUCCESS)
        native = 0;
    return native >= 16 ? 16u : 8u;
}

const char* exact_arithmetic_name(bool fp64) {
    return fp64 ? "fp64" : "float-float";
}

OpenClRenderChoice choose_opencl_render(const ClDevice& device, const RenderInputs& inputs) {
    OpenClRenderChoice choice;
    choice.fp64 = render_uses_fp64(device);
    choice.effects = inputs.effects.bits();
    choice.intersect = inputs.intersect;
    choice.packets = use_packets(device, inputs.intersect, inputs.packets);
    choice.packet_lanes = choice.packets ? render_packet_lanes(device) : 0u;
    // The shadow rays from the packets' primary hits are traced as packets too with shadows and
    // no more lights than a bit mask holds.
    // The path integrator casts its own (kd_path.h) and reads none.
    const bool path = (choice.effects & KDRAY_EFFECT_PATH) != 0u;
    choice.shadow_packets =
        choice.packets && !path && (choice.effects & KDRAY_EFFECT_SHADOWS) != 0u &&
        inputs.view.light_count > 0u && inputs.view.light_count <= KDRAY_PACKET_SHADOW_LIGHTS;
    // kd_shade_traced_pixels when the packets traced the pixel's only primary ray and no ray
    // follows from a hit but shadow rays: without the pending-ray stack and the primary walk,
    // PoCL compiles it to half kd_render_pixels' time per pixel (BART Kitchen, 1024x768
    // headlight: 28 -> 15 ms).
    const bool one_ray_tree =
        !path && (choice.effects & (KDRAY_EFFECT_REFLECTION | KDRAY_EFFECT_REFRACTION)) == 0u;
    // Without shadow packets between them, the packets' kernel shades its own hits
    // (kd_trace_shade_camera_packets): the bunny primary rays 1024x768, trace min 34.7 -> 30.7 ms,
    // median 39.3 -> 35.9 ms (24 frames x 4 interleaved rounds, pthread-skylake-avx512 PoCL).
    choice.pixel_kernel = !(choice.packets && inputs.view.spp == 1u && one_ray_tree)
                              ? "kd_render_pixels"
                          : choice.shadow_packets ? "kd_shade_traced_pixels"
                                                  : kTraceAndShade;
    choice.cost = inputs.cost;
    return choice;
}

OpenClRenderPlan plan_opencl_render(ClDevice& device, const OpenClRenderChoice& choice) {
    const cl::Program program = cached_program(device, "render.cl", render_options(device, choice));
    OpenClRenderPlan plan;
    plan.choice = choice;
    plan.pixel = make_kernel(program, choice.pixel_kernel.c_str());
    const bool traced_and_shaded = choice.pixel_kernel == kTraceAndShade;
    if (choice.packets && !traced_and_shaded)
        plan.packet = make_kernel(program, "kd_trace_camera_packets");
    if (choice.shadow_packets) plan.shadow = make_kernel(program, "kd_trace_shadow_packets");
    if (choice.cost) plan.cost = make_kernel(program, "kd_trace_costs");
    // One packet group for both packet kernels: the smaller of what each allows.
    const cl_device_id id = device.device()();
    plan.tile = choose_tile(choice.pixel_kernel, query_kernel_limits(plan.pixel, id),
                            preferred_pixel_tile(device.is_cpu(), choice));
    plan.packet_group = kPacketGroup;
    if (traced_and_shaded)
        plan.packet_group =
            choose_group_1d(kTraceAndShade, query_kernel_limits(plan.pixel, id), kPacketGroup);
    else if (choice.packets)
        plan.packet_group = choose_group_1d("kd_trace_camera_packets",
                                            query_kernel_limits(plan.packet, id), kPacketGroup);
    if (choice.shadow_packets)
        plan.packet_group = std::min(
            plan.packet_group, choose_group_1d("kd_trace_shadow_packets",
                                               query_kernel_limits(plan.shadow, id), kPacketGroup));
    return plan;
}

void warm_up_opencl_render(ClDevice& device, OpenClRenderPlan& plan) {
    // One tile over an image of width 0: every work-item returns at once, but the device
    // compiles each kernel for the tile size it will run with (PoCL: seconds with a cold cache),
    // so its time is compilation.
    const auto start = std::chrono::steady_clock::now();
    with_cl_context("preparing the render kernel on " + device.info().name, [&] {
        const cl::Buffer dummy = device.allocate(sizeof(KdHit), "render kernel warm-up buffer");
        RenderBuffers buffers;
        buffers.nodes = buffers.leaf_indices = buffers.triangles = buffers.scene_data = dummy;
        buffers.rgb = buffers.hits = buffers.normals = buffers.counts = dummy;
        buffers.traced = buffers.occluded = buffers.costs = dummy;
        launch_rows(device, plan, buffers, KdRenderLaunch{}, {0, 1});
    });
    device.finish("preparing the render kernel on " + device.info().name);
    add_compile_ms(
        std::chrono::duration<double, std::milli>(std::chrono::steady_clock::now() - start)
            .count());
}

FrameResult render_opencl(ClDevice& device, OpenClRenderPlan& plan, const KdTree& tree,
                          const Scene& scene, const RenderInputs& inputs,
                          const DeviceTree* on_device) {
    const KdView& view = inputs.view;
    const std::size_t pixels = std::size_t(view.width) * view.height;
    const bool packets = plan.choice.packets, shadow_packets = plan.choice.shadow_packets;

    // The builder's buffers where it hands them over (a copy each way less per frame: 12 MB for
    // the BART Kitchen, over PCIe on a GPU), else the host's arrays uploaded.
    const bool built_here =
        on_device && on_device->nodes() && on_device->leaf_indices() && on_device->triangles();
    // Normals only for the AOV; per-pixel ray counts only from a kernel with effects (without
    // any, every pixel casts its primary rays and nothing else).
    const bool count_rays = inputs.effects.bits() != 0;
    const std::size_t step = rows_per_launch(view, packets);
    RenderBuffers b;
    b.nodes = built_here ? on_device->nodes : upload(device, tree.nodes, "kd-tree nodes");
    b.leaf_indices = built_here ? on_device->leaf_indices
                                : upload(device, tree.leaf_indices, "leaf triangle indices");
    b.triangles = built_here ? on_device->triangles : upload(device, scene.triangles, "triangles");
    // The scene and the inputs outlive the frame's device.finish() below, which the uploads need.
    DeviceSceneArrays arrays = upload_scene_arrays(device, frame_scene_arrays(scene, inputs));
    b.scene_data = std::move(arrays.buffer);
    b.layout = arrays.layout;
    b.rgb = device.allocate(pixels * 3 * sizeof(float), "image");
    b.hits = device.allocate(pixels * sizeof(KdHit), "hit buffer");
    b.normals = device.allocate(inputs.normals ? pixels * 3 * sizeof(float) : 1, "normal buffer");
    b.counts = device.allocate(count_rays ? pixels * sizeof(KdRayCounts) : 1, "ray counts");
    b.costs =
        device.allocate(inputs.cost ? pixels * sizeof(KdTraceCost) : 1, "centre ray walk costs");
    // The primary hits of one launch's rows (all of its pixels' primary rays), when a packet
    // kernel traces them for another to shade (kd_trace_shade_camera_packets keeps its own);
    // in-order queue, so one buffer serves every launch.
    const bool hits_between_kernels = packets && plan.choice.pixel_kernel != kTraceAndShade;
    const std::size_t traced_rays = step * view.width * kd_primary_rays_per_pixel(&view);
    b.traced = device.allocate(hits_between_kernels ? traced_rays * sizeof(KdHit) : sizeof(KdHit),
                               "primary hit buffer");
    // ... and, beside each, the lights its shadow rays find blocked.
    b.occluded = device.allocate(shadow_packets ? traced_rays * sizeof(kd_u32) : sizeof(kd_u32),
                                 "shadow ray results");
    const kd_u32 outputs = (packets ? KDRAY_RENDER_TRACED_PRIMARY : 0u) |
                           (shadow_packets ? KDRAY_RENDER_TRACED_SHADOWS : 0u) |
                           (inputs.normals ? KDRAY_RENDER_NORMALS : 0u);
    const KdRenderLaunch launch = frame_launch(view, tree.bounds, outputs);
    const std::uint64_t rays_per_row = std::uint64_t(view.width) * kd_primary_rays_per_pixel(&view);
    const std::uint64_t total_rays = rays_per_row * view.height;
    if (inputs.progress) inputs.progress(0, total_rays);
    with_cl_context("rendering a frame on " + device.info().name, [&] {
        // With a progress callback, a marker after each launch; the host waits for the launch
        // before the one just queued, so that the device always has the next one to run.
        cl::Event previous;
        std::size_t previous_rows = 0;
        for (std::size_t row = 0; row < view.height; row += step) {
            const std::size_t rows = std::min<std::size_t>(step, view.height - row);
            launch_rows(device, plan, b, launch, {row, rows});
            if (!inputs.progress) continue;
            cl::Event marker;
            device.queue().enqueueMarkerWithWaitList(nullptr, &marker);
            if (previous()) {
                previous.wait();
                inputs.progress(previous_rows * rays_per_row, total_rays);
            }
            previous = marker;
            previous_rows = row + rows;
        }
    });

    FrameResult frame;
    frame.primary_packets = packets;
    frame.shadow_packets = shadow_packets;
    frame.packet_lanes = plan.choice.packet_lanes;
    frame.image.width = frame.hits.width = int(view.width);
    frame.image.height = frame.hits.height = int(view.height);
    frame.image.rgb.resize(pixels * 3);
    frame.hits.hits.resize(pixels);
    std::vector<float> normal_floats(inputs.normals ? pixels * 3 : 0);
    std::vector<KdRayCounts> pixel_counts(count_rays ? pixels : 0);
    if (inputs.cost) frame.hits.costs.resize(pixels);
    const std::string reading = "reading back a frame";
    device.enqueue_read(b.rgb, 0, pixels * 3 * sizeof(float), frame.image.rgb.data(), reading);
    device.enqueue_read(b.hits, 0, pixels * sizeof(KdHit), frame.hits.hits.data(), reading);
    if (inputs.normals)
        device.enqueue_read(b.normals, 0, pixels * 3 * sizeof(float), normal_floats.data(),
                            reading);
    if (count_rays)
        device.enqueue_read(b.counts, 0, pixels * sizeof(KdRayCounts), pixel_counts.data(),
                            reading);
    if (inputs.cost)
        device.enqueue_read(b.costs, 0, pixels * sizeof(KdTraceCost), frame.hits.costs.data(),
                            reading);
    device.finish(reading);
    if (inputs.normals) {
        frame.hits.normals.resize(pixels);
        for (std::size_t i = 0; i < pixels; ++i)
            frame.hits.normals[i] = {normal_floats[3 * i], normal_floats[3 * i + 1],
                                     normal_floats[3 * i + 2]};
    }
    if (count_rays)
        for (const KdRayCounts& c : pixel_counts) frame.rays.add(c);
    else
        frame.rays.primary = std::uint64_t(pixels) * kd_primary_rays_per_pixel(&view);
    return frame;
}

FrameResult render_opencl(ClDevice& device, const KdTree& tree, const Scene& scene,
                          const RenderInputs& inputs, const DeviceTree* on_device) {
    OpenClRenderPlan plan = plan_opencl_render(device, choose_opencl_render(device, inputs));
    return render_opencl(device, plan, tree, scene, inputs, on_device);
}

}  // namespace kdray
