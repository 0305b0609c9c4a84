// reference_tracer.cpp — the CPU reference tracer: kd_trace_closest of kd_traverse.h (the very code
// the OpenCL kernels run) over batches of rays and over the pixels of a frame on std::threads, and
// a deliberately simple shading (Lambert under point and directional lights, no shadows, plus
// emission) so that the reference path yields a viewable picture.
#include "core/reference_tracer.h"

#include <algorithm>
#include <atomic>
#include <cmath>
#include <cstddef>
#include <numbers>
#include <string>
#include <thread>
#include <vector>

#include "core/camera.h"
#include "core/error.h"
#include "core/kd_traverse.h"

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
    return kd_trace_closest(in.nodes, in.leaf_indices, in.triangles, in.bounds, ray);
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

FrameResult render_reference(const KdTree& tree, const Scene& scene, const RenderSettings& settings,
                             const Camera& camera, int threads) {
    const int width = settings.width, height = settings.height;
    if (width <= 0 || height <= 0)
        throw Error("render: image size " + std::to_string(width) + "x" + std::to_string(height) +
                    " is empty");
    const TraceInput in = trace_input(tree, scene);
    if (scene.material_ids.size() != scene.triangle_count())
        throw Error("scene " + scene.path.string() + ": " +
                    std::to_string(scene.material_ids.size()) + " material ids for " +
                    std::to_string(scene.triangle_count()) + " triangles");
    for (kd_u32 id : scene.material_ids)
        if (id >= scene.materials.size())
            throw Error("scene " + scene.path.string() + ": material id " + std::to_string(id) +
                        " but only " + std::to_string(scene.materials.size()) + " materials");

    const CameraRays rays(camera, width, height);
    // Without lights the picture would be black (or emission only): a headlight, a directional
    // light travelling along the view direction with irradiance 1, shows the shape instead.
    std::vector<Light> lights = settings.lights;
    if (lights.empty()) {
        Light headlight;
        headlight.type = Light::Type::directional;
        headlight.direction = rays.forward;
        headlight.intensity = {1, 1, 1};
        lights.push_back(headlight);
    }

    FrameResult frame;
    frame.hits.width = frame.image.width = width;
    frame.hits.height = frame.image.height = height;
    const std::size_t pixels = std::size_t(width) * std::size_t(height);
    frame.hits.hits.resize(pixels);
    frame.hits.normals.resize(pixels);
    frame.image.rgb.resize(3 * pixels);

    auto shade_pixel = [&](int x, int y) {
        const std::size_t index = std::size_t(y) * std::size_t(width) + std::size_t(x);
        const KdRay ray = rays.ray(float(x) + 0.5f, float(y) + 0.5f);
        const KdHit hit = trace_one(in, ray);
        frame.hits.hits[index] = hit;
        Vec3 color = settings.background;
        Vec3 normal{0, 0, 0};
        if (hit.prim != KDRAY_NO_HIT) {
            // Geometric normal, turned to face the ray: triangles are two-sided.
            const Vec3 v0 = scene.vertex(hit.prim, 0), v1 = scene.vertex(hit.prim, 1),
                       v2 = scene.vertex(hit.prim, 2);
            const Vec3 dir{ray.dir[0], ray.dir[1], ray.dir[2]};
            normal = normalize(cross(v1 - v0, v2 - v0));
            if (dot(normal, dir) > 0.0f) normal = -normal;
            const Vec3 p = Vec3{ray.org[0], ray.org[1], ray.org[2]} + dir * hit.t;

            // Lambert: outgoing radiance = Kd / pi * irradiance, where a point light of intensity
            // I at distance r gives I cos(theta) / r^2 and a directional light E cos(theta).
            const Material& material = scene.materials[scene.material_ids[hit.prim]];
            Vec3 irradiance{0, 0, 0};
            for (const Light& light : lights) {
                if (light.type == Light::Type::point) {
                    const Vec3 to_light = light.position - p;
                    const float r2 = dot(to_light, to_light);
                    if (r2 <= 0.0f) continue;
                    const float cos_theta = dot(normal, to_light) / std::sqrt(r2);
                    if (cos_theta > 0.0f)
                        irradiance = irradiance + light.intensity * (cos_theta / r2);
                } else {
                    const float cos_theta = -dot(normal, normalize(light.direction));
                    if (cos_theta > 0.0f) irradiance = irradiance + light.intensity * cos_theta;
                }
            }
            color =
                material.diffuse * irradiance * std::numbers::inv_pi_v<float> + material.emission;
        }
        frame.hits.normals[index] = normal;
        frame.image.rgb[3 * index + 0] = color.x;
        frame.image.rgb[3 * index + 1] = color.y;
        frame.image.rgb[3 * index + 2] = color.z;
    };

    // Rows handed out dynamically: a row is a few hundred rays, and neighbouring rows cost alike.
    parallel_chunks(std::size_t(height), 1, threads, [&](std::size_t begin, std::size_t end) {
        for (std::size_t y = begin; y < end; ++y)
            for (int x = 0; x < width; ++x) shade_pixel(x, int(y));
    });
    return frame;
}

}  // namespace kdray
