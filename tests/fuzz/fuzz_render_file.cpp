// fuzz_render_file.cpp — libFuzzer target for parse_render_json, the render-file reader (the part
// of load_render_file after the file is read). kdray::Error is the expected outcome of a bad file;
// a sanitizer report, any other exception, or accepted settings that break the promises of
// render_file.h are bugs.
#include <cmath>
#include <cstdint>
#include <cstdio>
#include <cstdlib>
#include <string>

#include "core/error.h"
#include "core/render/camera.h"
#include "core/render/render_file.h"

namespace {

[[noreturn]] void bug(const char* what) {
    std::fprintf(stderr, "fuzz_render_file: invariant broken: %s\n", what);
    std::abort();
}

bool finite(const kdray::Vec3& v) {
    return std::isfinite(v.x) && std::isfinite(v.y) && std::isfinite(v.z);
}

void check_settings(const kdray::RenderSettings& s) {
    if (s.width < 1 || s.height < 1 || s.spp < 1 || s.max_depth < 1) bug("size out of range");
    if (s.camera_keys.empty()) bug("no camera key");
    for (std::size_t i = 0; i < s.camera_keys.size(); ++i) {
        const kdray::SceneCamera& c = s.camera_keys[i].camera;
        if (!is_finite(c.position) || !is_finite(c.look_at) || !is_finite(c.up))
            bug("non-finite camera");
        if (!(c.fov_y > 0.0f && c.fov_y < 180.0f)) bug("fov_y out of (0, 180)");
        // The traced camera (identity frame) either has a finite basis or is refused.
        try {
            const kdray::CameraRays rays(s.camera_at(s.camera_keys[i].frame), s.width, s.height);
            if (!finite(rays.forward) || !finite(rays.right) || !finite(rays.up))
                bug("accepted camera without a finite basis");
        } catch (const kdray::Error&) {
        }
        if (i > 0 && !(s.camera_keys[i - 1].frame < s.camera_keys[i].frame))
            bug("camera keys not strictly increasing");
    }
    for (const kdray::Light& l : s.lights)
        if (!is_finite(l.position) || !is_finite(l.direction) || !is_finite(l.intensity))
            bug("non-finite light");
        else if (l.type == kdray::Light::Type::directional && !(kdray::length(l.direction) > 0.0))
            bug("accepted directional light that does not normalise");
    if (!finite(s.background)) bug("non-finite background");
    // camera_at must hold at, between and around the keys, without overflow.
    const int first = s.camera_keys.front().frame, last = s.camera_keys.back().frame;
    for (int frame : {0, first, last, first + (last - first) / 2, -1, 2147483647}) {
        try {
            s.check_camera_at(frame);
            const kdray::Camera c = s.camera_at(frame);
            if (!std::isfinite(c.fov_y)) bug("camera_at gave a non-finite fov");
        } catch (const kdray::Error&) {
        }
    }
}

}  // namespace

extern "C" int LLVMFuzzerTestOneInput(const std::uint8_t* data, std::size_t size) {
    const std::string text(reinterpret_cast<const char*>(data), size);
    try {
        check_settings(kdray::parse_render_json(text, "fuzz.json"));
    } catch (const kdray::Error&) {
        // a bad file, reported as it should be
    }
    return 0;
}
