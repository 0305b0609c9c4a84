// render_file.h — the render file of conventions.md: image size and samples, a camera (fixed or
// keyframed), lights, background, ambient light, exposure and the maximum path depth. Every field
// has a default; an unknown field or a wrong type is an Error that names the field and the file.
#pragma once

#include <filesystem>
#include <string>
#include <vector>

#include "core/math.h"

namespace kdray {

struct Camera {
    Vec3 position{0, 0, 1};
    Vec3 look_at{0, 0, 0};
    Vec3 up{0, 1, 0};
    float fov_y = 45.0f;  // full vertical field of view, degrees
};

struct CameraKey {
    int frame = 0;
    Camera camera;
};

struct Light {
    enum class Type { point, directional };
    Type type = Type::point;
    Vec3 position{0, 0, 0};    // point lights
    Vec3 direction{0, -1, 0};  // directional lights: the direction the light travels
    Vec3 intensity{1, 1, 1};   // point: intensity; directional: irradiance
};

struct RenderSettings {
    std::filesystem::path path;  // empty when built from defaults
    int width = 640;
    int height = 480;
    int spp = 1;
    /// One key for a fixed camera; sorted by frame for a keyframed one.
    std::vector<CameraKey> camera_keys{CameraKey{}};
    bool camera_given = false;  // false: no camera in the file, frame the scene instead
    std::vector<Light> lights;
    Vec3 background{0.05f, 0.05f, 0.08f};
    /// Ambient light: a hit adds Ka x ambient (conventions.md). A number in the file is a grey.
    Vec3 ambient{0, 0, 0};
    /// In stops: every radiance that reaches an image is multiplied by 2^exposure.
    float exposure = 0.0f;
    int max_depth = 4;

    /// The camera for a frame number: linear interpolation between keys, the nearest key held
    /// before the first and after the last.
    Camera camera_at(int frame) const;
};

RenderSettings load_render_file(const std::filesystem::path& path);
RenderSettings parse_render_json(const std::string& text, const std::filesystem::path& name);

}  // namespace kdray
