// The shared pieces of core/ that the structure change made one: the polygon clipping of
// core/device/kd_clip.h (host and device alike) against closed forms, and the one atomic file
// writer of core/io/atomic_file.h (a failed write leaves neither the file nor its temporary
// behind).
#include <doctest/doctest.h>

#include <filesystem>
#include <fstream>
#include <iterator>
#include <string>

#include "core/error.h"
#include "core/io/atomic_file.h"

#define KDRAY_CLIP_REAL double
#include "core/device/kd_clip.h"
#include "tests/support.h"

namespace kdray {
namespace {

namespace fs = std::filesystem;
using test::read_file;

fs::path fresh_dir(const std::string& name) {
    const fs::path dir = fs::temp_directory_path() / ("kdray_test_" + name);
    fs::remove_all(dir);
    fs::create_directories(dir);
    return dir;
}

}  // namespace

TEST_CASE("kd_clip_polygon_to_plane keeps the inner side, with crossings exactly on the plane") {
    // The unit square in z = 0, cut by x = 0.25: above keeps [0.25, 1] x [0, 1], below the rest.
    const double square[4][3] = {{0, 0, 0}, {1, 0, 0}, {1, 1, 0}, {0, 1, 0}};
    double out[5][3];
    kd_u32 n = kd_clip_polygon_to_plane(square, 4, 0, 0.25, 1, out);
    REQUIRE(n == 4);
    const double above[4][3] = {{0.25, 0, 0}, {1, 0, 0}, {1, 1, 0}, {0.25, 1, 0}};
    for (kd_u32 i = 0; i < n; ++i)
        for (int k = 0; k < 3; ++k) CHECK(out[i][k] == above[i][k]);
    n = kd_clip_polygon_to_plane(square, 4, 0, 0.25, 0, out);
    REQUIRE(n == 4);
    const double below[4][3] = {{0, 0, 0}, {0.25, 0, 0}, {0.25, 1, 0}, {0, 1, 0}};
    for (kd_u32 i = 0; i < n; ++i)
        for (int k = 0; k < 3; ++k) CHECK(out[i][k] == below[i][k]);

    // A triangle that loses a corner gains one: (0,0) (2,0) (0,2) kept below y = 1.5 is the
    // quadrilateral (0,0) (2,0) (0.5,1.5) (0,1.5).
    const double tri[3][3] = {{0, 0, 0}, {2, 0, 0}, {0, 2, 0}};
    n = kd_clip_polygon_to_plane(tri, 3, 1, 1.5, 0, out);
    REQUIRE(n == 4);
    CHECK(out[2][0] == doctest::Approx(0.5));
    CHECK(out[2][1] == 1.5);
    CHECK(out[3][0] == 0.0);
    CHECK(out[3][1] == 1.5);

    // Wholly outside: nothing. Touching the plane at a corner: only that corner (perhaps
    // repeated), which is inside.
    CHECK(kd_clip_polygon_to_plane(tri, 3, 2, 1.0, 1, out) == 0);
    n = kd_clip_polygon_to_plane(tri, 3, 0, 2.0, 1, out);
    REQUIRE(n >= 1);
    for (kd_u32 i = 0; i < n; ++i) {
        CHECK(out[i][0] == 2.0);
        CHECK(out[i][1] == 0.0);
    }
}

TEST_CASE("write_atomically: the file appears whole, and a failed write leaves nothing") {
    const fs::path dir = fresh_dir("atomic");
    const fs::path target = dir / "frame.png";
    write_file_atomically(target, "first");
    CHECK(read_file(target) == "first");
    write_file_atomically(target, "second");
    CHECK(read_file(target) == "second");

    // A writer that fails after creating its temporary: the old file stays, no temporary remains.
    CHECK_THROWS_AS(write_atomically(target,
                                     [](const fs::path& temp) {
                                         std::ofstream(temp) << "half";
                                         throw Error("disk full");
                                     }),
                    Error);
    CHECK(read_file(target) == "second");
    CHECK(std::distance(fs::directory_iterator(dir), fs::directory_iterator()) == 1);

    // The temporary is hidden, beside the target, and keeps its extension for OpenImageIO.
    const fs::path temp = temporary_path(target);
    CHECK(temp.parent_path() == dir);
    CHECK(temp.filename().string().front() == '.');
    CHECK(temp.extension() == ".png");

    // A folder that does not exist: an Error naming the target.
    try {
        write_file_atomically(dir / "missing" / "stats.json", "{}");
        FAIL("no error");
    } catch (const Error& e) {
        CHECK(std::string(e.what()).find("stats.json") != std::string::npos);
    }
    fs::remove_all(dir);
}

}  // namespace kdray
