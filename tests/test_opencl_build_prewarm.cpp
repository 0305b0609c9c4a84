// test_opencl_build_prewarm.cpp — the buffers made ahead of a first build (build_prewarm.h): on
// scenes of several shapes the build takes them instead of making its own, builds the same tree,
// and holds about the same peak.
#include <doctest/doctest.h>

#include <cmath>
#include <cstdint>
#include <random>
#include <string>
#include <vector>

#include "cl/builder/build_prewarm.h"
#include "cl/builder/opencl_builder.h"
#include "cl/builder/opencl_tree_builder.h"
#include "cl/runtime/device_session.h"
#include "tests/support.h"
#include "tests/test_opencl_fixture.h"

using namespace kdray;

namespace {

/// A flat, finely tessellated floor with a few hundred boxes standing on it (an architectural
/// scene's shape: large flat triangles' neighbours and many small separate objects).
Scene floor_and_boxes(int cells, int boxes) {
    std::vector<float> tris;
    auto quad = [&](const float a[3], const float b[3], const float c[3], const float d[3]) {
        tris.insert(tris.end(), {a[0], a[1], a[2], b[0], b[1], b[2], c[0], c[1], c[2]});
        tris.insert(tris.end(), {a[0], a[1], a[2], c[0], c[1], c[2], d[0], d[1], d[2]});
    };
    for (int i = 0; i < cells; ++i)
        for (int j = 0; j < cells; ++j) {
            const float x0 = float(i) / cells, x1 = float(i + 1) / cells;
            const float z0 = float(j) / cells, z1 = float(j + 1) / cells;
            const float a[3] = {x0, 0, z0}, b[3] = {x1, 0, z0}, c[3] = {x1, 0, z1},
                        d[3] = {x0, 0, z1};
            quad(a, b, c, d);
        }
    std::mt19937 rng(28);
    std::uniform_real_distribution<float> u(0.0f, 1.0f);
    for (int k = 0; k < boxes; ++k) {
        const float x = u(rng), z = u(rng), s = 0.005f + 0.03f * u(rng), h = 0.2f * u(rng);
        const float p[8][3] = {{x, 0, z}, {x + s, 0, z}, {x + s, 0, z + s}, {x, 0, z + s},
                               {x, h, z}, {x + s, h, z}, {x + s, h, z + s}, {x, h, z + s}};
        quad(p[4], p[5], p[6], p[7]);
        quad(p[0], p[1], p[5], p[4]);
        quad(p[1], p[2], p[6], p[5]);
        quad(p[2], p[3], p[7], p[6]);
        quad(p[3], p[0], p[4], p[7]);
    }
    return make_scene(std::move(tris), "floor and boxes");
}

/// Long thin triangles in every direction through a cube: most splits cut many of them.
Scene random_slivers(int count) {
    std::mt19937 rng(7);
    std::uniform_real_distribution<float> u(0.0f, 1.0f);
    std::vector<float> tris;
    for (int t = 0; t < count; ++t) {
        const float a[3] = {u(rng), u(rng), u(rng)}, b[3] = {u(rng), u(rng), u(rng)};
        const float e = 0.01f * u(rng);
        tris.insert(tris.end(), {a[0], a[1], a[2], b[0], b[1], b[2], a[0] + e, a[1], a[2] + e});
    }
    return make_scene(std::move(tris), "slivers");
}

}  // namespace

TEST_CASE("opencl builder: a first build takes the buffers made ahead for its triangle count") {
    ClDevice& device = test::opencl_test_device();
    // The slivers are the estimate's worst case: most splits cut them, so their small roots hold
    // more references per triangle than the buffers were sized for, and the build makes its own.
    struct Case {
        Scene scene;
        bool estimated;  // of the shapes the estimate is for
    };
    // The default, and binned small nodes, which make no split masks (nor expect any).
    BuildParams binned;
    binned.small_split_bins = 8;
    for (const Case& c : {Case{build_detail::uv_sphere(100, 100), true},
                          Case{floor_and_boxes(60, 600), true}, Case{random_slivers(6000), false}})
        for (const BuildParams& params : {BuildParams{}, binned}) {
            const Scene& scene = c.scene;
            CAPTURE(scene.path);
            CAPTURE(params.small_split_bins);
            const std::size_t n = scene.triangle_count();
            REQUIRE(!build_detail::expected_build_buffers(n, params).empty());

            device.buffer_pool().clear();
            std::uint64_t before = device.allocated_bytes();
            BuildReport cold;
            const KdTree cold_tree = build_opencl(device, scene, params, &cold);
            const std::uint64_t cold_allocated = device.allocated_bytes() - before;

            device.buffer_pool().clear();
            const std::size_t made = build_detail::prewarm_build_buffers(device, n, params);
            before = device.allocated_bytes();
            BuildReport ready;
            const KdTree ready_tree = build_opencl(device, scene, params, &ready);
            const std::uint64_t ready_allocated = device.allocated_bytes() - before;
            device.buffer_pool().clear();

            INFO("triangles " << n << ", made ahead " << made << ", allocated without "
                              << cold_allocated << " and with " << ready_allocated << ", peak "
                              << cold.device_bytes << " and " << ready.device_bytes);
            // The buffers made ahead are most of what a first build would make: when a size is off
            // (a request above a buffer, or under half of it) the build makes its own again. With
            // the growing arrays made ahead too, the sphere and the floor make 6.5% of it; the
            // masks and the first-pass records are each over a quarter of it, so that were either
            // not taken, the build would make over 1/4 (with the masks and records alone, 47% and
            // 52%).
            if (c.estimated) CHECK(ready_allocated < cold_allocated / 5);
            // Taken a little larger than asked for (up to twice, by another array when the sizes
            // are off), they raise the peak: this sphere 12.8%, the floor 7.8% on the PoCL CPU
            // device; a first `kdray build`'s device bytes per triangle rose 2% (Sponza) to 15%
            // (the BART Robots) when the growing arrays joined the masks and records. The bound is
            // that 15%.
            CHECK(ready.device_bytes <= cold.device_bytes * 115 / 100);
            test::check_same_tree(ready_tree, cold_tree, scene, 28);
        }
}

TEST_CASE("opencl builder: a run's builder makes the first build's buffers once") {
    // FramePipeline prepares the builder before every frame, after expect_triangles: only the
    // first prepare makes buffers ahead; the frames after take those the frame before gave back.
    DeviceSession session("");
    OpenClTreeBuilder builder(session, {});
    const std::size_t n = 20000;
    std::size_t expected = 0;
    for (const build_detail::ExpectedBuffer& b : build_detail::expected_build_buffers(n, {}))
        expected += b.bytes;
    REQUIRE(expected > 0);
    ClDevice& device = session.device();
    builder.expect_triangles(n);
    std::uint64_t before = device.allocated_bytes();
    builder.prepare();
    CHECK(device.allocated_bytes() - before >= expected);
    before = device.allocated_bytes();
    builder.expect_triangles(n);
    builder.prepare();
    CHECK(device.allocated_bytes() - before < expected / 10);
}

TEST_CASE("opencl builder: nothing is made ahead for a small scene") {
    CHECK(build_detail::expected_build_buffers(0, {}).empty());
    CHECK(build_detail::expected_build_buffers(1000, {}).empty());
}

TEST_CASE("opencl builder: a build fills the host storage it is lent and builds the same tree") {
    ClDevice& device = test::opencl_test_device();
    const Scene scene = floor_and_boxes(60, 600);
    const std::size_t n = scene.triangle_count();
    const KdTree fresh = build_opencl(device, scene);

    // Storage of the size prepare() makes: the tree's vectors are those, not new ones.
    KdTree storage = build_detail::prewarm_host_tree(n);
    REQUIRE(storage.nodes.capacity() >= fresh.nodes.size());
    REQUIRE(storage.leaf_indices.capacity() >= fresh.leaf_indices.size());
    const KdNode* nodes_memory = storage.nodes.data();
    const kd_u32* leaf_memory = storage.leaf_indices.data();
    const KdTree lent = build_opencl(device, scene, {}, nullptr, nullptr, &storage);
    CHECK(lent.nodes.data() == nodes_memory);
    CHECK(lent.leaf_indices.data() == leaf_memory);
    test::check_same_tree(lent, fresh, scene, 28);

    // Storage too small for the tree (a small scene's) is grown, the tree the same.
    KdTree small = build_opencl(device, build_detail::uv_sphere(4, 8));
    REQUIRE(small.nodes.capacity() < fresh.nodes.size());
    const KdTree grown = build_opencl(device, scene, {}, nullptr, nullptr, &small);
    test::check_same_tree(grown, fresh, scene, 28);
}

TEST_CASE("opencl builder: a run's builder builds into the tree the caller recycled") {
    DeviceSession session("");
    OpenClTreeBuilder builder(session, {});
    const Scene scene = floor_and_boxes(60, 600);
    builder.expect_triangles(scene.triangle_count());
    builder.prepare();
    BuiltTree first = builder.build(scene);
    const KdTree first_copy = first.tree;
    const KdNode* memory = first.tree.nodes.data();
    builder.recycle(std::move(first.tree));
    const BuiltTree second = builder.build(scene);
    CHECK(second.tree.nodes.data() == memory);
    test::check_same_tree(second.tree, first_copy, scene, 28);
}

TEST_CASE("opencl builder: host storage is made ahead only for scenes worth it") {
    CHECK(build_detail::prewarm_host_tree(1000).nodes.capacity() == 0);
    const KdTree made = build_detail::prewarm_host_tree(10000);
    CHECK(made.nodes.empty());
    CHECK(made.nodes.capacity() >= 10 * 10000);
    CHECK(made.leaf_indices.capacity() >= 7 * 10000);
}

TEST_CASE("opencl builder: a small scene's first build finds its arrays left by the warm-up") {
    // Below the size at which buffers are made ahead, the launch warm-up's sphere is sized after
    // the scene, so that the arrays it leaves in the pool fit the first build's.
    const Scene scene = floor_and_boxes(30, 100);
    const std::size_t n = scene.triangle_count();
    REQUIRE(build_detail::expected_build_buffers(n, {}).empty());
    DeviceSession session("");
    ClDevice& device = session.device();
    std::uint64_t before = device.allocated_bytes();
    build_opencl(device, scene);
    const std::uint64_t fresh = device.allocated_bytes() - before;

    DeviceSession prepared_session("");
    OpenClTreeBuilder builder(prepared_session, {});
    builder.expect_triangles(n);
    builder.prepare();
    before = prepared_session.device().allocated_bytes();
    builder.build(scene);
    const std::uint64_t first = prepared_session.device().allocated_bytes() - before;
    INFO("triangles " << n << ", allocated by a build into an empty pool " << fresh
                      << ", by the first build after prepare " << first);
    // 9% of it here (a cube sphere; a UV sphere, whose poles made the depth-first stage run again:
    // 29%); with the 1280-triangle sphere of before, 61%.
    CHECK(first < fresh / 4);
}
