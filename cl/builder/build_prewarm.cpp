// build_prewarm.cpp — the first build's large buffers made ahead (build_prewarm.h).
#include "cl/builder/build_prewarm.h"

#include <algorithm>

#include "cl/runtime/cl_error.h"

namespace kdray::build_detail {

namespace {

/// Below this many triangles a build's arrays are a few hundred pages: not worth a buffer each.
constexpr std::size_t kPrewarmMinTriangles = 4096;

/// Bytes per triangle of each buffer: above the most a build asked for on the benchmark scenes
/// (`kdray build`, default quality; Kitchen, Robots, bunny, dragon res2 and res4, teapot), and
/// under twice the least, so that each scene's request fits (BufferPool::take keeps a buffer
/// for requests of half its size and more). Asked for, per triangle: masks 200-230 (128 bytes
/// per small-root reference), first-pass small node records 255-294 (10 KdSmallNode per
/// reference and root), child boxes 48-61, output nodes 50-66, leaf indices 15-22; the triangles
/// (36) and their boxes (24) exactly. The small roots' growing arrays and the large stage's
/// per-level ones are left out: their sizes follow the splits, and the levels recycle them.
struct PerTriangle {
    const char* what;
    std::size_t bytes;
};
constexpr PerTriangle kPerTriangle[] = {
    {"candidate masks", 240}, {"small node records", 300},  {"reference child boxes", 50},
    {"kd-tree nodes", 68},    {"kd-tree leaf indices", 24}, {"triangles", 36},
    {"triangle boxes", 24},
};

}  // namespace

std::vector<ExpectedBuffer> expected_build_buffers(std::size_t triangles) {
    std::vector<ExpectedBuffer> buffers;
    if (triangles < kPrewarmMinTriangles) return buffers;
    for (const PerTriangle& p : kPerTriangle) buffers.push_back({p.what, p.bytes * triangles});
    return buffers;
}

std::size_t prewarm_build_buffers(ClDevice& device, std::size_t triangles) {
    std::size_t made = 0;
    for (const ExpectedBuffer& expected : expected_build_buffers(triangles)) {
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

}  // namespace kdray::build_detail
