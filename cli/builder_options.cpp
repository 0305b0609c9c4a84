#include "cli/commands.h"

namespace kdray::cli {

BuildParams BuilderOptions::build_params(BuildQuality default_quality) const {
    // main.cpp's --quality check admits only the ladder's names.
    BuildParams p =
        with_build_quality(params, parse_build_quality(quality).value_or(default_quality));
    if (large_split_bins) p.large_split_bins = *large_split_bins;
    if (small_reclip_refs) p.small_reclip_refs = *small_reclip_refs;
    if (small_leaf_refs) p.small_leaf_refs = *small_leaf_refs;
    if (small_split_bins) p.small_split_bins = *small_split_bins;
    // main.cpp's --small-stage check admits only small_stage_name's names.
    p.small_stage = parse_small_stage(small_stage).value_or(SmallStage::Auto);
    p.large_stage = parse_large_stage(large_stage).value_or(LargeStage::Auto);
    return p;
}

}  // namespace kdray::cli
