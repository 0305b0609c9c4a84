// render_file.h — the render file of conventions.md: image size and samples, a camera (fixed or
// keyframed), lights, background, ambient light, exposure and the maximum path depth. Every field
// has a default; an unknown field or a wrong type is an Error that names the field and the file.
#pragma once

#include <filesystem>
#include <string>
#include <vector>

#include "core/geometry/math.h"
#include "core/io/image.h"
#include "core/scene/scene_frame.h"

namespace kdray {

/// The most stops an exposure may have either way (the render file's "exposure", --exposure):
/// 2^64 and 2^-64 keep every float radiance finite and above zero where it was; an exposure
/// beyond them is a typo.
inline constexpr float kMaxExposureStops = 64.0f;

/// The camera kdray traces with: in the scene's frame (scene_frame.h), in float, as conventions.md
/// defines the model.
struct Camera {
    Vec3 position{0, 0, 1};
    Vec3 look_at{0, 0, 0};
    Vec3 up{0, 1, 0};
    float fov_y = 45.0f;  // full vertical field of view, degrees
};

/// A camera of the render file: in the scene's own units, in double.
struct SceneCamera {
    DVec3 position{0, 0, 1};
    DVec3 look_at{0, 0, 0};
    DVec3 up{0, 1, 0};
    float fov_y = 45.0f;

    SceneCamera() = default;
    SceneCamera(const Camera& c)
        : position(c.position), look_at(c.look_at), up(c.up), fov_y(c.fov_y) {}
};

/// A render file's camera in the scene's frame: its points mapped there, its up vector as the
/// file gives it (or made unit length in double first when it has no square in float).
Camera in_frame(const SceneCamera& camera, const SceneFrame& frame);
/// A traced camera back in the scene's units.
SceneCamera in_scene_units(const Camera& camera, const SceneFrame& frame);

struct CameraKey {
    int frame = 0;
    SceneCamera camera;
};

struct Light {
    enum class Type { point, directional };
    Type type = Type::point;
    DVec3 position{0, 0, 0};    // point lights, in the scene's units
    DVec3 direction{0, -1, 0};  // directional lights: the direction the light travels
    /// Point: intensity, any finite double (the frame scales it); directional: irradiance.
    DVec3 intensity{1, 1, 1};
};

/// How a render estimates the light (conventions.md, "Integrators"; docs/path-tracing.md):
/// Whitted's ray tree (direct light, ideal mirror and glass rays), or the path integrator.
enum class Integrator { whitted, path };
const char* integrator_name(Integrator integrator);

/// The deepest path the path integrator takes (max_depth), past which a value is a typo; -1 is
/// unbounded.
inline constexpr int kMaxPathDepth = 65536;

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
    /// How 8-bit images map radiance to display values ("display"; image.h). Filmic by default:
    /// renders with emitters or bright lights hold radiances far above 1 (CornellBox-Original's
    /// lamp: Ke = 17, 12, 4), which a clamp turns into flat white patches and, sampled, combs of
    /// white and dark pixels along their edges; the filmic shoulder keeps gradations up to about
    /// 7, at the price of mid tones a little brighter (0.18 -> 0.27, 0.5 -> 0.62) and 1 -> 0.80.
    /// "clamp" gives the earlier images exactly.
    DisplayTransform display = DisplayTransform::filmic;
    Integrator integrator = Integrator::whitted;
    /// Whitted: ray generations, 1 to KDRAY_MAX_BOUNCES (default 4). Path: path segments, as
    /// Mitsuba 3 counts them (1 sees emitters only, 2 adds direct light), 1 to kMaxPathDepth or
    /// -1, unbounded (the default with "integrator": "path").
    int max_depth = 4;
    /// Independent random numbers per sample (KDRAY_SAMPLER_INDEPENDENT) instead of each pixel's
    /// low-discrepancy sequence: not a render-file field; for tests whose statistics assume
    /// independent samples.
    bool independent_samples = false;

    /// The camera for a frame number in `scene_frame`: the keys mapped into the frame, then
    /// interpolated linearly in float, the nearest key held before the first and after the last.
    /// Throws Error naming the render file and the frame when the camera has no basis in float
    /// there (a look_at 1e-30 scene extents from the position, say).
    Camera camera_at(int frame, const SceneFrame& scene_frame = {}) const;
    /// Throws Error naming the render file and the frame when the camera of a frame, interpolated
    /// in the scene's units (double), has no basis there: keys valid alone may give one that
    /// looks at its own position or along its up vector.
    void check_camera_at(int frame) const;
};

RenderSettings load_render_file(const std::filesystem::path& path);
RenderSettings parse_render_json(const std::string& text, const std::filesystem::path& name);

}  // namespace kdray
