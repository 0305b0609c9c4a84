// tree.h — a built kd-tree on the host: the shared node layout of kd_shared.h plus the root box
// and the parameters it was built with. Every builder produces one; every tracer walks one.
#pragma once

#include <cstddef>
#include <cstdint>
#include <optional>
#include <string>
#include <string_view>
#include <utility>
#include <vector>

#include "core/device/kd_build_shared.h"
#include "core/device/kd_shared.h"
#include "core/geometry/math.h"

namespace kdray {

/// The surface area heuristic's constants, stated alongside every SAH figure (conventions.md).
/// Defaults are Wald & Havran's (2006) K_T = 15, K_I = 20.
struct SahCosts {
    float traversal = 15.0f;     // C_t: cost of one traversal step
    float intersection = 20.0f;  // C_i: cost of one triangle test
};

/// Most SAH bins a large node of the OpenCL builder may use (BuildParams::large_split_bins).
inline constexpr int kMaxLargeSplitBins = 64;

/// The shape of the OpenCL builder's small-node stage (`--small-stage`); both build the same tree.
/// PerRoot: one work-item builds a small root's whole subtree, depth first (tuned on CPU devices).
/// PerLevel: the paper's shape (Zhou et al. 2008, section 4.2), the small nodes of one level at a
/// time, one work-group per node pricing its candidates in parallel (GPUs). Auto: PerLevel on a
/// GPU device, PerRoot otherwise.
enum class SmallStage { Auto, PerRoot, PerLevel };

/// "auto", "per-root" or "per-level".
const char* small_stage_name(SmallStage stage);

/// The stage named `name` (small_stage_name's names), or nothing.
std::optional<SmallStage> parse_small_stage(std::string_view name);

/// The shape of the OpenCL builder's large-node stage (`--large-stage`); all build the same tree
/// (but for budget leaves, on input whose splits cut most triangles: large_level.h).
/// Chunked and Level go level by level (Zhou et al. 2008, section 4.1). Chunked: a work-item
/// walks a reduction chunk of KDRAY_REDUCE_CHUNK references in order (CPU devices, which run a
/// group's items one after another). Level: the paper's element-parallel shape, a work-item per
/// reference and a work-group per chunk reducing its boxes, bins and counts in local memory
/// (GPUs). DepthFirst: chunked levels until a level has a few nodes per compute unit, then a
/// work-item builds each of its nodes' large subtrees depth first, in cache (CPUs). Auto: Level
/// on a GPU device, DepthFirst otherwise.
enum class LargeStage { Auto, Chunked, Level, DepthFirst };

/// "auto", "chunked", "level" or "depth-first".
const char* large_stage_name(LargeStage stage);

/// The stage named `name` (large_stage_name's names), or nothing.
std::optional<LargeStage> parse_large_stage(std::string_view name);

/// Build parameters. The reference builder uses costs, empty_bonus and max_depth; the OpenCL
/// builder of Zhou et al. (2008) uses them all.
struct BuildParams {
    SahCosts costs;
    /// Reference builder: a split with an empty side has its cost scaled by (1 - empty_bonus).
    float empty_bonus = 0.2f;
    /// Zhou et al.: nodes with more than this many triangles are "large" (empty-space cutting,
    /// then a binned-SAH or spatial-median split); the rest are split by the full SAH with bit
    /// masks.
    int large_node_threshold = 64;
    /// Zhou et al. C_e: cut off empty space when the empty slab exceeds this share of the extent.
    float empty_space_ratio = 0.25f;
    /// OpenCL builder: a large node (after its empty-space cuts) splits at the cheapest by the SAH
    /// of this many equal bins per axis of its tight box; 0 splits it at the spatial median of
    /// its longest axis, as Zhou et al. do. At most kMaxLargeSplitBins.
    int large_split_bins = 32;
    /// OpenCL builder: a small node of at most this many triangles, some of them reaching past
    /// its box, re-clips them to the box and searches its subtree over the clipped boxes
    /// (build_small_reclip.cl); 0 never does. At most KDRAY_RECLIP_REFS.
    int small_reclip_refs = KDRAY_RECLIP_REFS;
    /// OpenCL builder: a small node of at most this many triangles is a leaf without a search;
    /// 0 searches every node (a leaf then only where no split beats C_i N).
    int small_leaf_refs = 0;
    /// OpenCL builder: a small node not on a re-clipped table splits at the cheapest by the SAH of
    /// this many equal bins per axis of its tight box, the large stage's rule, with no
    /// split-candidate masks (build_small_bins.cl); 0 prices every candidate exactly over the
    /// masks, as Zhou et al. do. At most KDRAY_SMALL_MAX_BINS.
    int small_split_bins = 0;
    int max_depth = KDRAY_MAX_DEPTH;
    /// OpenCL builder: the small stage's shape. It changes how the tree is built, not the tree,
    /// so tree files do not record it.
    SmallStage small_stage = SmallStage::Auto;
    /// OpenCL builder: the large stage's shape; like small_stage, not recorded in tree files.
    LargeStage large_stage = LargeStage::Auto;
};

/// Throws Error naming the parameter (and the command-line option that sets it) when `params`
/// is outside what the builders support: C_t finite >= 0, C_i finite > 0, empty_bonus in [0, 1),
/// large_node_threshold in [1, KDRAY_SMALL_ROOT_MAX_REFS] (the small stage's 64-bit masks),
/// empty_space_ratio in [0, 1], large_split_bins in [0, kMaxLargeSplitBins], small_reclip_refs
/// in [0, KDRAY_RECLIP_REFS], small_leaf_refs in [0, KDRAY_SMALL_ROOT_MAX_REFS],
/// small_split_bins in [0, KDRAY_SMALL_MAX_BINS], max_depth in
/// [0, KDRAY_MAX_DEPTH], small_stage and large_stage each one of their values. NaN fails every
/// test. The one check of every builder, the command line and tree files read back.
void validate_build_params(const BuildParams& params);

/// What a build reports about itself beyond the tree: per-stage wall times in the order the stages
/// ran (e.g. upload, aabbs, large_nodes, small_nodes, output, download), level counts, and the
/// device memory it held at its peak. The tree's own figures come from compute_tree_stats.
struct BuildReport {
    std::vector<std::pair<std::string, double>> timings_ms;
    double build_ms = 0;  // the whole build, as the caller sees it
    int large_node_levels = 0;
    int small_node_levels = 0;
    std::size_t device_bytes = 0;  // peak device memory held by the build (0 for CPU builders)
    /// The OpenCL builder's traffic with its device (cl/runtime/device.h, DeviceTraffic): host
    /// waits (blocking reads and writes, finishes), kernel launches, and host-device transfers.
    std::uint64_t device_syncs = 0;
    std::uint64_t kernel_launches = 0;
    std::uint64_t device_transfers = 0;
    /// Large nodes the OpenCL builder made leaves, unsplit, because their level would have held
    /// more references than its budget (pathological input; each is also a warning below).
    std::size_t budget_leaves = 0;
    /// The small stage's shape the OpenCL builder ran, "per-root" or "per-level" (never "auto";
    /// empty for other builders).
    std::string small_stage;
    /// The large stage's shape it ran, "chunked", "level" or "depth-first" (likewise), and with
    /// depth-first the subtrees it built so (its deep roots).
    std::string large_stage;
    std::size_t depth_first_subtrees = 0;
    /// Runs of the depth-first kernel: 1, more when a subtree's arenas ran out and it was built
    /// again with larger ones (0 without depth-first subtrees).
    int depth_first_rounds = 0;
    /// The subtrees those runs after the first built again: only those whose arenas ran out.
    std::size_t depth_first_rebuilt = 0;
    std::vector<std::string> warnings;  // one line each, for the user and stats.json
};

struct KdTree {
    Aabb bounds;  // root box: the scene's bounds
    std::vector<KdNode> nodes;
    std::vector<kd_u32> leaf_indices;
    BuildParams params;
    std::string builder;  // "reference" or "opencl"
};

}  // namespace kdray
