// test_path_tracing.cpp — the path integrator ("integrator": "path", core/device/kd_path.h)
// against closed forms: a furnace (a closed emitting Lambertian sphere around the camera), whose
// radiance is known at every depth, with lossless glass and a mirror inside it, on both tracers;
// the OpenCL kernel against the reference renderer on the bundled glass room; the render file's
// integrator through the command line. Direct light: test_path_direct.cpp.
#include <doctest/doctest.h>

#include <algorithm>
#include <cmath>
#include <filesystem>
#include <sstream>
#include <string>
#include <vector>

#include "cl/renderer/opencl_renderer.h"
#include "core/render/reference_tracer.h"
#include "core/render/render_file.h"
#include "core/render/render_setup.h"
#include "core/scene/scene.h"
#include "core/tree/reference_builder.h"
#include "tests/support.h"
#include "tests/test_opencl_fixture.h"

using namespace kdray;
namespace fs = std::filesystem;

namespace {

// The furnace's material: albedo a and emitted radiance Le per channel, so that each channel has
// its own closed form.
constexpr float kAlbedo[3] = {0.5f, 0.7f, 0.3f};
constexpr float kEmitted[3] = {1.0f, 0.5f, 0.25f};

/// Appends to `obj` a closed UV sphere of `radius` about `centre`, `rings` x 2 `rings` faces, in
/// material `material`, every triangle wound to face the centre (`inward`) or away from it;
/// `first` is the 1-based index of its first vertex, and returns the next sphere's.
int add_sphere(std::ostringstream& obj, int first, Vec3 centre, float radius, int rings,
               bool inward, const std::string& material) {
    obj << "usemtl " << material << "\n";
    const int segments = 2 * rings;
    std::vector<Vec3> v;
    v.push_back({0, 1, 0});
    for (int i = 1; i < rings; ++i)
        for (int j = 0; j < segments; ++j) {
            const double theta = M_PI * i / rings, phi = 2 * M_PI * j / segments;
            v.push_back({float(std::sin(theta) * std::cos(phi)), float(std::cos(theta)),
                         float(std::sin(theta) * std::sin(phi))});
        }
    v.push_back({0, -1, 0});
    for (const Vec3& p : v) {
        const Vec3 q = centre + p * radius;
        obj << "v " << q.x << " " << q.y << " " << q.z << "\n";
    }
    const int south = int(v.size()) - 1;  // 0-based index of the last vertex
    auto ring = [&](int i, int j) { return 1 + (i - 1) * segments + (j % segments); };
    auto face = [&](int a, int b, int c) {
        // The winding normal of the unit sphere's face against (inward) or along its centroid.
        const Vec3 n = cross(v[b] - v[a], v[c] - v[a]);
        if ((dot(n, v[a] + v[b] + v[c]) > 0) == inward) std::swap(b, c);
        obj << "f " << first + a << " " << first + b << " " << first + c << "\n";
    };
    for (int j = 0; j < segments; ++j) {
        face(0, ring(1, j), ring(1, j + 1));
        face(south, ring(rings - 1, j), ring(rings - 1, j + 1));
        for (int i = 1; i + 1 < rings; ++i) {
            face(ring(i, j), ring(i + 1, j), ring(i + 1, j + 1));
            face(ring(i, j), ring(i + 1, j + 1), ring(i, j + 1));
        }
    }
    return first + int(v.size());
}

/// The furnace scene, written and loaded: a closed sphere of radius 1 about the origin, facing
/// inward (conventions.md: Ke shines from the front side only), in Lambertian kAlbedo emitting
/// kEmitted. With `lossless_balls`, two balls inside it that neither absorb nor emit: clear
/// glass (illum 7, Ni 1.5) and a white ideal mirror (illum 3, Ks 1), wound outward (the glass
/// is entered through its front), which leave the closed form unchanged.
Scene furnace_scene(bool lossless_balls = false) {
    const auto dir = test::fresh_temp_dir(lossless_balls ? "path_furnace_balls" : "path_furnace");
    std::ostringstream mtl;
    mtl << "newmtl wall\nKd " << kAlbedo[0] << " " << kAlbedo[1] << " " << kAlbedo[2] << "\nKe "
        << kEmitted[0] << " " << kEmitted[1] << " " << kEmitted[2] << "\nKs 0 0 0\nillum 1\n"
        << "newmtl glass\nKd 0 0 0\nKs 0 0 0\nNi 1.5\nillum 7\n"
        << "newmtl mirror\nKd 0 0 0\nKs 1 1 1\nillum 3\n";
    test::write_text_file(dir / "furnace.mtl", mtl.str());
    std::ostringstream obj;
    obj.precision(9);
    obj << "mtllib furnace.mtl\n";
    int next = add_sphere(obj, 1, {0, 0, 0}, 1.0f, 12, true, "wall");
    if (lossless_balls) {
        next = add_sphere(obj, next, {0.45f, 0.1f, -0.3f}, 0.3f, 8, false, "glass");
        add_sphere(obj, next, {0.2f, -0.35f, 0.1f}, 0.2f, 8, false, "mirror");
    }
    return load_obj(test::write_text_file(dir / "furnace.obj", obj.str()));
}

/// The camera inside the sphere, off its centre, looking along a skew direction with a wide
/// view: every pixel sees the wall at a different distance and angle.
RenderSettings furnace_settings(int size, int spp, int max_depth) {
    RenderSettings s;
    s.width = s.height = size;
    s.spp = spp;
    s.integrator = Integrator::path;
    s.max_depth = max_depth;
    s.background = {0, 0, 0};  // a path that leaked out of the sphere would bring nothing
    // check_furnace's spread and worst-pixel bounds are those of independent samples; a pixel's
    // low-discrepancy samples (every render's) have a narrower bulk and the same rare paths, so
    // the test that renders with them checks the mean alone.
    s.independent_samples = true;
    s.camera_keys = {CameraKey{
        0, SceneCamera(Camera{{0.2f, -0.1f, 0.3f}, {1, 0.4f, -0.7f}, {0, 1, 0}, 100.0f})}};
    s.camera_given = true;
    return s;
}

/// Le (1 + a + ... + a^(segments - 1)): the furnace's radiance when paths have at most
/// `segments` segments (Le / (1 - a) for -1, unbounded).
double furnace_radiance(int c, int segments) {
    if (segments < 0) return kEmitted[c] / (1.0 - kAlbedo[c]);
    double sum = 0, term = kEmitted[c];
    for (int i = 0; i < segments; ++i, term *= kAlbedo[c]) sum += term;
    return sum;
}

/// Per channel, over the pixels `in` selects (all without it): their mean, the standard deviation
/// of their values about it, the largest |pixel - expected| and how many there are.
struct ChannelStats {
    double mean = 0, pixel_sd = 0, worst = 0, pixels = 0;
};

ChannelStats channel_stats(const Image& image, int c, double expected,
                           const std::vector<bool>* in) {
    const std::size_t pixels = image.rgb.size() / 3;
    ChannelStats s;
    for (std::size_t i = 0; i < pixels; ++i)
        if (!in || (*in)[i]) {
            s.mean += image.rgb[3 * i + c];
            s.pixels += 1;
        }
    s.mean /= s.pixels;
    for (std::size_t i = 0; i < pixels; ++i)
        if (!in || (*in)[i]) {
            const double d = image.rgb[3 * i + c] - s.mean;
            s.pixel_sd += d * d;
            s.worst = std::max(s.worst, std::fabs(image.rgb[3 * i + c] - expected));
        }
    s.pixel_sd = std::sqrt(s.pixel_sd / (s.pixels - 1));
    return s;
}

/// The furnace's image (the pixels `in` selects) against its closed form at `max_depth`, channel
/// by channel. Pixels are independent estimates (each has its own random numbers) of one value,
/// so where they see alike their spread estimates one pixel's Monte Carlo error: their mean must
/// lie within 4 standard errors of the closed form (pixel_sd / sqrt(pixels): 6e-5 of the cases
/// by chance), and no pixel farther than 6 pixel standard deviations from it (a lost or doubled
/// contribution in one pixel). The spread itself is bounded by `max_relative_sd` of the
/// radiance, so that a noisy estimator cannot pass by its wide error bars. mean_only: the mean
/// alone, for low-discrepancy samples (pixels are still independent estimates, each with its own
/// rotation of the sequence, but not normally distributed ones). repeat: the same render with
/// samples of its own, for estimators with a heavy tail (below), where a pixel is wrong only
/// when it is that far off in both renders: a lost or doubled contribution is the pixel's in
/// every render, a rare long path in one.
void check_furnace(const Image& image, int max_depth, double max_relative_sd,
                   const std::vector<bool>* in = nullptr, bool mean_only = false,
                   const Image* repeat = nullptr) {
    for (int c = 0; c < 3; ++c) {
        CAPTURE(c);
        const double expected = furnace_radiance(c, max_depth);
        const ChannelStats s = channel_stats(image, c, expected, in);
        CAPTURE(expected);
        CAPTURE(s.mean);
        CAPTURE(s.pixel_sd);
        CAPTURE(s.worst);
        CAPTURE(s.pixels);
        CHECK(std::fabs(s.mean - expected) <=
              4 * s.pixel_sd / std::sqrt(s.pixels) + 1e-6 * expected);
        if (mean_only) continue;
        CHECK(s.pixel_sd <= max_relative_sd * expected);
        const double far = 6 * s.pixel_sd + 1e-6 * expected;
        if (!repeat) {
            CHECK(s.worst <= far);
            continue;
        }
        const ChannelStats r = channel_stats(*repeat, c, expected, in);
        CHECK(r.pixel_sd <= max_relative_sd * expected);
        const double repeat_far = 6 * r.pixel_sd + 1e-6 * expected;
        int far_in_both = 0;
        for (std::size_t i = 0; i < image.rgb.size() / 3; ++i)
            if ((!in || (*in)[i]) && std::fabs(image.rgb[3 * i + c] - expected) > far &&
                std::fabs(repeat->rgb[3 * i + c] - expected) > repeat_far)
                ++far_in_both;
        CHECK(far_in_both == 0);
    }
}

RenderInputs furnace_inputs(const Scene& scene, const RenderSettings& settings) {
    RenderInputs inputs = prepare_render(scene, settings, settings.camera_at(0, scene.frame), 7);
    REQUIRE(inputs.effects.path);
    REQUIRE(inputs.effects.area_lights);
    return inputs;
}

}  // namespace

TEST_CASE("path: a closed emitting Lambertian sphere has radiance Le / (1 - a) everywhere") {
    const Scene scene = furnace_scene();
    const KdTree tree = build_reference(scene);
    // Unbounded paths, ended by Russian roulette: 32x32 pixels of 64 samples.
    RenderSettings settings = furnace_settings(32, 64, -1);
    const FrameResult host = render_reference(tree, scene, furnace_inputs(scene, settings), 2);
    check_furnace(host.image, -1, 0.1);
    // Every render's samples, each pixel's low-discrepancy sequence: unbiased too.
    settings.independent_samples = false;
    const FrameResult sequence = render_reference(tree, scene, furnace_inputs(scene, settings), 2);
    check_furnace(sequence.image, -1, 0.1, nullptr, true);
}

TEST_CASE("path: the furnace at each max_depth is Le (1 + a + ... + a^(max_depth - 1))") {
    const Scene scene = furnace_scene();
    const KdTree tree = build_reference(scene);
    // One segment: the wall's own emission, nothing random, so every pixel is Le in float.
    SUBCASE("max_depth 1") {
        const RenderSettings settings = furnace_settings(16, 4, 1);
        const FrameResult host = render_reference(tree, scene, furnace_inputs(scene, settings), 2);
        for (std::size_t i = 0; i < host.image.rgb.size(); ++i)
            CHECK(host.image.rgb[i] == doctest::Approx(kEmitted[i % 3]).epsilon(1e-6));
    }
    for (int depth : {2, 3, 5}) {
        CAPTURE(depth);
        const RenderSettings settings = furnace_settings(24, 32, depth);
        const FrameResult host = render_reference(tree, scene, furnace_inputs(scene, settings), 2);
        check_furnace(host.image, depth, 0.1);
    }
}

TEST_CASE("path: glass and a mirror in the furnace change nothing: Le / (1 - a) everywhere") {
    // Lossless delta lobes carry the enclosure's radiance unchanged: the dielectric reflects F
    // and transmits 1 - F (no Tf, no absorption), the white mirror reflects all. A lost or
    // doubled Fresnel share, or a refracted ray started on the wrong side, shows through them.
    const Scene scene = furnace_scene(true);
    const KdTree tree = build_reference(scene);
    const RenderSettings settings = furnace_settings(32, 64, -1);
    const RenderInputs inputs = furnace_inputs(scene, settings);
    REQUIRE(inputs.effects.refraction);
    REQUIRE(inputs.effects.reflection);
    const FrameResult host = render_reference(tree, scene, inputs, 2);
    CHECK(host.rays.refraction > 0);
    // Paths trapped in the faceted glass ball by total internal reflection keep their
    // throughput, which roulette's survival of 0.95 raises by 1/0.95 a segment, and leave it
    // after tens of segments with several times their weight: one sample of 47 where the pixel
    // is 2. At 64 samples a pixel, a wall pixel lay more than 6 standard deviations off in 4 of
    // 16 seeds with the path's earlier random numbers and in 5 of 16 with today's, so the worst
    // pixel must be that far off in a second render too, of samples of its own (seed 8), to
    // count.
    const FrameResult repeat = render_reference(
        tree, scene, prepare_render(scene, settings, settings.camera_at(0, scene.frame), 8), 2);
    // The wall's pixels and the balls' (by the centre ray's triangle: the wall's come first) have
    // errors of different sizes, paths through glass more (their Fresnel choice, and roulette
    // sooner), so each group is held to its own spread.
    const kd_u32 wall_triangles = 2 * 24 + 2 * 24 * 10;
    std::vector<bool> wall(host.hits.hits.size()), balls(host.hits.hits.size());
    for (std::size_t i = 0; i < wall.size(); ++i) {
        wall[i] = host.hits.hits[i].prim < wall_triangles;
        balls[i] = !wall[i];
    }
    REQUIRE(std::count(balls.begin(), balls.end(), true) > 50);
    check_furnace(host.image, -1, 0.1, &wall, false, &repeat.image);
    check_furnace(host.image, -1, 0.2, &balls, false, &repeat.image);
}

TEST_CASE("path: at max_depth 2 a mirror shows what its one bounce sees (Mitsuba's count)") {
    // Segment 1 reaches the white mirror ball, segment 2 leaves it and finds the wall's Le. The
    // second segment was refused to mirrors and glass (reflection off below max_depth 3), so the
    // ball was black where Mitsuba's path integrator at the same depth shows the wall: found
    // against scripts/compare_mitsuba.py on CornellBox-Sphere (mean 0.0607 against 0.0644).
    const Scene scene = furnace_scene(true);
    const KdTree tree = build_reference(scene);
    const RenderSettings settings = furnace_settings(48, 1, 2);  // the centre rays alone
    const RenderInputs inputs = furnace_inputs(scene, settings);
    CHECK(inputs.effects.reflection);
    CHECK(inputs.effects.refraction);
    const FrameResult host = render_reference(tree, scene, inputs, 2);
    // The mirror ball's triangles come last (after the wall's 528 and the glass ball's 256).
    const kd_u32 first_mirror = 528 + 256;
    int mirror = 0, wall_seen = 0;
    for (std::size_t i = 0; i < host.hits.hits.size(); ++i) {
        if (host.hits.hits[i].prim == KDRAY_NO_HIT || host.hits.hits[i].prim < first_mirror)
            continue;
        ++mirror;
        // Le where the bounce finds the wall; 0 where it finds the glass ball, whose own
        // emission is none and whose light would need a third segment.
        const bool le = host.image.rgb[3 * i] == doctest::Approx(kEmitted[0]).epsilon(1e-5) &&
                        host.image.rgb[3 * i + 1] == doctest::Approx(kEmitted[1]).epsilon(1e-5) &&
                        host.image.rgb[3 * i + 2] == doctest::Approx(kEmitted[2]).epsilon(1e-5);
        wall_seen += le;
        if (!le) CHECK(host.image.rgb[3 * i] == 0.0f);
    }
    REQUIRE(mirror > 20);
    // From where the camera looks, the glass ball fills much of the mirror (26 of 64 pixels
    // see the wall); without the second segment none would.
    CHECK(wall_seen >= mirror / 4);
}

TEST_CASE("path: the OpenCL kernel's furnace has radiance Le / (1 - a) everywhere") {
    const Scene scene = furnace_scene();
    const KdTree tree = build_reference(scene);
    const RenderSettings settings = furnace_settings(32, 32, -1);
    // With the primary rays traced as packets (a CPU device's default) and by the pixel kernel
    // itself (a GPU's way).
    for (const auto packets : {RenderInputs::Packets::Auto, RenderInputs::Packets::Off}) {
        CAPTURE(packets_name(packets));
        RenderInputs inputs = furnace_inputs(scene, settings);
        inputs.packets = packets;
        const FrameResult device = render_opencl(test::opencl_test_device(), tree, scene, inputs);
        check_furnace(device.image, -1, 0.15);
    }
}

TEST_CASE("path: the OpenCL kernel's image is the reference renderer's") {
    // The bundled glass room: a mirror, a glass block, an emitter and a point light, so every
    // lobe and both light samplers run. The same random numbers follow the same paths on both
    // sides; a hit that differs in its last bit can send one path elsewhere (a GPU's arithmetic
    // may), so the images are compared by the share of pixels that agree closely and by their
    // mean, not pixel for pixel.
    const Scene scene = load_obj(test::source_dir() / "testdata/cornell/room.obj");
    RenderSettings settings = load_render_file(test::source_dir() / "testdata/cornell/render.json");
    settings.width = 64;
    settings.height = 48;
    settings.spp = 4;
    settings.integrator = Integrator::path;
    settings.max_depth = -1;
    const KdTree tree = build_reference(scene);
    const RenderInputs inputs =
        prepare_render(scene, settings, settings.camera_at(0, scene.frame), 11);
    REQUIRE(inputs.effects.path);
    REQUIRE(inputs.effects.refraction);
    REQUIRE(inputs.effects.area_lights);
    const FrameResult device = render_opencl(test::opencl_test_device(), tree, scene, inputs);
    const FrameResult host = render_reference(tree, scene, inputs, 2);
    const std::size_t pixels = host.image.rgb.size() / 3;
    std::size_t close = 0;
    double mean_host = 0, mean_device = 0;
    for (std::size_t i = 0; i < pixels; ++i) {
        bool same = true;
        for (int c = 0; c < 3; ++c) {
            const double h = host.image.rgb[3 * i + c], d = device.image.rgb[3 * i + c];
            mean_host += h;
            mean_device += d;
            same = same && std::fabs(h - d) <= 1e-4 * std::max(1.0, std::fabs(h));
        }
        close += same;
    }
    CHECK(host.rays.reflection > 0);
    CHECK(host.rays.refraction > 0);
    CHECK(host.rays.area_shadow > 0);
    CHECK(double(close) >= 0.98 * double(pixels));
    CHECK(mean_device == doctest::Approx(mean_host).epsilon(0.01));
}

TEST_CASE("kdray render: the path integrator in stats.json, --ray-depth in its range") {
    const auto dir = test::fresh_temp_dir("path_cli");
    const auto obj = test::write_text_file(
        dir / "tri.obj", "mtllib m.mtl\nusemtl lamp\nv -1 -1 0\nv 1 -1 0\nv 0 1 0\nf 1 2 3\n");
    test::write_text_file(dir / "m.mtl", "newmtl lamp\nKd 0.5 0.5 0.5\nKe 2 2 2\n");
    const auto path_file = test::write_text_file(
        dir / "path.json",
        R"({"camera": {"position": [0, 0, 3]}, "integrator": "path", "image": {"spp": 2}})");
    const auto whitted_file =
        test::write_text_file(dir / "whitted.json", R"({"camera": {"position": [0, 0, 3]}})");
    auto render = [&](const fs::path& file, std::vector<std::string> extra) {
        std::vector<std::string> args = {
            "render", obj.string(), "-o", (dir / "out").string(), "--camera", file.string(),
            "--size", "8x8",        "-q"};
        args.insert(args.end(), extra.begin(), extra.end());
        return test::run_kdray(args, 120);
    };
    for (const char* tracer : {"reference", "opencl"}) {
        CAPTURE(tracer);
        const test::CommandResult r = render(path_file, {"--tracer", tracer});
        INFO("stderr: " << r.err);
        REQUIRE(r.status == 0);
        const nlohmann::json stats = test::read_json(dir / "out" / "stats.json");
        CHECK(stats["integrator"] == "path");
        CHECK(stats["ray_depth"] == -1);
        const nlohmann::json& effects = stats["frames"][0]["effects"];
        CHECK(effects["path"] == true);
        CHECK(effects["reasons"]["path"] == "the render file asks for \"integrator\": \"path\"");
        CHECK(effects["ambient"] == false);
        fs::remove_all(dir / "out");
    }
    // -1 and depths past Whitted's 16 are the path's alone.
    const test::CommandResult deep = render(path_file, {"--ray-depth", "40"});
    CHECK(deep.status == 0);
    CHECK(test::read_json(dir / "out" / "stats.json")["ray_depth"] == 40);
    test::check_error(render(whitted_file, {"--ray-depth", "-1"}), 2, {"--ray-depth", "16"});
    test::check_error(render(path_file, {"--ray-depth", "0"}), 2, {"--ray-depth", "-1"});
    const nlohmann::json whitted = [&] {
        fs::remove_all(dir / "out");
        REQUIRE(render(whitted_file, {}).status == 0);
        return test::read_json(dir / "out" / "stats.json");
    }();
    CHECK(whitted["integrator"] == "whitted");
    CHECK(whitted["frames"][0]["effects"]["path"] == false);
    fs::remove_all(dir);
}
