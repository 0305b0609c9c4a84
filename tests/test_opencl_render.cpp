// test_opencl_render.cpp — the OpenCL render kernel against the reference renderer (the same
// shading code run on the host) and brute force: hits ray by ray on the hard scenes, images and
// ray counts on the bundled glass room, and the effects a scene calls for — and only those.
#include <doctest/doctest.h>

#include <algorithm>
#include <cmath>
#include <cstring>
#include <string>
#include <vector>

#include "cl/renderer/opencl_renderer.h"
#include "cl/renderer/opencl_tracer.h"
#include "cl/renderer/scene_arrays.h"
#include "cl/runtime/program_cache.h"
#include "core/device/kd_render.h"
#include "core/error.h"
#include "core/render/camera.h"
#include "core/render/reference_tracer.h"
#include "core/render/render_file.h"
#include "core/render/render_setup.h"
#include "core/tree/reference_builder.h"
#include "tests/support.h"
#include "tests/needle_distances.h"
#include "tests/test_opencl_fixture.h"

using namespace kdray;

namespace {

RenderSettings small_settings(int width, int height) {
    RenderSettings s;
    s.width = width;
    s.height = height;
    return s;
}

Light point_light(Vec3 position, Vec3 power) {
    return Light{Light::Type::point, position, {}, power};
}

/// A camera outside the scene's box looking at its centre along a skew direction, so that rays
/// cross split planes of every axis.
Camera skew_camera(const Scene& scene) {
    Aabb b = scene.bounds();
    Vec3 centre = (b.lo + b.hi) * 0.5f, e = b.extent();
    float r = std::max({e.x, e.y, e.z, 1e-30f});
    Camera c;
    c.look_at = centre;
    c.position = centre + Vec3{0.9f * r, 0.7f * r, 1.6f * r};
    c.fov_y = 50.0f;
    return c;
}

/// The hard scene's own camera where it has one, else skew_camera.
Camera camera_of(const test::NamedScene& s) {
    return s.camera ? *s.camera : skew_camera(s.scene);
}

double rgb_rmse(const Image& a, const Image& b) {
    double sum = 0;
    for (std::size_t i = 0; i < a.rgb.size(); ++i)
        sum += double(a.rgb[i] - b.rgb[i]) * (a.rgb[i] - b.rgb[i]);
    return std::sqrt(sum / double(a.rgb.size()));
}

/// The largest difference of one channel of one pixel: a shadow ray answered wrongly changes a
/// pixel by its light's whole share, which an image-wide RMSE can average away.
double rgb_max_difference(const Image& a, const Image& b) {
    double worst = 0;
    for (std::size_t i = 0; i < a.rgb.size(); ++i)
        worst = std::max(worst, double(std::fabs(a.rgb[i] - b.rgb[i])));
    return worst;
}

}  // namespace

TEST_CASE("opencl render: centre hits equal brute force and the reference on the hard scenes") {
    for (const test::NamedScene& s : test::hard_scenes()) {
        CAPTURE(s.name);
        const KdTree tree = build_reference(s.scene);
        RenderSettings settings = small_settings(40, 30);
        const RenderInputs inputs = prepare_render(s.scene, settings, camera_of(s), 0);
        const FrameResult device = render_opencl(test::opencl_test_device(), tree, s.scene, inputs);
        const FrameResult host = render_reference(tree, s.scene, inputs, 1);
        int against_brute = 0, against_reference = 0, hits = 0;
        for (int y = 0; y < settings.height; ++y)
            for (int x = 0; x < settings.width; ++x) {
                const std::size_t i = std::size_t(y) * settings.width + x;
                KdRay ray;
                kd_camera_ray(&inputs.view, float(x) + 0.5f, float(y) + 0.5f, &ray);
                const KdHit want = test::brute_force_closest(s.scene, ray);
                hits += want.prim != KDRAY_NO_HIT;
                against_brute += !test::hits_agree(device.hits.hits[i], want);
                against_reference += !test::hits_agree(device.hits.hits[i], host.hits.hits[i]);
            }
        CHECK(hits > 0);
        CHECK(against_brute == 0);
        CHECK(against_reference == 0);
        CHECK(rgb_rmse(device.image, host.image) < 1e-4);
    }
}

TEST_CASE("opencl render: the glass room matches the reference image and its ray counts") {
    const Scene scene = load_obj(test::source_dir() / "testdata/cornell/room.obj");
    RenderSettings settings = load_render_file(test::source_dir() / "testdata/cornell/render.json");
    settings.width = 160;
    settings.height = 120;
    const KdTree tree = build_reference(scene);
    const RenderInputs inputs =
        prepare_render(scene, settings, settings.camera_at(0, scene.frame), 0);
    REQUIRE(inputs.effects.shadows);
    REQUIRE(inputs.effects.reflection);
    REQUIRE(inputs.effects.refraction);
    const FrameResult device = render_opencl(test::opencl_test_device(), tree, scene, inputs);
    const FrameResult host = render_reference(tree, scene, inputs, 2);
    CHECK(device.rays.primary == 160u * 120u);
    CHECK(device.rays.shadow > 0);
    CHECK(device.rays.reflection > 0);
    CHECK(device.rays.refraction > 0);
    // Secondary rays follow the hits; a hit that differs in its last ulp may branch differently
    // on a GPU, so the counts may differ by a hair there, and are equal on a CPU device: there
    // every kind is compared exactly.
    if (test::opencl_test_device().is_cpu()) {
        CHECK(device.rays.primary == host.rays.primary);
        CHECK(device.rays.shadow == host.rays.shadow);
        CHECK(device.rays.reflection == host.rays.reflection);
        CHECK(device.rays.refraction == host.rays.refraction);
        CHECK(device.rays.area_shadow == host.rays.area_shadow);
        CHECK(device.rays.total() == host.rays.total());
    } else {
        CHECK(double(device.rays.total()) ==
              doctest::Approx(double(host.rays.total())).epsilon(1e-3));
    }
    CHECK(rgb_rmse(device.image, host.image) < 1e-3);
}

TEST_CASE("opencl render: only the effects a scene calls for") {
    const Scene matte = test::random_triangles(500, 21);
    const KdTree tree = build_reference(matte);
    RenderSettings settings = small_settings(32, 24);

    SUBCASE("a matte scene under a light: shadow rays, no secondary rays") {
        settings.lights.push_back(point_light({0.5f, 3.0f, 0.5f}, {5, 5, 5}));
        const RenderInputs inputs = prepare_render(matte, settings, skew_camera(matte), 0);
        CHECK(inputs.effects.shadows);
        CHECK_FALSE(inputs.effects.reflection);
        CHECK_FALSE(inputs.effects.refraction);
        const FrameResult f = render_opencl(test::opencl_test_device(), tree, matte, inputs);
        CHECK(f.rays.shadow > 0);
        CHECK(f.rays.reflection == 0);
        CHECK(f.rays.refraction == 0);
    }
    SUBCASE("no lights: a headlight and no shadow rays") {
        const RenderInputs inputs = prepare_render(matte, settings, skew_camera(matte), 0);
        CHECK_FALSE(inputs.effects.shadows);
        const FrameResult f = render_opencl(test::opencl_test_device(), tree, matte, inputs);
        CHECK(f.rays.shadow == 0);
        CHECK(f.rays.primary == 32u * 24u);
    }
    SUBCASE("a mirror without glass: reflection rays, no refraction") {
        Scene mirror = matte;
        Material m;
        m.name = "mirror";
        m.illum = 3;
        m.specular = {0.9f, 0.9f, 0.9f};
        mirror.materials.push_back(m);
        for (std::size_t t = 0; t < mirror.triangle_count(); t += 2) mirror.material_ids[t] = 1;
        const RenderInputs inputs = prepare_render(mirror, settings, skew_camera(mirror), 0);
        CHECK(inputs.effects.reflection);
        CHECK_FALSE(inputs.effects.refraction);
        const FrameResult f = render_opencl(test::opencl_test_device(), tree, mirror, inputs);
        CHECK(f.rays.reflection > 0);
        CHECK(f.rays.refraction == 0);
    }
}

TEST_CASE("opencl render: a program is built once per effects combination") {
    const Scene scene = test::random_triangles(50, 22);
    const KdTree tree = build_reference(scene);
    const RenderInputs inputs = prepare_render(scene, small_settings(8, 8), skew_camera(scene), 0);
    render_opencl(test::opencl_test_device(), tree, scene, inputs);
    const int builds = program_build_count();
    render_opencl(test::opencl_test_device(), tree, scene, inputs);
    CHECK(program_build_count() == builds);
}

TEST_CASE("opencl render: the tracer's prepare builds the program that frames then reuse") {
    // Effects 3 (shadows and reflection) is a combination no other test renders, so the first
    // prepare must build it; the second prepare and the frame must not build again.
    Scene scene = test::random_triangles(50, 23);
    Material mirror;
    mirror.name = "mirror";
    mirror.illum = 3;
    mirror.specular = {0.9f, 0.9f, 0.9f};
    scene.materials.push_back(mirror);
    scene.material_ids[0] = 1;
    RenderSettings settings = small_settings(8, 8);
    settings.max_depth = 2;
    settings.lights.push_back(point_light({0.5f, 3.0f, 0.5f}, {5, 5, 5}));
    const RenderInputs inputs = prepare_render(scene, settings, skew_camera(scene), 0);
    REQUIRE(inputs.effects.bits() == (KDRAY_EFFECT_SHADOWS | KDRAY_EFFECT_REFLECTION));

    OpenClTracer tracer(test::opencl_test_device());
    const int before = program_build_count();
    tracer.prepare(inputs);
    CHECK(program_build_count() == before + 1);
    tracer.prepare(inputs);
    BuiltTree built;
    built.tree = build_reference(scene);
    const KdTree& tree = built.tree;
    const FrameResult f = tracer.trace(built, scene, inputs);
    CHECK(program_build_count() == before + 1);
    CHECK(f.rays.primary == 64u);
    // The prepared program renders what the reference renders.
    const FrameResult host = render_reference(tree, scene, inputs, 1);
    for (std::size_t i = 0; i < host.hits.hits.size(); ++i)
        CHECK(test::hits_agree(f.hits.hits[i], host.hits.hits[i]));
}

namespace {

/// Whether two hits are the same bit for bit: the packet walk must be the scalar walk exactly.
bool same_bits(const KdHit& a, const KdHit& b) {
    return std::memcmp(&a, &b, sizeof(KdHit)) == 0;
}

/// The device's centre hits with packets on, at 8 and 16 lanes (KDRAY_PACKET_LANES: 4x2 and 4x4
/// tiles, whichever the device would choose), and off, against the reference tracer's, bit for
/// bit, and its image against the reference's.
void check_packets(const Scene& scene, const KdTree& tree, const RenderInputs& base) {
    const FrameResult host = render_reference(tree, scene, base, 1);
    std::vector<Image> images;
    for (unsigned lanes : {8u, 16u, 0u}) {
        CAPTURE(lanes);
        const test::ScopedEnv width("KDRAY_PACKET_LANES", lanes ? std::to_string(lanes) : "");
        RenderInputs inputs = base;
        inputs.packets = lanes ? RenderInputs::Packets::On : RenderInputs::Packets::Off;
        const FrameResult device = render_opencl(test::opencl_test_device(), tree, scene, inputs);
        // The width asked for is the one that ran (the override is not silently ignored).
        CHECK(device.primary_packets == (lanes != 0u));
        CHECK(device.packet_lanes == lanes);
        REQUIRE(device.hits.hits.size() == host.hits.hits.size());
        int differ = 0;
        for (std::size_t i = 0; i < host.hits.hits.size(); ++i)
            differ += !same_bits(device.hits.hits[i], host.hits.hits[i]);
        CHECK(differ == 0);
        CHECK(device.rays.primary == host.rays.primary);
        CHECK(device.rays.shadow == host.rays.shadow);
        CHECK(rgb_rmse(device.image, host.image) < 1e-4);
        CHECK(rgb_max_difference(device.image, host.image) < 1e-3);
        images.push_back(device.image);
    }
    // On the device the paths run the same shading on the same hits and shadow answers: the
    // images are the same bit for bit.
    for (std::size_t k = 0; k + 1 < images.size(); ++k) {
        CAPTURE(k);
        REQUIRE(images[k].rgb.size() == images.back().rgb.size());
        CHECK(std::memcmp(images[k].rgb.data(), images.back().rgb.data(),
                          images[k].rgb.size() * sizeof(float)) == 0);
    }
}

/// A unit normal of random direction at every corner of the scene's triangles.
void add_random_vertex_normals(Scene& scene) {
    std::uint32_t state = 12345;
    auto next = [&] {
        state = state * 1664525u + 1013904223u;
        return float(state >> 8) / float(1u << 24) * 2.0f - 1.0f;
    };
    scene.vertex_normals.clear();
    for (std::size_t c = 0; c < 3 * scene.triangle_count(); ++c) {
        const Vec3 n = normalize(Vec3{next(), next(), next()} + Vec3{0, 0, 0.01f});
        scene.vertex_normals.insert(scene.vertex_normals.end(), {n.x, n.y, n.z});
    }
}

}  // namespace

TEST_CASE("opencl render: packets of primary rays give the reference's hits bit for bit") {
    // 37 x 29 pixels: tiles of 4 x 4 and 4 x 2 that the image's right and bottom edges cut, whose
    // lanes outside the image must neither be traced nor written.
    for (const test::NamedScene& s : test::hard_scenes()) {
        CAPTURE(s.name);
        const KdTree tree = build_reference(s.scene);
        const RenderInputs inputs =
            prepare_render(s.scene, small_settings(37, 29), camera_of(s), 0);
        check_packets(s.scene, tree, inputs);
    }
    SUBCASE("spp 3: three jittered samples and the centre ray per pixel, one packet each") {
        const Scene scene = test::random_triangles(2000, 41);
        const KdTree tree = build_reference(scene);
        RenderSettings settings = small_settings(21, 14);
        settings.spp = 3;
        check_packets(scene, tree, prepare_render(scene, settings, skew_camera(scene), 7));
    }
    SUBCASE("a point light: shadow rays from the packets' hits, flat and smooth") {
        Scene scene = test::random_triangles(2000, 43);
        for (bool smooth : {false, true}) {
            CAPTURE(smooth);
            // Random corner normals: lights in front of the interpolated normal but behind the
            // triangle, and the reverse; the packets must cast the shadow rays the shading reads.
            if (smooth) add_random_vertex_normals(scene);
            const KdTree tree = build_reference(scene);
            RenderSettings settings = small_settings(23, 19);
            const Aabb b = scene.bounds();
            settings.lights.push_back(point_light(b.hi + (b.hi - b.lo) * 0.25f, {40, 40, 40}));
            const RenderInputs inputs = prepare_render(scene, settings, skew_camera(scene), 0);
            REQUIRE(inputs.effects.bits() == KDRAY_EFFECT_SHADOWS);
            check_packets(scene, tree, inputs);
        }
    }
    SUBCASE("lights among the cubes: most shadow rays blocked, as packets of shadow rays") {
        // Point lights inside a lattice of cubes and a directional light from outside: the cubes
        // block most shadow rays, and a wrong answer shows as a pixel off by a light's share.
        const Scene scene = test::cube_lattice(4);
        const KdTree tree = build_reference(scene);
        const Aabb b = scene.bounds();
        const Vec3 size = b.hi - b.lo;
        for (int spp : {1, 3}) {
            CAPTURE(spp);
            RenderSettings settings = small_settings(29, 21);
            settings.spp = spp;
            settings.lights.push_back(point_light(b.lo + size * 0.51f, {2, 2, 2}));
            settings.lights.push_back(
                point_light(b.lo + size * Vec3{0.2f, 0.8f, 0.37f}, {1, 2, 1}));
            settings.lights.push_back(
                Light{Light::Type::directional, {}, Vec3{-0.3f, -1.0f, -0.2f}, {0.5f, 0.5f, 0.5f}});
            check_packets(scene, tree, prepare_render(scene, settings, skew_camera(scene), 5));
        }
    }
    SUBCASE("several launches: rows past the first launch, at spp 3 under lights") {
        // A launch holds 2^18 primary rays' hits: at 2048 pixels a row and 4 rays a pixel, 32
        // rows, so 40 rows take two launches, and the second's first_row offsets every buffer.
        const Scene scene = test::cube_lattice(3);
        const KdTree tree = build_reference(scene);
        const Aabb b = scene.bounds();
        RenderSettings settings = small_settings(2048, 40);
        settings.spp = 3;
        settings.lights.push_back(point_light(b.lo + (b.hi - b.lo) * 0.49f, {2, 2, 2}));
        check_packets(scene, tree, prepare_render(scene, settings, skew_camera(scene), 9));
    }
    SUBCASE("more lights than a mask holds: shadow rays one at a time, the same image") {
        const Scene scene = test::random_triangles(500, 47);
        const KdTree tree = build_reference(scene);
        RenderSettings settings = small_settings(17, 13);
        const Aabb b = scene.bounds();
        for (kd_u32 i = 0; i <= KDRAY_PACKET_SHADOW_LIGHTS; ++i) {
            const float f = float(i) / float(KDRAY_PACKET_SHADOW_LIGHTS);
            settings.lights.push_back(
                point_light(b.lo + (b.hi - b.lo) * Vec3{f, 1.3f, 1.0f - f}, {1, 1, 1}));
        }
        check_packets(scene, tree, prepare_render(scene, settings, skew_camera(scene), 0));
    }
}

TEST_CASE("opencl render: distances on needles within 4 ulps, one ray at a time and in packets") {
    // Needles 1e4 long and 1e-3 wide seen along their length from 1.6 away
    // (test::needle_bundle_camera): there the watertight test's float t is off by up to 1.5e-4
    // relative, and the tracer must refine it against the triangle's plane. render.cl's
    // one-ray walk and packet_traverse.cl's lanes (which refine lane by lane) must each give
    // brute force's triangle, and a distance within 4 ulps of the exact one in long double: the
    // refined t is within one, and a float t kept unrefined (its condition at most 4 |t|,
    // kd_intersect_triangle) within a few (3 on one pixel here, on the host as on the device).
    // With the refinement off on the device (KDRAY_T_REFINE_CONDITION 1e30 in OpenCL C), 18 of
    // these pixels hit another triangle than brute force and distances were off by thousands of
    // units, on both paths; off in packet_traverse.cl alone, in packets only.
    test::check_needle_distances();
}

TEST_CASE("opencl render: packets whose lanes walk a node's children in opposite orders") {
    // The camera sits inside the scene, exactly on the root's split plane, and looks along it:
    // the image's left half leaves the plane below, its right half above, and the centre column
    // (odd width, direction exactly 0 on the axis) lies in it. Every ray crosses the plane at
    // t = 0, so each visits both children, in its own order, and tiles across the middle hold
    // all three kinds: the packet must visit below, above and below again for them. The order
    // shows in the hits only where triangles tie, so the scene is a lattice of cubes whose faces
    // and edges are shared and lie on split planes.
    const Scene scene = test::cube_lattice(4);
    const KdTree tree = build_reference(scene);
    REQUIRE(!kd_node_is_leaf(tree.nodes[0]));
    const int axis = int(kd_node_axis(tree.nodes[0]));
    const float split = kd_node_split(tree.nodes[0]);
    const int ahead = (axis + 1) % 3, up = (axis + 2) % 3;
    const Aabb b = scene.bounds();
    Camera camera;
    camera.position = (b.lo + b.hi) * 0.5f;
    camera.position[axis] = split;
    camera.position[ahead] = b.lo[ahead] + 0.3f * (b.hi[ahead] - b.lo[ahead]);
    camera.look_at = camera.position;
    camera.look_at[ahead] += 1.0f;
    camera.up = Vec3{0, 0, 0};
    camera.up[up] = 1.0f;
    camera.fov_y = 70.0f;
    const RenderInputs inputs = prepare_render(scene, small_settings(33, 20), camera, 0);
    REQUIRE(inputs.view.right[axis] != 0.0f);
    REQUIRE(inputs.view.forward[axis] == 0.0f);
    REQUIRE(inputs.view.up[axis] == 0.0f);
    check_packets(scene, tree, inputs);
}

TEST_CASE(
    "opencl render: the scene arrays' layout is aligned, in order, and refuses 32-bit overflow") {
    // Sizes that are no multiple of the alignment, an empty array in the middle (no lights) and
    // an empty vertex-normal array (flat shading): each array starts at the first aligned byte
    // after the one before, and an empty one takes no room.
    SceneArrays a;
    a.materials.bytes = 3 * sizeof(KdMaterial);
    a.emitters.bytes = sizeof(KdEmitter);
    a.textures.bytes = 2 * sizeof(KdTexture);
    a.material_ids.bytes = 1001 * sizeof(kd_u32);
    a.texcoords.bytes = 1001 * 6 * sizeof(float);
    a.texels.bytes = 5 * 4 * sizeof(float);
    std::size_t total = 0;
    const KdSceneLayout l = layout_scene_arrays(a, &total);
    const kd_u32 offsets[] = {l.materials,    l.lights,         l.emitters,  l.textures,
                              l.material_ids, l.vertex_normals, l.texcoords, l.texels};
    for (kd_u32 offset : offsets) CHECK(offset % KDRAY_SCENE_ALIGN == 0u);
    CHECK(l.materials == 0u);
    CHECK(l.lights == 384u);  // 288 bytes of materials, rounded up to 128
    CHECK(l.emitters == l.lights);
    CHECK(l.textures == 512u);
    CHECK(l.material_ids == 640u);
    CHECK(l.vertex_normals == 4736u);  // 640 + 4004 bytes of ids, rounded up
    CHECK(l.texcoords == l.vertex_normals);
    CHECK(l.texels == 28800u);  // 4736 + 24024, rounded up
    CHECK(total == 28800u + a.texels.bytes);
    CHECK(l.has_vertex_normals == 0u);
    a.vertex_normals.bytes = 1001 * KDRAY_FLOATS_PER_TRIANGLE * sizeof(float);
    CHECK(layout_scene_arrays(a, &total).has_vertex_normals == 1u);

    // The atlas, last, may reach past 4 GiB; an array before it may not end there, since the
    // atlas's offset would not fit in 32 bits.
    a.texels.bytes = std::size_t(5) << 30;
    CHECK(layout_scene_arrays(a, &total).texels < 0xFFFFFFFFu);
    CHECK(total > (std::size_t(4) << 30));
    a.texcoords.bytes = std::size_t(4) << 30;
    CHECK_THROWS_AS(layout_scene_arrays(a, &total), Error);
}
