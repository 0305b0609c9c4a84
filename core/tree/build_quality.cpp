#include "core/tree/build_quality.h"

namespace kdray {
namespace {

/// The ladder (docs/quality-ladder.md has the measurements behind each level). high is the
/// builder at its best: exact SAH over every candidate, re-clipped small nodes. medium is high
/// that stops searching nodes of 4 triangles or fewer (the deep levels hold most of the small
/// stage's nodes); low stops at 8, never re-clips, and bins large nodes in 8 bins. No level bins
/// small nodes (small_split_bins): at 8 bins the binned search made 24-88% more nodes, a higher
/// SAH and a slower build than the exact one over masks on Kitchen, the bunny and the dragon
/// (docs/small-bins.md), its planes cutting the triangles that a candidate at their bounds
/// would have left whole.
struct Level {
    BuildQuality quality;
    const char* name;
    int large_split_bins, small_reclip_refs, small_leaf_refs, small_split_bins;
};

constexpr Level kLevels[] = {
    {BuildQuality::Low, "low", 8, 0, 8, 0},
    {BuildQuality::Medium, "medium", 32, int(KDRAY_RECLIP_REFS), 4, 0},
    {BuildQuality::High, "high", 32, int(KDRAY_RECLIP_REFS), 0, 0},
};

const Level& level(BuildQuality quality) {
    for (const Level& l : kLevels)
        if (l.quality == quality) return l;
    return kLevels[2];
}

}  // namespace

const char* build_quality_name(BuildQuality quality) {
    return level(quality).name;
}

std::optional<BuildQuality> parse_build_quality(std::string_view name) {
    for (const Level& l : kLevels)
        if (name == l.name) return l.quality;
    return std::nullopt;
}

BuildParams with_build_quality(BuildParams params, BuildQuality quality) {
    const Level& l = level(quality);
    params.large_split_bins = l.large_split_bins;
    params.small_reclip_refs = l.small_reclip_refs;
    params.small_leaf_refs = l.small_leaf_refs;
    params.small_split_bins = l.small_split_bins;
    return params;
}

std::string build_quality_of(const BuildParams& params) {
    for (const Level& l : kLevels)
        if (params.large_split_bins == l.large_split_bins &&
            params.small_reclip_refs == l.small_reclip_refs &&
            params.small_leaf_refs == l.small_leaf_refs &&
            params.small_split_bins == l.small_split_bins)
            return l.name;
    return "custom";
}

}  // namespace kdray
