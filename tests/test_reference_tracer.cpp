// test_reference_tracer.cpp — the CPU reference tracer against brute force, ray by ray, on the hard
// scenes and on the rays that stress a kd walk (parallel to split planes, starting on them, lying
// in the faces of the root box, flat nodes); render_reference on a closed-form scene; and the image
// and AOV files it writes.
#include <doctest/doctest.h>
#include <unistd.h>

#include <OpenImageIO/imageio.h>

#include <cmath>
#include <cstdint>
#include <cstdlib>
#include <cstring>
#include <filesystem>
#include <fstream>
#include <numbers>
#include <random>
#include <sstream>
#include <string>
#include <vector>

#include "core/error.h"
#include "core/io/image.h"
#include "core/render/reference_tracer.h"
#include "core/tree/reference_builder.h"
#include "tests/support.h"

namespace kdray {
namespace {

namespace fs = std::filesystem;

using test::make_ray;

/// A tree of one leaf holding every triangle: the walk reduces to the root clip and brute force.
KdTree single_leaf_tree(const Scene& scene) {
    KdTree tree;
    tree.bounds = scene.bounds();
    tree.builder = "single-leaf";
    tree.nodes.push_back(kd_make_leaf(kd_u32(scene.triangle_count()), 0));
    for (std::size_t i = 0; i < scene.triangle_count(); ++i) tree.leaf_indices.push_back(kd_u32(i));
    return tree;
}

std::string describe(const KdRay& r) {
    std::ostringstream s;
    s.precision(9);
    s << "org (" << r.org[0] << ", " << r.org[1] << ", " << r.org[2] << ") dir (" << r.dir[0]
      << ", " << r.dir[1] << ", " << r.dir[2] << ")";
    return s.str();
}

std::string describe(const KdHit& h) {
    if (h.prim == KDRAY_NO_HIT) return "miss";
    std::ostringstream s;
    s.precision(9);
    s << "prim " << h.prim << " t " << h.t;
    return s.str();
}

/// Traces `rays` through `tree` on two threads and checks every hit against brute force; the
/// first five mismatches are reported with the ray. Returns the number of mismatches.
int compare_with_brute_force(const KdTree& tree, const Scene& scene, const std::vector<KdRay>& rays,
                             const std::string& what) {
    const std::vector<KdHit> hits = trace_closest(tree, scene, rays, 2);
    REQUIRE(hits.size() == rays.size());
    int mismatches = 0;
    for (std::size_t i = 0; i < rays.size(); ++i) {
        const KdHit expected = test::brute_force_closest(scene, rays[i]);
        if (test::hits_agree(hits[i], expected)) continue;
        if (++mismatches <= 5) {
            INFO(what, ": ray ", i, " ", describe(rays[i]), ": tree ", describe(hits[i]),
                 ", brute force ", describe(expected));
            CHECK(test::hits_agree(hits[i], expected));
        }
    }
    CHECK_MESSAGE(mismatches == 0, what, ": ", mismatches, " of ", rays.size(), " rays disagree");
    return mismatches;
}

/// Rays that start exactly on the split planes of `tree`'s inner nodes, inside the root box:
/// crossing the plane either way, lying in it, and leaving it along another axis.
std::vector<KdRay> split_plane_rays(const KdTree& tree, int count, std::uint32_t seed) {
    std::vector<KdRay> rays;
    std::vector<std::pair<int, float>> planes;
    for (const KdNode& n : tree.nodes)
        if (!kd_node_is_leaf(n)) planes.emplace_back(int(kd_node_axis(n)), kd_node_split(n));
    if (planes.empty()) return rays;
    std::mt19937 rng(seed);
    std::uniform_real_distribution<float> unit(0.0f, 1.0f), sym(-1.0f, 1.0f);
    const Aabb& b = tree.bounds;
    for (int i = 0; i < count; ++i) {
        const auto [axis, split] = planes[rng() % planes.size()];
        Vec3 org = b.lo + b.extent() * Vec3{unit(rng), unit(rng), unit(rng)};
        org[axis] = split;
        Vec3 dir{sym(rng), sym(rng), sym(rng)};
        switch (i % 4) {
            case 0:
                dir[axis] = 0.0f;
                break;  // lying in the plane
            case 1:
                dir = Vec3{}, dir[(axis + 1 + i / 4 % 2) % 3] = (i & 8) ? 1.0f : -1.0f;
                break;
            default:
                break;  // crossing it either way
        }
        if (dot(dir, dir) == 0.0f) dir[axis] = 1.0f;
        rays.push_back(make_ray(org, dir));
    }
    return rays;
}

/// Rays lying in a face of the root box (origin on the face, no motion across it), aimed at
/// random points of that face: they graze every triangle with an edge or corner on the face.
std::vector<KdRay> box_face_rays(const Aabb& b, int count, std::uint32_t seed) {
    std::mt19937 rng(seed);
    std::uniform_real_distribution<float> unit(0.0f, 1.0f);
    std::vector<KdRay> rays;
    for (int i = 0; i < count; ++i) {
        const int axis = i % 3;
        const float plane = (i / 3) % 2 ? b.hi[axis] : b.lo[axis];
        Vec3 from =
            b.lo + b.extent() * Vec3{unit(rng), unit(rng), unit(rng)} * 1.4f - b.extent() * 0.2f;
        Vec3 to = b.lo + b.extent() * Vec3{unit(rng), unit(rng), unit(rng)};
        from[axis] = to[axis] = plane;
        Vec3 dir = to - from;
        if (dot(dir, dir) == 0.0f) dir[(axis + 1) % 3] = 1.0f;
        rays.push_back(make_ray(from, dir));
    }
    return rays;
}

/// A temporary directory for one test, removed with everything in it at the end.
struct TempDir {
    fs::path path;
    explicit TempDir(const std::string& name)
        : path(fs::temp_directory_path() / ("kdray_" + name + "_" + std::to_string(::getpid()))) {
        fs::remove_all(path);
        fs::create_directories(path);
    }
    ~TempDir() {
        std::error_code ignored;
        fs::remove_all(path, ignored);
    }
    std::vector<std::string> entries() const {
        std::vector<std::string> names;
        for (const auto& e : fs::directory_iterator(path)) names.push_back(e.path().filename());
        return names;
    }
};

}  // namespace

TEST_CASE("reference tracer equals brute force on the hard scenes") {
    for (const test::NamedScene& named : test::hard_scenes()) {
        CAPTURE(named.name);
        const Scene& scene = named.scene;
        const std::vector<KdRay> rays = test::random_rays(scene, 3000, 17);
        compare_with_brute_force(single_leaf_tree(scene), scene, rays, named.name + "/one leaf");
        const KdTree tree = build_reference(scene);
        compare_with_brute_force(tree, scene, rays, named.name + "/reference");
    }
}

TEST_CASE("pinned: a ray starting on a split plane walks into the child it moves into") {
    // Hand-made tree: x = 0 splits the root, y = 1 splits both children. C (x = -2) and B (x = 2)
    // lie only above y = 1; F (y = 0) lies in both cells below. The rays start on the x = 0 plane
    // at y = 0.75 and climb, so they reach the cell holding their triangle only after crossing
    // y = 1: visiting the child they move into with a zero-length range [0, 0], or the other
    // child, loses the hit (leaves test the whole ray, so a one-level tree would not show it).
    Scene scene = make_scene({-2, 1.05f, -1, -2, 1.45f, -1, -2, 1.25f, 1,   // C = 0
                              2,  1.05f, -1, 2,  1.45f, -1, 2,  1.25f, 1,   // B = 1
                              -2, 0,     -1, 2,  0,     -1, 0,  0,     1},  // F = 2
                             "split-plane start");
    KdTree tree;
    tree.bounds = scene.bounds();
    tree.builder = "hand-made";
    tree.nodes = {kd_make_inner(0, 0.0f, 4), kd_make_inner(1, 1.0f, 3), kd_make_leaf(1, 0),
                  kd_make_leaf(1, 1),        kd_make_inner(1, 1.0f, 6), kd_make_leaf(1, 2),
                  kd_make_leaf(1, 3)};
    tree.leaf_indices = {2, 0, 2, 1};
    const std::vector<KdRay> rays = {make_ray({0, 0.75f, 0}, {1, 0.25f, 0}),
                                     make_ray({0, 0.75f, 0}, {-1, 0.25f, 0})};
    const std::vector<KdHit> hits = trace_closest(tree, scene, rays, 1);
    CHECK(hits[0].prim == 1u);
    CHECK(hits[0].t == doctest::Approx(2.0f));
    CHECK(hits[1].prim == 0u);
    CHECK(hits[1].t == doctest::Approx(2.0f));
}

TEST_CASE("pinned: a ray lying in a face of the root box is not clipped away") {
    // Unit cube; the ray runs in its bottom face z = 0 (direction 0 on z, origin on the box's
    // lo.z) and meets the bottom edge of face x = 0 at t = 1, a hit watertight brute force finds.
    // Slab clipping computes 0 * inf = NaN for z and must not turn that into "outside".
    const Scene cube = test::cube_lattice(1);
    const KdRay ray = make_ray({-1, 0.5f, 0}, {1, 0, 0});
    const KdHit expected = test::brute_force_closest(cube, ray);
    REQUIRE(expected.prim != KDRAY_NO_HIT);
    CHECK(expected.t == 1.0f);
    const KdHit hit = trace_closest(single_leaf_tree(cube), cube, {ray}, 1)[0];
    CHECK(hit.prim == expected.prim);
    CHECK(hit.t == expected.t);
}

TEST_CASE("rays starting on split planes and lying in them") {
    // The planes come from the built tree itself, so every ray starts exactly where the walk
    // must decide between two children with t_plane = 0, or has to visit both (lying in it).
    for (const test::NamedScene& named : test::hard_scenes()) {
        CAPTURE(named.name);
        const KdTree tree = build_reference(named.scene);
        compare_with_brute_force(tree, named.scene, split_plane_rays(tree, 3000, 23),
                                 named.name + "/split planes");
    }
}

TEST_CASE("rays lying in the faces of the root box") {
    // Cube faces lie exactly on the root box's faces: a ray running along the bottom face meets
    // the side faces' bottom edges, which brute force hits.
    const Scene cubes = test::cube_lattice(2);
    compare_with_brute_force(single_leaf_tree(cubes), cubes, box_face_rays(cubes.bounds(), 600, 3),
                             "cube_lattice/one leaf/box faces");
    compare_with_brute_force(build_reference(cubes), cubes, box_face_rays(cubes.bounds(), 600, 3),
                             "cube_lattice/reference/box faces");
}

TEST_CASE("flat scene: rays in the plane, across it and along its normal") {
    // The root box is flat in z; every node is. Rays in z = 0 never hit (parallel), rays across
    // it must find the same triangle as brute force despite zero-thickness slabs.
    const Scene scene = test::planar_triangles(800, 31);
    const KdTree tree = build_reference(scene);
    std::mt19937 rng(4);
    std::uniform_real_distribution<float> unit(-0.2f, 1.2f);
    std::vector<KdRay> rays;
    for (int i = 0; i < 2000; ++i) {
        const Vec3 p{unit(rng), unit(rng), 0.0f};
        if (i % 3 == 0) rays.push_back(make_ray(p, Vec3{unit(rng), unit(rng), 0.0f} - p));
        if (i % 3 == 1) rays.push_back(make_ray(p + Vec3{0, 0, 1}, {0, 0, -1}));
        if (i % 3 == 2) rays.push_back(make_ray(p - Vec3{0.3f, 0.1f, 0.5f}, {0.3f, 0.1f, 0.5f}));
    }
    compare_with_brute_force(tree, scene, rays, "planar/reference");
    const std::vector<KdHit> hits = trace_closest(tree, scene, rays, 2);
    for (std::size_t i = 0; i < rays.size(); i += 3) CHECK(hits[i].prim == KDRAY_NO_HIT);
}

TEST_CASE("trace_closest gives the same hits on any number of threads") {
    const Scene scene = test::random_triangles(3000, 9);
    const KdTree tree = build_reference(scene);
    const std::vector<KdRay> rays = test::random_rays(scene, 5000, 10);
    const std::vector<KdHit> one = trace_closest(tree, scene, rays, 1);
    for (int threads : {0, 2, 3, 7}) {
        const std::vector<KdHit> many = trace_closest(tree, scene, rays, threads);
        REQUIRE(many.size() == one.size());
        CHECK(std::memcmp(many.data(), one.data(), one.size() * sizeof(KdHit)) == 0);
    }
    CHECK(trace_closest(tree, scene, {}, 2).empty());
}

TEST_CASE("render_reference on a closed-form scene") {
    // A quad at z = 0 facing a camera at z = 5, Kd = 0.5. Hits: t is the distance to the plane
    // along the unit ray, 5 / |d.z|. The radiance of a Lambert surface is Kd / pi * E.
    const float h = 10.0f;
    Scene scene = make_scene({-h, -h, 0, h, -h, 0, h, h, 0, -h, -h, 0, h, h, 0, -h, h, 0}, "quad");
    scene.materials[0].diffuse = {0.5f, 0.5f, 0.5f};
    const KdTree tree = build_reference(scene);
    RenderSettings settings;
    settings.width = 16;
    settings.height = 12;
    settings.background = {0.1f, 0.2f, 0.3f};
    Camera camera;
    camera.position = {0, 0, 5};
    camera.look_at = {0, 0, 0};
    camera.fov_y = 60.0f;
    const float inv_pi = std::numbers::inv_pi_v<float>;

    SUBCASE("headlight: E = 1 along the view direction, cos = 1 on the facing quad") {
        const FrameResult frame =
            render_reference(tree, scene, prepare_render(scene, settings, camera, 0), 2);
        REQUIRE(frame.image.rgb.size() == 16u * 12u * 3u);
        REQUIRE(frame.hits.normals.size() == 16u * 12u);
        for (std::size_t i = 0; i < frame.hits.hits.size(); ++i) {
            CHECK(frame.hits.hits[i].prim < 2u);
            CHECK(frame.hits.normals[i] == Vec3{0, 0, 1});
            for (int c = 0; c < 3; ++c)
                CHECK(frame.image.rgb[3 * i + c] == doctest::Approx(0.5f * inv_pi).epsilon(1e-6));
        }
    }
    SUBCASE("a point light at the camera: E = I cos / r^2 with cos = 5 / r") {
        settings.lights.push_back(Light{Light::Type::point, {0, 0, 5}, {0, -1, 0}, {20, 10, 5}});
        const FrameResult frame =
            render_reference(tree, scene, prepare_render(scene, settings, camera, 0), 2);
        for (std::size_t i = 0; i < frame.hits.hits.size(); ++i) {
            const double t = frame.hits.hits[i].t;  // also the distance to the light
            const double e = 5.0 / t / (t * t);
            const double expected[3] = {0.5 / std::numbers::pi * 20 * e,
                                        0.5 / std::numbers::pi * 10 * e,
                                        0.5 / std::numbers::pi * 5 * e};
            for (int c = 0; c < 3; ++c)
                CHECK(frame.image.rgb[3 * i + c] == doctest::Approx(expected[c]).epsilon(1e-5));
        }
    }
    SUBCASE("slanted directional light plus emission; a light from behind adds nothing") {
        const Vec3 dir = normalize(Vec3{1, 2, -2});  // cos with the normal (0,0,1): 2/3
        settings.lights.push_back(Light{Light::Type::directional, {}, dir, {3, 3, 3}});
        settings.lights.push_back(Light{Light::Type::directional, {}, {0, 0, 1}, {9, 9, 9}});
        scene.materials[0].emission = {0.25f, 0, 0};
        const FrameResult frame =
            render_reference(tree, scene, prepare_render(scene, settings, camera, 0), 2);
        const double lambert = 0.5 / std::numbers::pi * 3.0 * (2.0 / 3.0);
        for (std::size_t i = 0; i < frame.hits.hits.size(); ++i) {
            CHECK(frame.image.rgb[3 * i + 0] == doctest::Approx(lambert + 0.25).epsilon(1e-5));
            CHECK(frame.image.rgb[3 * i + 1] == doctest::Approx(lambert).epsilon(1e-5));
        }
    }
    SUBCASE("distances follow the camera model; misses get the background") {
        camera.look_at = {0, 8, 0};  // the upper rows look past the quad's top edge (y = 10)
        const FrameResult frame =
            render_reference(tree, scene, prepare_render(scene, settings, camera, 0), 2);
        int misses = 0;
        for (std::size_t i = 0; i < frame.hits.hits.size(); ++i) {
            const KdHit& hit = frame.hits.hits[i];
            if (hit.prim == KDRAY_NO_HIT) {
                ++misses;
                CHECK(std::isinf(hit.t));
                CHECK(frame.hits.normals[i] == Vec3{0, 0, 0});
                CHECK(frame.image.rgb[3 * i + 2] == 0.3f);
                continue;
            }
            // conventions.md camera model for this pixel, in double.
            const int x = int(i % 16), y = int(i / 16);
            // f = (0, 8, -5) / |.|, r = (1, 0, 0), u = cross(r, f) = (0, -f.z, f.y).
            const double fz = -5.0 / std::hypot(5.0, 8.0), uz = 8.0 / std::hypot(5.0, 8.0);
            const double t = std::tan(30.0 * std::numbers::pi / 180.0);
            const double sy = (1 - 2 * (y + 0.5) / 12) * t,
                         sx = (2 * (x + 0.5) / 16 - 1) * t * 16 / 12;
            const double dz = fz + sy * uz, len = std::sqrt(1 + sx * sx + sy * sy);
            CHECK(hit.t == doctest::Approx(5.0 / std::fabs(dz / len)).epsilon(1e-5));
        }
        CHECK(misses > 0);
        CHECK(misses < 16 * 12);
    }
}

TEST_CASE("hit AOV: write_aov then read_aov is exact; the channels are embree_ref's") {
    TempDir dir("aov");
    HitBuffer hits;
    hits.width = 7;
    hits.height = 5;
    std::mt19937 rng(2);
    std::uniform_real_distribution<float> unit(0.0f, 100.0f);
    for (int i = 0; i < 35; ++i) {
        const bool miss = i % 4 == 0;
        hits.hits.push_back(
            KdHit{miss ? INFINITY : unit(rng), miss ? KDRAY_NO_HIT : kd_u32(rng()), 0.0f, 0.0f});
        hits.normals.push_back(miss ? Vec3{} : normalize(Vec3{unit(rng), -unit(rng), 1.0f}));
    }
    // 0xFFFFFFFE is not representable as a float: prim_id must travel as uint32, not float.
    hits.hits[1].prim = 0xFFFFFFFEu;

    for (bool with_normals : {true, false}) {
        CAPTURE(with_normals);
        HitBuffer written = hits;
        if (!with_normals) written.normals.clear();
        const fs::path path = dir.path / "hits.exr";
        write_aov(path, written);
        const HitBuffer read = read_aov(path);
        REQUIRE(read.width == 7);
        REQUIRE(read.height == 5);
        REQUIRE(read.hits.size() == written.hits.size());
        for (std::size_t i = 0; i < read.hits.size(); ++i) {
            CHECK(std::memcmp(&read.hits[i].t, &written.hits[i].t, 4) == 0);
            CHECK(read.hits[i].prim == written.hits[i].prim);
        }
        REQUIRE(read.normals.size() == written.normals.size());
        for (std::size_t i = 0; i < read.normals.size(); ++i)
            CHECK(read.normals[i] == written.normals[i]);

        // Per-channel formats as embree_ref reads them.
        auto in = OIIO::ImageInput::open(path.string());
        REQUIRE(in);
        const OIIO::ImageSpec& spec = in->spec();
        CHECK(spec.channelformat(spec.channelindex("Z")) == OIIO::TypeDesc::FLOAT);
        CHECK(spec.channelformat(spec.channelindex("prim_id")) == OIIO::TypeDesc::UINT);
        CHECK(spec.nchannels == (with_normals ? 5 : 2));

        // oiiotool, the tool a person reaches for, lists the channels too.
        const fs::path info = dir.path / "info.txt";
        const std::string command =
            "oiiotool --info -v '" + path.string() + "' > '" + info.string() + "' 2>&1";
        REQUIRE(std::system(command.c_str()) == 0);
        std::ifstream text(info);
        const std::string listing((std::istreambuf_iterator<char>(text)), {});
        CHECK(listing.find("Z (float)") != std::string::npos);
        CHECK(listing.find("prim_id (uint)") != std::string::npos);
        CHECK((listing.find("N.X") != std::string::npos) == with_normals);
    }
}

TEST_CASE("PNG holds sRGB-encoded 8-bit values; EXR holds the linear floats") {
    TempDir dir("png");
    // Black, the linear segment, its knee, mid grey, white, and out-of-range values that clamp.
    const std::vector<float> linear = {0.0f, 0.001f, 0.0031308f, 0.18f, 0.5f,
                                       1.0f, 2.0f,   -1.0f,      0.05f};
    const std::vector<int> expected = {0, 3, 10, 118, 188, 255, 255, 0, 63};
    Image image;
    image.width = 3;
    image.height = 3;
    for (float v : linear) image.rgb.insert(image.rgb.end(), {v, v, v});

    write_image(dir.path / "frame.png", image);
    auto in = OIIO::ImageInput::open((dir.path / "frame.png").string());
    REQUIRE(in);
    REQUIRE(in->spec().nchannels == 3);
    std::vector<std::uint8_t> pixels(27);
    REQUIRE(in->read_image(0, 0, 0, 3, OIIO::TypeDesc::UINT8, pixels.data()));
    for (std::size_t i = 0; i < linear.size(); ++i) {
        CAPTURE(linear[i]);
        CHECK(int(pixels[3 * i]) == expected[i]);
    }

    // The render file's "display": clamp is the bytes above; filmic is sRGB(Narkowicz(x)),
    // evaluated apart in Python (double); an EXR stays linear under either.
    CHECK(encode_image(dir.path / "c.png", image, 0.0f, DisplayTransform::clamp) ==
          encode_image(dir.path / "c.png", image));
    write_image(dir.path / "filmic.png", image, 0.0f, DisplayTransform::filmic);
    const std::vector<int> filmic = {0, 1, 3, 141, 206, 232, 245, 0, 59};
    auto in_filmic = OIIO::ImageInput::open((dir.path / "filmic.png").string());
    REQUIRE(in_filmic);
    REQUIRE(in_filmic->read_image(0, 0, 0, 3, OIIO::TypeDesc::UINT8, pixels.data()));
    for (std::size_t i = 0; i < linear.size(); ++i) {
        CAPTURE(linear[i]);
        CHECK(int(pixels[3 * i]) == filmic[i]);
    }

    write_image(dir.path / "frame.exr", image, 0.0f, DisplayTransform::filmic);
    auto exr = OIIO::ImageInput::open((dir.path / "frame.exr").string());
    REQUIRE(exr);
    std::vector<float> back(27);
    REQUIRE(exr->read_image(0, 0, 0, 3, OIIO::TypeDesc::FLOAT, back.data()));
    CHECK(back == image.rgb);
    // Only the three files: no temporary left behind.
    CHECK(dir.entries().size() == 3);
}

TEST_CASE("failed writes throw, name the path and leave no file") {
    TempDir dir("fail");
    Image image{2, 2, std::vector<float>(12, 0.5f)};
    HitBuffer hits{2, 2, std::vector<KdHit>(4, KdHit{1.0f, 0, 0, 0}), {}};

    const fs::path missing = dir.path / "no such dir" / "frame.png";
    CHECK_THROWS_WITH_AS(write_image(missing, image), doctest::Contains(missing.string().c_str()),
                         Error);
    CHECK_THROWS_AS(write_aov(dir.path / "no such dir" / "hits.exr", hits), Error);
    // The target is a directory: the temporary file is written, the rename fails, and the
    // temporary must be removed.
    fs::create_directory(dir.path / "taken.png");
    CHECK_THROWS_WITH_AS(write_image(dir.path / "taken.png", image),
                         doctest::Contains((dir.path / "taken.png").string().c_str()), Error);
    // Formats kdray does not write (it writes .png, .jpg, .tif and .exr), and an AOV that is
    // not OpenEXR.
    CHECK_THROWS_WITH_AS(write_image(dir.path / "frame.bmp", image),
                         doctest::Contains("unknown image extension '.bmp'"), Error);
    CHECK_THROWS_AS(write_aov(dir.path / "hits.png", hits), Error);
    // A buffer whose size does not match its dimensions.
    CHECK_THROWS_AS(write_image(dir.path / "bad.png", Image{3, 2, std::vector<float>(12)}), Error);
    CHECK(dir.entries() == std::vector<std::string>{"taken.png"});
    CHECK_THROWS_AS(read_aov(dir.path / "absent.exr"), Error);
}

}  // namespace kdray
