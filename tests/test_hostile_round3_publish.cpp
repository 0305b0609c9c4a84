// test_hostile_round3_publish.cpp — issue #29, problem 16: a frame's files (image, AOV, heat map)
// are put into place as one. When the folder changes under the run so that a later file cannot
// be renamed into place, the files already renamed get their earlier versions back: kdray never
// deletes a frame's earlier image that the folder's stats.json lists; and problem 10: a stats.json
// is read within a budget of its own. Each runs the binary.
#include <doctest/doctest.h>
#include <fcntl.h>
#include <linux/fs.h>
#include <sys/ioctl.h>
#include <unistd.h>

#include <filesystem>
#include <string>
#include <vector>

#include "core/run/render_stats.h"
#include "tests/support.h"

namespace fs = std::filesystem;
using namespace kdray::test;

namespace {

// Runs that should end at once get 60 s: a hang fails the test instead of stalling CI.
constexpr int kNoHang = 60;

const char* kTriangleObj = "v 0 0 0\nv 1 0 0\nv 0 1 0\nf 1 2 3\n";
const char* kTinyRender =
    R"({"image":{"width":16,"height":12},"camera":{"position":[0.3,0.3,2],"look_at":[0.3,0.3,0]}})";

CommandResult render(const fs::path& obj, const fs::path& out, const fs::path& camera,
                     std::vector<std::string> extra = {}) {
    std::vector<std::string> args = {"render",   obj.string(),    "-o",        out.string(),
                                     "--camera", camera.string(), "--builder", "reference",
                                     "--tracer", "reference",     "-q"};
    args.insert(args.end(), extra.begin(), extra.end());
    return run_kdray(args, kNoHang);
}

/// Sets or clears `path`'s immutable attribute (chattr +i): a regular file that no rename can
/// replace, which kdray's checks before a frame's writes accept. False where it cannot be set
/// (not root, a file system without the attribute).
bool set_immutable(const fs::path& path, bool on) {
    const int fd = ::open(path.c_str(), O_RDONLY | O_CLOEXEC);
    if (fd < 0) return false;
    int flags = 0;
    bool ok = ::ioctl(fd, FS_IOC_GETFLAGS, &flags) == 0;
    if (ok) {
        flags = on ? (flags | FS_IMMUTABLE_FL) : (flags & ~FS_IMMUTABLE_FL);
        ok = ::ioctl(fd, FS_IOC_SETFLAGS, &flags) == 0;
    }
    ::close(fd);
    return ok;
}

}  // namespace

TEST_CASE("an AOV that cannot be renamed into place puts the frame's earlier image back") {
    // The AOV made immutable after kdray's checks would have passed (the folder changed under
    // the run): the image was renamed over the earlier run's, then the AOV's rename failed and
    // the new image was deleted, leaving the frame without an image while stats.json listed it.
    // Now the earlier image is put back, byte for byte, and the error names the AOV.
    const fs::path dir = fresh_temp_dir("round3-publish");
    const fs::path camera = write_text_file(dir / "small.json", kTinyRender);
    const fs::path obj = write_text_file(dir / "tri.obj", kTriangleObj);
    const fs::path out = dir / "out";
    REQUIRE(render(obj, out, camera, {"--aov"}).status == 0);
    const std::string image = read_file(out / "tri.png");
    const std::string stats = read_file(out / "stats.json");
    REQUIRE(!image.empty());
    if (!set_immutable(out / "tri.aov.exr", true)) {
        MESSAGE("skipped: cannot make a file immutable here (needs root on ext4, xfs, btrfs)");
        fs::remove_all(dir);
        return;
    }
    // Another camera: the new image differs from the earlier one, so a kept new image fails.
    const fs::path moved = write_text_file(
        dir / "moved.json",
        R"({"image":{"width":16,"height":12},"camera":{"position":[0.1,0.1,1],"look_at":[0.1,0.1,0]}})");
    const CommandResult r = render(obj, out, moved, {"--aov", "--heatmap"});
    set_immutable(out / "tri.aov.exr", false);
    check_error(r, 1, {"tri.aov.exr", "tri.png is as it was"});
    CHECK(read_file(out / "tri.png") == image);
    CHECK(read_file(out / "stats.json") == stats);
    // The heat map, renamed after the AOV, was never put in place; no temporary stays behind.
    CHECK_FALSE(fs::exists(out / "tri.cost.png"));
    for (const fs::directory_entry& entry : fs::directory_iterator(out))
        CHECK_MESSAGE(entry.path().filename().string().find(".kdray.tmp@") == std::string::npos,
                      entry.path());
    fs::remove_all(dir);
}

TEST_CASE("an AOV name too long for the folder fails the frame before anything is written") {
    // A 248-byte stem: tri.png fits the 255-byte NAME_MAX, the AOV's name (stem + ".aov.exr",
    // 256 bytes) does not. The image's rename succeeded and the AOV's failed, which deleted the
    // earlier run's image; the names are now checked before any file is written. Needs no root.
    const fs::path dir = fresh_temp_dir("round3-publish-long");
    const fs::path camera = write_text_file(dir / "small.json", kTinyRender);
    const std::string stem(248, 'n');
    const fs::path obj = write_text_file(dir / (stem + ".obj"), kTriangleObj);
    const fs::path out = dir / "out";
    REQUIRE(render(obj, out, camera).status == 0);
    const std::string image = read_file(out / (stem + ".png"));
    const std::string stats = read_file(out / "stats.json");
    REQUIRE(!image.empty());
    check_error(render(obj, out, camera, {"--aov"}), 1, {stem + ".aov.exr", "name too long"});
    CHECK(read_file(out / (stem + ".png")) == image);
    CHECK(read_file(out / "stats.json") == stats);
    fs::remove_all(dir);
}

TEST_CASE("a stats.json past the stats budget is refused before a run renders, naming it") {
    // A 48 MB stats.json took 1.4 GB to parse and merge (std::bad_alloc, exit 134, under a
    // memory limit), and the only bound was a quarter of the machine's memory. One byte past
    // kMaxStatsBytes (a sparse file: nothing is written) is refused by its size, unread, by a
    // run into the folder and by `kdray stats`.
    const fs::path dir = fresh_temp_dir("round3-stats-budget");
    const fs::path camera = write_text_file(dir / "small.json", kTinyRender);
    const fs::path obj = write_text_file(dir / "tri.obj", kTriangleObj);
    const fs::path out = dir / "out";
    fs::create_directories(out);
    {
        const int fd = ::open((out / "stats.json").c_str(), O_WRONLY | O_CREAT | O_CLOEXEC, 0644);
        REQUIRE(fd >= 0);
        REQUIRE(::ftruncate(fd, off_t(kdray::kMaxStatsBytes + 1)) == 0);
        ::close(fd);
    }
    const std::string size = std::to_string(kdray::kMaxStatsBytes + 1) + " bytes, more than the ";
    check_error(render(obj, out, camera), 1, {"stats.json: " + size, "move it away"});
    CHECK_FALSE(fs::exists(out / "tri.png"));
    check_error(run_kdray({"stats", out.string()}, kNoHang), 1, {"stats.json: " + size});
    CHECK(fs::file_size(out / "stats.json") == kdray::kMaxStatsBytes + 1);
    fs::remove_all(dir);
}
