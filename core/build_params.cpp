// build_params.cpp — the one check of kd-tree build parameters, and the small stage's names
// (kd_tree.h).
#include <cmath>
#include <optional>
#include <sstream>
#include <string>
#include <string_view>

#include "core/error.h"
#include "core/kd_tree.h"

namespace kdray {
namespace {

template <class T>
[[noreturn]] void reject(const char* what, const char* option, T value, const char* rule) {
    std::ostringstream s;
    s << what << " (" << option << ") must be " << rule << ", not " << value;
    throw Error(s.str());
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

void validate_build_params(const BuildParams& p) {
    const float ct = p.costs.traversal, ci = p.costs.intersection;
    if (!(std::isfinite(ct) && ct >= 0))
        reject("the SAH cost of a traversal step C_t", "--ct", ct, "a finite number >= 0");
    if (!(std::isfinite(ci) && ci > 0))
        reject("the SAH cost of a triangle test C_i", "--ci", ci, "a finite number > 0");
    if (!(p.empty_bonus >= 0 && p.empty_bonus < 1))
        reject("the empty-space bonus", "empty_bonus", p.empty_bonus, "in [0, 1)");
    if (p.large_node_threshold < 1 || p.large_node_threshold > 64)
        reject("the large-node threshold T", "--large-threshold", p.large_node_threshold,
               "an integer from 1 to 64");
    if (!(p.empty_space_ratio >= 0 && p.empty_space_ratio <= 1))
        reject("the empty-space ratio C_e", "--empty-ratio", p.empty_space_ratio, "in [0, 1]");
    if (p.large_split_bins < 0 || p.large_split_bins > kMaxLargeSplitBins)
        reject("the large-node SAH bins", "--large-bins", p.large_split_bins,
               "an integer from 0 to 64");
    if (p.small_reclip_refs < 0 || p.small_reclip_refs > int(KDRAY_RECLIP_REFS))
        reject("the small-node re-clip size", "--reclip-refs", p.small_reclip_refs,
               "an integer from 0 to 32");
    if (p.small_leaf_refs < 0 || p.small_leaf_refs > KDRAY_SMALL_ROOT_MAX_REFS)
        reject("the small-node leaf size", "--leaf-refs", p.small_leaf_refs,
               "an integer from 0 to 64");
    if (p.max_depth < 0 || p.max_depth > KDRAY_MAX_DEPTH)
        reject("the tree depth limit", "--tree-depth", p.max_depth, "an integer from 0 to 64");
    if (p.small_stage != SmallStage::Auto && p.small_stage != SmallStage::PerRoot &&
        p.small_stage != SmallStage::PerLevel)
        reject("the small-node stage", "--small-stage", int(p.small_stage),
               "auto, per-root or per-level");
}

}  // namespace kdray
