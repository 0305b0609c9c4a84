// cmd_compare.cpp — `kdray compare A B`: two hit AOVs (conventions.md's agreement, as
// `embree_ref --compare` counts it) or two images, with kdray alone, for the device check
// (scripts/device-check.sh) on a machine without Python or the Embree peer.
#include <cmath>
#include <iostream>
#include <nlohmann/json.hpp>
#include <sstream>

#include "cli/commands.h"
#include "cli/log.h"
#include "core/error.h"
#include "core/io/image.h"
#include "core/io/image_codec.h"
#include "core/io/image_compare.h"

namespace kdray::cli {
namespace {

/// Whether `path` is an EXR with the AOV's Z and prim_id channels.
bool is_aov(const std::filesystem::path& path) {
    try {
        const ExrImage exr = read_exr(path);
        return exr.find("Z") && exr.find("prim_id");
    } catch (const Error&) {
        return false;
    }
}

/// A double for JSON: nlohmann writes inf as null, so a perfect PSNR is the string "inf".
nlohmann::json number(double v) {
    if (std::isinf(v)) return v > 0 ? "inf" : "-inf";
    return v;
}

}  // namespace

int run_compare(const CompareCommand& command) {
    if (!std::filesystem::exists(command.a)) throw UsageError("no such file: " + command.a);
    if (!std::filesystem::exists(command.b)) throw UsageError("no such file: " + command.b);
    const bool aovs = is_aov(command.a) && is_aov(command.b);
    nlohmann::json out{{"a", command.a}, {"b", command.b}, {"kind", aovs ? "aov" : "image"}};
    double fraction = 0.0;
    const double max_fraction = command.max_fraction.value_or(aovs ? 1e-4 : 0.0);
    if (aovs) {
        const AovComparison r = compare_aovs(read_aov(command.a), read_aov(command.b));
        out.update({{"pixels", r.pixels},
                    {"both_miss", r.both_miss},
                    {"both_hit", r.both_hit},
                    {"only_a_hits", r.only_a_hits},
                    {"only_b_hits", r.only_b_hits},
                    {"z_differs", r.z_differs},
                    {"prim_differs", r.prim_differs},
                    {"mismatches", r.mismatches},
                    {"mismatch_fraction", r.mismatch_fraction}});
        fraction = r.mismatch_fraction;
    } else {
        const ImageComparison r = compare_image_files(command.a, command.b, command.tolerance);
        out.update({{"pixels", r.pixels},
                    {"channels", r.channels},
                    {"max_abs_difference", number(r.max_abs_difference)},
                    {"mean_abs_difference", number(r.mean_abs_difference)},
                    {"psnr_db", number(r.psnr_db)},
                    {"tolerance", r.tolerance},
                    {"pixels_over", r.pixels_over},
                    {"fraction_over", r.fraction_over}});
        fraction = r.fraction_over;
    }
    const bool agree = fraction <= max_fraction;
    out["max_fraction"] = max_fraction;
    out["agree"] = agree;
    if (command.json) {
        std::cout << out.dump(2) << "\n";
    } else {
        std::cout << (aovs ? "hit AOVs" : "images") << " " << command.a << " and " << command.b
                  << ": " << (aovs ? "mismatch_fraction " : "fraction of pixels over tolerance ")
                  << fraction << " (at most " << max_fraction
                  << "): " << (agree ? "agree" : "DISAGREE") << "\n";
        for (const auto& [key, value] : out.items())
            if (key != "a" && key != "b" && key != "kind" && key != "agree")
                std::cout << "  " << key << " " << value.dump() << "\n";
    }
    if (!agree) {
        std::ostringstream message;
        message << command.a << " and " << command.b
                << " disagree: " << (aovs ? "mismatch_fraction " : "fraction_over ") << fraction
                << " > " << max_fraction;
        print_error(message.str());
    }
    return agree ? 0 : 1;
}

}  // namespace kdray::cli
