// build_prewarm.cpp — the first build's large buffers made ahead (build_prewarm.h).
#include "cl/builder/build_prewarm.h"

#include <algorithm>
#include <cmath>
#include <new>
#include <string_view>

#include "cl/runtime/cl_error.h"

namespace kdray::build_detail {

namespace {

constexpr double kPi = 3.14159265358979323846;

/// Below this many triangles a build's arrays are a few hundred pages: not worth a buffer each.
constexpr std::size_t kPrewarmMinTriangles = 4096;

/// Bytes per triangle of each buffer, most valuable first (prewarm_build_buffers stops at the
/// pool's capacity): above the most a build asked for on the benchmark scenes (`kdray build` at
/// high and low; Kitchen, Robots, bunny, Sponza, dragon res2 and res4, teapot), and under twice
/// the least, so that each scene's request fits (BufferPool::take keeps a buffer for requests of
/// half its size and more). Asked for, per triangle: masks 207-250 (128 bytes per small-root
/// reference), first-pass small node records 255-317 (10 KdSmallNode per reference and root),
/// the triangles (36) and their boxes (24) exactly, then the arrays that grow with the splits
/// (below). A first build then makes about 7% of its arrays afresh (tests/
/// test_opencl_build_prewarm.cpp): the BART Robots' large stage took 74 page faults, against
/// 1,766 with the masks, records, triangles and arenas alone. Left out, since a request of
/// another array takes them first when they are made ahead (the pool matches by size): the child
/// boxes (48-61), output nodes (50-66) and leaf indices (15-22), which on the dragon raised the
/// peak by 13% and the page faults too. Buffers taken a little larger than asked for raise a
/// first build's peak: 2% (Sponza) to 15% (the Robots) for the growing arrays.
struct PerTriangle {
    const char* what;
    std::size_t bytes;
};
constexpr PerTriangle kPerTriangle[] = {
    {"candidate masks", 260},
    {"small node records", 320},
    {"triangles", 36},
    {"triangle boxes", 24},
    // The depth-first large stage's two largest arenas (large_depth_first.cpp): 4 and 3 boxes
    // per deep-root reference, about 1.1 of those per triangle.
    {"depth-first workspace boxes", 120},
    {"depth-first small reference boxes", 90},
    // The arrays that grow with the splits, at about their final sizes: the small roots' and
    // deep roots' references (1.6-2 per triangle, 24-byte boxes, 4-byte ids) and two levels'
    // reference boxes (with room).
    {"small root triangle boxes", 72},
    {"deep root triangle boxes", 72},
    {"level reference boxes", 40},
    {"level reference boxes", 40},
    {"small root triangle ids", 12},
    {"small root of each reference", 12},
    {"depth-first small references", 16},
    {"level triangle references", 8},
    {"level triangle references", 8},
};

}  // namespace

std::vector<ExpectedBuffer> expected_build_buffers(std::size_t triangles,
                                                   const BuildParams& params) {
    std::vector<ExpectedBuffer> buffers;
    if (triangles < kPrewarmMinTriangles) return buffers;
    const std::string_view masks = "candidate masks";
    for (const PerTriangle& p : kPerTriangle)
        if (!(p.what == masks && params.small_split_bins > 0))
            buffers.push_back({p.what, p.bytes * triangles});
    return buffers;
}

std::size_t prewarm_build_buffers(ClDevice& device, std::size_t triangles,
                                  const BuildParams& params) {
    std::size_t made = 0;
    for (const ExpectedBuffer& expected : expected_build_buffers(triangles, params)) {
        // A full pool releases its oldest buffers, the most valuable of these: stop before.
        if (made + expected.bytes > device.buffer_pool().capacity()) break;
        // A buffer the device could not make is one the build will fail to make too, with its
        // own error: here it is only left out.
        if (expected.bytes > device.info().max_alloc_bytes) continue;
        // The widest pattern OpenCL allows: PoCL fills pattern by pattern, and 4-byte patterns
        // took 100 ms for the Kitchen's 80 MB.
        const std::size_t bytes =
            (expected.bytes + sizeof(cl_ulong16) - 1) / sizeof(cl_ulong16) * sizeof(cl_ulong16);
        cl::Buffer buffer = device.allocate(bytes, expected.what);
        with_cl_context(std::string("filling ") + expected.what + " ahead of the first build",
                        [&] { device.queue().enqueueFillBuffer(buffer, cl_ulong16{}, 0, bytes); });
        device.buffer_pool().keep(std::move(buffer), bytes);
        made += bytes;
    }
    return made;
}

KdTree prewarm_host_tree(std::size_t triangles) {
    KdTree tree;
    if (triangles < kPrewarmMinTriangles) return tree;
    // Per triangle, above the most the benchmark scenes' trees hold at high quality: 8.2 nodes
    // (the bunny; 5.4-6.9 elsewhere) and 5.6 leaf references (the bunny; 3.7-5.3 elsewhere).
    // resize writes every page; clear keeps them.
    try {
        tree.nodes.resize(10 * triangles);
        tree.leaf_indices.resize(7 * triangles);
    } catch (const std::bad_alloc&) {
        // Only a head start: the build makes its own and says so if the host lacks memory.
        return KdTree{};
    }
    tree.nodes.clear();
    tree.leaf_indices.clear();
    return tree;
}

Scene uv_sphere(int rings, int segments) {
    std::vector<float> tris;
    auto point = [&](int ring, int segment) {
        const double theta = kPi * ring / rings, phi = 2 * kPi * segment / segments;
        tris.insert(tris.end(), {float(std::sin(theta) * std::cos(phi)), float(std::cos(theta)),
                                 float(std::sin(theta) * std::sin(phi))});
    };
    for (int r = 0; r < rings; ++r)
        for (int g = 0; g < segments; ++g) {
            point(r, g), point(r + 1, g), point(r + 1, g + 1);
            point(r, g), point(r + 1, g + 1), point(r, g + 1);
        }
    return make_scene(std::move(tris), "sphere");
}

Scene cube_sphere(int n) {
    std::vector<float> tris;
    // Corner (i, j) of face (axis, sign), on the sphere.
    auto point = [&](int axis, double sign, int i, int j) {
        double p[3];
        p[axis] = sign;
        p[(axis + 1) % 3] = 2.0 * i / n - 1.0;
        p[(axis + 2) % 3] = (2.0 * j / n - 1.0) * sign;
        const double length = std::sqrt(p[0] * p[0] + p[1] * p[1] + p[2] * p[2]);
        tris.insert(tris.end(), {float(p[0] / length), float(p[1] / length), float(p[2] / length)});
    };
    // The two triangles of cell (i, j): its corners' offsets, in order.
    constexpr int kCellCorners[6][2] = {{0, 0}, {1, 0}, {1, 1}, {0, 0}, {1, 1}, {0, 1}};
    for (int axis = 0; axis < 3; ++axis)
        for (double sign : {-1.0, 1.0})
            for (int i = 0; i < n; ++i)
                for (int j = 0; j < n; ++j)
                    for (const auto& corner : kCellCorners)
                        point(axis, sign, i + corner[0], j + corner[1]);
    return make_scene(std::move(tris), "cube sphere");
}

void warm_up_launches(ClDevice& device, const BuildParams& params, std::size_t triangles) {
    // At least 2 * 16 * 40 triangles: more than a large node holds, and more than a deep root of
    // the depth-first large stage at T = 64 (large_depth_first.cpp: at least 16 T), so that the
    // large stage's levels, its depth-first subtrees, the small stage and the output all run, yet
    // a build of a few milliseconds once its kernels are loaded. Up to the size at which
    // prewarm_build_buffers takes over, a third more than the scene's: the sphere's arrays, left
    // in the pool, then fit the scene's (a request takes a buffer of up to twice its size), so
    // that a small scene's first build makes none (testdata/cornell, 2130 triangles: 1.37 times
    // its warm build's time with the 1280-triangle sphere). A cube sphere: the fans of thin
    // triangles at a UV sphere's poles, which every split near a pole cuts, ran the depth-first
    // stage's arenas out, and its second run left the pool other arrays than a scene's build
    // wants (tests/test_opencl_build_prewarm.cpp's 2800-triangle scene: its first build made 731 KB
    // of arrays afresh after the UV sphere, 225 KB after this one, 187 KB before the reruns were
    // partial).
    const std::size_t wanted = std::max<std::size_t>(
        2 * 16 * 40, triangles < kPrewarmMinTriangles ? triangles * 4 / 3 : 0);
    const int n = int(std::ceil(std::sqrt(double(wanted) / 12.0)));
    build_opencl(device, cube_sphere(n), params);
}

}  // namespace kdray::build_detail
