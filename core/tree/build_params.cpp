// build_params.cpp — the one check of kd-tree build parameters, and the small stage's names
// (tree.h).
#include <cmath>
#include <optional>
#include <sstream>
#include <string>
#include <string_view>

#include "core/error.h"
#include "core/tree/tree.h"

namespace kdray {
namespace {

template <class T>
[[noreturn]] void reject(const char* what, const char* option, T value, const std::string& rule) {
    std::ostringstream s;
    s << what << " (" << option << ") must be " << rule << ", not " << value;
    throw Error(s.str());
}

/// "an integer from LO to HI", the rule of a parameter bounded by the builders' constants.
std::string integer_rule(int lo, int hi) {
    return "an integer from " + std::to_string(lo) + " to " + std::to_string(hi);
}

}  // namespace

const char* small_stage_name(SmallStage stage) {
    switch (stage) {
        case SmallStage::Auto:
            return "auto";
        case SmallStage::PerRoot:
            return "per-root";
        case SmallStage::PerLevel:
            return "per-level";
    }
    return "?";
}

std::optional<SmallStage> parse_small_stage(std::string_view name) {
    for (SmallStage stage : {SmallStage::Auto, SmallStage::PerRoot, SmallStage::PerLevel})
        if (name == small_stage_name(stage)) return stage;
    return std::nullopt;
}

const char* large_stage_name(LargeStage stage) {
    switch (stage) {
        case LargeStage::Auto:
            return "auto";
        case LargeStage::Chunked:
            return "chunked";
        case LargeStage::Level:
            return "level";
        case LargeStage::DepthFirst:
            return "depth-first";
    }
    return "?";
}

std::optional<LargeStage> parse_large_stage(std::string_view name) {
    for (LargeStage stage :
         {LargeStage::Auto, LargeStage::Chunked, LargeStage::Level, LargeStage::DepthFirst})
        if (name == large_stage_name(stage)) return stage;
    return std::nullopt;
}

void validate_build_params(const BuildParams& p) {
    const float ct = p.costs.traversal, ci = p.costs.intersection;
    if (!(std::isfinite(ct) && ct >= 0))
        reject("the SAH cost of a traversal step C_t", "--cost-traversal/--ct", ct,
               "a finite number >= 0");
    if (!(std::isfinite(ci) && ci > 0))
        reject("the SAH cost of a triangle test C_i", "--cost-intersection/--ci", ci,
               "a finite number > 0");
    if (!(p.empty_bonus >= 0 && p.empty_bonus < 1))
        reject("the empty-space bonus", "--empty-bonus", p.empty_bonus, "in [0, 1)");
    // A large node holds more than T references and a small root at most T, which its masks bound.
    if (p.large_node_threshold < 1 || p.large_node_threshold > KDRAY_SMALL_ROOT_MAX_REFS)
        reject("the large-node threshold T", "--large-node-threshold/--large-threshold",
               p.large_node_threshold, integer_rule(1, KDRAY_SMALL_ROOT_MAX_REFS));
    if (!(p.empty_space_ratio >= 0 && p.empty_space_ratio <= 1))
        reject("the empty-space ratio C_e", "--empty-space-ratio/--empty-ratio",
               p.empty_space_ratio, "in [0, 1]");
    if (p.large_split_bins < 0 || p.large_split_bins > kMaxLargeSplitBins)
        reject("the large-node SAH bins", "--large-split-bins/--large-bins", p.large_split_bins,
               integer_rule(0, kMaxLargeSplitBins));
    if (p.small_reclip_refs < 0 || p.small_reclip_refs > int(KDRAY_RECLIP_REFS))
        reject("the small-node re-clip size", "--small-reclip-refs/--reclip-refs",
               p.small_reclip_refs, integer_rule(0, int(KDRAY_RECLIP_REFS)));
    if (p.small_leaf_refs < 0 || p.small_leaf_refs > KDRAY_SMALL_ROOT_MAX_REFS)
        reject("the small-node leaf size", "--small-leaf-refs/--leaf-refs", p.small_leaf_refs,
               integer_rule(0, KDRAY_SMALL_ROOT_MAX_REFS));
    if (p.small_split_bins < 0 || p.small_split_bins > int(KDRAY_SMALL_MAX_BINS))
        reject("the small-node SAH bins", "--small-split-bins/--small-bins", p.small_split_bins,
               integer_rule(0, int(KDRAY_SMALL_MAX_BINS)));
    if (p.max_depth < 0 || p.max_depth > KDRAY_MAX_DEPTH)
        reject("the tree depth limit", "--tree-depth", p.max_depth,
               integer_rule(0, KDRAY_MAX_DEPTH));
    if (p.small_stage != SmallStage::Auto && p.small_stage != SmallStage::PerRoot &&
        p.small_stage != SmallStage::PerLevel)
        reject("the small-node stage", "--small-stage", int(p.small_stage),
               "auto, per-root or per-level");
    if (!parse_large_stage(large_stage_name(p.large_stage)))
        reject("the large-node stage", "--large-stage", int(p.large_stage),
               "auto, chunked, level or depth-first");
}

}  // namespace kdray
