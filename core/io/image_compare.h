// image_compare.h — two hit AOVs or two images compared pixel by pixel, for `kdray compare`: the
// device check (scripts/device-check.sh) holds a device's output against references rendered on
// another machine without any tool but kdray. AOVs agree as conventions.md says (both miss, or
// both hit with |Z_a - Z_b| <= 1e-4 max(1, Z_b)), the rule of `embree_ref --compare`.
#pragma once

#include <cstdint>
#include <filesystem>

#include "core/io/image.h"

namespace kdray {

struct AovComparison {
    std::uint64_t pixels = 0;
    std::uint64_t both_miss = 0, both_hit = 0;
    std::uint64_t only_a_hits = 0, only_b_hits = 0;  // one hits, the other misses
    std::uint64_t z_differs = 0;                     // both hit, Z beyond the tolerance
    std::uint64_t prim_differs = 0;                  // both hit, other triangles (ties included)
    std::uint64_t mismatches = 0;                    // pixels that do not agree
    double mismatch_fraction = 0.0;
};

/// `a` against `b` (b the reference: the tolerance scales with its Z). Throws Error when their
/// sizes differ.
AovComparison compare_aovs(const HitBuffer& a, const HitBuffer& b);

struct ImageComparison {
    std::uint64_t pixels = 0;
    int channels = 0;
    double max_abs_difference = 0.0;   // the largest |a - b| of one channel of one pixel
    double mean_abs_difference = 0.0;  // over every channel of every pixel
    double psnr_db = 0.0;              // 10 log10(1 / mean squared difference); inf when equal
    double tolerance = 0.0;
    std::uint64_t pixels_over = 0;  // pixels with a channel differing by more than tolerance
    double fraction_over = 0.0;
};

/// The image files at `a` and `b` (PNG as values in [0, 1], EXR linear) compared channel by
/// channel. Throws Error naming the files when their sizes or channel counts differ.
ImageComparison compare_image_files(const std::filesystem::path& a, const std::filesystem::path& b,
                                    double tolerance);

}  // namespace kdray
