// reference_tracer.cpp — the CPU reference tracer: kd_trace_closest of kd_traverse.h (the very code
// the OpenCL kernels run) over batches of rays, and kd_render_pixel of kd_render.h (the shading the
// render kernel runs) over the pixels of a frame on std::threads: the oracle for the OpenCL image.
#include "core/render/reference_tracer.h"

#include <algorithm>
#include <atomic>
#include <cmath>
#include <cstddef>
#include <cstdint>
#include <string>
#include <thread>
#include <vector>

#include "core/device/kd_render.h"
#include "core/device/kd_traverse.h"
#include "core/error.h"
#include "core/render/camera.h"

namespace kdray {
namespace {

int resolve_threads(int threads) {
    if (threads > 0) return threads;
    const unsigned cores = std::thread::hardware_concurrency();
    return cores > 0 ? int(cores) : 1;
}

/// Runs work(begin, end) over [0, count) in chunks of `chunk` items handed out by an atomic counter
/// (dynamic distribution: a thread that drew cheap rays simply takes the next chunk). The calling
/// thread is one of the workers.
template <class Work>
void parallel_chunks(std::size_t count, std::size_t chunk, int threads, const Work& work) {
    std::atomic<std::size_t> next{0};
    auto worker = [&] {
        for (;;) {
            const std::size_t begin = next.fetch_add(chunk);
            if (begin >= count) return;
            work(begin, std::min(count, begin + chunk));
        }
    };
    const std::size_t chunks = (count + chunk - 1) / chunk;
    const int helpers =
        int(std::min<std::size_t>(std::size_t(resolve_threads(threads)), chunks)) - 1;
    std::vector<std::jthread> pool;
    for (int i = 0; i < helpers; ++i) pool.emplace_back(worker);
    worker();
}

/// The tree and scene in the form kd_trace_closest takes, checked once so that the walk itself can
/// trust every index.
struct TraceInput {
    const KdNode* nodes;
    const kd_u32* leaf_indices;
    const float* triangles;
    float bounds[6];
    bool empty;
};

TraceInput trace_input(const KdTree& tree, const Scene& scene) {
    if (scene.triangles.size() % KDRAY_FLOATS_PER_TRIANGLE != 0)
        throw Error("scene " + scene.path.string() + ": " + std::to_string(scene.triangles.size()) +
                    " triangle floats is not a multiple of " +
                    std::to_string(KDRAY_FLOATS_PER_TRIANGLE));
    const std::size_t triangles = scene.triangle_count();
    for (kd_u32 id : tree.leaf_indices)
        if (id >= triangles)
            throw Error("kd-tree (" + tree.builder + ") names triangle " + std::to_string(id) +
                        " but scene " + scene.path.string() + " has " + std::to_string(triangles));
    TraceInput in{tree.nodes.data(),
                  tree.leaf_indices.data(),
                  scene.triangles.data(),
                  {tree.bounds.lo.x, tree.bounds.lo.y, tree.bounds.lo.z, tree.bounds.hi.x,
                   tree.bounds.hi.y, tree.bounds.hi.z},
                  tree.nodes.empty() || tree.bounds.empty()};
    return in;
}

KdHit trace_one(const TraceInput& in, const KdRay& ray) {
    if (in.empty) return KdHit{INFINITY, KDRAY_NO_HIT, 0.0f, 0.0f};
    KdHit hit;
    kd_trace_closest(in.nodes, in.leaf_indices, in.triangles, in.bounds, &ray, &hit);
    return hit;
}

/// Rays per work item: large enough that the atomic counter is never contended, small enough that
/// two threads finish together on scenes whose cost is concentrated in a few places.
constexpr std::size_t kRayChunk = 1024;

}  // namespace

std::vector<KdHit> trace_closest(const KdTree& tree, const Scene& scene,
                                 const std::vector<KdRay>& rays, int threads) {
    const TraceInput in = trace_input(tree, scene);
    std::vector<KdHit> hits(rays.size());
    parallel_chunks(rays.size(), kRayChunk, threads, [&](std::size_t begin, std::size_t end) {
        for (std::size_t i = begin; i < end; ++i) hits[i] = trace_one(in, rays[i]);
    });
    return hits;
}

FrameResult render_reference(const KdTree& tree, const Scene& scene, const RenderInputs& inputs,
                             int threads) {
    const KdView& view = inputs.view;
    if (view.width == 0 || view.height == 0)
        throw Error("render: image size " + std::to_string(view.width) + "x" +
                    std::to_string(view.height) + " is empty");
    const TraceInput in = trace_input(tree, scene);
    if (scene.material_ids.size() != scene.triangle_count())
        throw Error("scene " + scene.path.string() + ": " +
                    std::to_string(scene.material_ids.size()) + " material ids for " +
                    std::to_string(scene.triangle_count()) + " triangles");
    for (kd_u32 id : scene.material_ids)
        if (id >= inputs.materials.size())
            throw Error("scene " + scene.path.string() + ": material id " + std::to_string(id) +
                        " but only " + std::to_string(inputs.materials.size()) + " materials");

    // The scene as kd_render_pixel reads it: the same code the OpenCL render kernel runs.
    KdSceneView scene_view{in.nodes,
                           in.leaf_indices,
                           in.triangles,
                           scene.has_vertex_normals() ? scene.vertex_normals.data() : nullptr,
                           scene.material_ids.data(),
                           inputs.materials.data(),
                           inputs.lights.data(),
                           inputs.emitters.data(),
                           inputs.effects.textures ? scene.texcoords.data() : nullptr,
                           inputs.effects.textures ? scene.texture_table.data() : nullptr,
                           inputs.effects.textures ? scene.texels.data() : nullptr,
                           {},
                           inputs.intersect};
    std::copy(in.bounds, in.bounds + 6, scene_view.bounds);

    FrameResult frame;
    frame.hits.width = frame.image.width = int(view.width);
    frame.hits.height = frame.image.height = int(view.height);
    const std::size_t pixels = std::size_t(view.width) * std::size_t(view.height);
    frame.hits.hits.resize(pixels);
    if (inputs.normals) frame.hits.normals.resize(pixels);
    if (inputs.cost) frame.hits.costs.resize(pixels);
    frame.image.rgb.resize(3 * pixels);
    std::vector<KdRayCounts> counts(pixels);

    // Rows handed out dynamically: a row is a few hundred rays, and neighbouring rows cost alike.
    // The calling thread, one of the workers, reports the rows done after each of its own.
    const std::uint64_t rays_per_row = std::uint64_t(view.width) * kd_primary_rays_per_pixel(&view);
    const std::uint64_t total_rays = rays_per_row * view.height;
    std::atomic<std::size_t> rows_done{0};
    const std::thread::id caller = std::this_thread::get_id();
    if (inputs.progress) inputs.progress(0, total_rays);
    parallel_chunks(std::size_t(view.height), 1, threads, [&](std::size_t begin, std::size_t end) {
        for (std::size_t y = begin; y < end; ++y, ++rows_done)
            for (kd_u32 x = 0; x < view.width; ++x) {
                const std::size_t i = y * view.width + x;
                if (in.empty) {
                    frame.hits.hits[i] = KdHit{INFINITY, KDRAY_NO_HIT, 0.0f, 0.0f};
                    for (int c = 0; c < 3; ++c) frame.image.rgb[3 * i + c] = view.background[c];
                    counts[i].primary = view.spp;
                    if (inputs.cost) frame.hits.costs[i] = KdTraceCost{0, 0};
                    continue;
                }
                KdPixel p;
                kd_render_pixel(&scene_view, &view, x, kd_u32(y), nullptr, nullptr, 0, &p);
                frame.hits.hits[i] = p.centre_hit;
                if (inputs.normals) frame.hits.normals[i] = {p.normal[0], p.normal[1], p.normal[2]};
                for (int c = 0; c < 3; ++c) frame.image.rgb[3 * i + c] = p.rgb[c];
                counts[i] = p.rays;
                if (inputs.cost)
                    kd_pixel_cost(&scene_view, &view, x, kd_u32(y), &frame.hits.costs[i]);
            }
        if (inputs.progress && std::this_thread::get_id() == caller)
            inputs.progress(rows_done * rays_per_row, total_rays);
    });
    for (const KdRayCounts& c : counts) frame.rays.add(c);
    return frame;
}

}  // namespace kdray
