// test_hostile_round3_messages.cpp — issue #29, problem 12: every message kdray prints is one
// bounded, printable line, whatever the files it quotes hold. Each runs the binary.
#include <doctest/doctest.h>

#include <algorithm>
#include <filesystem>
#include <string>

#include "tests/support.h"

namespace fs = std::filesystem;
using namespace kdray::test;

namespace {

// Runs that should end at once get 60 s: a hang fails the test instead of stalling CI.
constexpr int kNoHang = 60;

/// One line starting with `prefix`, no control character in it but its final newline.
void check_one_printable_line(const std::string& err, const std::string& prefix) {
    INFO("stderr: " << err);
    CHECK(err.rfind(prefix, 0) == 0);
    CHECK(std::count(err.begin(), err.end(), '\n') == 1);
    CHECK(std::none_of(err.begin(), err.end() - 1, [](char c) {
        const auto byte = static_cast<unsigned char>(c);
        return byte < 0x20 || byte == 0x7f;
    }));
}

}  // namespace

TEST_CASE("render-file strings cannot forge message lines or send terminal escapes") {
    // A key holding "\n" + "kdray: error: forged" printed a second error line a script would
    // take for kdray's, and an ESC sequence recoloured (or cleared) the user's terminal. JSON's
    // \n and \u001b escapes put the raw bytes into the key kdray quotes.
    const fs::path dir = fresh_temp_dir("round3-forged");
    const fs::path obj = write_text_file(dir / "tri.obj", "v 0 0 0\nv 1 0 0\nv 0 1 0\nf 1 2 3\n");
    const fs::path camera = write_text_file(
        dir / "cam.json", R"({"a\nkdray: error: forged\u001b[31m\r\u007f\u0001": 1})");
    const CommandResult r = run_kdray(
        {"render", obj.string(), "-o", (dir / "out").string(), "--camera", camera.string(), "-q"},
        kNoHang);
    CHECK(r.status == 1);
    check_one_printable_line(r.err, "kdray: error: ");
    for (const char* shown : {"cam.json", "a\\nkdray: error: forged\\x1b[31m\\r\\x7f\\x01"})
        CHECK_MESSAGE(r.err.find(shown) != std::string::npos, shown);

    // A 30 MB string gave a 30 MB line: a quoted value is cut (with "...") at 200 bytes.
    const fs::path long_key =
        write_text_file(dir / "long.json", "{\"" + std::string(1 << 20, 'y') + "\": 1}");
    const CommandResult cut = run_kdray(
        {"render", obj.string(), "-o", (dir / "out").string(), "--camera", long_key.string(), "-q"},
        kNoHang);
    CHECK(cut.status == 1);
    check_one_printable_line(cut.err, "kdray: error: ");
    CHECK(cut.err.size() < 400);
    CHECK(cut.err.find(std::string(200, 'y') + "...'") != std::string::npos);
    fs::remove_all(dir);
}

TEST_CASE("a warning quoting an MTL texture name with an escape sequence stays one line") {
    // The warnings of a render go through the logger rather than main's error path; an MTL
    // names a texture with ESC [2J (clear the screen) in it, and UTF-8 text must survive.
    const fs::path dir = fresh_temp_dir("round3-forged-warning");
    write_text_file(dir / "s.mtl", "newmtl t\nKd 1 1 1\nmap_Kd caf\xc3\xa9\x1b[2J.png\n");
    const fs::path obj = write_text_file(
        dir / "s.obj", "mtllib s.mtl\nusemtl t\nv 0 0 0\nv 1 0 0\nv 0 1 0\nf 1 2 3\n");
    const CommandResult r = run_kdray({"render", obj.string(), "-o", (dir / "out").string(),
                                       "--builder", "reference", "--tracer", "reference", "-q"},
                                      kNoHang);
    CHECK(r.status == 0);
    check_one_printable_line(r.err, "kdray: warning: ");
    CHECK(r.err.find("caf\xc3\xa9\\x1b[2J.png") != std::string::npos);
    fs::remove_all(dir);
}

TEST_CASE("a broken PNG is one kdray line, with no libpng line beside it") {
    // libpng prints "libpng error: ..." on stderr by itself (OpenImageIO lets it through), even
    // with --log-level quiet: a second line beside kdray's warning (render) or error (compare)
    // about the same file, in no format a script expects. A PNG cut inside its image data makes
    // libpng fail while it decodes, after the header was read and its size checked.
    const fs::path dir = fresh_temp_dir("round3-libpng");
    kdray::Image texture;
    texture.width = texture.height = 8;
    texture.rgb.resize(8 * 8 * 3);
    for (std::size_t i = 0; i < texture.rgb.size(); ++i) texture.rgb[i] = float(i % 7) / 7.0f;
    kdray::write_image(dir / "good.png", texture);
    const std::string png = read_file(dir / "good.png");
    REQUIRE(png.size() > 60);
    write_text_file(dir / "cut.png", png.substr(0, png.size() - 20));
    write_text_file(dir / "s.mtl", "newmtl t\nKd 1 1 1\nmap_Kd cut.png\n");
    const fs::path obj = write_text_file(dir / "s.obj",
                                         "mtllib s.mtl\nusemtl t\nv 0 0 0\nv 1 0 0\nv 0 1 0\n"
                                         "vt 0 0\nvt 1 0\nvt 0 1\nf 1/1 2/2 3/3\n");
    const CommandResult r =
        run_kdray({"render", obj.string(), "-o", (dir / "out").string(), "--builder", "reference",
                   "--tracer", "reference", "--log-level", "quiet"},
                  kNoHang);
    CHECK(r.status == 0);
    check_one_printable_line(r.err, "kdray: warning: ");
    CHECK(r.err.find("cut.png") != std::string::npos);
    CHECK(r.err.find("renders untextured") != std::string::npos);

    const CommandResult compared =
        run_kdray({"compare", (dir / "cut.png").string(), (dir / "good.png").string()}, kNoHang);
    CHECK(compared.status == 1);
    check_one_printable_line(compared.err, "kdray: error: ");
    CHECK(compared.err.find("cut.png") != std::string::npos);
    fs::remove_all(dir);
}
