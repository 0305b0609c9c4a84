#include "cl/program_catalogue.h"

#include <set>

#include "cl/builder/build_context.h"
#include "cl/renderer/opencl_renderer.h"
#include "cl/runtime/program_cache.h"
#include "core/device/kd_intersect_moller.h"
#include "core/tree/build_quality.h"

namespace kdray {

std::vector<ProgramSpec> buildable_programs(bool cpu_device, bool correctly_rounded_divide_sqrt) {
    std::vector<ProgramSpec> programs;
    auto add = [&](const char* file, const std::string& defines) {
        programs.push_back({file, program_build_options(defines)});
    };
    add("primitives.cl", "");

    // Builder: one large-stage program per bin count (BuildParams::large_split_bins).
    std::set<int> bins{0, kMaxLargeSplitBins};
    for (BuildQuality q : {BuildQuality::Low, BuildQuality::Medium, BuildQuality::High})
        bins.insert(with_build_quality(BuildParams{}, q).large_split_bins);
    for (int b : bins) add("build_large.cl", build_detail::large_program_defines(b));
    add("build_small.cl", build_detail::small_program_defines(cpu_device));
    add("build_output.cl", "");

    // Renderer: every set of KDRAY_EFFECT_* bits decide_effects can make (the path integrator
    // never with ambient light), each triangle test, and packets where choose_opencl_render puts
    // them by default (CPU devices, watertight test; --packets off leaves them out there), at
    // each width (render_packet_lanes: 8 on AVX2, 16 on AVX-512, or KDRAY_PACKET_LANES).
    // `--packets on` on a GPU is left out: a CPU-only path there.
    constexpr kd_u32 kWhittedEffects = KDRAY_EFFECT_SHADOWS | KDRAY_EFFECT_REFLECTION |
                                       KDRAY_EFFECT_REFRACTION | KDRAY_EFFECT_AMBIENT |
                                       KDRAY_EFFECT_AREA_LIGHTS | KDRAY_EFFECT_TEXTURES;
    constexpr kd_u32 kPathEffects = (kWhittedEffects & ~KDRAY_EFFECT_AMBIENT) | KDRAY_EFFECT_PATH;
    for (kd_u32 intersect : {KDRAY_INTERSECT_WATERTIGHT, KDRAY_INTERSECT_MOLLER})
        for (kd_u32 effects = 0; effects <= (kWhittedEffects | KDRAY_EFFECT_PATH); ++effects) {
            if ((effects & KDRAY_EFFECT_PATH) && (effects & KDRAY_EFFECT_AMBIENT)) continue;
            OpenClRenderChoice choice;
            choice.effects = effects;
            choice.intersect = intersect;
            add("render.cl", render_program_defines(choice, correctly_rounded_divide_sqrt));
            // A device without fp64 (Intel Arc, Xe-LP) gets the float-float path: once per
            // triangle test and integrator, with every effect.
            if (effects == kWhittedEffects || effects == kPathEffects) {
                choice.fp64 = false;
                add("render.cl", render_program_defines(choice, correctly_rounded_divide_sqrt));
                choice.fp64 = true;
            }
            choice.packets = true;
            if (cpu_device && intersect == KDRAY_INTERSECT_WATERTIGHT)
                for (kd_u32 lanes : {8u, 16u}) {
                    choice.packet_lanes = lanes;
                    add("render.cl", render_program_defines(choice, correctly_rounded_divide_sqrt));
                }
        }
    return programs;
}

}  // namespace kdray
