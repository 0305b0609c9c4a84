// test_intersect.cpp — the shared ray–triangle test of core/device/kd_traverse.h (Woop, Benthin,
// Wald 2013, "Watertight Ray/Triangle Intersection", JCGT 2(1)): rays aimed exactly at the edges
// and vertices of closed meshes never slip through, degenerate triangles are never hit, and
// distances and barycentrics match closed forms on a known triangle. The hard cases (edges,
// vertices, needles) run through both arithmetics of the test's exact steps: double, and the
// float-float that devices without fp64 use (core/device/kd_float_float.h).
#include <doctest/doctest.h>

#include <algorithm>
#include <cmath>
#include <cstdint>
#include <random>
#include <string>
#include <vector>

#include "core/device/kd_traverse.h"
#include "core/geometry/math.h"
#include "core/scene/scene.h"
#include "tests/support.h"

namespace kdray {
namespace {

using test::make_ray;

KdHit no_hit(float tmax = INFINITY) {
    return KdHit{tmax, KDRAY_NO_HIT, 0.0f, 0.0f};
}

/// The arithmetics of the exact steps (kd_intersect_triangle_with's fp64): double, float-float.
constexpr int kArithmetics[] = {1, 0};

/// One triangle against one ray, with [tmin, tmax) taken from the ray as the tracer does.
KdHit intersect(const std::vector<float>& tri, const KdRay& ray, int fp64 = KDRAY_EXACT_FP64) {
    KdRayPrecomp p;
    kd_ray_precompute(&ray, &p);
    KdHit hit = no_hit(ray.tmax);
    kd_intersect_triangle_with(&p, tri.data(), 0, ray.tmin, &hit, fp64);
    return hit;
}

/// A triangle mesh as a soup plus, for each target point a test aims at, the triangles that
/// share it (the only ones a ray through it may hit first).
struct Mesh {
    std::vector<float> triangles;
    void add(Vec3 a, Vec3 b, Vec3 c) {
        for (Vec3 v : {a, b, c}) triangles.insert(triangles.end(), {v.x, v.y, v.z});
    }
    std::size_t count() const { return triangles.size() / KDRAY_FLOATS_PER_TRIANGLE; }
};

struct Target {
    Vec3 point;
    std::vector<kd_u32> sharing;  // triangles incident to the vertex or edge
};

/// Every triangle the ray hits, each tested on its own (not just the nearest).
std::vector<kd_u32> all_hits(const Mesh& mesh, const KdRay& ray, int fp64) {
    std::vector<kd_u32> ids;
    KdRayPrecomp p;
    kd_ray_precompute(&ray, &p);
    for (std::size_t i = 0; i < mesh.count(); ++i) {
        KdHit hit = no_hit(ray.tmax);
        if (kd_intersect_triangle_with(&p, &mesh.triangles[i * KDRAY_FLOATS_PER_TRIANGLE],
                                       kd_u32(i), ray.tmin, &hit, fp64))
            ids.push_back(kd_u32(i));
    }
    return ids;
}

/// An n x n grid of quads spanned by e1, e2 from `origin`, each quad cut along its diagonal into
/// two triangles. Vertices are computed once, so neighbouring triangles share bit-identical
/// corners as a loaded mesh does. Targets: every interior vertex (6 triangles) and the midpoint
/// of every interior edge (2 triangles).
void make_grid(int n, Vec3 origin, Vec3 e1, Vec3 e2, Mesh& mesh, std::vector<Target>& targets) {
    std::vector<Vec3> v((n + 1) * (n + 1));
    auto at = [&](int i, int j) -> Vec3& { return v[j * (n + 1) + i]; };
    for (int j = 0; j <= n; ++j)
        for (int i = 0; i <= n; ++i) at(i, j) = origin + e1 * float(i) + e2 * float(j);
    // Triangles of quad (i, j): 2 (j n + i) is (i,j)-(i+1,j)-(i+1,j+1), the next one
    // (i,j)-(i+1,j+1)-(i,j+1).
    for (int j = 0; j < n; ++j)
        for (int i = 0; i < n; ++i) {
            mesh.add(at(i, j), at(i + 1, j), at(i + 1, j + 1));
            mesh.add(at(i, j), at(i + 1, j + 1), at(i, j + 1));
        }
    auto lower = [&](int i, int j) { return kd_u32(2 * (j * n + i)); };
    auto upper = [&](int i, int j) { return kd_u32(2 * (j * n + i) + 1); };
    auto mid = [](Vec3 a, Vec3 b) { return (a + b) * 0.5f; };
    for (int j = 1; j < n; ++j)
        for (int i = 1; i < n; ++i)
            targets.push_back({at(i, j),
                               {lower(i - 1, j - 1), upper(i - 1, j - 1), lower(i, j), upper(i, j),
                                lower(i - 1, j), upper(i, j - 1)}});
    for (int j = 0; j < n; ++j)
        for (int i = 0; i < n; ++i) {
            // Diagonal of quad (i, j).
            targets.push_back({mid(at(i, j), at(i + 1, j + 1)), {lower(i, j), upper(i, j)}});
            // Horizontal edge above the quad, vertical edge right of it, when interior.
            if (j + 1 < n)
                targets.push_back(
                    {mid(at(i, j + 1), at(i + 1, j + 1)), {upper(i, j), lower(i, j + 1)}});
            if (i + 1 < n)
                targets.push_back(
                    {mid(at(i + 1, j), at(i + 1, j + 1)), {lower(i, j), upper(i + 1, j)}});
        }
}

/// Aims `rays_per_target` rays from random origins on both sides of the mesh at every target and
/// checks that each hits at least one triangle, that its nearest hit is one sharing the target,
/// and that it lies at the target (t = 1, since the direction is target - origin). Returns the
/// number of rays shot.
int sweep(const Mesh& mesh, const std::vector<Target>& targets, Vec3 normal, float distance,
          int rays_per_target, std::uint32_t seed, int fp64) {
    std::mt19937 rng(seed);
    std::uniform_real_distribution<float> side(-1.0f, 1.0f);
    int shot = 0, reported = 0;
    for (const Target& target : targets)
        for (int k = 0; k < rays_per_target; ++k) {
            // Origins above and below, every fifth one grazing (height 0.05 of the distance).
            Vec3 offset{side(rng), side(rng), side(rng)};
            offset = offset - normal * dot(offset, normal);
            const float height = (k % 5 == 0 ? 0.05f : 0.3f + 0.7f * std::fabs(side(rng)));
            offset = offset + normal * (k % 2 ? height : -height);
            const Vec3 org = target.point + offset * distance;
            const KdRay ray = make_ray(org, target.point - org);
            ++shot;
            const std::vector<kd_u32> hits = all_hits(mesh, ray, fp64);
            KdRayPrecomp p;
            kd_ray_precompute(&ray, &p);
            KdHit best = no_hit();
            for (std::size_t i = 0; i < mesh.count(); ++i)
                kd_intersect_triangle_with(&p, &mesh.triangles[i * KDRAY_FLOATS_PER_TRIANGLE],
                                           kd_u32(i), 0.0f, &best, fp64);
            bool shared = false;
            for (kd_u32 id : target.sharing) shared = shared || id == best.prim;
            const bool ok = !hits.empty() && shared && std::fabs(best.t - 1.0f) < 1e-2f;
            if (!ok && reported++ < 5) {
                INFO("target (", target.point.x, ", ", target.point.y, ", ", target.point.z,
                     ") from (", org.x, ", ", org.y, ", ", org.z, "): ", hits.size(),
                     " triangles hit, nearest ", best.prim, " at t = ", best.t);
                CHECK(ok);
            }
        }
    CHECK(reported == 0);
    return shot;
}

}  // namespace

TEST_CASE("rays through shared edges and vertices of a grid never slip through") {
    struct Case {
        std::string name;
        Vec3 origin, e1, e2;
        float distance;
    };
    // Axis-aligned unit grid; a rotated, non-uniform one whose vertices are inexact in float; and
    // both far from the origin (1e5), where a float's spacing is 1/128 and the translation to the
    // ray origin is where precision is lost.
    const Vec3 r1 = normalize(Vec3{0.8f, 0.3f, -0.52f}), r2 = normalize(cross(r1, {0.1f, 1, 0.2f}));
    const std::vector<Case> cases = {
        {"axis-aligned", {0, 0, 0}, {1, 0, 0}, {0, 1, 0}, 3.0f},
        {"rotated", {0.3f, -0.7f, 0.1f}, r1 * 0.37f, r2 * 0.61f, 2.0f},
        {"sheared", {-1, 2, 0.5f}, Vec3{0.9f, 0.1f, 0.33f}, Vec3{-0.2f, 0.7f, 0.45f}, 2.0f},
        {"axis-aligned at 1e5", {1e5f, 1e5f, 1e5f}, {1, 0, 0}, {0, 1, 0}, 5.0f},
        {"rotated at 1e5", {1e5f, -1e5f, 1e5f}, r1 * 3.0f, r2 * 2.0f, 20.0f},
    };
    for (const int fp64 : kArithmetics) {
        CAPTURE(fp64);
        int total = 0;
        for (const Case& c : cases) {
            CAPTURE(c.name);
            Mesh mesh;
            std::vector<Target> targets;
            make_grid(8, c.origin, c.e1, c.e2, mesh, targets);
            total += sweep(mesh, targets, normalize(cross(c.e1, c.e2)), c.distance, 40, 7, fp64);
        }
        CHECK(total > 10000);
    }
}

TEST_CASE("rays straight down onto exact grid vertices and edges hit") {
    // Axis-aligned rays through exactly representable vertices and edge points: the sheared edge
    // functions are exactly zero, the case the double-precision fallback exists for.
    Mesh mesh;
    std::vector<Target> targets;
    make_grid(6, {0, 0, 0}, {1, 0, 0}, {0, 1, 0}, mesh, targets);
    for (const int fp64 : kArithmetics) {
        CAPTURE(fp64);
        int misses = 0;
        for (const Target& target : targets)
            for (float dz : {-1.0f, 1.0f}) {
                const KdRay ray = make_ray(target.point - Vec3{0, 0, dz * 2.0f}, {0, 0, dz});
                const std::vector<kd_u32> hits = all_hits(mesh, ray, fp64);
                if (hits.empty()) ++misses;
                for (kd_u32 id : hits) {
                    bool shared = false;
                    for (kd_u32 s : target.sharing) shared = shared || s == id;
                    CHECK(shared);
                }
            }
        CHECK(misses == 0);
    }
}

TEST_CASE("rays through the centre of an irregular fan hit one of its triangles") {
    // A fan of 13 triangles around a centre vertex, rim at random heights: every ray through the
    // centre crosses a vertex shared by all of them.
    std::mt19937 rng(11);
    std::uniform_real_distribution<float> unit(-1.0f, 1.0f);
    const Vec3 centre{0.123f, -0.456f, 0.789f};
    const int n = 13;
    std::vector<Vec3> rim;
    for (int i = 0; i < n; ++i) {
        const float a = 2.0f * 3.14159265f * (float(i) + 0.3f * unit(rng)) / float(n);
        rim.push_back(centre + Vec3{std::cos(a), std::sin(a), 0.3f * unit(rng)});
    }
    Mesh mesh;
    for (int i = 0; i < n; ++i) mesh.add(centre, rim[i], rim[(i + 1) % n]);
    int misses[2] = {0, 0};
    for (int k = 0; k < 5000; ++k) {
        Vec3 org = centre + Vec3{unit(rng), unit(rng), unit(rng)} * 3.0f;
        if (std::fabs(org.z - centre.z) < 0.5f) org.z += 1.0f;
        const KdRay ray = make_ray(org, centre - org);
        for (const int fp64 : kArithmetics) misses[fp64] += all_hits(mesh, ray, fp64).empty();
    }
    CHECK(misses[1] == 0);
    CHECK(misses[0] == 0);
}

namespace {

/// Rays from random origins at points of the degenerate triangle `tri` (its first corner, the
/// middle and random points between its first and last corners); returns how many hit it.
int hits_on_degenerate(const std::vector<float>& tri, std::uint32_t seed, int fp64) {
    std::mt19937 rng(seed);
    std::uniform_real_distribution<float> unit(-1.0f, 1.0f);
    const Vec3 a{tri[0], tri[1], tri[2]}, c{tri[6], tri[7], tri[8]};
    int hits = 0;
    for (int k = 0; k < 2000; ++k) {
        const float s = k % 3 == 0 ? 0.0f : k % 3 == 1 ? 0.5f : 0.5f + 0.5f * unit(rng);
        const Vec3 target = a + (c - a) * s;
        const Vec3 org = target + Vec3{unit(rng), unit(rng), unit(rng)} * 4.0f;
        if (intersect(tri, make_ray(org, target - org), fp64).prim != KDRAY_NO_HIT) ++hits;
    }
    return hits;
}

}  // namespace

TEST_CASE("triangles with coincident corners are never hit") {
    // Two equal corners make one edge function exactly zero and the other two exact negatives
    // of each other, so the sign test or det == 0 rejects every ray.
    const Vec3 p{0.25f, 0.5f, 0.0f}, q{1.0f, 2.0f, 3.0f};
    for (const int fp64 : kArithmetics) {
        CAPTURE(fp64);
        CHECK(hits_on_degenerate({p.x, p.y, p.z, p.x, p.y, p.z, p.x, p.y, p.z}, 5, fp64) == 0);
        CHECK(hits_on_degenerate({p.x, p.y, p.z, p.x, p.y, p.z, q.x, q.y, q.z}, 6, fp64) == 0);
        CHECK(hits_on_degenerate({q.x, q.y, q.z, p.x, p.y, p.z, p.x, p.y, p.z}, 7, fp64) == 0);
    }
}

// Three distinct collinear corners stop being collinear once rounded into ray space, so the
// watertight test alone would hit them with meaningless barycentrics (e.g. (0,0,0) (1,0,0)
// (2,0,0), ray from (0.3, 0.82, 1.14) along (1.4, -0.82, -1.14)). Scenes therefore collapse
// zero-area triangles to a point when made or loaded; after that no ray hits them.
TEST_CASE("collinear zero-area triangles are collapsed and never hit") {
    for (std::vector<float> tri : {std::vector<float>{0, 0, 0, 1, 0, 0, 2, 0, 0},
                                   std::vector<float>{0, 0, 0, 1, 1, 1, 2, 2, 2},
                                   std::vector<float>{0, 0, 0, 2, 2, 2, 1, 1, 1}}) {
        kdray::Scene scene = kdray::make_scene(tri);
        CHECK(scene.zero_area_triangles == 1);
        for (const int fp64 : kArithmetics)
            CHECK(hits_on_degenerate(scene.triangles, 8, fp64) == 0);
    }
}

TEST_CASE("closed-form distance and barycentrics on a known triangle") {
    const std::vector<float> tri = {0, 0, 0, 1, 0, 0, 0, 1, 0};
    SUBCASE("straight down") {
        KdHit h = intersect(tri, make_ray({0.25f, 0.5f, 2.0f}, {0, 0, -1}));
        CHECK(h.prim == 0);
        CHECK(h.t == doctest::Approx(2.0f).epsilon(1e-6));
        CHECK(h.u == doctest::Approx(0.25f).epsilon(1e-6));  // weight of vertex 1
        CHECK(h.v == doctest::Approx(0.5f).epsilon(1e-6));   // weight of vertex 2
    }
    SUBCASE("a direction that is not unit length scales t") {
        KdHit h = intersect(tri, make_ray({0.25f, 0.5f, 2.0f}, {0, 0, -4}));
        CHECK(h.t == doctest::Approx(0.5f).epsilon(1e-6));
    }
    SUBCASE("oblique, dominant axis x") {
        // Hit point (0.1, 0.2, 0); origin = hit + 2 * (3, 0.5, 0.25), direction the reverse.
        const Vec3 hit{0.1f, 0.2f, 0.0f}, back{3.0f, 0.5f, 0.25f};
        KdHit h = intersect(tri, make_ray(hit + back * 2.0f, -back));
        CHECK(h.prim == 0);
        CHECK(h.t == doctest::Approx(2.0f).epsilon(1e-5));
        CHECK(h.u == doctest::Approx(0.1f).epsilon(1e-5));
        CHECK(h.v == doctest::Approx(0.2f).epsilon(1e-5));
    }
    SUBCASE("back faces are hit: no culling") {
        KdHit h = intersect(tri, make_ray({0.25f, 0.5f, -2.0f}, {0, 0, 1}));
        CHECK(h.prim == 0);
        CHECK(h.t == doctest::Approx(2.0f).epsilon(1e-6));
        CHECK(h.u == doctest::Approx(0.25f).epsilon(1e-6));
        CHECK(h.v == doctest::Approx(0.5f).epsilon(1e-6));
    }
    SUBCASE("outside the triangle misses") {
        CHECK(intersect(tri, make_ray({0.6f, 0.6f, 2.0f}, {0, 0, -1})).prim == KDRAY_NO_HIT);
        CHECK(intersect(tri, make_ray({-0.01f, 0.5f, 2.0f}, {0, 0, -1})).prim == KDRAY_NO_HIT);
    }
}

TEST_CASE("distances on long thin triangles are exact to a few float ulps") {
    // Needles 1e4 long and 1e-3 wide, hit near their middle by rays from about 1.6 away: the
    // watertight test's own t was off by up to 1.5e-4 relative there (a far corner swamps the
    // sum). The exact distance, in long double from the same float corners and ray, is
    // n.(p0 - o) / n.d with n from the edges.
    std::mt19937 rng(7);
    std::uniform_real_distribution<float> unit(0.0f, 1.0f);
    int tested = 0, worst_ulps[2] = {0, 0}, paths_differ = 0;
    for (int i = 0; i < 2000; ++i) {
        const float y = unit(rng), z = 1e-3f * unit(rng);
        const Vec3 p0{-5000.0f + unit(rng), y, z}, p1{5000.0f + unit(rng), y + 1e-3f, z},
            p2{5000.0f + unit(rng), y, z + 1e-3f * (0.5f + unit(rng))};
        const std::vector<float> tri = {p0.x, p0.y, p0.z, p1.x, p1.y, p1.z, p2.x, p2.y, p2.z};
        // Aim at a point inside: barycentrics (a, b) of p1 and p2.
        const float a = 0.3f + 0.2f * unit(rng), b = 0.2f * unit(rng);
        const Vec3 target = p0 + (p1 - p0) * a + (p2 - p0) * b;
        // Mostly along the needle: its far corners are then far along the ray's own axis, where
        // the watertight test's t sums them.
        const float along = unit(rng) < 0.5f ? -1.0f : 1.0f;
        const Vec3 dir = normalize(Vec3{along, -0.5f + 0.2f * (unit(rng) - 0.5f),
                                        0.5f + 0.2f * (unit(rng) - 0.5f)});
        const Vec3 org = target - dir * 1.632f;
        const KdHit h = intersect(tri, make_ray(org, dir), 1);
        const KdHit h_ff = intersect(tri, make_ray(org, dir), 0);
        // The inside test is float in both; only the distance's arithmetic differs.
        REQUIRE(h_ff.prim == h.prim);
        paths_differ += h_ff.t != h.t;
        // About half of these rays miss: seen along its length a needle 1e-3 wide is a few
        // float spacings of its 5000-away corners wide in ray space, and the inside test is the
        // float one (watertight). The distances of the hits are what this test is about.
        if (h.prim != 0) continue;
        ++tested;
        using L = long double;
        const L e1[3] = {L(p1.x) - p0.x, L(p1.y) - p0.y, L(p1.z) - p0.z};
        const L e2[3] = {L(p2.x) - p0.x, L(p2.y) - p0.y, L(p2.z) - p0.z};
        const L n[3] = {e1[1] * e2[2] - e1[2] * e2[1], e1[2] * e2[0] - e1[0] * e2[2],
                        e1[0] * e2[1] - e1[1] * e2[0]};
        const L exact =
            (n[0] * (L(p0.x) - org.x) + n[1] * (L(p0.y) - org.y) + n[2] * (L(p0.z) - org.z)) /
            (n[0] * dir.x + n[1] * dir.y + n[2] * dir.z);
        const float ulp = std::nextafter(float(exact), INFINITY) - float(exact);
        worst_ulps[1] = std::max(worst_ulps[1], int(std::fabs(L(h.t) - exact) / ulp + 0.5L));
        worst_ulps[0] = std::max(worst_ulps[0], int(std::fabs(L(h_ff.t) - exact) / ulp + 0.5L));
    }
    CAPTURE(tested);
    CHECK(tested > 500);
    CAPTURE(worst_ulps[1]);
    CAPTURE(worst_ulps[0]);
    CHECK(worst_ulps[1] <= 2);
    CHECK(worst_ulps[0] <= 2);
    // Both round a value exact to far more than a float: they differ only at near-ties.
    CAPTURE(paths_differ);
    CHECK(paths_differ <= tested / 100);
}

TEST_CASE("the hit must lie in [tmin, best)") {
    const std::vector<float> tri = {0, 0, 0, 1, 0, 0, 0, 1, 0};
    const Vec3 org{0.25f, 0.25f, 2.0f}, dir{0, 0, -1};  // hits at exactly t = 2
    CHECK(intersect(tri, make_ray(org, dir, 0.0f, INFINITY)).prim == 0);
    CHECK(intersect(tri, make_ray(org, dir, 2.0f, INFINITY)).prim == 0);  // tmin is inclusive
    CHECK(intersect(tri, make_ray(org, dir, std::nextafter(2.0f, 3.0f), INFINITY)).prim ==
          KDRAY_NO_HIT);
    CHECK(intersect(tri, make_ray(org, dir, 0.0f, 2.0f)).prim == KDRAY_NO_HIT);  // best exclusive
    CHECK(intersect(tri, make_ray(org, dir, 0.0f, std::nextafter(2.0f, 3.0f))).prim == 0);
    // Behind the origin.
    CHECK(intersect(tri, make_ray(org, -dir)).prim == KDRAY_NO_HIT);

    // A nearer hit already found is kept.
    const KdRay p_ray = make_ray(org, dir);
    KdRayPrecomp p;
    kd_ray_precompute(&p_ray, &p);
    KdHit best{1.5f, 42, 0.0f, 0.0f};
    CHECK(kd_intersect_triangle(&p, tri.data(), 0, 0.0f, &best) == 0);
    CHECK(best.prim == 42);
    CHECK(best.t == 1.5f);
}

TEST_CASE("rays parallel to the triangle's plane miss") {
    const std::vector<float> tri = {0, 0, 0, 1, 0, 0, 0, 1, 0};
    // In the plane, crossing the triangle's interior and running along its edges.
    CHECK(intersect(tri, make_ray({-1, 0.25f, 0}, {1, 0, 0})).prim == KDRAY_NO_HIT);
    CHECK(intersect(tri, make_ray({0.2f, -1, 0}, {0, 1, 0})).prim == KDRAY_NO_HIT);
    CHECK(intersect(tri, make_ray({-1, 0, 0}, {1, 0, 0})).prim == KDRAY_NO_HIT);
    CHECK(intersect(tri, make_ray({-1, 2, 0}, {1, -1, 0})).prim == KDRAY_NO_HIT);
    // Above the plane.
    CHECK(intersect(tri, make_ray({-1, 0.25f, 1}, {1, 0, 0})).prim == KDRAY_NO_HIT);
    CHECK(intersect(tri, make_ray({-1, -1, 0.5f}, {1, 1, 0})).prim == KDRAY_NO_HIT);
}

}  // namespace kdray
