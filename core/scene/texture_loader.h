// texture_loader.h — the images of map_Kd and map_Ka into a scene's texel atlas (conventions.md,
// "Textures"): a file name resolves relative to the MTL file's folder, else to the one file there
// whose name matches it but for case; 8-bit (integer) images are sRGB and decoded to linear, float
// images are linear. A file that is missing or unreadable is one warning naming the material and
// the file (one per name, however many materials and statements give it, with their count), and the
// material renders untextured. Each name is resolved once, and each folder listed once: loading is
// linear in the names and the folder's files.
#pragma once

#include <filesystem>
#include <map>
#include <string>
#include <unordered_map>
#include <utility>
#include <vector>

#include "core/scene/scene.h"

namespace kdray {

class TextureLoader {
  public:
    /// `folder`: the MTL file's folder; `where`: what warnings begin with (the OBJ file).
    TextureLoader(Scene& scene, std::filesystem::path folder, std::string where)
        : scene_(scene), folder_(std::move(folder)), where_(std::move(where)) {}

    /// The entry of scene.texture_table for `file` (map_Kd or map_Ka, `statement`, of
    /// `material`), each file loaded once; -1 with a warning when it cannot be read. A name
    /// that more materials give is resolved once, and warned about once with their count.
    int load(const std::string& material, const std::string& statement, const std::string& file);

  private:
    /// A name as the MTL gives it, resolved: its texture (-1: none), and the warning about it
    /// (an index into scene.warnings, with what it says and how many materials named it).
    struct Named {
        int id = -1;
        std::size_t warning = 0;
        std::string name, why;
        // The materials and the statements (map_Kd, map_Ka) that name it, each once, in order:
        // a material whose map_Kd and map_Ka name one missing file is one warning naming both.
        std::vector<std::string> materials, statements;
    };

    std::filesystem::path resolve(const std::string& name);
    int load_path(const std::filesystem::path& path, std::string& why);
    void warn(Named& named) const;

    Scene& scene_;
    std::filesystem::path folder_;
    std::string where_;
    std::map<std::filesystem::path, std::pair<int, std::string>> loaded_;  // id, why not
    std::unordered_map<std::string, Named> named_;
    /// Each folder's files by their lower-case name (the first found of names that match but
    /// for case), listed once: a scan per name made 10,000 names in a folder of 10,000 textures
    /// take 35 s.
    std::map<std::filesystem::path, std::unordered_map<std::string, std::filesystem::path>>
        folders_;
};

}  // namespace kdray
