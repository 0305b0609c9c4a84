#include "core/scene/scene.h"

#include <algorithm>
#include <array>
#include <cmath>
#include <limits>

#include "core/error.h"

namespace kdray {

namespace {

float largest(Vec3 v) {
    return std::max({v.x, v.y, v.z});
}

bool is_dielectric_model(int illum) {
    return illum == 4 || illum == 6 || illum == 7;
}

bool tf_marks_glass(const Material& m) {
    float tf = largest(m.transmission);
    return tf > 0.0f && tf < 1.0f;
}

}  // namespace

bool Material::is_mirror() const {
    return (illum == 3 || illum == 5) && largest(specular) > 0.0f;
}

float Material::transmit_fraction() const {
    if (is_dielectric_model(illum)) return 1.0f;
    if (dissolve < 1.0f) return std::clamp(1.0f - dissolve, 0.0f, 1.0f);
    if (tf_marks_glass(*this)) return largest(transmission);
    return 0.0f;
}

Vec3 Material::transmission_filter() const {
    if (!is_dielectric_model(illum) && dissolve >= 1.0f && tf_marks_glass(*this))
        return transmission / largest(transmission);
    return {1.0f, 1.0f, 1.0f};
}

Aabb Scene::bounds() const {
    // A running bound per float of a triangle (each corner's x, y, z), folded at the end: one
    // running bound per axis made every vertex wait for the one before (the OpenCL build computes
    // this on the host first; 1.6 ms of a 43 ms Kitchen build), these are independent and vector
    // wide.
    constexpr std::size_t kFloats = KDRAY_FLOATS_PER_TRIANGLE;
    std::array<float, kFloats> lo, hi;
    lo.fill(std::numeric_limits<float>::infinity());
    hi.fill(-std::numeric_limits<float>::infinity());
    const float* t = triangles.data();
    for (std::size_t i = 0; i + kFloats <= triangles.size(); i += kFloats)
        for (std::size_t k = 0; k < kFloats; ++k) {
            lo[k] = std::min(lo[k], t[i + k]);
            hi[k] = std::max(hi[k], t[i + k]);
        }
    Aabb b;
    if (triangles.size() < kFloats) return b;
    for (std::size_t k = 0; k < kFloats; k += 3) {
        b.grow(Vec3{lo[k], lo[k + 1], lo[k + 2]});
        b.grow(Vec3{hi[k], hi[k + 1], hi[k + 2]});
    }
    return b;
}

void triangle_cross_double(const float* v, double out[3]) {
    double e1[3], e2[3];
    for (int a = 0; a < 3; ++a) {
        e1[a] = double(v[3 + a]) - double(v[a]);
        e2[a] = double(v[6 + a]) - double(v[a]);
    }
    out[0] = e1[1] * e2[2] - e1[2] * e2[1];
    out[1] = e1[2] * e2[0] - e1[0] * e2[2];
    out[2] = e1[0] * e2[1] - e1[1] * e2[0];
}

void collapse_zero_area_triangles(Scene& scene) {
    scene.zero_area_triangles = 0;
    for (std::size_t t = 0; t < scene.triangle_count(); ++t) {
        float* v = &scene.triangles[t * KDRAY_FLOATS_PER_TRIANGLE];
        for (int i = 0; i < KDRAY_FLOATS_PER_TRIANGLE; ++i)
            if (!std::isfinite(v[i]))
                throw Error(scene.path.string() + ": triangle " + std::to_string(t) +
                            " has a non-finite coordinate");
        double n[3];
        triangle_cross_double(v, n);
        if (n[0] != 0.0 || n[1] != 0.0 || n[2] != 0.0) continue;
        ++scene.zero_area_triangles;
        for (int i = 3; i < KDRAY_FLOATS_PER_TRIANGLE; ++i) v[i] = v[i % 3];
    }
}

Scene make_scene(std::vector<float> triangles, std::string name) {
    if (triangles.size() % KDRAY_FLOATS_PER_TRIANGLE != 0)
        throw Error(name + ": triangle array of " + std::to_string(triangles.size()) +
                    " floats is not a whole number of triangles");
    Scene scene;
    scene.path = name;
    scene.triangles = std::move(triangles);
    scene.materials.push_back(Material{.name = "default"});
    scene.material_ids.assign(scene.triangle_count(), 0);
    collapse_zero_area_triangles(scene);
    return scene;
}

}  // namespace kdray
