// test_hostile_input.cpp — input a hostile or unlucky user gives kdray: FIFOs and devices where a
// file should be, outputs that are device nodes or links, corrupt tree files, MTL files with
// impossible values, NaN build parameters, names at the file system's length limit, temporaries
// a killed run left behind. Each runs the binary: one `kdray: error:` line naming the file, exit 1
// (2 for usage), nothing hangs, nothing the user owns is replaced.
#include <doctest/doctest.h>
#include <fcntl.h>
#include <sys/file.h>
#include <sys/stat.h>
#include <sys/types.h>
#include <unistd.h>

#include <algorithm>
#include <cmath>
#include <cstring>
#include <filesystem>
#include <fstream>
#include <iterator>
#include <random>
#include <string>
#include <vector>

#include "core/device/kd_shared.h"
#include "core/io/atomic_file.h"
#include "core/io/image_codec.h"
#include "core/tree/tree_file.h"
#include "tests/support.h"

namespace fs = std::filesystem;
using namespace kdray::test;

namespace {

const char* kTriangleObj = "v 0 0 0\nv 1 0 0\nv 0 1 0\nf 1 2 3\n";
const char* kTinyRender =
    R"({"image":{"width":16,"height":12},"camera":{"position":[0.3,0.3,3],"look_at":[0.3,0.3,0]}})";
// Runs that should end at once get 30 s: a hang fails the test instead of stalling CI.
constexpr int kNoHang = 30;

CommandResult render(const fs::path& obj, const fs::path& out, const fs::path& camera,
                     std::vector<std::string> extra = {}) {
    std::vector<std::string> args = {"render",   obj.string(),    "-o",        out.string(),
                                     "--camera", camera.string(), "--builder", "reference",
                                     "--tracer", "reference",     "-q"};
    args.insert(args.end(), extra.begin(), extra.end());
    return run_kdray(args, kNoHang);
}

}  // namespace

TEST_CASE("inputs that are not regular files are refused at once, never read or waited on") {
    const fs::path dir = fresh_temp_dir("hostile-inputs");
    const fs::path camera = write_text_file(dir / "small.json", kTinyRender);
    const fs::path tri = write_text_file(dir / "tri.obj", kTriangleObj);
    const fs::path fifo = dir / "f.obj";
    REQUIRE(::mkfifo(fifo.c_str(), 0600) == 0);

    SUBCASE("an OBJ that is a FIFO (it would block the loader for ever)") {
        check_error(render(fifo, dir / "out", camera), 1, {"f.obj", "not a regular file", "FIFO"});
    }
    SUBCASE("a render file that is a FIFO") {
        const fs::path json_fifo = dir / "r.json";
        REQUIRE(::mkfifo(json_fifo.c_str(), 0600) == 0);
        check_error(render(tri, dir / "out", json_fifo), 1, {"r.json", "not a regular file"});
    }
    SUBCASE("an mtllib naming a FIFO") {
        const fs::path mtl_fifo = dir / "m.mtl";
        REQUIRE(::mkfifo(mtl_fifo.c_str(), 0600) == 0);
        const fs::path obj =
            write_text_file(dir / "m.obj", std::string("mtllib m.mtl\n") + kTriangleObj);
        check_error(render(obj, dir / "out", camera), 1,
                    {"m.obj:1", "m.mtl", "not a regular file"});
    }
    SUBCASE("an mtllib naming a directory") {
        fs::create_directories(dir / "lib.mtl");
        const fs::path obj =
            write_text_file(dir / "d.obj", std::string("mtllib lib.mtl\n") + kTriangleObj);
        check_error(render(obj, dir / "out", camera), 1,
                    {"d.obj:1", "lib.mtl", "not a regular file"});
    }
    SUBCASE("an OBJ and a render file that are links to /dev/zero (unbounded bytes)") {
        fs::create_symlink("/dev/zero", dir / "zero.obj");
        fs::create_symlink("/dev/zero", dir / "zero.json");
        check_error(render(dir / "zero.obj", dir / "out", camera), 1,
                    {"zero.obj", "character device"});
        check_error(render(tri, dir / "out", dir / "zero.json"), 1,
                    {"zero.json", "character device"});
        check_error(run_kdray({"stats", (dir / "zero.obj").string()}, kNoHang), 1, {"zero.obj"});
    }
    CHECK_FALSE(fs::exists(dir / "out" / "stats.json"));
    fs::remove_all(dir);
}

TEST_CASE("an output that is a device node, a link or a directory is refused and left as it is") {
    const fs::path dir = fresh_temp_dir("hostile-outputs");
    const fs::path tri = write_text_file(dir / "tri.obj", kTriangleObj);
    const fs::path target = write_text_file(dir / "precious.txt", "keep me");
    fs::create_symlink(target, dir / "link.kdt");
    fs::create_symlink("/dev/null", dir / "null.kdt");
    for (const char* name : {"link.kdt", "null.kdt"}) {
        const fs::path out = dir / name;
        check_error(run_kdray({"build", tri.string(), "--builder", "reference", "-o", out.string()},
                              kNoHang),
                    1, {name, "symbolic link", "replaces only regular files"});
        CHECK(fs::is_symlink(fs::symlink_status(out)));
    }
    CHECK(read_file(target) == "keep me");
    CHECK(fs::is_character_file("/dev/null"));
    // A folder named like an output (stats.json): said plainly, not "Success".
    const fs::path camera = write_text_file(dir / "small.json", kTinyRender);
    fs::create_directories(dir / "out" / "stats.json");
    const CommandResult r = render(tri, dir / "out", camera);
    CHECK(r.status == 1);
    CHECK(r.err.find("stats.json: exists and is a directory") != std::string::npos);
    fs::remove_all(dir);
}

TEST_CASE("a corrupt tree file is refused with its name; every corruption is caught") {
    const fs::path dir = fresh_temp_dir("hostile-tree");
    const fs::path tri = write_text_file(dir / "quad.obj",
                                         "v 0 0 0\nv 1 0 0\nv 1 1 0\nv 0 1 0\nv 0 0 1\nf 1 2 3\n"
                                         "f 1 3 4\nf 1 2 5\nf 2 3 5\n");
    const fs::path tree = dir / "t.kdt";
    REQUIRE(
        run_kdray({"build", tri.string(), "--builder", "reference", "-o", tree.string()}).status ==
        0);
    const std::string good = read_file(tree);
    REQUIRE(run_kdray({"stats", tree.string()}).status == 0);
    // 40 random single-byte changes (a flipped bit, a random byte), then truncations: none
    // may pass as a tree.
    std::mt19937 rng(17);
    int refused = 0;
    for (int i = 0; i < 40; ++i) {
        std::string bad = good;
        const std::size_t at = rng() % bad.size();
        bad[at] = char(i % 2 ? bad[at] ^ (1 << (rng() % 8)) : char(bad[at] + 1 + rng() % 255));
        const fs::path corrupt = write_text_file(dir / "bad.kdt", bad);
        const CommandResult r = run_kdray({"stats", corrupt.string(), "--json"}, kNoHang);
        INFO("byte " << at << ": " << r.err);
        CHECK(r.status == 1);
        CHECK(r.err.find("bad.kdt") != std::string::npos);
        refused += r.status == 1;
    }
    CHECK(refused == 40);
    for (std::size_t keep : {std::size_t(0), std::size_t(10), good.size() / 2, good.size() - 1}) {
        const fs::path cut = write_text_file(dir / "cut.kdt", good.substr(0, keep));
        check_error(run_kdray({"stats", cut.string()}, kNoHang), 1, {"cut.kdt"});
    }
    fs::remove_all(dir);
}

TEST_CASE(
    "a tree file with a sound checksum but an invalid tree is refused, named, with the fault") {
    // The checksum catches damage; a file written with a broken tree and a checksum to match
    // (another program, a bug in a builder) must still fail on what it holds. Each case patches
    // one value of a valid file and recomputes the checksum as tree_file.cpp does.
    const fs::path dir = fresh_temp_dir("hostile-tree-content");
    const fs::path obj = write_obj(dir / "scene.obj", random_triangles(200, 3));
    const fs::path tree_path = dir / "t.kdt";
    const CommandResult built =
        run_kdray({"build", obj.string(), "--builder", "reference", "-o", tree_path.string()});
    REQUIRE_MESSAGE(built.status == 0, built.err);
    const std::string good = read_file(tree_path);
    const kdray::KdTree tree = kdray::read_tree_file(tree_path).tree;
    REQUIRE(tree.nodes.size() > 1);
    REQUIRE(!kd_node_is_leaf(tree.nodes[0]));
    // The file ends with the nodes (a count, 8 bytes each), the leaf indices (a count, 4 bytes
    // each) and the 8-byte checksum; it starts with the magic, the version, the scene's path,
    // its triangle count and hash, the builder's name, then the parameters, C_t first.
    const std::size_t checksum_at = good.size() - 8;
    const std::size_t indices_at = checksum_at - 4 * tree.leaf_indices.size();
    const std::size_t nodes_at = indices_at - 8 - 8 * tree.nodes.size();
    auto u32_at = [&](std::size_t at) {
        std::uint32_t v = 0;
        std::memcpy(&v, good.data() + at, 4);
        return v;
    };
    const std::size_t builder_at = 12 + 4 + u32_at(12) + 8 + 8;
    const std::size_t traversal_cost_at = builder_at + 4 + u32_at(builder_at);
    std::size_t filled_leaf = 0;
    while (!kd_node_is_leaf(tree.nodes[filled_leaf]) || kd_leaf_count(tree.nodes[filled_leaf]) == 0)
        ++filled_leaf;
    struct Patch {
        const char* what;
        std::size_t at;
        std::uint32_t value;
        std::string problem;
    };
    float negative_cost = -15.0f;
    std::uint32_t negative_cost_bits = 0;
    std::memcpy(&negative_cost_bits, &negative_cost, 4);
    const std::size_t nodes = tree.nodes.size();
    const std::vector<Patch> patches = {
        {"a leaf index of 4294967295", indices_at, 0xFFFFFFFFu,
         "lists triangle 4294967295 of a scene of 200"},
        {"the root's above child past the last node", nodes_at + 4,
         std::uint32_t(nodes << 2) | kd_node_axis(tree.nodes[0]),
         "node 0 has above child " + std::to_string(nodes)},
        {"a leaf whose run ends past the leaf indices", nodes_at + 8 * filled_leaf,
         std::uint32_t(tree.leaf_indices.size() + 1),
         "leaf " + std::to_string(filled_leaf) + " names entries"},
        {"a negative C_t (every SAH cost negative)", traversal_cost_at, negative_cost_bits, "C_t"}};
    for (const Patch& patch : patches) {
        INFO(std::string(patch.what));
        std::string bad = good;
        std::memcpy(bad.data() + patch.at, &patch.value, 4);
        const std::uint64_t checksum =
            kdray::tree_file_checksum(std::string_view(bad.data(), checksum_at));
        std::memcpy(bad.data() + checksum_at, &checksum, 8);
        const fs::path file = write_text_file(dir / "patched.kdt", bad);
        check_error(run_kdray({"stats", file.string(), "--builder", "reference"}, kNoHang), 1,
                    {"patched.kdt", patch.problem});
    }
    fs::remove_all(dir);
}

TEST_CASE("inputs past their size limit are refused from their size, before any byte is read") {
    // Sparse files: the sizes cost no disk. A render file is read up to 64 MiB, an MTL file up to
    // 256 MiB (input_file.h's callers); an OBJ up to a quarter of the machine's memory, so one
    // of 1 TiB is past it anywhere, and reading it would fail on memory, not on its size.
    const fs::path dir = fresh_temp_dir("hostile-size");
    const fs::path camera = write_text_file(dir / "small.json", kTinyRender);
    const fs::path tri = write_text_file(dir / "tri.obj", kTriangleObj);
    auto sparse = [&](const fs::path& path, std::uintmax_t bytes) {
        std::ofstream(path).close();
        fs::resize_file(path, bytes);
        REQUIRE(fs::file_size(path) == bytes);
        return path;
    };
    const std::uintmax_t render_limit = std::uintmax_t(64) << 20;
    const std::uintmax_t mtl_limit = std::uintmax_t(256) << 20;
    check_error(render(tri, dir / "out", sparse(dir / "huge.json", render_limit + 1)), 1,
                {"huge.json: " + std::to_string(render_limit + 1) + " bytes, more than the " +
                 std::to_string(render_limit) + " bytes kdray reads of one render file"});
    sparse(dir / "huge.mtl", mtl_limit + 1);
    const fs::path obj =
        write_text_file(dir / "m.obj", std::string("mtllib huge.mtl\n") + kTriangleObj);
    check_error(render(obj, dir / "out", camera), 1,
                {"huge.mtl: " + std::to_string(mtl_limit + 1) + " bytes, more than the " +
                 std::to_string(mtl_limit) + " bytes kdray reads of one MTL file"});
    const std::uintmax_t tebibyte = std::uintmax_t(1) << 40;
    check_error(render(sparse(dir / "huge.obj", tebibyte), dir / "out", camera), 1,
                {"huge.obj: " + std::to_string(tebibyte) + " bytes, more than the "});
    CHECK_FALSE(fs::exists(dir / "out" / "stats.json"));
    fs::remove_all(dir);
}

TEST_CASE("a frame whose AOV cannot be written leaves neither its image nor a record") {
    // A directory where the AOV goes makes its write fail, as a full disk would, without root.
    // The frame's image must not stay without it, nor replace an earlier run's.
    const fs::path dir = fresh_temp_dir("hostile-aov");
    const fs::path camera = write_text_file(dir / "small.json", kTinyRender);
    const fs::path a = write_text_file(dir / "in" / "a.obj", kTriangleObj);
    const fs::path b = write_text_file(dir / "in" / "b.obj", kTriangleObj);
    fs::create_directories(dir / "one" / "a.aov.exr");
    check_error(render(a, dir / "one", camera, {"--aov"}), 1, {"a.aov.exr", "directory"});
    CHECK_FALSE(fs::exists(dir / "one" / "a.png"));
    CHECK_FALSE(fs::exists(dir / "one" / "stats.json"));
    // Rendered again, now with its AOV, the frame fails with the earlier run's image as it was
    // (it was written, then removed with the failed AOV) and that run's record kept.
    REQUIRE(render(a, dir / "again", camera).status == 0);
    const std::string earlier = read_file(dir / "again" / "a.png");
    REQUIRE(!earlier.empty());
    fs::create_directories(dir / "again" / "a.aov.exr");
    check_error(render(a, dir / "again", camera, {"--aov"}), 1, {"a.aov.exr", "directory"});
    CHECK(read_file(dir / "again" / "a.png") == earlier);
    CHECK(read_json(dir / "again" / "stats.json")["frames"].size() == 1);
    // A later frame: the run stops at it; the frame before keeps its files and its record.
    fs::create_directories(dir / "two" / "b.aov.exr");
    const CommandResult r = run_kdray(
        {"render", a.string(), b.string(), "-o", (dir / "two").string(), "--camera",
         camera.string(), "--aov", "--builder", "reference", "--tracer", "reference", "-q"},
        kNoHang);
    INFO(r.err);
    CHECK(r.status == 1);
    CHECK(r.err.find("b.aov.exr") != std::string::npos);
    CHECK(fs::exists(dir / "two" / "a.png"));
    CHECK(fs::exists(dir / "two" / "a.aov.exr"));
    CHECK_FALSE(fs::exists(dir / "two" / "b.png"));
    const nlohmann::json stats = read_json(dir / "two" / "stats.json");
    REQUIRE(stats["frames"].size() == 1);
    CHECK(stats["frames"][0]["image"] == "a.png");
    REQUIRE(stats["failed_frames"].size() == 1);
    CHECK(stats["failed_frames"][0]["image"] == "b.png");
    fs::remove_all(dir);
}

TEST_CASE("a face past the triangulation budget: one error line with its line, at once") {
    // One face of 20000 vertices: 20000^2 is past the 2^28 of triangulation work kdray allows
    // (obj_validate.cpp), refused by the pre-scan before tinyobjloader's ear clipping, which
    // would take seconds on it.
    const fs::path dir = fresh_temp_dir("hostile-polygon");
    const fs::path camera = write_text_file(dir / "small.json", kTinyRender);
    std::string text;
    constexpr int kVertices = 20000;
    for (int k = 0; k < kVertices; ++k) {
        const double a = 2 * 3.14159265358979 * k / kVertices;
        text += "v " + std::to_string(std::cos(a)) + " " + std::to_string(std::sin(a)) + " 0\n";
    }
    text += "f";
    for (int k = 1; k <= kVertices; ++k) {
        text += ' ';  // apart: GCC 12's -Wrestrict misreads " " + std::to_string(k)
        text += std::to_string(k);
    }
    text += "\n";
    const fs::path obj = write_text_file(dir / "disc.obj", text);
    check_error(render(obj, dir / "out", camera), 1,
                {"disc.obj:20001: face of 20000 vertices", "2^28"});
    CHECK_FALSE(fs::exists(dir / "out" / "disc.png"));
    fs::remove_all(dir);
}

TEST_CASE("MTL files: values kdray cannot shade are errors with the MTL file and line") {
    const fs::path dir = fresh_temp_dir("hostile-mtl");
    const fs::path camera = write_text_file(dir / "small.json", kTinyRender);
    struct Case {
        const char* statement;
        const char* problem;
    };
    for (const Case& c : {Case{"Kd nan 0 0", "Kd value 'nan'"}, Case{"Kd -5 0 0", "Kd value '-5'"},
                          Case{"Ni -1", "Ni value '-1'"}, Case{"Ni nan", "Ni value 'nan'"},
                          Case{"d 2", "d value '2'"}, Case{"Ks 1e999 0 0", "not a finite number"},
                          Case{"illum 2.5", "illum value '2.5'"}, Case{"Kd 1 2", "Kd expects"}}) {
        INFO(std::string(c.statement));
        write_text_file(dir / "bad.mtl",
                        std::string("newmtl m\nKd 0.5 0.5 0.5\n") + c.statement + "\n");
        const fs::path obj = write_text_file(
            dir / "scene.obj", std::string("mtllib bad.mtl\nusemtl m\n") + kTriangleObj);
        check_error(render(obj, dir / "out", camera), 1, {"bad.mtl:3", c.problem});
    }
    // An absolute mtllib path is the file it names (tinyobjloader would join it to the folder):
    // its red applies. Lit by the headlight alone (no lights, no ambient), red Kd shades the
    // triangle (0, 0, 0) to (1, 0, 0); the grey default would give three equal channels.
    write_text_file(dir / "lib" / "red.mtl", "newmtl red\nKd 1 0 0\n");
    const fs::path obj =
        write_text_file(dir / "abs.obj", "mtllib " + (dir / "lib" / "red.mtl").string() +
                                             "\nusemtl red\n" + kTriangleObj);
    const CommandResult r = render(obj, dir / "out", camera);
    INFO(r.err);
    CHECK(r.status == 0);
    CHECK(r.err.find("warning") == std::string::npos);
    const kdray::DecodedImage image = kdray::read_image(dir / "out" / "abs.png");
    REQUIRE(image.width == 16);
    REQUIRE(image.channels >= 3);
    // The centre pixel looks at (0.3, 0.3, 0), inside the triangle.
    const float* centre = &image.values[std::size_t(6 * 16 + 8) * std::size_t(image.channels)];
    CHECK(centre[0] > 0.1f);
    CHECK(centre[1] == 0.0f);
    CHECK(centre[2] == 0.0f);

    // A missing library, absolute or not, is a warning with the OBJ's line of its mtllib.
    const fs::path gone =
        write_text_file(dir / "gone.obj", "# made by hand\nmtllib " + (dir / "none.mtl").string() +
                                              "\nusemtl red\n" + kTriangleObj);
    const CommandResult missing = render(gone, dir / "out", camera);
    CHECK(missing.status == 0);
    CHECK(missing.err.rfind("kdray: warning: ", 0) == 0);
    CHECK(missing.err.find("gone.obj:2: material library '" + (dir / "none.mtl").string() +
                           "' not found") != std::string::npos);

    // Ni 0 is what BART's exporter writes for opaque materials (26 in the Kitchen, 137 in the
    // Robots), so it is accepted; a material that transmits with it is said, not silent.
    for (const std::string illum : {"2", "7"}) {
        CAPTURE(illum);
        write_text_file(dir / "ni.mtl", "newmtl m\nKd 0.5 0.5 0.5\nNi 0\nillum " + illum + "\n");
        const fs::path ni = write_text_file(
            dir / "ni.obj", std::string("mtllib ni.mtl\nusemtl m\n") + kTriangleObj);
        const CommandResult n = render(ni, dir / "out", camera);
        CHECK(n.status == 0);
        const bool warned = n.err.find(
                                "material 'm' transmits light but has no index of "
                                "refraction") != std::string::npos;
        CHECK(warned == (illum == "7"));
    }
    fs::remove_all(dir);
}

TEST_CASE("NaN and overflowing build parameters are usage errors, on every command") {
    const fs::path dir = fresh_temp_dir("hostile-params");
    const fs::path tri = write_text_file(dir / "tri.obj", kTriangleObj);
    for (const std::vector<std::string>& option : {std::vector<std::string>{"--ct", "nan"},
                                                   {"--ci", "1e39"},
                                                   {"--empty-ratio", "nan"},
                                                   {"--ci", "nan"},
                                                   {"--large-threshold", "0"},
                                                   {"--cost-traversal", "nan"},
                                                   {"--empty-space-ratio", "nan"},
                                                   {"--empty-bonus", "nan"},
                                                   {"--empty-bonus", "1"}}) {
        INFO(option[0] << " " << option[1]);
        std::vector<std::string> args = {"build", tri.string(), option[0], option[1]};
        const CommandResult r = run_kdray(args);
        CHECK(r.status == 2);
        // An alias (--large-threshold, --ct) is named as typed.
        CHECK(r.err.find(option[0]) != std::string::npos);
    }
    fs::remove_all(dir);
}

TEST_CASE("a stem at the file name limit renders; temporaries of a killed run are cleaned") {
    const fs::path dir = fresh_temp_dir("hostile-names");
    const fs::path camera = write_text_file(dir / "small.json", kTinyRender);
    // 246 characters + ".png" is a legal name; its temporary name must still fit.
    const std::string stem(246, 's');
    const fs::path obj = write_text_file(dir / (stem + ".obj"), kTriangleObj);
    const fs::path out = dir / "out";
    CommandResult r = render(obj, out, camera, {"--aov", "--format", "exr"});
    INFO(r.err);
    CHECK(r.status == 0);
    CHECK(fs::exists(out / (stem + ".exr")));
    CHECK(fs::exists(out / (stem + ".aov.exr")));

    // A temporary whose writer no longer runs goes; one that a live writer (this test) holds
    // locked, as kdray's writers hold theirs, stays. temporary_path names them as kdray does on
    // this host, for this process's id.
    const fs::path live = kdray::temporary_path(out / "frame.png");
    // Appended piece by piece: GCC 12 warns falsely (-Wstringop-overflow) on "@" + std::string.
    std::string pid = "@";
    pid += std::to_string(::getpid());
    pid += '@';
    std::string dead_name = live.filename().string();
    dead_name.replace(dead_name.find(pid), pid.size(), "@2147483600@");  // above any pid_max
    write_text_file(out / dead_name, "half");
    write_text_file(live, "in progress");
    const int live_lock = ::open(live.c_str(), O_RDONLY | O_CLOEXEC);
    REQUIRE(live_lock >= 0);
    REQUIRE(::flock(live_lock, LOCK_EX) == 0);
    write_text_file(out / ".user-notes.tmp", "not ours");
    r = render(obj, out, camera);
    ::close(live_lock);
    CHECK(r.status == 0);
    CHECK_FALSE(fs::exists(out / dead_name));
    CHECK(fs::exists(live));
    CHECK(fs::exists(out / ".user-notes.tmp"));
    fs::remove_all(dir);
}

TEST_CASE("a full disk: the run fails naming the file, and no image is left under its name") {
    // A 200 KB tmpfs, nearly filled; mounting needs root (CI runs as root): elsewhere, skipped.
    const fs::path dir = fresh_temp_dir("hostile-full");
    const fs::path mount = dir / "disk";
    fs::create_directories(mount);
    const std::string mount_command =
        "mount -t tmpfs -o size=200k tmpfs '" + mount.string() + "' 2>/dev/null";
    if (::geteuid() != 0 || std::system(mount_command.c_str()) != 0) {
        MESSAGE("skipped: cannot mount a small tmpfs here (needs root)");
        fs::remove_all(dir);
        return;
    }
    write_text_file(mount / "filler", std::string(190 * 1024, 'x'));
    const fs::path camera = write_text_file(
        dir / "big.json",
        R"({"image":{"width":256,"height":256},"camera":{"position":[0.3,0.3,3],"look_at":[0.3,0.3,0]}})");
    const fs::path tri = write_text_file(dir / "room.obj", kTriangleObj);
    const CommandResult r = render(tri, mount / "out", camera, {"--aov"});
    INFO(r.err);
    CHECK(r.status == 1);
    CHECK(r.err.find("room") != std::string::npos);
    CHECK(r.err.find("No space left on device") != std::string::npos);
    // Nothing of the frame under a final name, and no temporary left.
    for (const auto& entry : fs::directory_iterator(mount / "out"))
        CHECK_MESSAGE(false, "left behind: " << entry.path().filename().string());

    // A frame rendered again onto a full disk fails with the earlier run's image as it was.
    fs::remove(mount / "filler");
    const fs::path again = mount / "again";
    REQUIRE(render(tri, again, write_text_file(dir / "small.json", kTinyRender)).status == 0);
    const std::string earlier = read_file(again / "room.png");
    REQUIRE(!earlier.empty());
    write_text_file(mount / "filler", std::string(200 * 1024, 'x'));  // what fits: the disk full
    const CommandResult full = render(tri, again, camera, {"--aov", "--overwrite"});
    CHECK(full.status == 1);
    CHECK(read_file(again / "room.png") == earlier);
    CHECK_FALSE(fs::exists(again / "room.aov.exr"));
    CHECK(read_json(again / "stats.json")["frames"].size() == 1);
    CHECK(std::system(("umount '" + mount.string() + "'").c_str()) == 0);
    fs::remove_all(dir);
}

TEST_CASE("two inputs that would write one file are a usage error naming both, before any frame") {
    const fs::path dir = fresh_temp_dir("hostile-collide");
    const fs::path camera = write_text_file(dir / "small.json", kTinyRender);
    write_text_file(dir / "A" / "scene.obj", kTriangleObj);
    write_text_file(dir / "B" / "scene.obj", kTriangleObj);
    write_text_file(dir / "x.obj", kTriangleObj);
    write_text_file(dir / "x.OBJ", kTriangleObj);
    write_text_file(dir / "a.obj", kTriangleObj);
    write_text_file(dir / "a.aov.obj", kTriangleObj);
    const fs::path out = dir / "out";
    auto run = [&](std::vector<std::string> inputs, std::vector<std::string> extra = {}) {
        std::vector<std::string> args = {"render"};
        for (const std::string& in : inputs) args.push_back((dir / in).string());
        args.insert(args.end(), {"-o", out.string(), "--camera", camera.string(), "--builder",
                                 "reference", "--tracer", "reference", "-q"});
        args.insert(args.end(), extra.begin(), extra.end());
        return run_kdray(args, kNoHang);
    };
    check_error(run({"A/scene.obj", "B/scene.obj"}), 2,
                {"A/scene.obj", "B/scene.obj", "scene.png"});
    check_error(run({"x.obj", "x.OBJ"}), 2, {"x.obj", "x.OBJ"});
    check_error(run({"x.obj", "./x.obj"}), 2, {"x.obj", "would both write"});
    check_error(run({"a.obj", "a.aov.obj"}, {"--aov", "--format", "exr"}), 2, {"a.aov.exr"});
    CHECK_FALSE(fs::exists(out));
    fs::remove_all(dir);
}

TEST_CASE("an interpolated camera without a basis is refused before the first frame") {
    const fs::path dir = fresh_temp_dir("hostile-camera");
    // Keys at frames 0 and 2 on opposite sides of look_at: frame 1's position is look_at.
    const fs::path camera = write_text_file(
        dir / "keys.json", R"({"image":{"width":16,"height":12},"camera":[)"
                           R"({"frame":0,"position":[0,0,3],"look_at":[0,0,0]},)"
                           R"({"frame":2,"position":[0,0,-3],"look_at":[0,0,0]}]})");
    std::vector<std::string> args = {"render"};
    for (int f = 0; f < 3; ++f)
        args.push_back(write_text_file(dir / ("f_" + std::to_string(f) + ".obj"), kTriangleObj));
    args.insert(args.end(), {"-o", (dir / "out").string(), "--camera", camera.string(), "--builder",
                             "reference", "--tracer", "reference", "-q"});
    check_error(run_kdray(args, kNoHang), 1, {"keys.json", "frame 1", "look_at"});
    CHECK_FALSE(fs::exists(dir / "out" / "f_0.png"));
    fs::remove_all(dir);
}

TEST_CASE("a file name that is not UTF-8 renders and gets a stats.json") {
    const fs::path dir = fresh_temp_dir("hostile-utf8");
    const fs::path camera = write_text_file(dir / "small.json", kTinyRender);
    const fs::path obj = write_text_file(dir / "b\xff.obj", kTriangleObj);
    const CommandResult r = render(obj, dir / "out", camera);
    INFO(r.err);
    CHECK(r.status == 0);
    CHECK(fs::exists(dir / "out" / "stats.json"));
    fs::remove_all(dir);
}

TEST_CASE("kdray stats on a stats.json with wrong types names the file and the field") {
    const fs::path dir = fresh_temp_dir("hostile-stats");
    const std::string head = R"({"summary":{},"frames":[)";
    write_text_file(dir / "a" / "stats.json", head + R"({"frame":0,"frame_ms":"abc"}]})");
    write_text_file(dir / "b" / "stats.json", head + R"({"frame":-5,"frame_ms":1}]})");
    check_error(run_kdray({"stats", (dir / "a").string()}, kNoHang), 1,
                {"stats.json", "frames[0].frame_ms"});
    check_error(run_kdray({"stats", (dir / "b").string()}, kNoHang), 1,
                {"stats.json", "frames[0].frame", "-5"});
    fs::remove_all(dir);
}

TEST_CASE("an image too large for the machine is refused with the figures before it renders") {
    const fs::path dir = fresh_temp_dir("hostile-huge");
    // 65536 x 65536 (the render file's largest size): 4.3 Gpixels, hundreds of GB of buffers.
    const fs::path camera = write_text_file(
        dir / "huge.json",
        R"({"image":{"width":65536,"height":65536},"camera":{"position":[0.3,0.3,3],"look_at":[0.3,0.3,0]}})");
    const fs::path tri = write_text_file(dir / "tri.obj", kTriangleObj);
    check_error(render(tri, dir / "out", camera), 1, {"huge.json", "65536 x 65536", "host memory"});
    CHECK_FALSE(fs::exists(dir / "out" / "tri.png"));
    fs::remove_all(dir);
}
