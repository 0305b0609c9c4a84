#include "core/render/render_setup.h"

#include "core/render/camera.h"

#include <algorithm>
#include <cmath>
#include <set>

namespace kdray {

kd_u32 Effects::bits() const {
    return (shadows ? KDRAY_EFFECT_SHADOWS : 0u) | (reflection ? KDRAY_EFFECT_REFLECTION : 0u) |
           (refraction ? KDRAY_EFFECT_REFRACTION : 0u) | (ambient ? KDRAY_EFFECT_AMBIENT : 0u) |
           (area_lights ? KDRAY_EFFECT_AREA_LIGHTS : 0u) | (textures ? KDRAY_EFFECT_TEXTURES : 0u) |
           (path ? KDRAY_EFFECT_PATH : 0u);
}

nlohmann::json Effects::to_json() const {
    return {{"shadows", shadows},
            {"reflection", reflection},
            {"refraction", refraction},
            {"ambient", ambient},
            {"area_lights", area_lights},
            {"textures", textures},
            {"path", path},
            {"ambient_unlit", ambient_unlit},
            {"reasons",
             {{"shadows", shadows_reason},
              {"reflection", reflection_reason},
              {"refraction", refraction_reason},
              {"ambient", ambient_reason},
              {"area_lights", area_lights_reason},
              {"textures", textures_reason},
              {"path", path_reason}}}};
}

Effects decide_effects(const Scene& scene, const RenderSettings& settings) {
    Effects e;
    std::set<kd_u32> used(scene.material_ids.begin(), scene.material_ids.end());
    const Material* mirror = nullptr;
    const Material* glass = nullptr;
    const Material* ambient = nullptr;
    const Material* textured = nullptr;
    for (kd_u32 id : used) {
        const Material& m = scene.materials.at(id);
        if (!textured && (m.diffuse_texture >= 0 || m.ambient_texture >= 0)) textured = &m;
        if (!mirror && m.is_mirror()) mirror = &m;
        if (!glass && m.transmits()) glass = &m;
        if (!ambient && m.reflects_ambient()) ambient = &m;
    }
    if (!textured) {
        e.textures_reason = "no material has a texture that loaded (map_Kd, map_Ka)";
    } else if (!scene.has_texcoords()) {
        e.textures_reason = "no face has texture coordinates (vt)";
    } else {
        e.textures = true;
        e.textures_reason = "material '" + textured->name + "' has a texture";
    }
    const bool path = settings.integrator == Integrator::path;
    if (path) {
        e.path = true;
        e.path_reason = "the render file asks for \"integrator\": \"path\"";
    } else {
        e.path_reason = "the render file's integrator is Whitted's (the default)";
    }
    const Vec3& light = settings.ambient;
    if (path) {
        e.ambient_reason = "the path integrator computes indirect light in its place";
    } else if (!(light.x > 0 || light.y > 0 || light.z > 0)) {
        // A material with Ka asks for an ambient term the render file does not give: said, so
        // that a user sees why the scene's shadows are black (the shared BART scenes).
        e.ambient_unlit = ambient != nullptr;
        e.ambient_reason = ambient ? "the render file has no ambient light, though material '" +
                                         ambient->name + "' reflects it (Ka > 0)"
                                   : "the render file has no ambient light";
    } else if (!ambient) {
        e.ambient_reason = "no material reflects ambient light (Ka 0)";
    } else {
        e.ambient = true;
        e.ambient_reason = "ambient light and material '" + ambient->name + "' has Ka > 0";
    }
    // The first triangle with some area whose material emits: the scene has area lights.
    const Material* emitter = nullptr;
    for (std::size_t t = 0; t < scene.triangle_count() && !emitter; ++t) {
        const Material& m = scene.materials.at(scene.material_ids[t]);
        double cross[3];
        if (m.emits())
            triangle_cross_double(&scene.triangles[t * KDRAY_FLOATS_PER_TRIANGLE], cross);
        if (m.emits() && (cross[0] != 0 || cross[1] != 0 || cross[2] != 0)) emitter = &m;
    }
    if (emitter) {
        e.area_lights = true;
        e.area_lights_reason = "material '" + emitter->name + "' emits (Ke > 0)";
    } else {
        e.area_lights_reason = "no triangle emits";
    }
    if (settings.lights.empty()) {
        e.shadows_reason = emitter ? "the render file has no lights (the emitters light the scene)"
                                   : "the render file has no lights (a headlight casts no "
                                     "visible shadow)";
    } else {
        e.shadows = true;
        e.shadows_reason = std::to_string(settings.lights.size()) + " light(s)";
    }
    if (!path && settings.max_depth < 2) {
        e.reflection_reason = e.refraction_reason = "max_depth 1 allows no secondary rays";
        return e;
    }
    // The path's first segment is the camera's; a second may leave a mirror or glass and see an
    // emitter (Mitsuba counts it so), so only max_depth 1 has no use for them.
    if (path && settings.max_depth == 1) {
        e.reflection_reason = e.refraction_reason = "max_depth 1 allows no bounce";
        return e;
    }
    if (mirror) {
        e.reflection = true;
        e.reflection_reason = "material '" + mirror->name + "' is a mirror";
    } else if (glass) {
        e.reflection = true;
        e.reflection_reason = "material '" + glass->name + "' reflects as a dielectric";
    } else {
        e.reflection_reason = "no material reflects";
    }
    if (glass) {
        e.refraction = true;
        e.refraction_reason = "material '" + glass->name + "' transmits";
    } else {
        e.refraction_reason = "no material transmits";
    }
    return e;
}

KdMaterial to_device_material(const Material& m, const Vec3& ambient) {
    KdMaterial d{};
    Vec3 filter = m.transmission_filter();
    for (int c = 0; c < 3; ++c) {
        d.ambient[c] = m.ambient[c] * ambient[c];
        d.diffuse[c] = m.diffuse[c];
        d.specular[c] = m.specular[c];
        d.emission[c] = m.emission[c];
        d.filter[c] = filter[c];
    }
    d.diffuse_texture = m.diffuse_texture >= 0 ? kd_u32(m.diffuse_texture) : KDRAY_NO_TEXTURE;
    d.ambient_texture = m.ambient_texture >= 0 ? kd_u32(m.ambient_texture) : KDRAY_NO_TEXTURE;
    d.shininess = m.shininess;
    d.ior = m.ior > 0.0f ? m.ior : 1.0f;  // BART writes Ni 0 for opaque materials
    d.transmit_fraction = m.transmit_fraction();
    d.flags = (m.is_mirror() ? KDRAY_MATERIAL_MIRROR : 0u) |
              (m.transmits() ? KDRAY_MATERIAL_DIELECTRIC : 0u) |
              (!m.is_mirror() && m.has_highlight() ? KDRAY_MATERIAL_HIGHLIGHT : 0u);
    return d;
}

std::vector<KdEmitter> emitter_table(const Scene& scene) {
    std::vector<KdEmitter> table;
    std::vector<double> power;
    double total = 0;
    for (std::size_t t = 0; t < scene.triangle_count(); ++t) {
        const Material& m = scene.materials.at(scene.material_ids[t]);
        if (!m.emits()) continue;
        double cross[3];
        triangle_cross_double(&scene.triangles[t * KDRAY_FLOATS_PER_TRIANGLE], cross);
        const double area =
            0.5 * std::sqrt(cross[0] * cross[0] + cross[1] * cross[1] + cross[2] * cross[2]);
        const double luminance =
            0.2126 * m.emission.x + 0.7152 * m.emission.y + 0.0722 * m.emission.z;
        if (!(area > 0 && luminance > 0)) continue;
        table.push_back(KdEmitter{kd_u32(t), 0.0f, 0.0f, 0u});
        power.push_back(area * luminance);
        total += area * luminance;
    }
    // The CDF in double, rounded once per entry; each entry's probability is the width of its
    // interval in float, exactly the chance that a uniform float falls in it.
    double running = 0;
    float below = 0.0f;
    for (std::size_t i = 0; i < table.size(); ++i) {
        running += power[i];
        const float cdf = i + 1 == table.size() ? 1.0f : float(running / total);
        table[i].cdf = cdf;
        table[i].probability = cdf - below;
        below = cdf;
    }
    return table;
}

KdLight to_device_light(const Light& light, const SceneFrame& frame) {
    KdLight d{};
    Vec3 v;
    double power_scale = 1.0;
    if (light.type == Light::Type::point) {
        d.type = KDRAY_LIGHT_POINT;
        v = frame.point(light.position);
        // Intensity / distance^2 at a hit: the frame's distances are the scene's times scale.
        power_scale = frame.scale * frame.scale;
    } else {
        d.type = KDRAY_LIGHT_DIRECTIONAL;
        // In float as before where it can be (a scene's image stays bit for bit what it was);
        // in double where the float has no square ([1e30, 0, 0]).
        const Vec3 f{float(light.direction.x), float(light.direction.y), float(light.direction.z)};
        const float squared = dot(f, f);
        if (squared > 0.0f && std::isfinite(squared)) {
            v = normalize(f);
        } else {
            const double l = length(light.direction);
            v = {float(light.direction.x / l), float(light.direction.y / l),
                 float(light.direction.z / l)};
        }
    }
    for (int c = 0; c < 3; ++c) {
        d.vec[c] = v[c];
        d.power[c] = float(light.intensity[c] * power_scale);
    }
    return d;
}

KdView make_view(const Camera& camera, const RenderSettings& settings, const Scene& scene,
                 const Effects& effects, kd_u32 seed) {
    KdView v = CameraRays(camera, settings.width, settings.height).view();
    for (int a = 0; a < 3; ++a) v.background[a] = settings.background[a];
    v.spp = kd_u32(settings.spp);
    if (effects.path)
        v.max_depth = settings.max_depth < 0 ? 0xFFFFFFFFu : kd_u32(settings.max_depth);
    else
        v.max_depth = kd_u32(std::clamp(settings.max_depth, 1, KDRAY_MAX_BOUNCES));
    v.light_count = kd_u32(settings.lights.size());
    v.effects = effects.bits();
    v.seed = seed;
    v.sampler =
        settings.independent_samples ? KDRAY_SAMPLER_INDEPENDENT : KDRAY_SAMPLER_LOW_DISCREPANCY;
    // Secondary rays start a little off the surface: far enough to clear the rounding of the hit
    // point (a few ulps of the largest coordinate), small against the scene.
    Aabb b = scene.bounds();
    float extent = b.empty() ? 1.0f : std::max({b.extent().x, b.extent().y, b.extent().z});
    float magnitude = b.empty()
                          ? 1.0f
                          : std::max({std::fabs(b.lo.x), std::fabs(b.lo.y), std::fabs(b.lo.z),
                                      std::fabs(b.hi.x), std::fabs(b.hi.y), std::fabs(b.hi.z)});
    v.ray_epsilon = 1e-5f * extent + 5e-7f * magnitude;
    return v;
}

RenderInputs prepare_render(const Scene& scene, const RenderSettings& settings,
                            const Camera& camera, kd_u32 seed) {
    RenderInputs in;
    in.effects = decide_effects(scene, settings);
    in.view = make_view(camera, settings, scene, in.effects, seed);
    for (const Material& m : scene.materials)
        in.materials.push_back(to_device_material(m, settings.ambient));
    for (const Light& l : settings.lights) in.lights.push_back(to_device_light(l, scene.frame));
    if (in.effects.area_lights) in.emitters = emitter_table(scene);
    in.view.emitter_count = kd_u32(in.emitters.size());
    if (in.emitters.empty()) in.emitters.push_back(KdEmitter{});
    if (in.lights.empty()) in.lights.push_back(KdLight{});  // never a zero-size device buffer
    return in;
}

std::string intersect_name(kd_u32 intersect) {
    return intersect == KDRAY_INTERSECT_MOLLER ? "moller" : "watertight";
}

std::string packets_name(RenderInputs::Packets packets) {
    switch (packets) {
        case RenderInputs::Packets::On:
            return "on";
        case RenderInputs::Packets::Off:
            return "off";
        case RenderInputs::Packets::Auto:
            break;
    }
    return "auto";
}

}  // namespace kdray
