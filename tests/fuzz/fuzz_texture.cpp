// fuzz_texture.cpp — libFuzzer target for a texture as a scene loads it: the bytes are a file in a
// scratch folder that a material names (map_Kd), read by TextureLoader through read_image, that is
// through read_input_file's budgets, the image library, check_image_size's declared-size budget
// and the loader's check of float texels (issue #29, problems 5 and 9). A texture that cannot be
// read is a warning naming the file and an untextured material; a sanitizer report, any exception
// out of load (the loader turns kdray::Error into the warning, so another type escaping means a
// library failure kdray does not report as its own), or an accepted texture whose texels are not
// finite numbers >= 0 or lie outside the atlas is a bug.
#include <unistd.h>

#include <cmath>
#include <cstdint>
#include <cstdio>
#include <cstdlib>
#include <filesystem>
#include <fstream>
#include <string>

#include "core/io/input_file.h"
#include "core/scene/scene.h"
#include "core/scene/texture_loader.h"
#include "tests/fuzz/fuzz_scratch.h"

namespace fs = std::filesystem;

namespace {

[[noreturn]] void bug(const char* what) {
    std::fprintf(stderr, "fuzz_texture: invariant broken: %s\n", what);
    std::abort();
}

/// This process's scratch folder (fuzz_scratch.h).
const fs::path& scratch() {
    return kdray::fuzz::scratch_folder("fuzz-texture");
}

/// The name a user would give the file: by its signature, so that the format the name implies
/// and the bytes agree as often as they do in a scene (the library is free to sniff either way).
std::string file_name(const std::uint8_t* data, std::size_t size) {
    auto starts = [&](const char* magic, std::size_t n) {
        return size >= n &&
               std::string(reinterpret_cast<const char*>(data), n) == std::string(magic, n);
    };
    if (starts("\x89PNG", 4)) return "tex.png";
    if (starts("\xff\xd8", 2)) return "tex.jpg";
    if (starts("v/1\x01", 4)) return "tex.exr";
    return "tex.png";
}

}  // namespace

extern "C" int LLVMFuzzerTestOneInput(const std::uint8_t* data, std::size_t size) {
    const std::string name = file_name(data, size);
    const fs::path path = scratch() / name;
    {
        std::ofstream out(path, std::ios::binary | std::ios::trunc);
        out.write(reinterpret_cast<const char*>(data), std::streamsize(size));
    }
    kdray::Scene scene;
    kdray::TextureLoader loader(scene, scratch(), "fuzz.obj");
    const int id = loader.load("m", "map_Kd", name);
    // A second material naming it: loaded once, the same answer.
    if (loader.load("n", "map_Kd", name) != id)
        bug("a second name for one file loaded differently");
    if (id < 0) {
        if (scene.warnings.empty() || scene.warnings.back().find(name) == std::string::npos)
            bug("an unreadable texture without a warning naming it");
        return 0;
    }
    if (std::size_t(id) >= scene.texture_table.size()) bug("texture id outside the table");
    const KdTexture& t = scene.texture_table[std::size_t(id)];
    const std::uint64_t texels = std::uint64_t(t.width) * t.height;
    if (texels == 0 || texels > kdray::kMaxImagePixels) bug("accepted an empty or oversized image");
    if (4 * (std::uint64_t(t.offset) + texels) != scene.texels.size())
        bug("texture outside the atlas");
    for (const float v : scene.texels)
        if (!(std::isfinite(v) && v >= 0.0f))
            bug("accepted a texel that is not a finite number >= 0");
    return 0;
}
