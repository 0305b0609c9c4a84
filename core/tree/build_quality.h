// build_quality.h — the OpenCL builder's ladder of tree qualities (`--quality low|medium|high`,
// named as Embree names its own): each level is a set of the small and large stages' parameters,
// a point on the frontier of build time against tree quality that docs/quality-ladder.md
// measures (scripts/quality_ladder.py). The other build parameters are the same at every level.
#pragma once

#include <optional>
#include <string>
#include <string_view>

#include "core/tree/tree.h"

namespace kdray {

enum class BuildQuality { Low, Medium, High };

/// "low", "medium" or "high".
const char* build_quality_name(BuildQuality quality);

/// The level named `name`, or nothing.
std::optional<BuildQuality> parse_build_quality(std::string_view name);

/// `params` with the ladder's parameters (large_split_bins, small_reclip_refs, small_leaf_refs,
/// small_split_bins) set to `quality`'s.
BuildParams with_build_quality(BuildParams params, BuildQuality quality);

/// The level whose ladder parameters `params` has, or "custom" when a user set one of them apart
/// from any level. Stats name it beside the parameters themselves.
std::string build_quality_of(const BuildParams& params);

/// The default for a render of several frames, rebuilt per frame: the level with the fastest
/// measured frame (build + trace) on the shared animations (docs/quality-ladder.md).
inline constexpr BuildQuality kAnimationBuildQuality = BuildQuality::Low;

/// The default for `build` and a single frame: the best tree (docs/quality-ladder.md).
inline constexpr BuildQuality kStaticBuildQuality = BuildQuality::High;

}  // namespace kdray
