#include "cli/inputs.h"

#include <glob.h>

#include <algorithm>
#include <cctype>
#include <filesystem>

#include "core/error.h"
#include "core/io/natural_order.h"

namespace kdray::cli {

void check_scene_input(const std::string& path) {
    std::string name = std::filesystem::path(path).filename().string();
    std::transform(name.begin(), name.end(), name.begin(),
                   [](unsigned char c) { return char(std::tolower(c)); });
    const auto ends_with = [&](const char* suffix) {
        const std::string s = suffix;
        return name.size() > s.size() && name.compare(name.size() - s.size(), s.size(), s) == 0;
    };
    // A render file among the frames read as an OBJ said "unknown statement '{'".
    if (ends_with(".json"))
        throw UsageError(path + " is a render file, not a scene: pass it with --render-file");
    if (ends_with(".obj.gz") || ends_with(".obj.zst") || ends_with(".obj.xz") ||
        ends_with(".obj.bz2"))
        throw UsageError(path +
                         ": kdray reads Wavefront OBJ (.obj) files, uncompressed; decompress "
                         "it first (e.g. gunzip -k)");
    for (const char* format : {".ply", ".gltf", ".glb", ".fbx", ".stl", ".usd", ".usda", ".usdc",
                               ".usdz", ".abc", ".dae", ".3ds", ".blend", ".pbrt", ".xml"})
        if (ends_with(format))
            throw UsageError(path +
                             ": kdray reads Wavefront OBJ (.obj) files; convert it first "
                             "(Blender: File > Import, then File > Export > Wavefront "
                             "(.obj); or assimp export IN OUT.obj)");
}

std::vector<std::string> expand_inputs(const std::vector<std::string>& arguments) {
    std::vector<std::string> files;
    for (const std::string& arg : arguments) {
        if (std::filesystem::exists(arg)) {
            if (std::filesystem::is_directory(arg))
                throw Error(arg + ": is a folder, not an OBJ file");
            check_scene_input(arg);
            files.push_back(arg);
            continue;
        }
        if (arg.find_first_of("*?[") == std::string::npos) throw Error(arg + ": no such file");
        glob_t matches{};
        int status = ::glob(arg.c_str(), 0, nullptr, &matches);
        const std::size_t before = files.size();
        if (status == 0)
            for (std::size_t k = 0; k < matches.gl_pathc; ++k)
                files.emplace_back(matches.gl_pathv[k]);
        ::globfree(&matches);
        if (status != 0) throw Error(arg + ": no file matches this pattern");
        for (std::size_t k = before; k < files.size(); ++k) check_scene_input(files[k]);
    }
    // Sorted, duplicates kept: a path given twice keeps the frame numbers of its positions, and
    // render refuses the two writers of one image by name (check_output_names).
    std::stable_sort(files.begin(), files.end(), natural_less);
    return files;
}

}  // namespace kdray::cli
