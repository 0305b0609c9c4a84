// texture_loader.h — the images of map_Kd and map_Ka into a scene's texel atlas (conventions.md,
// "Textures"): a file name resolves relative to the MTL file's folder, else to the one file there
// whose name matches it but for case; 8-bit (integer) images are sRGB and decoded to linear, float
// images are linear. A file that is missing or unreadable is one warning naming the material and
// the file, and the material renders untextured.
#pragma once

#include <filesystem>
#include <map>
#include <string>

#include "core/scene/scene.h"

namespace kdray {

class TextureLoader {
  public:
    /// `folder`: the MTL file's folder; `where`: what warnings begin with (the OBJ file).
    TextureLoader(Scene& scene, std::filesystem::path folder, std::string where)
        : scene_(scene), folder_(std::move(folder)), where_(std::move(where)) {}

    /// The entry of scene.texture_table for `file` (map_Kd or map_Ka, `statement`, of
    /// `material`), each file loaded once; -1 with a warning when it cannot be read.
    int load(const std::string& material, const std::string& statement, const std::string& file);

  private:
    Scene& scene_;
    std::filesystem::path folder_;
    std::string where_;
    std::map<std::filesystem::path, int> loaded_;
};

}  // namespace kdray
