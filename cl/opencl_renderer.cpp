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

}  // namespace

FrameResult render_opencl(ClDevice& device, const KdTree& tree, const Scene& scene,
                          const RenderInputs& inputs) {
    const KdView& view = inputs.view;
    const std::size_t pixels = std::size_t(view.width) * view.height;
    cl::Program program = cached_program(
        device, "render.cl", "-DKDRAY_COMPILED_EFFECTS=" + std::to_string(inputs.effects.bits()));
    cl::Kernel kernel = make_kernel(program, "kd_render_pixels");

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
        for (std::size_t row = 0; row < view.height; row += step) {
            const std::size_t rows = std::min<std::size_t>(step, view.height - row);
            kernel.setArg(8, kd_u32(row));
            kernel.setArg(9, kd_u32(rows));
            // Work-groups of 8x8 pixels keep neighbouring rays (and their tree paths) together.
            const std::size_t gx = (view.width + 7) / 8 * 8, gy = (rows + 7) / 8 * 8;
            device.queue().enqueueNDRangeKernel(kernel, cl::NullRange, cl::NDRange(gx, gy),
                                                cl::NDRange(8, 8));
        }
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
