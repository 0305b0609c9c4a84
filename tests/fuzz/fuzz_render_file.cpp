// fuzz_render_file.cpp — libFuzzer target for parse_render_json, the render-file reader (the part
// of load_render_file after the file is read). kdray::Error is the expected outcome of a bad file;
// a sanitizer report, any other exception, or accepted settings that break the promises of
// render_file.h are bugs.
#include <cmath>
#include <cstdint>
#include <cstdio>
#include <cstdlib>
#include <string>

#include "core/camera.h"
#include "core/error.h"
#include "core/render_file.h"

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
        const kdray::Camera& c = s.camera_keys[i].camera;
        if (!finite(c.position) || !finite(c.look_at) || !finite(c.up)) bug("non-finite camera");
        if (!(c.fov_y > 0.0f && c.fov_y < 180.0f)) bug("fov_y out of (0, 180)");
        // The camera model's basis, as the renderer computes it, must exist (render_file.h).
        const kdray::CameraRays rays(c, s.width, s.height);
        if (!finite(rays.forward) || !finite(rays.right) || !finite(rays.up))
            bug("accepted camera without a finite basis");
        if (i > 0 && !(s.camera_keys[i - 1].frame < s.camera_keys[i].frame))
            bug("camera keys not strictly increasing");
    }
    for (const kdray::Light& l : s.lights)
        if (!finite(l.position) || !finite(l.direction) || !finite(l.intensity))
            bug("non-finite light");
        else if (l.type == kdray::Light::Type::directional &&
                 !(kdray::length(kdray::normalize(l.direction)) > 0.5f))
            bug("accepted directional light that does not normalise");
    if (!finite(s.background)) bug("non-finite background");
    // camera_at must hold at, between and around the keys, without overflow.
    const int first = s.camera_keys.front().frame, last = s.camera_keys.back().frame;
    for (int frame : {0, first, last, first + (last - first) / 2, -1, 2147483647}) {
        const kdray::Camera c = s.camera_at(frame);
        if (!std::isfinite(c.fov_y)) bug("camera_at gave a non-finite fov");
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
