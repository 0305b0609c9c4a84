// `kdray compare` and core/io/image_compare.h, what scripts/device-check.sh decides a device's
// correctness by: the agreement of conventions.md counted pixel by pixel (a NaN Z or an image NaN
// must disagree, never pass), and the exit status a script reads.
#include <doctest/doctest.h>

#include <cmath>
#include <limits>

#include "core/error.h"
#include "core/io/image.h"
#include "core/io/image_compare.h"
#include "tests/support.h"

using namespace kdray;
using namespace kdray::test;

namespace {

struct PixelHit {
    float t;
    kd_u32 prim;
};

/// One row of hits; the comparison reads only t and the triangle id.
HitBuffer buffer(const std::vector<PixelHit>& pixels) {
    HitBuffer b;
    b.width = int(pixels.size());
    b.height = 1;
    for (const PixelHit& p : pixels) b.hits.push_back(KdHit{p.t, p.prim, 0.0f, 0.0f});
    return b;
}

const float kInf = std::numeric_limits<float>::infinity();

}  // namespace

TEST_CASE("hit AOVs agree as conventions.md says, pixel by pixel") {
    const HitBuffer reference = buffer({{10.0f, 1},
                                        {kInf, KDRAY_NO_HIT},
                                        {0.5f, 2},
                                        {100.0f, 3},
                                        {kInf, KDRAY_NO_HIT},
                                        {2.0f, 4},
                                        {3.0f, 5}});
    // Z within 1e-4 max(1, Z); another triangle at the same Z (a tie); a hit beyond the
    // tolerance at Z = 100 (0.011 > 0.01); a leak; a hit where the reference misses; a NaN Z.
    const HitBuffer device = buffer({{10.0009f, 1},
                                     {kInf, KDRAY_NO_HIT},
                                     {0.5f, 7},
                                     {100.011f, 3},
                                     {1.0f, 9},
                                     {kInf, KDRAY_NO_HIT},
                                     {std::nanf(""), 5}});
    const AovComparison r = compare_aovs(device, reference);
    CHECK(r.pixels == 7);
    CHECK(r.both_miss == 1);
    CHECK(r.only_a_hits == 1);
    CHECK(r.only_b_hits == 1);
    CHECK(r.both_hit == 4);
    CHECK(r.prim_differs == 1);
    CHECK(r.z_differs == 2);
    CHECK(r.mismatches == 4);
    CHECK(r.mismatch_fraction == doctest::Approx(4.0 / 7.0));
    CHECK(compare_aovs(reference, reference).mismatches == 0);
    CHECK_THROWS_AS(compare_aovs(device, buffer({{1.0f, 1}})), Error);
}

TEST_CASE("kdray compare: AOVs and images, JSON, and exit 1 when they disagree") {
    const auto dir = fresh_temp_dir("compare");
    const HitBuffer reference = buffer({{1.0f, 0}, {2.0f, 1}, {kInf, KDRAY_NO_HIT}, {4.0f, 3}});
    HitBuffer device = reference;
    write_aov(dir / "ref.aov.exr", reference);
    write_aov(dir / "same.aov.exr", device);
    device.hits[3] = {kInf, KDRAY_NO_HIT, 0.0f, 0.0f};
    write_aov(dir / "leak.aov.exr", device);

    CommandResult same = run_kdray(
        {"compare", (dir / "same.aov.exr").string(), (dir / "ref.aov.exr").string(), "--json"});
    CHECK(same.status == 0);
    CHECK(same.out.find("\"kind\": \"aov\"") != std::string::npos);
    CHECK(same.out.find("\"agree\": true") != std::string::npos);
    CommandResult leak = run_kdray(
        {"compare", (dir / "leak.aov.exr").string(), (dir / "ref.aov.exr").string(), "--json"});
    CHECK(leak.status == 1);
    CHECK(leak.out.find("\"only_b_hits\": 1") != std::string::npos);
    CHECK(leak.err.find("disagree") != std::string::npos);
    // One pixel in four may disagree.
    CHECK(run_kdray({"compare", (dir / "leak.aov.exr").string(), (dir / "ref.aov.exr").string(),
                     "--max-fraction", "0.25"})
              .status == 0);

    Image a{2, 1, {0.5f, 0.5f, 0.5f, 0.25f, 0.25f, 0.25f}};
    Image b = a;
    b.rgb[4] = 0.26f;
    write_image(dir / "a.exr", a);
    write_image(dir / "b.exr", b);
    const ImageComparison r = compare_image_files(dir / "a.exr", dir / "b.exr", 0.001);
    CHECK(r.pixels == 2);
    CHECK(r.pixels_over == 1);
    CHECK(r.max_abs_difference == doctest::Approx(0.01));
    CommandResult images =
        run_kdray({"compare", (dir / "a.exr").string(), (dir / "b.exr").string(), "--json"});
    CHECK(images.status == 1);
    CHECK(images.out.find("\"kind\": \"image\"") != std::string::npos);
    CHECK(run_kdray({"compare", (dir / "a.exr").string(), (dir / "b.exr").string(), "--tolerance",
                     "0.02"})
              .status == 0);
    CHECK(run_kdray({"compare", (dir / "a.exr").string(), (dir / "missing.exr").string()}).status ==
          2);
}
