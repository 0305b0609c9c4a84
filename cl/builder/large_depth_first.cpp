// large_depth_first.cpp — the host side of the large stage's depth-first schedule
// (build_large_depth_first.cl; large_depth_first.h): arenas sized per deep root, the subtrees
// built, then committed to the build's stores.
#include "cl/builder/large_depth_first.h"

#include <algorithm>
#include <array>
#include <cstdint>
#include <string>
#include <vector>

#include "cl/runtime/launch.h"
#include "core/error.h"

namespace kdray::build_detail {
namespace {

/* A deep root holds at most this many references: its workspace (28 bytes a reference, twice
 * over with the lists a split writes) stays within a core's L2 cache (512 KiB on the EPYC the
 * figures come from). */
constexpr std::size_t kCacheReferences = 8192;

/* ... and at least a few subtrees per compute unit, whose sizes differ, so that the cores'
 * shares even out. */
constexpr std::size_t kSubtreesPerUnit = 4;

/* An arena's capacity for a subtree of n references, doubled `grow` times (after it ran out;
 * halved while negative, tests). */
std::uint64_t arena_capacity(unsigned kind, std::uint64_t n, std::uint64_t threshold, int grow) {
    std::uint64_t cap = 0;
    switch (kind) {
        case KDRAY_DF_WORK:
            // The stack of live references and the top node's above list; fixed, since a full
            // workspace makes budget leaves instead of a retry.
            return kReferenceBudgetPerTriangle * n;
        case KDRAY_DF_RECORDS:
            // About 2n / T large nodes, each two records, more with empty-space cuts: up to
            // 0.17 n at T = 64 on the shared scenes.
            cap = 16 * n / threshold + 16;
            break;
        case KDRAY_DF_ROOTS:
            // Up to 0.054 n at T = 64.
            cap = 8 * n / threshold + 16;
            break;
        case KDRAY_DF_SMALL_REFS:
            // Clipping copies straddlers: up to 2.2 references per reference of the deep root
            // (Kitchen at high).
            cap = 3 * n + 64;
            break;
        default:  // KDRAY_DF_LEAF_REFS: only nodes at the depth limit or that nothing separates
            cap = n / 4 + 64;
            break;
    }
    return grow >= 0 ? cap << grow : cap >> -grow;
}

/// The arena starts of a run (kd_depth_first_root, build_large_depth_first.cl): for every arena
/// kind a row of nodes + 1 starts, from the sizes of the subtrees the run builds (the others get
/// none), then the run's items, the deep roots it builds, then 0: the count of items taken.
std::vector<cl_uint> arena_starts(const std::vector<cl_uint>& refs, std::uint64_t threshold,
                                  const std::vector<std::array<int, KDRAY_DF_KINDS>>& grow,
                                  const std::vector<cl_uint>& items) {
    const std::size_t nodes = refs.size();
    std::vector<bool> built(nodes, false);
    for (cl_uint w : items) built[w] = true;
    std::vector<cl_uint> start(KDRAY_DF_KINDS * (nodes + 1));
    for (unsigned kind = 0; kind < KDRAY_DF_KINDS; ++kind) {
        std::uint64_t at = 0;
        for (std::size_t w = 0; w <= nodes; ++w) {
            start[kind * (nodes + 1) + w] = checked_u32(at, "depth-first arena entries");
            if (w < nodes && built[w])
                at += arena_capacity(kind, refs[w], threshold, grow[w][kind]);
        }
    }
    start.insert(start.end(), items.begin(), items.end());
    start.push_back(0);  // the kernel's counter of items taken
    return start;
}

/// The arenas of one run of the depth-first kernel, kept until its subtrees are committed.
struct Arenas {
    DeviceArray start, work_tri, work_box, records, roots, small_tri, small_box, leaf_refs, stacks,
        counts;
    cl_uint item_count = 0;  // deep roots the run built
};

/* Work-items for a run of `items` subtrees, which take them off the kernel's counter: on a CPU
 * one per compute unit, each taking subtree after subtree; on a GPU one per subtree, since it
 * runs them all at once. */
std::size_t depth_first_workers(const BuildContext& ctx, std::size_t items) {
    if (!ctx.device.is_cpu()) return items;
    return std::min<std::size_t>(items, std::max(1u, ctx.device.info().compute_units));
}

cl_uint arena_total(const std::vector<cl_uint>& start, unsigned kind, std::size_t nodes) {
    // At least one entry: OpenCL has no empty buffers.
    return std::max<cl_uint>(1, start[kind * (nodes + 1) + nodes]);
}

}  // namespace

cl_uint deep_root_refs(const BuildContext& ctx, std::size_t triangles) {
    const std::size_t units = std::max(1u, ctx.device.info().compute_units);
    const std::size_t share = triangles / (kSubtreesPerUnit * units);
    const std::size_t floor = std::size_t(ctx.params.large_node_threshold) * 16;
    return cl_uint(std::clamp(share, floor, std::max(floor, kCacheReferences)));
}

DepthFirstResult build_depth_first(BuildContext& ctx, const TriangleBounds& triangles,
                                   const DeepRoots& deep, BuildOutput& output, SmallRoots& small,
                                   unsigned arena_shift) {
    const std::size_t nodes = deep.count;
    std::vector<cl_uint> refs(nodes);
    ctx.device.read(deep.ref_count.buffer(), 0, nodes * sizeof(cl_uint), refs.data(),
                    "reading the depth-first subtrees' sizes");
    const BuildParams& p = ctx.params;
    const KdDepthFirstArgs args{cl_uint(nodes),
                                cl_uint(p.max_depth),
                                cl_uint(p.large_node_threshold),
                                p.empty_space_ratio,
                                p.costs.traversal,
                                p.costs.intersection,
                                p.empty_bonus,
                                cl_uint(kReferenceBudgetPerTriangle)};

    /* Build; an output arena that ran out is made 4 times larger for its subtree and the kernel
     * runs again for those subtrees alone (it only reads the deep roots). Real scenes fit at the
     * first run; input whose splits cut most triangles fills arenas of any size made from the
     * root's size alone (the per-depth budget bounds each depth, not their sum), and takes a few
     * runs. Each run's arenas are kept until its subtrees are committed: on such input the peak
     * holds a kept run's arenas of the subtrees that ran out in it too (their kinds that did not
     * run out, not grown, once more per run), which committing each run's subtrees at once would
     * spare; real scenes make one run. */
    const int shift = -int(arena_shift);
    std::vector<std::array<int, KDRAY_DF_KINDS>> grow(nodes, {0, shift, shift, shift, shift});
    std::vector<cl_uint> counts(nodes * KDRAY_DF_COUNTS);  // of every subtree, from its last run
    std::vector<cl_uint> items(nodes);
    for (std::size_t w = 0; w < nodes; ++w) items[w] = cl_uint(w);
    // Largest first: the work-items take items in this order (kd_build_large_depth_first), so the
    // last to start are the smallest and the compute units finish together.
    std::stable_sort(items.begin(), items.end(),
                     [&](cl_uint a, cl_uint b) { return refs[a] > refs[b]; });
    std::vector<Arenas> runs;
    DepthFirstResult result;
    for (int round = 0;; ++round) {
        result.rounds = round + 1;
        const std::vector<cl_uint> start =
            arena_starts(refs, cl_uint(p.large_node_threshold), grow, items);
        Arenas& a = runs.emplace_back();
        a.item_count = cl_uint(items.size());
        a.start = ctx.allocate<cl_uint>(start.size(), "depth-first arena starts");
        ctx.write(a.start, start);
        const std::size_t work = arena_total(start, KDRAY_DF_WORK, nodes);
        a.work_tri = ctx.allocate<cl_uint>(work, "depth-first workspace references");
        a.work_box = ctx.allocate<KdBuildBox>(work, "depth-first workspace boxes");
        a.records = ctx.allocate<KdBuildNode>(arena_total(start, KDRAY_DF_RECORDS, nodes),
                                              "depth-first node records");
        a.roots = ctx.allocate<KdSmallRoot>(arena_total(start, KDRAY_DF_ROOTS, nodes),
                                            "depth-first small roots");
        const std::size_t small_refs = arena_total(start, KDRAY_DF_SMALL_REFS, nodes);
        a.small_tri = ctx.allocate<cl_uint>(small_refs, "depth-first small references");
        a.small_box = ctx.allocate<KdBuildBox>(small_refs, "depth-first small reference boxes");
        a.leaf_refs = ctx.allocate<cl_uint>(arena_total(start, KDRAY_DF_LEAF_REFS, nodes),
                                            "depth-first leaf references");
        a.stacks =
            ctx.allocate<KdDepthFirstTask>(items.size() * KDRAY_DF_STACK, "depth-first stacks");
        a.counts = ctx.allocate<cl_uint>(items.size() * KDRAY_DF_COUNTS, "depth-first counts");
        enqueue_per_item(
            ctx.device, ctx.kernels.build_depth_first, depth_first_workers(ctx, a.item_count), args,
            a.item_count, deep.node.buffer(), deep.ref_start.buffer(), deep.ref_count.buffer(),
            deep.ref_tri.buffer(), deep.ref_box.buffer(), triangles.triangles.buffer(),
            a.start.buffer(), a.work_tri.buffer(), a.work_box.buffer(), a.records.buffer(),
            a.roots.buffer(), a.small_tri.buffer(), a.small_box.buffer(), a.leaf_refs.buffer(),
            a.stacks.buffer(), a.counts.buffer());
        std::vector<cl_uint> run_counts(items.size() * KDRAY_DF_COUNTS);
        ctx.device.read(a.counts.buffer(), 0, run_counts.size() * sizeof(cl_uint),
                        run_counts.data(), "reading the depth-first subtrees' counts");
        // The run is over (the read waited for it); only its outputs are committed.
        a.work_tri = DeviceArray();
        a.work_box = DeviceArray();
        a.stacks = DeviceArray();
        std::vector<cl_uint> full_items;
        for (std::size_t g = 0; g < items.size(); ++g) {
            const cl_uint w = items[g];
            const cl_uint* run = &run_counts[g * KDRAY_DF_COUNTS];
            std::copy(run, run + KDRAY_DF_COUNTS, &counts[w * KDRAY_DF_COUNTS]);
            if (run[KDRAY_DF_WORK] == 0) continue;
            for (unsigned kind = 1; kind < KDRAY_DF_KINDS; ++kind)
                if (run[KDRAY_DF_WORK] & (1u << kind)) grow[w][kind] += 2;
            full_items.push_back(w);
        }
        if (full_items.empty()) break;
        if (full_items.size() == items.size()) runs.pop_back();  // nothing of it to commit
        if (round == 16 + int(arena_shift))
            throw Error(
                "OpenCL kd-tree build: the depth-first large stage's arenas kept running "
                "out after " +
                std::to_string(round + 1) + " rounds");
        items = std::move(full_items);
        result.rebuilt += items.size();
    }

    /* Where each subtree's output goes: after what the levels made, subtree after subtree. */
    std::vector<cl_uint> base(KDRAY_DF_KINDS * nodes, 0);
    std::array<std::uint64_t, KDRAY_DF_KINDS> at{0, output.node_count, small.count, small.refs,
                                                 output.leaf_refs};
    for (std::size_t w = 0; w < nodes; ++w) {
        const cl_uint* used = &counts[w * KDRAY_DF_COUNTS];
        for (unsigned kind = 1; kind < KDRAY_DF_KINDS; ++kind) {
            base[kind * nodes + w] = checked_u32(at[kind], "depth-first output entries");
            // A subtree's root keeps the record id its level gave it.
            at[kind] += used[kind] - (kind == KDRAY_DF_RECORDS ? 1 : 0);
        }
        result.budget_leaves += used[KDRAY_DF_BUDGET_LEAVES];
    }
    output.reserve_records(ctx, at[KDRAY_DF_RECORDS]);
    small.reserve(ctx, checked_u32(at[KDRAY_DF_ROOTS], "small roots"),
                  checked_u32(at[KDRAY_DF_SMALL_REFS], "small references"));
    const cl_uint leaf_total = checked_u32(at[KDRAY_DF_LEAF_REFS], "leaf references");
    ctx.reserve<cl_uint>(output.leaf_store, std::max<cl_uint>(1, leaf_total), output.leaf_refs,
                         "leaf references");
    DeviceArray base_array = ctx.allocate<cl_uint>(base.size(), "depth-first output bases");
    ctx.write(base_array, base);
    output.regions = ctx.allocate<KdLargeRegion>(nodes, "depth-first subtrees");
    // Each run commits the subtrees that fit in its arenas.
    for (const Arenas& a : runs)
        enqueue_per_item(ctx.device, ctx.kernels.commit_depth_first, a.item_count, cl_uint(nodes),
                         a.item_count, a.start.buffer(), a.counts.buffer(), base_array.buffer(),
                         deep.node.buffer(), a.records.buffer(), a.roots.buffer(),
                         a.small_tri.buffer(), a.small_box.buffer(), a.leaf_refs.buffer(),
                         output.records.buffer(), small.roots.buffer(), small.ref_tri.buffer(),
                         small.ref_box.buffer(), small.ref_root.buffer(),
                         output.leaf_store.buffer(), output.regions.buffer());
    output.region_count = cl_uint(nodes);
    output.node_count = cl_uint(at[KDRAY_DF_RECORDS]);
    small.count = cl_uint(at[KDRAY_DF_ROOTS]);
    small.refs = cl_uint(at[KDRAY_DF_SMALL_REFS]);
    output.leaf_refs = leaf_total;
    return result;
}

}  // namespace kdray::build_detail
