#include "core/io/image_compare.h"

#include <algorithm>
#include <cmath>
#include <limits>
#include <string>

#include "core/error.h"
#include "core/io/image_codec.h"

namespace kdray {

AovComparison compare_aovs(const HitBuffer& a, const HitBuffer& b) {
    if (a.width != b.width || a.height != b.height || a.hits.size() != b.hits.size())
        throw Error("cannot compare hit AOVs of " + std::to_string(a.width) + "x" +
                    std::to_string(a.height) + " and " + std::to_string(b.width) + "x" +
                    std::to_string(b.height) + " pixels");
    AovComparison r;
    r.pixels = a.hits.size();
    for (std::size_t i = 0; i < a.hits.size(); ++i) {
        const KdHit& ha = a.hits[i];
        const KdHit& hb = b.hits[i];
        // A miss is prim_id 0xFFFFFFFF (conventions.md); its Z is +inf.
        const bool hit_a = ha.prim != KDRAY_NO_HIT, hit_b = hb.prim != KDRAY_NO_HIT;
        if (!hit_a && !hit_b) {
            ++r.both_miss;
            continue;
        }
        if (hit_a != hit_b) {
            ++(hit_a ? r.only_a_hits : r.only_b_hits);
            ++r.mismatches;
            continue;
        }
        ++r.both_hit;
        if (ha.prim != hb.prim) ++r.prim_differs;
        // Written so that a NaN Z disagrees.
        const double tolerance = 1e-4 * std::max(1.0, double(hb.t));
        if (!(std::abs(double(ha.t) - double(hb.t)) <= tolerance)) {
            ++r.z_differs;
            ++r.mismatches;
        }
    }
    r.mismatch_fraction = r.pixels ? double(r.mismatches) / double(r.pixels) : 0.0;
    return r;
}

ImageComparison compare_image_files(const std::filesystem::path& a, const std::filesystem::path& b,
                                    double tolerance) {
    const DecodedImage ia = read_image(a), ib = read_image(b);
    if (ia.width != ib.width || ia.height != ib.height || ia.channels != ib.channels)
        throw Error("cannot compare " + a.string() + " (" + std::to_string(ia.width) + "x" +
                    std::to_string(ia.height) + ", " + std::to_string(ia.channels) +
                    " channels) with " + b.string() + " (" + std::to_string(ib.width) + "x" +
                    std::to_string(ib.height) + ", " + std::to_string(ib.channels) + " channels)");
    ImageComparison r;
    r.pixels = std::uint64_t(ia.width) * std::uint64_t(ia.height);
    r.channels = ia.channels;
    r.tolerance = tolerance;
    double sum = 0.0, sum_squares = 0.0;
    for (std::uint64_t p = 0; p < r.pixels; ++p) {
        bool over = false;
        for (int c = 0; c < ia.channels; ++c) {
            const std::size_t i = p * ia.channels + c;
            const double d = std::abs(double(ia.values[i]) - double(ib.values[i]));
            // A NaN on either side counts as the largest difference.
            const double diff = std::isnan(d) ? std::numeric_limits<double>::infinity() : d;
            r.max_abs_difference = std::max(r.max_abs_difference, diff);
            sum += diff;
            sum_squares += diff * diff;
            over = over || diff > tolerance;
        }
        r.pixels_over += over;
    }
    const double values = double(r.pixels) * ia.channels;
    r.mean_abs_difference = values > 0 ? sum / values : 0.0;
    const double mse = values > 0 ? sum_squares / values : 0.0;
    r.psnr_db = mse > 0 ? 10.0 * std::log10(1.0 / mse) : std::numeric_limits<double>::infinity();
    r.fraction_over = r.pixels ? double(r.pixels_over) / double(r.pixels) : 0.0;
    return r;
}

}  // namespace kdray
