#include "cl/opencl_renderer.h"

#include <algorithm>
#include <string>

#include "cl/cl_error.h"
#include "cl/program_cache.h"

namespace kdray {
namespace {

template <class T>
cl::Buffer upload(ClDevice& device, const std::vector<T>& data, const std::string& what) {
    cl::Buffer buffer = device.allocate(std::max<std::size_t>(1, data.size() * sizeof(T)), what);
    if (!data.empty())
        with_cl_context("uploading " + what, [&] {
            device.queue().enqueueWriteBuffer(buffer, CL_FALSE, 0, data.size() * sizeof(T),
                                              data.data());
        });
    return buffer;
}

/// Rows per launch: small enough that no single launch runs for seconds on a slow device (GPU
/// drivers kill long kernels behind a display), large enough to keep every compute unit busy.
std::size_t rows_per_launch(const KdView& view) {
    const std::size_t pixels_per_launch = std::size_t(1) << 18;
    return std::max<std::size_t>(1, pixels_per_launch / std::max<kd_u32>(1, view.width));
}

/// Pixels of a work-group. Square tiles keep neighbouring rays, and their paths through the tree,
/// together, which is what a GPU's SIMD lanes want. On PoCL (which runs a work-group as a loop
/// over its work-items) the shape made no measurable difference: process CPU time per frame for
/// 8x8, 16x16, 8x4, 16x1, 32x1 and 64x1 stayed within the noise of one another (kitchen
/// frame_000, 1024x768 primary rays, 2 cores, medians of 5).
constexpr std::size_t kTileWidth = 8, kTileHeight = 8;

/// Build options of the render program. Correctly rounded division and square root, where the
/// device offers them, make the device's camera rays and normals round as the host's do (a GPU's
/// default single-precision divide and sqrt may be off by an ulp or more); a CPU device rounds
/// correctly either way. Nothing that changes float results (fast or relaxed math) is used.
std::string render_options(const ClDevice& device, kd_u32 effects, kd_u32 intersect) {
    std::string options = "-DKDRAY_COMPILED_EFFECTS=" + std::to_string(effects) +
                          " -DKDRAY_COMPILED_INTERSECT=" + std::to_string(intersect);
    cl_device_fp_config fp = 0;
    if (clGetDeviceInfo(device.device()(), CL_DEVICE_SINGLE_FP_CONFIG, sizeof(fp), &fp, nullptr) ==
            CL_SUCCESS &&
        (fp & CL_FP_CORRECTLY_ROUNDED_DIVIDE_SQRT))
        options += " -cl-fp32-correctly-rounded-divide-sqrt";
    return options;
}

cl::Kernel render_kernel(const ClDevice& device, kd_u32 effects, kd_u32 intersect) {
    return make_kernel(
        cached_program(device, "render.cl", render_options(device, effects, intersect)),
        "kd_render_pixels");
}

/// The launch of `rows` image rows from `first_row`, in tiles.
void enqueue_rows(ClDevice& device, cl::Kernel& kernel, std::size_t width, std::size_t first_row,
                  std::size_t rows) {
    kernel.setArg(8, kd_u32(first_row));
    kernel.setArg(9, kd_u32(rows));
    const std::size_t gx = (width + kTileWidth - 1) / kTileWidth * kTileWidth;
    const std::size_t gy = (rows + kTileHeight - 1) / kTileHeight * kTileHeight;
    device.queue().enqueueNDRangeKernel(kernel, cl::NullRange, cl::NDRange(gx, gy),
                                        cl::NDRange(kTileWidth, kTileHeight));
}

}  // namespace

void prepare_opencl_renderer(ClDevice& device, kd_u32 effects, kd_u32 intersect) {
    cl::Kernel kernel = render_kernel(device, effects, intersect);
    // One tile over an image of width 0: every work-item returns at once, but the device
    // compiles the kernel for the tile size it will run with.
    KdView view{};
    with_cl_context("preparing the render kernel on " + device.info().name, [&] {
        cl::Buffer dummy = device.allocate(sizeof(KdHit), "render kernel warm-up buffer");
        for (cl_uint arg = 0; arg < 14; ++arg)
            if (arg != 7 && arg != 8 && arg != 9) kernel.setArg(arg, dummy);
        kernel.setArg(7, sizeof(KdView), &view);
        enqueue_rows(device, kernel, 1, 0, 1);
        device.queue().finish();
    });
}

FrameResult render_opencl(ClDevice& device, const KdTree& tree, const Scene& scene,
                          const RenderInputs& inputs) {
    const KdView& view = inputs.view;
    const std::size_t pixels = std::size_t(view.width) * view.height;
    cl::Kernel kernel = render_kernel(device, inputs.effects.bits(), inputs.intersect);

    std::vector<float> bounds = {tree.bounds.lo.x, tree.bounds.lo.y, tree.bounds.lo.z,
                                 tree.bounds.hi.x, tree.bounds.hi.y, tree.bounds.hi.z};
    cl::Buffer nodes = upload(device, tree.nodes, "kd-tree nodes");
    cl::Buffer leaf_indices = upload(device, tree.leaf_indices, "leaf triangle indices");
    cl::Buffer triangles = upload(device, scene.triangles, "triangles");
    cl::Buffer material_ids = upload(device, scene.material_ids, "material ids");
    cl::Buffer materials = upload(device, inputs.materials, "materials");
    cl::Buffer lights = upload(device, inputs.lights, "lights");
    cl::Buffer bounds_buffer = upload(device, bounds, "scene bounds");
    cl::Buffer rgb = device.allocate(pixels * 3 * sizeof(float), "image");
    cl::Buffer hits = device.allocate(pixels * sizeof(KdHit), "hit buffer");
    cl::Buffer normals = device.allocate(pixels * 3 * sizeof(float), "normal buffer");
    cl::Buffer counts = device.allocate(pixels * sizeof(KdRayCounts), "ray counts");

    const std::size_t step = rows_per_launch(view);
    with_cl_context("rendering a frame on " + device.info().name, [&] {
        kernel.setArg(0, nodes);
        kernel.setArg(1, leaf_indices);
        kernel.setArg(2, triangles);
        kernel.setArg(3, material_ids);
        kernel.setArg(4, materials);
        kernel.setArg(5, lights);
        kernel.setArg(6, bounds_buffer);
        kernel.setArg(7, sizeof(KdView), &view);
        kernel.setArg(10, rgb);
        kernel.setArg(11, hits);
        kernel.setArg(12, normals);
        kernel.setArg(13, counts);
        for (std::size_t row = 0; row < view.height; row += step)
            enqueue_rows(device, kernel, view.width, row,
                         std::min<std::size_t>(step, view.height - row));
    });

    FrameResult frame;
    frame.image.width = frame.hits.width = int(view.width);
    frame.image.height = frame.hits.height = int(view.height);
    frame.image.rgb.resize(pixels * 3);
    frame.hits.hits.resize(pixels);
    std::vector<float> normal_floats(pixels * 3);
    std::vector<KdRayCounts> pixel_counts(pixels);
    with_cl_context("reading back a frame", [&] {
        cl::CommandQueue& q = device.queue();
        q.enqueueReadBuffer(rgb, CL_FALSE, 0, pixels * 3 * sizeof(float), frame.image.rgb.data());
        q.enqueueReadBuffer(hits, CL_FALSE, 0, pixels * sizeof(KdHit), frame.hits.hits.data());
        q.enqueueReadBuffer(normals, CL_FALSE, 0, pixels * 3 * sizeof(float), normal_floats.data());
        q.enqueueReadBuffer(counts, CL_TRUE, 0, pixels * sizeof(KdRayCounts), pixel_counts.data());
    });
    frame.hits.normals.resize(pixels);
    for (std::size_t i = 0; i < pixels; ++i) {
        frame.hits.normals[i] = {normal_floats[3 * i], normal_floats[3 * i + 1],
                                 normal_floats[3 * i + 2]};
        frame.rays.add(pixel_counts[i]);
    }
    return frame;
}

}  // namespace kdray
