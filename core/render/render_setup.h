// render_setup.h — turns a frame's scene, render file and camera into what the shared shading of
// kd_render.h reads (KdView, KdMaterial, KdLight), and decides which effects the frame calls for:
// shadow rays only with lights, reflection only when a material reflects, refraction only when
// one transmits, ambient light only when the render file has some and a material reflects it
// (Ka > 0), area lights only when a triangle with some area emits (Ke > 0), textures only when a
// material has map_Kd or map_Ka and the scene has vt, the path integrator only when the render
// file asks for it. The decision and its reasons go to stats.json.
#pragma once

#include <cstdint>
#include <functional>
#include <string>
#include <vector>

#include <nlohmann/json.hpp>

#include "core/device/kd_shared.h"
#include "core/device/kd_traverse.h"
#include "core/render/render_file.h"
#include "core/scene/scene.h"

namespace kdray {

struct Effects {
    bool shadows = false, reflection = false, refraction = false, ambient = false;
    bool area_lights = false, textures = false;
    /// The path integrator (kd_path.h) in place of Whitted's ray tree.
    bool path = false;
    /// A material reflects ambient light (Ka > 0) but Whitted's integrator has none to give it:
    /// the scene's shadows stay black, which render says once (ambient_reason names the material).
    bool ambient_unlit = false;
    std::string shadows_reason, reflection_reason, refraction_reason, ambient_reason;
    std::string area_lights_reason, textures_reason, path_reason;

    kd_u32 bits() const;
    nlohmann::json to_json() const;
};

/// Looks only at the materials some triangle uses, and at the render file's lights and depth.
Effects decide_effects(const Scene& scene, const RenderSettings& settings);

/// `ambient`: the render file's ambient light, which the material reflects by its Ka.
KdMaterial to_device_material(const Material& material, const Vec3& ambient);
/// The light in the scene's frame: a point light's position mapped there and its intensity
/// scaled by the frame's scale squared, so that intensity / distance^2 is the scene's.
KdLight to_device_light(const Light& light, const SceneFrame& frame);
/// The emitter table of conventions.md's emitters: every triangle of non-zero area whose material
/// has Ke > 0, in triangle order, chosen in proportion to luminance(Ke) x area (Rec. 709
/// luminance). Empty when nothing emits.
std::vector<KdEmitter> emitter_table(const Scene& scene);

/// Camera basis exactly as conventions.md (and the Embree peer) computes it.
KdView make_view(const Camera& camera, const RenderSettings& settings, const Scene& scene,
                 const Effects& effects, kd_u32 seed);

struct RenderInputs {
    KdView view;
    std::vector<KdMaterial> materials;
    std::vector<KdLight> lights;
    /// emitter_table's, or one unread entry when nothing emits (never a zero-size buffer).
    std::vector<KdEmitter> emitters;
    Effects effects;
    /// KDRAY_INTERSECT_*: the ray-triangle test of every trace (`kdray render --intersect`).
    kd_u32 intersect = KDRAY_INTERSECT_WATERTIGHT;
    /// Whether the OpenCL tracer traces primary rays as packets of 16 (`kdray render --packets`):
    /// Auto does on CPU devices, whose SIMD lanes a single ray leaves idle. Packets exist for the
    /// watertight test only; the hits are the same either way.
    enum class Packets { Auto, On, Off } packets = Packets::Auto;
    /// Whether the frame's hit buffer carries the centre hits' normals (the AOV's N channels).
    bool normals = true;
    /// Whether it carries each centre ray's walk (kd_pixel_cost: the AOV's cost channels and the
    /// heat map), traced in a pass of its own.
    bool cost = false;
    /// Told, on the calling thread, how far the trace is: `done` of `total` primary rays (camera
    /// samples) traced, once with 0 as it starts and then between chunks of work (the OpenCL
    /// tracer's launches, the reference's rows). Empty: nobody asks.
    std::function<void(std::uint64_t done, std::uint64_t total)> progress;
};
RenderInputs prepare_render(const Scene& scene, const RenderSettings& settings,
                            const Camera& camera, kd_u32 seed);

/// The names `kdray render --intersect` and `--packets` take, as stats.json records them:
/// "watertight" or "moller"; "auto", "on" or "off".
std::string intersect_name(kd_u32 intersect);
std::string packets_name(RenderInputs::Packets packets);

}  // namespace kdray
