// render_file.cpp — reading and checking the render file of conventions.md.
//
// Every field is optional and a JSON null counts as absent (exporters write `"background": null`
// for "no opinion"; BART's robots scene does). Anything else that is not exactly what the format
// says is an Error naming the file and the field's path, e.g. `camera[2].fov_y`, so that a typo
// never silently falls back to a default.
#include "core/render/render_file.h"

#include <algorithm>
#include <cerrno>
#include <cmath>
#include <cstring>
#include <fstream>
#include <initializer_list>
#include <limits>
#include <optional>
#include <sstream>
#include <string_view>

#include <nlohmann/json.hpp>

#include "core/device/kd_shared.h"
#include "core/error.h"
#include "core/io/input_file.h"
#include "core/render/camera.h"
#include "core/text/nearest_name.h"

namespace kdray {
namespace {

using nlohmann::json;

/// Sane upper bounds: larger values are typos, and would ask for absurd amounts of memory.
constexpr long long kMaxImageSize = 65536;
constexpr long long kMaxSpp = 65536;

bool finite(const Vec3& v) {
    return std::isfinite(v.x) && std::isfinite(v.y) && std::isfinite(v.z);
}

/// True when `v` normalises to a finite unit vector in float: its squared length neither
/// overflows nor underflows to zero.
bool normalizable(const Vec3& v) {
    const float squared = dot(v, v);
    return finite(v) && squared > 0.0f && std::isfinite(squared);
}

/// The same in double, where the render file's vectors are read.
bool normalizable(const DVec3& v) {
    const double squared = dot(v, v);
    return is_finite(v) && squared > 0.0 && std::isfinite(squared);
}

/// What is wrong with a camera's basis, if anything: the field to blame and the problem.
struct CameraProblem {
    const char* field;
    std::string what;
};

/// The basis of conventions.md's camera model must exist in the scene's units: a view direction
/// and an up vector that is not along it. Checked for every key of a render file and for every
/// frame's interpolated camera, which two valid keys can still make degenerate.
std::optional<CameraProblem> camera_basis_problem(const SceneCamera& camera) {
    const DVec3 view = camera.look_at - camera.position;
    if (view == DVec3{0, 0, 0})
        return CameraProblem{"look_at", "must differ from the camera position"};
    if (!normalizable(view))
        return CameraProblem{"look_at", "is too close to the camera position to give a direction"};
    if (camera.up == DVec3{0, 0, 0}) return CameraProblem{"up", "must not be the zero vector"};
    if (!normalizable(camera.up)) return CameraProblem{"up", "is too short to give a direction"};
    // `!(... >= ...)` so that a NaN can never pass.
    if (!(length(cross(view, camera.up)) >= 1e-6 * length(view) * length(camera.up)))
        return CameraProblem{"up", "is parallel to the view direction (look_at - position)"};
    return std::nullopt;
}

}  // namespace

Camera in_frame(const SceneCamera& camera, const SceneFrame& frame) {
    Camera out;
    out.position = frame.point(camera.position);
    out.look_at = frame.point(camera.look_at);
    out.up = {float(camera.up.x), float(camera.up.y), float(camera.up.z)};
    if (!normalizable(out.up)) {
        const double l = length(camera.up);
        out.up = {float(camera.up.x / l), float(camera.up.y / l), float(camera.up.z / l)};
    }
    out.fov_y = camera.fov_y;
    return out;
}

SceneCamera in_scene_units(const Camera& camera, const SceneFrame& frame) {
    SceneCamera out;
    out.position = frame.scene_point(camera.position);
    out.look_at = frame.scene_point(camera.look_at);
    out.up = camera.up;
    out.fov_y = camera.fov_y;
    return out;
}

namespace {

/// The basis of the camera that is traced, in the scene's frame and in 32-bit floats, exactly as
/// camera.cpp computes it. A camera with a basis in the scene's units can still lack one here:
/// a position 1e-30 scene extents from look_at, or 1e39 away from the scene.
std::optional<CameraProblem> traced_basis_problem(const Camera& camera) {
    if (!finite(camera.position))
        return CameraProblem{"position", "is too far from the scene to trace in 32-bit floats"};
    if (!finite(camera.look_at))
        return CameraProblem{"look_at", "is too far from the scene to trace in 32-bit floats"};
    if (!normalizable(camera.look_at - camera.position))
        return CameraProblem{"look_at",
                             "is too far from or too close to the camera position for the scene's "
                             "size: look_at - position cannot be normalised in 32-bit floats"};
    if (!(length(cross(normalize(camera.look_at - camera.position), normalize(camera.up))) >=
          1e-6f))
        return CameraProblem{"up", "is parallel to the view direction (look_at - position)"};
    const CameraRays rays(camera, 1, 1);
    if (!finite(rays.forward) || !finite(rays.right) || !finite(rays.up))
        return CameraProblem{"up",
                             "gives no camera basis in 32-bit floats with this view direction"};
    return std::nullopt;
}

class RenderFileParser {
  public:
    explicit RenderFileParser(std::string file) : file_(std::move(file)) {}

    RenderSettings parse(const std::string& text) {
        json root = parse_json(text, file_);
        if (!root.is_object()) throw Error(file_ + ": the render file must be a JSON object");

        RenderSettings settings;
        // `$schema` lets an editor find docs/render-file.schema.json; kdray only checks its type.
        check_fields(root, "",
                     {"$schema", "image", "camera", "lights", "background", "ambient", "exposure",
                      "display", "integrator", "max_depth"});
        if (present(root, "$schema") && !root["$schema"].is_string())
            fail("$schema", "must be a string (the path or URL of the render file's JSON Schema)");
        if (present(root, "image")) read_image(root["image"], settings);
        if (present(root, "camera")) {
            read_camera(root["camera"], settings);
            settings.camera_given = true;
        }
        if (present(root, "lights")) read_lights(root["lights"], settings);
        if (present(root, "background")) {
            settings.background = vec3(root["background"], "background");
            if (settings.background.x < 0 || settings.background.y < 0 || settings.background.z < 0)
                fail("background", "must not be negative");
        }
        if (present(root, "ambient")) {
            const json& ambient = root["ambient"];
            if (ambient.is_number()) {
                const float grey = number(ambient, "ambient");
                settings.ambient = {grey, grey, grey};
            } else if (ambient.is_array()) {
                settings.ambient = vec3(ambient, "ambient");
            } else {
                fail("ambient", "must be a number (a grey) or an array of 3 numbers");
            }
            if (settings.ambient.x < 0 || settings.ambient.y < 0 || settings.ambient.z < 0)
                fail("ambient", "must not be negative");
        }
        if (present(root, "exposure")) {
            settings.exposure = number(root["exposure"], "exposure");
            if (!(std::fabs(settings.exposure) <= kMaxExposureStops))
                fail("exposure", "must be between -64 and 64 stops");
        }
        if (present(root, "display")) {
            const json& display = root["display"];
            if (display == "clamp")
                settings.display = DisplayTransform::clamp;
            else if (display == "filmic")
                settings.display = DisplayTransform::filmic;
            else
                fail("display", "must be \"clamp\" or \"filmic\"");
        }
        if (present(root, "integrator")) {
            const json& integrator = root["integrator"];
            if (integrator == "whitted")
                settings.integrator = Integrator::whitted;
            else if (integrator == "path")
                settings.integrator = Integrator::path;
            else
                fail("integrator", "must be \"whitted\" or \"path\"");
        }
        if (settings.integrator == Integrator::path) {
            settings.max_depth = -1;
            if (present(root, "max_depth")) {
                settings.max_depth = integer(root["max_depth"], "max_depth", -1, kMaxPathDepth,
                                             "the deepest path kdray takes");
                if (settings.max_depth == 0)
                    fail("max_depth",
                         "must be -1 (unbounded) or at least 1 with the path "
                         "integrator (1 sees emitters only)");
            }
        } else if (present(root, "max_depth")) {
            // The Whitted renderer's pending-ray stack holds KDRAY_MAX_BOUNCES rays: a deeper
            // max_depth was clamped to it without a word while stats.json recorded the value.
            settings.max_depth = integer(root["max_depth"], "max_depth", 1, KDRAY_MAX_BOUNCES,
                                         "the most bounces kdray's Whitted renderer follows");
        }
        return settings;
    }

  private:
    [[noreturn]] void fail(const std::string& path, const std::string& what) const {
        throw Error(file_ + ": field '" + path + "' " + what);
    }

    static bool present(const json& object, const char* key) {
        const auto it = object.find(key);
        return it != object.end() && !it->is_null();
    }

    static std::string join(const std::string& parent, std::string_view key) {
        return parent.empty() ? std::string(key) : parent + "." + std::string(key);
    }

    /// Every key of `object` must be one of `allowed`; an unknown one is named with the nearest
    /// allowed name ("max_dpeth": did you mean 'max_depth'?).
    void check_fields(const json& object, const std::string& path,
                      std::initializer_list<std::string_view> allowed) const {
        for (const auto& item : object.items()) {
            if (std::find(allowed.begin(), allowed.end(), item.key()) != allowed.end()) continue;
            throw Error(file_ + ": unknown field '" + join(path, item.key()) + "'" +
                        did_you_mean(item.key(), {allowed.begin(), allowed.end()}));
        }
    }

    /// A light's strength under the other type's name (pbrt's and Mitsuba's directional lights
    /// take an `intensity`-like value): told which name this type reads and why.
    void check_light_strength(const json& light, const std::string& path, bool point) const {
        const char* wrong = point ? "irradiance" : "intensity";
        if (!light.contains(wrong)) return;
        throw Error(file_ + ": unknown field '" + path + "." + wrong + "': " +
                    (point ? "a point light's strength is its 'intensity' (falling off with "
                             "the squared distance); 'irradiance' is a directional light's"
                           : "a directional light's strength is its 'irradiance' (what a surface "
                             "facing it receives, at any distance); 'intensity' is a point "
                             "light's"));
    }

    void require_object(const json& value, const std::string& path) const {
        if (!value.is_object()) fail(path, "must be an object");
    }

    /// A number as the file writes it, in double; finite as a float too unless `any_double`
    /// (a point light's intensity, which the scene's frame scales by its scale squared).
    double real(const json& value, const std::string& path, bool any_double = false) const {
        if (!value.is_number()) fail(path, "must be a number");
        const double d = value.get<double>();
        if (!std::isfinite(d) || (!any_double && std::fabs(d) > std::numeric_limits<float>::max()))
            fail(path, "must be a finite number");
        return d;
    }

    float number(const json& value, const std::string& path) const {
        return static_cast<float>(real(value, path));
    }

    /// `why_hi`, when given, says in the message why `hi` is the limit.
    int integer(const json& value, const std::string& path, long long lo, long long hi,
                const char* why_hi = nullptr) const {
        if (!value.is_number_integer()) fail(path, "must be an integer");
        // Unsigned values above int64's range read as huge; compare as signed when they fit.
        const bool too_big =
            value.is_number_unsigned() &&
            value.get<unsigned long long>() >
                static_cast<unsigned long long>(std::numeric_limits<long long>::max());
        const long long v =
            too_big ? std::numeric_limits<long long>::max() : value.get<long long>();
        if (v < lo || v > hi)
            fail(path, "must be between " + std::to_string(lo) + " and " + std::to_string(hi) +
                           " (is " + value.dump() + ")" +
                           (why_hi ? ": " + std::to_string(hi) + " is " + why_hi : ""));
        return static_cast<int>(v);
    }

    DVec3 dvec3(const json& value, const std::string& path, bool any_double = false) const {
        if (!value.is_array() || value.size() != 3) fail(path, "must be an array of 3 numbers");
        return {real(value[0], path + "[0]", any_double), real(value[1], path + "[1]", any_double),
                real(value[2], path + "[2]", any_double)};
    }

    Vec3 vec3(const json& value, const std::string& path) const {
        const DVec3 v = dvec3(value, path);
        return {float(v.x), float(v.y), float(v.z)};
    }

    void read_image(const json& image, RenderSettings& settings) const {
        require_object(image, "image");
        check_fields(image, "image", {"width", "height", "spp"});
        if (present(image, "width"))
            settings.width = integer(image["width"], "image.width", 1, kMaxImageSize);
        if (present(image, "height"))
            settings.height = integer(image["height"], "image.height", 1, kMaxImageSize);
        if (present(image, "spp")) settings.spp = integer(image["spp"], "image.spp", 1, kMaxSpp);
    }

    SceneCamera read_camera_fields(const json& c, const std::string& path) const {
        SceneCamera camera;
        if (present(c, "position")) camera.position = dvec3(c["position"], join(path, "position"));
        if (present(c, "look_at")) camera.look_at = dvec3(c["look_at"], join(path, "look_at"));
        if (present(c, "up")) camera.up = dvec3(c["up"], join(path, "up"));
        if (present(c, "fov_y")) {
            camera.fov_y = number(c["fov_y"], join(path, "fov_y"));
            if (!(camera.fov_y > 0.0f && camera.fov_y < 180.0f))
                fail(join(path, "fov_y"), "must be between 0 and 180 degrees, exclusive");
        }
        if (const auto problem = camera_basis_problem(camera))
            fail(join(path, problem->field), problem->what);
        return camera;
    }

    void read_camera(const json& value, RenderSettings& settings) const {
        settings.camera_keys.clear();
        if (value.is_object()) {
            check_fields(value, "camera", {"position", "look_at", "up", "fov_y"});
            settings.camera_keys.push_back({0, read_camera_fields(value, "camera")});
            return;
        }
        if (!value.is_array()) fail("camera", "must be an object or an array of keyframes");
        if (value.empty()) fail("camera", "must have at least one keyframe");
        std::vector<std::size_t> source;  // each key's index in the file, for messages
        for (std::size_t i = 0; i < value.size(); ++i) {
            const std::string path = "camera[" + std::to_string(i) + "]";
            const json& key = value[i];
            require_object(key, path);
            check_fields(key, path, {"frame", "position", "look_at", "up", "fov_y"});
            if (!present(key, "frame"))
                fail(path + ".frame", "is missing: every camera keyframe needs an integer frame");
            const int frame =
                integer(key["frame"], path + ".frame", 0, std::numeric_limits<int>::max());
            settings.camera_keys.push_back({frame, read_camera_fields(key, path)});
            source.push_back(i);
        }
        // Sort by frame, keeping the file's indices alongside to name duplicates.
        std::vector<std::size_t> order(source.size());
        for (std::size_t i = 0; i < order.size(); ++i) order[i] = i;
        std::stable_sort(order.begin(), order.end(), [&](std::size_t a, std::size_t b) {
            return settings.camera_keys[a].frame < settings.camera_keys[b].frame;
        });
        std::vector<CameraKey> sorted;
        for (std::size_t k = 0; k < order.size(); ++k) {
            const CameraKey& key = settings.camera_keys[order[k]];
            if (k > 0 && sorted.back().frame == key.frame)
                fail("camera[" + std::to_string(source[order[k]]) + "].frame",
                     "repeats frame " + std::to_string(key.frame) + " of camera[" +
                         std::to_string(source[order[k - 1]]) + "]");
            sorted.push_back(key);
        }
        settings.camera_keys = std::move(sorted);
    }

    void read_lights(const json& value, RenderSettings& settings) const {
        if (!value.is_array()) fail("lights", "must be an array");
        for (std::size_t i = 0; i < value.size(); ++i) {
            const std::string path = "lights[" + std::to_string(i) + "]";
            const json& l = value[i];
            require_object(l, path);
            Light light;
            if (present(l, "type")) {
                if (!l["type"].is_string()) fail(path + ".type", "must be a string");
                const std::string type = l["type"].get<std::string>();
                if (type == "point")
                    light.type = Light::Type::point;
                else if (type == "directional")
                    light.type = Light::Type::directional;
                else
                    fail(path + ".type",
                         "must be \"point\" or \"directional\" (is \"" + type + "\")");
            }
            if (light.type == Light::Type::point) {
                check_light_strength(l, path, true);
                check_fields(l, path, {"type", "position", "intensity"});
                if (present(l, "position"))
                    light.position = dvec3(l["position"], path + ".position");
                if (present(l, "intensity"))
                    light.intensity = dvec3(l["intensity"], path + ".intensity", true);
            } else {
                check_light_strength(l, path, false);
                check_fields(l, path, {"type", "direction", "irradiance"});
                if (present(l, "direction"))
                    light.direction = dvec3(l["direction"], path + ".direction");
                if (light.direction == DVec3{0, 0, 0})
                    fail(path + ".direction", "must not be the zero vector");
                // Normalised in double (render_setup.cpp); 1e-200 has no square even there.
                if (!normalizable(light.direction))
                    fail(path + ".direction", "is too short to give a direction");
                if (present(l, "irradiance"))
                    light.intensity = dvec3(l["irradiance"], path + ".irradiance");
            }
            if (light.intensity.x < 0 || light.intensity.y < 0 || light.intensity.z < 0)
                fail(path + (light.type == Light::Type::point ? ".intensity" : ".irradiance"),
                     "must not be negative");
            settings.lights.push_back(light);
        }
    }

    std::string file_;
};

}  // namespace

const char* integrator_name(Integrator integrator) {
    return integrator == Integrator::path ? "path" : "whitted";
}

namespace {

/// The keys around `frame`, and how far between them it lies; a and b are the same key before
/// the first key, after the last and for a fixed camera.
struct KeyPair {
    const CameraKey *a, *b;
};

KeyPair keys_around(const std::vector<CameraKey>& keys, int frame) {
    if (frame <= keys.front().frame) return {&keys.front(), &keys.front()};
    if (frame >= keys.back().frame) return {&keys.back(), &keys.back()};
    // The first key after `frame`; the one before it is at or before `frame`.
    const auto next = std::upper_bound(keys.begin(), keys.end(), frame,
                                       [](int f, const CameraKey& key) { return f < key.frame; });
    return {&*(next - 1), &*next};
}

std::string camera_of_frame(const std::filesystem::path& path, int frame, const KeyPair& keys) {
    std::string where = path.string() + ": the camera of frame " + std::to_string(frame);
    if (keys.a != keys.b)
        where += ", between the keys of frames " + std::to_string(keys.a->frame) + " and " +
                 std::to_string(keys.b->frame);
    return where;
}

}  // namespace

Camera RenderSettings::camera_at(int frame, const SceneFrame& scene_frame) const {
    if (camera_keys.empty()) return in_frame(SceneCamera{}, scene_frame);
    const KeyPair keys = keys_around(camera_keys, frame);
    const Camera a = in_frame(keys.a->camera, scene_frame);
    Camera c = a;
    if (keys.a != keys.b) {
        // Interpolated in the frame, in float: a scene near the origin is only scaled by a power
        // of two there, so its frames' cameras are those of the unscaled scene, bit for bit.
        const Camera b = in_frame(keys.b->camera, scene_frame);
        const float t = static_cast<float>(frame - keys.a->frame) /
                        static_cast<float>(keys.b->frame - keys.a->frame);
        c.position = lerp(a.position, b.position, t);
        c.look_at = lerp(a.look_at, b.look_at, t);
        c.up = lerp(a.up, b.up, t);
        c.fov_y = a.fov_y + (b.fov_y - a.fov_y) * t;
    }
    if (const auto problem = traced_basis_problem(c))
        throw Error(camera_of_frame(path, frame, keys) + ": its " + problem->field + " " +
                    problem->what);
    return c;
}

void RenderSettings::check_camera_at(int frame) const {
    if (camera_keys.empty()) return;
    const KeyPair keys = keys_around(camera_keys, frame);
    if (keys.a == keys.b) return;  // a key, checked when the file was read
    const double t = double(frame - keys.a->frame) / double(keys.b->frame - keys.a->frame);
    const SceneCamera& a = keys.a->camera;
    const SceneCamera& b = keys.b->camera;
    SceneCamera c;
    c.position = a.position + (b.position - a.position) * t;
    c.look_at = a.look_at + (b.look_at - a.look_at) * t;
    c.up = a.up + (b.up - a.up) * t;
    if (const auto problem = camera_basis_problem(c))
        throw Error(camera_of_frame(path, frame, keys) + ": its " + problem->field + " " +
                    problem->what);
}

RenderSettings parse_render_json(const std::string& text, const std::filesystem::path& name) {
    RenderSettings settings = RenderFileParser(name.string()).parse(text);
    settings.path = name;
    return settings;
}

RenderSettings load_render_file(const std::filesystem::path& path) {
    // Render files are a few kilobytes (a long keyframed camera, a few hundred); 64 MiB is far
    // past any real one.
    return parse_render_json(read_input_file(path, "render file", std::uint64_t(64) << 20), path);
}

}  // namespace kdray
