// test_intersect_moller.cpp — the Möller–Trumbore test of core/device/kd_intersect_moller.h, the
// fast alternative that `kdray render --intersect moller` selects: it agrees with the watertight
// test (brute force) on generic rays, through the kd-tree too; on rays aimed at the vertices and
// edges of a closed mesh around the camera the watertight test never leaks while Möller–Trumbore
// may (its leaks are counted, not asserted); and the OpenCL tracer gives the reference tracer's
// hits for either test.
#include <doctest/doctest.h>

#include <cmath>
#include <cstdint>
#include <random>
#include <string>
#include <vector>

#include "cl/renderer/opencl_renderer.h"
#include "core/device/kd_render.h"
#include "core/device/kd_traverse.h"
#include "core/render/reference_tracer.h"
#include "core/render/render_setup.h"
#include "core/tree/reference_builder.h"
#include "tests/support.h"
#include "tests/test_opencl_fixture.h"

using namespace kdray;

namespace {

KdHit no_hit() {
    return KdHit{INFINITY, KDRAY_NO_HIT, 0.0f, 0.0f};
}

/// Nearest hit over every triangle with the test `intersect` picks.
KdHit brute_force(const Scene& scene, const KdRay& ray, kd_u32 intersect) {
    KdRayPrecomp p;
    kd_ray_precompute(&ray, &p);
    KdHit best = no_hit();
    best.t = ray.tmax;
    for (std::size_t i = 0; i < scene.triangle_count(); ++i) {
        const float* tri = &scene.triangles[i * KDRAY_FLOATS_PER_TRIANGLE];
        if (intersect == KDRAY_INTERSECT_MOLLER)
            kd_intersect_triangle_moller(&p, tri, kd_u32(i), ray.tmin, &best);
        else
            kd_intersect_triangle(&p, tri, kd_u32(i), ray.tmin, &best);
    }
    if (best.prim == KDRAY_NO_HIT) best.t = INFINITY;
    return best;
}

KdHit trace(const KdTree& tree, const Scene& scene, const KdRay& ray, kd_u32 intersect) {
    const float bounds[6] = {tree.bounds.lo.x, tree.bounds.lo.y, tree.bounds.lo.z,
                             tree.bounds.hi.x, tree.bounds.hi.y, tree.bounds.hi.z};
    KdHit hit;
    kd_trace(tree.nodes.data(), tree.leaf_indices.data(), scene.triangles.data(), bounds, &ray, 0,
             intersect, &hit, nullptr);
    return hit;
}

/// Rays from random points around the scene's box towards random points inside it: generic
/// rays, which meet an edge or a vertex within rounding only by a negligible chance.
std::vector<KdRay> generic_rays(const Scene& scene, int count, std::uint32_t seed) {
    std::mt19937 rng(seed);
    std::uniform_real_distribution<float> unit(0.0f, 1.0f);
    const Aabb b = scene.bounds();
    const Vec3 e = b.extent();
    std::vector<KdRay> rays;
    for (int i = 0; i < count; ++i) {
        const Vec3 from{b.lo.x + e.x * (3 * unit(rng) - 1), b.lo.y + e.y * (3 * unit(rng) - 1),
                        b.lo.z + e.z * (3 * unit(rng) - 1)};
        const Vec3 to{b.lo.x + e.x * unit(rng), b.lo.y + e.y * unit(rng), b.lo.z + e.z * unit(rng)};
        const Vec3 d = normalize(to - from);
        rays.push_back(KdRay{{from.x, from.y, from.z}, 0.0f, {d.x, d.y, d.z}, INFINITY});
    }
    return rays;
}

/// The cube [-1, 1]^3 scaled by `scale` about `centre`, each face an n x n grid of cells cut
/// along a diagonal; grid vertices are computed once per integer coordinate, so the triangles
/// that share a vertex or an edge hold bit-identical corners, as a loaded closed mesh does.
/// Also returns every grid vertex and edge midpoint on the faces: targets of the leak rays.
Scene closed_box(int n, float scale, Vec3 centre, std::vector<Vec3>& targets) {
    auto at = [&](int i, int j, int k) {
        const float s = 2.0f / float(n);
        return centre + Vec3{-1 + s * i, -1 + s * j, -1 + s * k} * scale;
    };
    Scene scene;
    for (int axis = 0; axis < 3; ++axis)
        for (int side : {0, n})
            for (int i = 0; i < n; ++i)
                for (int j = 0; j < n; ++j) {
                    auto corner = [&](int di, int dj) {
                        int c[3];
                        c[axis] = side, c[(axis + 1) % 3] = i + di, c[(axis + 2) % 3] = j + dj;
                        return at(c[0], c[1], c[2]);
                    };
                    const Vec3 q[4] = {corner(0, 0), corner(1, 0), corner(1, 1), corner(0, 1)};
                    for (const Vec3& v : {q[0], q[1], q[2], q[0], q[2], q[3]})
                        scene.triangles.insert(scene.triangles.end(), {v.x, v.y, v.z});
                    targets.push_back(q[0]);
                    targets.push_back((q[0] + q[1]) * 0.5f);
                    targets.push_back((q[0] + q[2]) * 0.5f);
                }
    scene.material_ids.assign(scene.triangle_count(), 0);
    scene.materials.push_back(Material{});
    return scene;
}

struct Leaks {
    int watertight = 0, moller = 0, moller_tree = 0, rays = 0;
};

/// Rays from the box's centre through every target: each must hit, so a miss is a leak.
Leaks count_leaks(const Scene& scene, const std::vector<Vec3>& targets, Vec3 centre) {
    const KdTree tree = build_reference(scene);
    Leaks leaks;
    for (const Vec3& target : targets) {
        const Vec3 d = normalize(target - centre);
        const KdRay ray{{centre.x, centre.y, centre.z}, 0.0f, {d.x, d.y, d.z}, INFINITY};
        ++leaks.rays;
        const KdHit wt = brute_force(scene, ray, KDRAY_INTERSECT_WATERTIGHT);
        const KdHit mt = brute_force(scene, ray, KDRAY_INTERSECT_MOLLER);
        leaks.watertight += wt.prim == KDRAY_NO_HIT;
        leaks.moller += mt.prim == KDRAY_NO_HIT;
        // Through the tree the watertight test holds as well. Moller-Trumbore's leaks there need
        // not be brute force's: a hit that rounding moves just past a shared edge may lie on a
        // triangle of a leaf the walk never visits.
        leaks.watertight +=
            trace(tree, scene, ray, KDRAY_INTERSECT_WATERTIGHT).prim == KDRAY_NO_HIT;
        leaks.moller_tree += trace(tree, scene, ray, KDRAY_INTERSECT_MOLLER).prim == KDRAY_NO_HIT;
    }
    return leaks;
}

}  // namespace

TEST_CASE("moller: agrees with the watertight test on generic rays, by brute force and tree") {
    for (std::uint32_t seed : {1u, 2u, 3u}) {
        CAPTURE(seed);
        const Scene scene = test::random_triangles(400, seed);
        const KdTree tree = build_reference(scene);
        int hits = 0, disagree = 0, tree_disagree = 0;
        for (const KdRay& ray : generic_rays(scene, 3000, seed)) {
            const KdHit mt = brute_force(scene, ray, KDRAY_INTERSECT_MOLLER);
            const KdHit wt = brute_force(scene, ray, KDRAY_INTERSECT_WATERTIGHT);
            hits += mt.prim != KDRAY_NO_HIT;
            disagree += !test::hits_agree(mt, wt);
            if (mt.prim == wt.prim && mt.prim != KDRAY_NO_HIT) {
                CHECK(mt.u == doctest::Approx(wt.u).epsilon(1e-3));
                CHECK(mt.v == doctest::Approx(wt.v).epsilon(1e-3));
            }
            const KdHit walked = trace(tree, scene, ray, KDRAY_INTERSECT_MOLLER);
            tree_disagree += walked.prim != mt.prim || walked.t != mt.t;
        }
        CHECK(hits > 500);
        CHECK(disagree == 0);
        CHECK(tree_disagree == 0);
    }
}

TEST_CASE("moller: the watertight test never leaks through a closed mesh; Moller-Trumbore may") {
    // Rays from the centre of a finely tessellated closed box through its vertices and edge
    // midpoints: the hardest rays there are, since each meets several triangles exactly on their
    // boundary. Far from the origin the rounding in the ray's frame is coarser still.
    struct Case {
        std::string name;
        float scale;
        Vec3 centre;
    };
    int moller_leaks = 0;
    for (const Case& c :
         {Case{"origin", 1.0f, {0, 0, 0}}, Case{"at 1e5", 100.0f, {1e5f, 1e5f, 1e5f}}}) {
        CAPTURE(c.name);
        std::vector<Vec3> targets;
        const Scene box = closed_box(12, c.scale, c.centre, targets);
        const Leaks leaks = count_leaks(box, targets, c.centre);
        CHECK(leaks.watertight == 0);
        MESSAGE("closed box ", c.name, ": Moller-Trumbore leaks ", leaks.moller, " of ", leaks.rays,
                " rays by brute force, ", leaks.moller_tree,
                " through the tree; the watertight test 0");
        moller_leaks += leaks.moller + leaks.moller_tree;
    }
    // Not a requirement of Moller-Trumbore, but the point of the comparison: if it never leaked
    // here, these rays would not be exercising shared edges at all.
    CHECK(moller_leaks > 0);
}

TEST_CASE("moller: the OpenCL tracer gives the reference tracer's hits for either test") {
    std::vector<Vec3> targets;
    const Scene box = closed_box(16, 1.0f, {0, 0, 0}, targets);
    const KdTree tree = build_reference(box);
    // Inside the box looking down -z, fov 90 over 33 x 33 pixels: with 16 cells of 1/8 per face,
    // every fourth pixel column and row of centre rays passes through grid lines of the far face.
    RenderSettings settings;
    settings.width = settings.height = 33;
    settings.max_depth = 1;
    Camera camera;
    camera.position = {0, 0, 0};
    camera.look_at = {0, 0, -1};
    camera.fov_y = 90.0f;
    for (kd_u32 intersect : {KDRAY_INTERSECT_WATERTIGHT, KDRAY_INTERSECT_MOLLER}) {
        CAPTURE(intersect);
        RenderInputs inputs = prepare_render(box, settings, camera, 0);
        inputs.intersect = intersect;
        const FrameResult device = render_opencl(test::opencl_test_device(), tree, box, inputs);
        const FrameResult host = render_reference(tree, box, inputs, 1);
        int differ = 0, misses = 0;
        for (std::size_t i = 0; i < host.hits.hits.size(); ++i) {
            const KdHit& a = device.hits.hits[i];
            const KdHit& b = host.hits.hits[i];
            differ += a.prim != b.prim || !(a.t == b.t || (std::isinf(a.t) && std::isinf(b.t)));
            misses += b.prim == KDRAY_NO_HIT;
            KdRay ray;
            kd_camera_ray(&inputs.view, float(i % 33) + 0.5f, float(i / 33) + 0.5f, &ray);
            CHECK(test::hits_agree(b, brute_force(box, ray, intersect)));
        }
        CHECK(differ == 0);
        if (intersect == KDRAY_INTERSECT_WATERTIGHT) CHECK(misses == 0);
    }
}
