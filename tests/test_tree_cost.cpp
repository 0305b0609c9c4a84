// test_tree_cost.cpp — the tree made visible: the `cost` AOV (nodes visited and triangles tested
// by each centre ray's walk, counted inside kd_trace) against walks whose counts follow from the
// tree by hand, the OpenCL tracer's counts against the reference's pixel for pixel, the AOV's
// cost channels through a file, and the heat map's colours against viridis' published values.
#include <doctest/doctest.h>

#include <algorithm>
#include <cmath>
#include <filesystem>
#include <string>
#include <vector>

#include "cl/renderer/opencl_renderer.h"
#include "core/device/kd_render.h"
#include "core/device/kd_traverse.h"
#include "core/io/image.h"
#include "core/io/image_codec.h"
#include "core/render/reference_tracer.h"
#include "core/render/render_file.h"
#include "core/render/render_setup.h"
#include "core/tree/reference_builder.h"
#include "tests/support.h"
#include "tests/test_opencl_fixture.h"

using namespace kdray;

namespace {

KdTraceCost walk_cost(const KdTree& tree, const Scene& scene, Vec3 org, Vec3 dir, KdHit* hit) {
    const float bounds[6] = {tree.bounds.lo.x, tree.bounds.lo.y, tree.bounds.lo.z,
                             tree.bounds.hi.x, tree.bounds.hi.y, tree.bounds.hi.z};
    const KdRay ray = test::make_ray(org, dir);
    KdTraceCost cost{0, 0};
    kd_trace(tree.nodes.data(), tree.leaf_indices.data(), scene.triangles.data(), bounds, &ray, 0,
             KDRAY_INTERSECT_WATERTIGHT, hit, &cost);
    return cost;
}

/// Two unit squares' worth of triangles facing x, T0 in the plane x = -1, T1 in x = +1, both over
/// y, z in [0, 1]; and the tree drawn by hand for them: root split x = 0, below leaf {T0}, above
/// leaf {T1}.
Scene two_walls() {
    return make_scene({-1, 0, 0, -1, 1, 0, -1, 0, 1,  //
                       1, 0, 0, 1, 1, 0, 1, 0, 1},
                      "two walls");
}
KdTree two_walls_tree() {
    KdTree tree;
    tree.bounds = two_walls().bounds();
    tree.nodes = {kd_make_inner(0, 0.0f, 2), kd_make_leaf(1, 0), kd_make_leaf(1, 1)};
    tree.leaf_indices = {0, 1};
    tree.builder = "hand";
    return tree;
}

}  // namespace

TEST_CASE("cost: one triangle, one leaf: a hit visits the root leaf and tests 1 triangle") {
    // The triangle lies in z = 0, so the root box is the flat rectangle [0,1] x [0,1] at z = 0.
    const Scene scene = make_scene({0, 0, 0, 1, 0, 0, 0, 1, 0}, "one");
    const KdTree tree = build_reference(scene);
    REQUIRE(tree.nodes.size() == 1);  // the closed form below is that of a single leaf
    KdHit hit;
    // Through the triangle: the root leaf, its one triangle.
    KdTraceCost c = walk_cost(tree, scene, {0.2f, 0.2f, 1}, {0, 0, -1}, &hit);
    CHECK(hit.prim == 0u);
    CHECK(c.nodes == 1u);
    CHECK(c.triangles == 1u);
    // Through the box but beside the triangle (x + y > 1): the same walk, no hit.
    c = walk_cost(tree, scene, {0.8f, 0.8f, 1}, {0, 0, -1}, &hit);
    CHECK(hit.prim == KDRAY_NO_HIT);
    CHECK(c.nodes == 1u);
    CHECK(c.triangles == 1u);
    // Beside the root box: no node at all.
    c = walk_cost(tree, scene, {2, 2, 1}, {0, 0, -1}, &hit);
    CHECK(hit.prim == KDRAY_NO_HIT);
    CHECK(c.nodes == 0u);
    CHECK(c.triangles == 0u);

    SUBCASE("per pixel through render_reference: (1, 1) inside the box, (0, 0) outside") {
        RenderSettings settings;
        settings.width = 24;
        settings.height = 18;
        Camera camera;
        camera.position = {0.5f, 0.5f, 2};
        camera.look_at = {0.5f, 0.5f, 0};
        camera.fov_y = 60.0f;
        RenderInputs inputs = prepare_render(scene, settings, camera, 0);
        inputs.cost = true;
        const FrameResult frame = render_reference(tree, scene, inputs, 2);
        REQUIRE(frame.hits.costs.size() == 24u * 18u);
        int inside = 0, outside = 0;
        for (int y = 0; y < settings.height; ++y)
            for (int x = 0; x < settings.width; ++x) {
                const std::size_t i = std::size_t(y) * settings.width + x;
                KdRay ray;
                kd_camera_ray(&inputs.view, float(x) + 0.5f, float(y) + 0.5f, &ray);
                // Where the centre ray crosses z = 0, in double; pixels within rounding of the
                // box's edge are left out.
                const double s = -double(ray.org[2]) / ray.dir[2];
                const double px = ray.org[0] + s * ray.dir[0], py = ray.org[1] + s * ray.dir[1];
                const double margin = std::min({px, py, 1 - px, 1 - py});
                if (std::fabs(margin) < 1e-4) continue;
                const kd_u32 want = margin > 0 ? 1u : 0u;
                inside += want == 1u;
                outside += want == 0u;
                CAPTURE(x);
                CAPTURE(y);
                CHECK(frame.hits.costs[i].nodes == want);
                CHECK(frame.hits.costs[i].triangles == want);
            }
        CHECK(inside > 0);
        CHECK(outside > 0);
    }
}

TEST_CASE("cost: the hand-built two-leaf tree counts the walk's order and its early exit") {
    const Scene scene = two_walls();
    const KdTree tree = two_walls_tree();
    KdHit hit;
    // Along +x through both walls: root, below leaf (T0 hit at t = 1); the above child's entry
    // (t = 2, the plane x = 0) lies past the hit, so the walk ends there.
    KdTraceCost c = walk_cost(tree, scene, {-2, 0.25f, 0.25f}, {1, 0, 0}, &hit);
    CHECK(hit.prim == 0u);
    CHECK(c.nodes == 2u);
    CHECK(c.triangles == 1u);
    // Along -x from the other side: the above leaf first, T1 hit, the same early exit.
    c = walk_cost(tree, scene, {2, 0.25f, 0.25f}, {-1, 0, 0}, &hit);
    CHECK(hit.prim == 1u);
    CHECK(c.nodes == 2u);
    CHECK(c.triangles == 1u);
    // Along +x beside both triangles (y + z > 1) but inside the box: all three nodes, both tests.
    c = walk_cost(tree, scene, {-2, 0.75f, 0.75f}, {1, 0, 0}, &hit);
    CHECK(hit.prim == KDRAY_NO_HIT);
    CHECK(c.nodes == 3u);
    CHECK(c.triangles == 2u);
    // Down the below half only (never crossing x = 0): root and one leaf.
    c = walk_cost(tree, scene, {-0.5f, 0.25f, 2}, {0, 0, -1}, &hit);
    CHECK(c.nodes == 2u);
    CHECK(c.triangles == 1u);
}

TEST_CASE("cost: the OpenCL tracer's counts equal the reference's pixel for pixel") {
    // The glass room (always in the repository) and, when ../shared is there, the bunny: the same
    // reference tree traced by both, one ray per pixel and with spp 4 (the extra centre ray).
    struct Case {
        std::filesystem::path obj, render;
    };
    std::vector<Case> cases = {{test::source_dir() / "testdata/cornell/room.obj",
                                test::source_dir() / "testdata/cornell/render.json"}};
    const std::filesystem::path bunny = test::shared_dir() / "scenes/bunny";
    if (std::filesystem::exists(bunny / "bunny.obj"))
        cases.push_back({bunny / "bunny.obj", bunny / "render.json"});
    for (const Case& k : cases) {
        for (const int spp : {1, 4}) {
            CAPTURE(k.obj.string());
            CAPTURE(spp);
            const Scene scene = load_obj(k.obj);
            RenderSettings settings = load_render_file(k.render);
            settings.width = 96;
            settings.height = 72;
            settings.spp = spp;
            const KdTree tree = build_reference(scene);
            RenderInputs inputs =
                prepare_render(scene, settings, settings.camera_at(0, scene.frame), 0);
            inputs.cost = true;
            const FrameResult device =
                render_opencl(test::opencl_test_device(), tree, scene, inputs);
            const FrameResult host = render_reference(tree, scene, inputs, 2);
            REQUIRE(device.hits.costs.size() == host.hits.costs.size());
            std::size_t differ = 0, walked = 0;
            for (std::size_t i = 0; i < host.hits.costs.size(); ++i) {
                walked += host.hits.costs[i].nodes > 0;
                differ += device.hits.costs[i].nodes != host.hits.costs[i].nodes ||
                          device.hits.costs[i].triangles != host.hits.costs[i].triangles;
            }
            CHECK(walked > 0);
            // The same walk with the same arithmetic: exact on a CPU device; a GPU's hit may
            // differ in its last ulp (see the glass room's ray counts), and its walk with it.
            if (test::opencl_test_device().is_cpu())
                CHECK(differ == 0);
            else
                CHECK(double(differ) <= 1e-3 * double(host.hits.costs.size()));
        }
    }
}

TEST_CASE("cost: the AOV's cost channels survive a file; Z and prim_id are unchanged") {
    const std::filesystem::path dir = test::fresh_temp_dir("cost_aov");
    HitBuffer hits;
    hits.width = 3;
    hits.height = 2;
    hits.hits = {{1.5f, 7, 0, 0}, {INFINITY, KDRAY_NO_HIT, 0, 0},
                 {2, 0, 0, 0},    {3, 1, 0, 0},
                 {4, 2, 0, 0},    {5, 3, 0, 0}};
    hits.costs = {{3, 4}, {0, 0}, {1, 1}, {40, 123}, {7, 0}, {4294967295u, 2}};
    const std::filesystem::path path = dir / "a.aov.exr";
    write_aov(path, hits);
    const ExrImage exr = read_exr(path);
    REQUIRE(exr.find("Z"));
    REQUIRE(exr.find("prim_id"));
    CHECK_FALSE(exr.find("Z")->is_uint);
    CHECK(exr.find("prim_id")->is_uint);
    REQUIRE(exr.find("cost.nodes"));
    CHECK(exr.find("cost.nodes")->is_uint);
    const HitBuffer back = read_aov(path);
    REQUIRE(back.costs.size() == hits.costs.size());
    for (std::size_t i = 0; i < hits.costs.size(); ++i) {
        CHECK(back.costs[i].nodes == hits.costs[i].nodes);
        CHECK(back.costs[i].triangles == hits.costs[i].triangles);
        CHECK(back.hits[i].prim == hits.hits[i].prim);
    }
    std::filesystem::remove_all(dir);
}

TEST_CASE("heat map: viridis at its published end points and middle; the map's scale") {
    // matplotlib's viridis: #440154 at 0, #21918c at 0.5, #fde725 at 1.
    auto near = [](Vec3 c, int r, int g, int b) {
        return std::fabs(c.x * 255 - r) <= 1.0f && std::fabs(c.y * 255 - g) <= 1.0f &&
               std::fabs(c.z * 255 - b) <= 1.0f;
    };
    CHECK(near(heatmap_colour(0.0f), 0x44, 0x01, 0x54));
    CHECK(near(heatmap_colour(0.5f), 0x21, 0x91, 0x8c));
    CHECK(near(heatmap_colour(1.0f), 0xfd, 0xe7, 0x25));
    CHECK(near(heatmap_colour(-3.0f), 0x44, 0x01, 0x54));
    CHECK(near(heatmap_colour(NAN), 0x44, 0x01, 0x54));
    CHECK(near(heatmap_colour(7.0f), 0xfd, 0xe7, 0x25));
    // Perceptual: lightness (here Rec. 709 luma of the encoded values) rises all the way.
    float last = -1;
    for (int i = 0; i <= 64; ++i) {
        const Vec3 c = heatmap_colour(float(i) / 64);
        const float luma = 0.2126f * c.x + 0.7152f * c.y + 0.0722f * c.z;
        CHECK(luma > last);
        last = luma;
    }

    // 100 walked pixels of cost 1..100 (C_t = 1, C_i = 0) and one that missed the box: the 99th
    // percentile of the walked ones, 99, is yellow; 100 saturates; the miss is the map's 0.
    HitBuffer hits;
    hits.width = 101;
    hits.height = 1;
    hits.hits.assign(101, KdHit{INFINITY, KDRAY_NO_HIT, 0, 0});
    for (kd_u32 i = 0; i < 100; ++i) hits.costs.push_back({i + 1, 5});
    hits.costs.push_back({0, 0});
    const std::filesystem::path dir = test::fresh_temp_dir("heatmap");
    const Heatmap map = encode_heatmap(dir / "h.cost.png", hits, 1.0f, 0.0f);
    CHECK(map.scale_cost == 99.0);
    CHECK(map.max_cost == 100.0);
    test::write_text_file(dir / "h.cost.png", map.png);
    const DecodedImage png = read_image(dir / "h.cost.png");
    REQUIRE(png.width == 101);
    auto pixel = [&](int x) {
        return Vec3{png.values[std::size_t(x) * png.channels],
                    png.values[std::size_t(x) * png.channels + 1],
                    png.values[std::size_t(x) * png.channels + 2]};
    };
    CHECK(near(pixel(98), 0xfd, 0xe7, 0x25));
    CHECK(near(pixel(99), 0xfd, 0xe7, 0x25));
    CHECK(near(pixel(100), 0x44, 0x01, 0x54));
    std::filesystem::remove_all(dir);
}

TEST_CASE("cli: --aov and --heatmap write the cost; build --json has the leaf histograms") {
    const std::filesystem::path dir = test::fresh_temp_dir("cost_cli");
    const std::filesystem::path obj =
        test::write_text_file(dir / "one.obj", "v 0 0 0\nv 1 0 0\nv 0 1 0\nf 1 2 3\n");
    const std::filesystem::path render =
        test::write_text_file(dir / "render.json",
                              R"({"image": {"width": 16, "height": 12},
            "camera": {"position": [0.3, 0.3, 2], "look_at": [0.3, 0.3, 0], "fov_y": 60}})");
    const test::CommandResult r = test::run_kdray(
        {"render", obj.string(), "-o", (dir / "out").string(), "--camera", render.string(), "--aov",
         "--heatmap", "--builder", "reference", "--tracer", "reference", "--quiet"});
    REQUIRE_MESSAGE(r.status == 0, r.err);
    CHECK(std::filesystem::is_regular_file(dir / "out/one.cost.png"));
    const nlohmann::json stats = test::read_json(dir / "out/stats.json");
    CHECK(stats["display"] == "filmic");
    const nlohmann::json& heatmap = stats["frames"][0]["heatmap"];
    CHECK(heatmap["file"] == "one.cost.png");
    // One leaf, one triangle: every ray that enters the box costs C_t + C_i (15 + 20).
    CHECK(heatmap["max_cost"].get<double>() == 35.0);
    CHECK(heatmap["scale_cost"].get<double>() == 35.0);
    const HitBuffer aov = read_aov(dir / "out/one.aov.exr");
    REQUIRE(aov.costs.size() == 16u * 12u);
    for (std::size_t i = 0; i < aov.costs.size(); ++i)
        if (aov.hits[i].prim != KDRAY_NO_HIT) CHECK(aov.costs[i].nodes == 1u);

    const test::CommandResult b =
        test::run_kdray({"build", obj.string(), "--json", "--builder", "reference"});
    REQUIRE_MESSAGE(b.status == 0, b.err);
    const nlohmann::json tree = nlohmann::json::parse(b.out);
    CHECK(tree["leaf_depth_histogram"] == nlohmann::json::parse("[1]"));
    CHECK(tree["leaf_size_histogram"] == nlohmann::json::parse("[[1, 1]]"));
    std::filesystem::remove_all(dir);
}
