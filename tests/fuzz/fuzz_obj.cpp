// fuzz_obj.cpp — libFuzzer target for load_obj, along the path a user's file takes: the bytes are
// written to a file and loaded (pre-scan, tinyobjloader, MTL). An input may carry a material
// library after a line "%%mtl": the part before it is scene.obj, the part after it scene.mtl beside
// it, so `mtllib scene.mtl` reaches tinyobjloader's MTL parser; without the marker scene.mtl is
// absent, which is the missing-library warning path.
//
// kdray::Error is the expected outcome of a bad file. Anything else is a bug: a sanitizer report,
// another exception, or a loaded scene that breaks what load_obj promises (checked below).
#include <unistd.h>

#include <cmath>
#include <cstdint>
#include <cstdio>
#include <cstdlib>
#include <filesystem>
#include <fstream>
#include <string>
#include <string_view>

#include "core/error.h"
#include "core/scene/obj_validate.h"
#include "core/scene/scene.h"

namespace fs = std::filesystem;

namespace {

[[noreturn]] void bug(const char* what) {
    std::fprintf(stderr, "fuzz_obj: invariant broken: %s\n", what);
    std::abort();
}

/// One folder per fuzzing process, removed at exit.
const fs::path& work_dir() {
    static const fs::path dir = [] {
        std::string pattern = (fs::temp_directory_path() / "kdray-fuzz-obj-XXXXXX").string();
        if (!::mkdtemp(pattern.data())) bug("cannot create a temporary folder");
        std::atexit([] {
            std::error_code ec;
            fs::remove_all(work_dir(), ec);
        });
        return fs::path(pattern);
    }();
    return dir;
}

void write_file(const fs::path& path, std::string_view bytes) {
    std::ofstream out(path, std::ios::binary | std::ios::trunc);
    out.write(bytes.data(), static_cast<std::streamsize>(bytes.size()));
    if (!out) bug("cannot write the input file");
}

/// What load_obj promises about a scene it returns (scene.h).
void check_scene(const kdray::Scene& scene, const kdray::ObjPrescan& prescan) {
    const std::size_t n = scene.triangle_count();
    if (n == 0) bug("a scene without triangles was returned");
    if (scene.triangles.size() != n * KDRAY_FLOATS_PER_TRIANGLE) bug("partial triangle");
    if (scene.material_ids.size() != n) bug("one material id per triangle");
    for (kd_u32 id : scene.material_ids)
        if (id >= scene.materials.size()) bug("material id out of range");
    for (float x : scene.triangles)
        if (!std::isfinite(x)) bug("non-finite coordinate in a loaded scene");
    if (scene.has_vertex_normals()) {
        if (scene.vertex_normals.size() != n * KDRAY_FLOATS_PER_TRIANGLE) bug("partial normals");
        for (std::size_t c = 0; c < 3 * n; ++c) {
            const float* v = &scene.vertex_normals[3 * c];
            const float length2 = v[0] * v[0] + v[1] * v[1] + v[2] * v[2];
            // Unit length, or zero at a zero-area triangle's corners.
            if (!(std::fabs(length2 - 1.0f) < 1e-5f || length2 == 0.0f))
                bug("a vertex normal that is not unit length");
        }
    }
    // Every triangle comes from a face the pre-scan saw.
    if (prescan.faces == 0) bug("triangles without a face in the pre-scan");
}

}  // namespace

extern "C" int LLVMFuzzerTestOneInput(const std::uint8_t* data, std::size_t size) {
    const std::string_view input(reinterpret_cast<const char*>(data), size);
    const fs::path obj = work_dir() / "scene.obj";
    const fs::path mtl = work_dir() / "scene.mtl";
    constexpr std::string_view marker = "\n%%mtl\n";
    const std::size_t split = input.find(marker);
    std::error_code ec;
    if (split == std::string_view::npos) {
        write_file(obj, input);
        fs::remove(mtl, ec);
    } else {
        write_file(obj, input.substr(0, split + 1));
        write_file(mtl, input.substr(split + marker.size()));
    }

    kdray::Scene scene;
    try {
        scene = kdray::load_obj(obj);
    } catch (const kdray::Error&) {
        return 0;  // a bad file, reported as it should be
    }
    std::string text(input.substr(0, split == std::string_view::npos ? input.size() : split + 1));
    check_scene(scene, kdray::validate_obj(text, obj.string()));
    return 0;
}
