#include "core/scene.h"

#include <cmath>

#include "core/error.h"

namespace kdray {

bool Material::reflects() const {
    return illum == 3 || illum == 5 || transmits();
}

bool Material::transmits() const {
    return illum == 4 || illum == 6 || illum == 7 || dissolve < 1.0f;
}

Aabb Scene::bounds() const {
    Aabb b;
    for (std::size_t i = 0; i + 2 < triangles.size(); i += 3)
        b.grow({triangles[i], triangles[i + 1], triangles[i + 2]});
    return b;
}

Scene make_scene(std::vector<float> triangles, std::string name) {
    if (triangles.size() % KDRAY_FLOATS_PER_TRIANGLE != 0)
        throw Error(name + ": triangle array of " + std::to_string(triangles.size()) +
                    " floats is not a whole number of triangles");
    for (std::size_t i = 0; i < triangles.size(); ++i)
        if (!std::isfinite(triangles[i]))
            throw Error(name + ": triangle " + std::to_string(i / KDRAY_FLOATS_PER_TRIANGLE) +
                        " has a non-finite coordinate");
    Scene scene;
    scene.path = name;
    scene.triangles = std::move(triangles);
    scene.materials.push_back(Material{.name = "default"});
    scene.material_ids.assign(scene.triangle_count(), 0);
    for (std::size_t t = 0; t < scene.triangle_count(); ++t) {
        Vec3 a = scene.vertex(t, 0), b = scene.vertex(t, 1), c = scene.vertex(t, 2);
        if (length(cross(b - a, c - a)) == 0.0f) ++scene.zero_area_triangles;
    }
    return scene;
}

}  // namespace kdray
