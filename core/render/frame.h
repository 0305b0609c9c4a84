// frame.h — what rendering a frame produces, whichever renderer ran: the shaded image, the
// centre-ray hits for the AOV, the rays cast by kind, and whether packets traced them.
#pragma once

#include <cstdint>

#include "core/device/kd_shared.h"
#include "core/io/image.h"

namespace kdray {

/// Rays cast in a frame, by kind (64-bit: a long, many-sample frame outgrows 32 bits).
struct RayTotals {
    std::uint64_t primary = 0, shadow = 0, reflection = 0, refraction = 0;
    std::uint64_t area_shadow = 0;  // shadow rays toward points on emissive triangles

    void add(const KdRayCounts& pixel) {
        primary += pixel.primary;
        shadow += pixel.shadow;
        reflection += pixel.reflection;
        refraction += pixel.refraction;
        area_shadow += pixel.area_shadow;
    }
    std::uint64_t total() const { return primary + shadow + reflection + refraction + area_shadow; }
};

struct FrameResult {
    HitBuffer hits;
    Image image;
    RayTotals rays;
    /// Whether the primary rays, and the shadow rays from their hits, were traced in packets:
    /// what ran, which `--packets auto` decides by device and triangle test (the reference
    /// tracer never does).
    bool primary_packets = false, shadow_packets = false;
    /// Rays per packet where packets traced (8 or 16: the device's float width), else 0.
    unsigned packet_lanes = 0;
};

}  // namespace kdray
