// large_level.cpp — the host side of the large-node stage (§4.1, build_large.cl; large_level.h).
// One level, as the kernels' file lists it: node bounds, the split decisions, the references
// classified per reduction chunk, the children counted and ranked, and the one read-back of the
// level (the totals that size the next), then the records and the next level written.
#include "cl/builder/large_level.h"

#include <algorithm>
#include <array>
#include <cstdint>
#include <utility>
#include <vector>

#include "cl/builder/large_depth_first.h"
#include "cl/runtime/launch.h"

namespace kdray::build_detail {
namespace {

/* Clipping makes a level hold a few percent more references than the one before (Kitchen: up to
 * 1.13 per triangle, dragon res2 1.24), so per-reference arrays of exactly a level's count never
 * fitted the next level: a first build, with no buffers kept from an earlier one, allocated
 * every level's afresh (the Kitchen: 380 MB of new buffers for a peak of 82 MB, 18 "reference
 * child boxes" of 6 MB), and on a CPU device a new buffer is new pages, each faulted in by the
 * kernel that first writes it (perf: page faults are the whole difference between a first
 * Kitchen build and a later one, about 50 of its 250 ms of CPU). New per-reference buffers get
 * a quarter more room than they need, so that the next levels reuse them, and the split's
 * arrays are kept from level to level: the Kitchen's first build allocates 100 MB, its page
 * faults 27k -> 22k (dragon res2 42k -> 35k); device bytes -5% (Kitchen) to +5% (bunny). */
std::size_t with_room(std::size_t count) {
    return count + count / 4;
}

/// Makes `array` hold `count` elements of T: kept when it does, else replaced (with_room).
template <class T>
void keep_room(BuildContext& ctx, DeviceArray& array, std::size_t count, const std::string& what) {
    if (array.bytes() >= count * sizeof(T)) return;
    array = DeviceArray();  // released first, for the new buffer to reuse if it can
    array = ctx.allocate<T>(count, what, with_room(count));
}

/// A pass over the level's reduction chunks in the build's shape (BuildContext::
/// element_parallel_large): `per_chunk` with a work-item per chunk, or `per_reference`, its
/// build_large_groups.cl twin taking the same arguments, with a work-group per chunk.
template <class... Args>
void enqueue_chunk_pass(BuildContext& ctx, cl::Kernel& per_chunk, cl::Kernel& per_reference,
                        std::size_t chunks, const Args&... args) {
    if (ctx.element_parallel_large)
        enqueue_chunk_groups(ctx.device, per_reference, chunks, args...);
    else
        enqueue_chunk_items(ctx.device, per_chunk, chunks, args...);
}

/// What one level decides about its nodes and references; it lives for that level only.
struct LevelSplit {
    DeviceArray tight_box;   // KdBuildBox per node: its references' bounds
    DeviceArray split;       // KdLargeSplit per node
    DeviceArray cuts;        // KdLargeCuts per node
    DeviceArray chunk_bins;  // SAH bin counts per reduction chunk (large_split_bins > 0)
    DeviceArray chunk_rank;  // per chunk and side: references to that side, then their rank
    DeviceArray slot_rank;   // KDRAY_SLOT_KINDS segments of 2 * nodes slots, scanned
};

/// The slot totals of a level: what it creates, which sizes the next level.
struct LevelTotals {
    std::array<cl_uint, KDRAY_SLOT_KINDS + 1> at{};
    cl_uint total(unsigned kind) const { return at[kind + 1] - at[kind]; }
    cl_uint new_nodes() const {
        cl_uint n = 0;
        for (unsigned g = 0; g <= KDRAY_MAX_CUTS; ++g) n += total(KDRAY_SLOT_CHILD + g);
        return n;
    }
};

/* Node bounds (the root: a segmented reduction of its reference boxes; below it, the union of
 * what the parent's chunks sent to each node), then each node's cuts and split. */
void decide_splits(BuildContext& ctx, const LargeLevel& level, bool force_leaf, LevelSplit& s) {
    const cl_uint nodes = level.nodes, chunks = level.chunks;
    s.tight_box = ctx.allocate<KdBuildBox>(nodes, "large node tight boxes");
    const bool per_reference = ctx.element_parallel_large;
    if (!force_leaf && level.from_parent.chunks > 0) {
        enqueue_kernel(ctx.device, ctx.kernels.union_parent_boxes, nodes, level.parent.buffer(),
                       level.from_parent.chunk_start.buffer(), level.from_parent.chunks,
                       level.from_parent.side_box.buffer(), nodes, s.tight_box.buffer());
    } else if (!force_leaf) {
        DeviceArray chunk_boxes = ctx.allocate<KdBuildBox>(chunks, "reduction chunks");
        if (per_reference) {
            enqueue_chunk_groups(ctx.device, ctx.kernels.reduce_box_groups, chunks,
                                 level.ref_box.buffer(), level.ref_start.buffer(),
                                 level.ref_count.buffer(), level.chunk_start.buffer(), nodes,
                                 chunk_boxes.buffer());
            ctx.primitives.union_chunk_boxes(chunk_boxes.buffer(), level.chunk_start.buffer(),
                                             nodes, s.tight_box.buffer());
        } else {
            ctx.primitives.reduce_box_segments(level.ref_box.buffer(), level.ref_start.buffer(),
                                               level.ref_count.buffer(), level.chunk_start.buffer(),
                                               nodes, chunks, chunk_boxes.buffer(),
                                               s.tight_box.buffer());
        }
    }
    s.split = ctx.allocate<KdLargeSplit>(nodes, "large splits");
    s.cuts = ctx.allocate<KdLargeCuts>(nodes, "empty-space cuts");
    const unsigned bins = unsigned(ctx.params.large_split_bins);
    // With the spatial median no kernel reads the bins; the argument still needs a buffer.
    s.chunk_bins = ctx.allocate<cl_uint>(
        bins > 0 ? std::size_t(chunks) * KDRAY_BIN_COUNTS * bins : 1, "large node SAH bins");
    // The element-parallel shape sums each node's bins in a kernel of its own (a work-item per
    // node and bin value), so that the split reads one set per node.
    const bool bins_by_node = per_reference && bins > 0 && !force_leaf;
    if (bins > 0 && !force_leaf && !per_reference)
        enqueue_chunk_items(ctx.device, ctx.kernels.bin_large, chunks, level.ref_box.buffer(),
                            level.ref_start.buffer(), level.ref_count.buffer(),
                            level.chunk_start.buffer(), nodes, chunks, level.node.buffer(),
                            s.tight_box.buffer(), s.chunk_bins.buffer());
    if (bins_by_node) {
        enqueue_chunk_groups(ctx.device, ctx.kernels.bin_large_groups, chunks,
                             level.ref_box.buffer(), level.ref_start.buffer(),
                             level.ref_count.buffer(), level.chunk_start.buffer(), nodes,
                             level.node.buffer(), s.tight_box.buffer(), s.chunk_bins.buffer());
        DeviceArray node_bins =
            ctx.allocate<cl_uint>(std::size_t(nodes) * KDRAY_BIN_COUNTS * bins, "node SAH bins");
        enqueue_kernel(ctx.device, ctx.kernels.sum_node_bins,
                       std::size_t(nodes) * KDRAY_BIN_COUNTS * bins, level.chunk_start.buffer(),
                       nodes, s.chunk_bins.buffer(), node_bins.buffer());
        s.chunk_bins = std::move(node_bins);
    }
    const KdLargeSplitArgs args{nodes,
                                cl_uint(ctx.params.max_depth),
                                cl_uint(force_leaf),
                                ctx.params.empty_space_ratio,
                                ctx.params.costs.traversal,
                                ctx.params.costs.intersection,
                                ctx.params.empty_bonus,
                                cl_uint(bins_by_node)};
    enqueue_kernel(ctx.device, ctx.kernels.split_large, nodes, args, level.node.buffer(),
                   s.tight_box.buffer(), level.chunk_start.buffer(), level.ref_count.buffer(),
                   s.chunk_bins.buffer(), s.split.buffer(), s.cuts.buffer());
}

/* Classify references, counted per chunk. Then the children's sizes and kinds (and the chunks
 * ranked within their nodes), ranked by one scan over all slot kinds, and the level's one
 * read-back: the totals of every slot kind. */
LevelTotals classify_and_count(BuildContext& ctx, const LargeLevel& level,
                               const TriangleBounds& triangles, const KdLargeLevelArgs& args,
                               LevelSplit& s, LargeScratch& scratch) {
    const std::size_t refs = level.refs, chunks = level.chunks;
    keep_room<cl_uchar>(ctx, scratch.ref_sides, std::max<std::size_t>(refs, 4), "reference sides");
    keep_room<KdBuildBox>(ctx, scratch.child_box, 2 * refs, "reference child boxes");
    s.chunk_rank = ctx.allocate<cl_uint>(2 * chunks, "chunk ranks");
    enqueue_chunk_pass(ctx, ctx.kernels.classify, ctx.kernels.classify_groups, chunks, args,
                       level.ref_start.buffer(), level.ref_count.buffer(),
                       level.chunk_start.buffer(), level.ref_tri.buffer(), level.ref_box.buffer(),
                       triangles.triangles.buffer(), level.node.buffer(), s.split.buffer(),
                       scratch.ref_sides.buffer(), scratch.child_box.buffer(),
                       s.chunk_rank.buffer());

    const std::size_t slots = 2 * std::size_t(level.nodes);
    const std::size_t slot_values = std::size_t(KDRAY_SLOT_KINDS) * slots;
    // A segment more than the scan needs (the total after the last): the totals' strided read
    // below may be checked a whole stride past its last value.
    s.slot_rank = ctx.allocate<cl_uint>(slot_values + slots, "child slots");
    enqueue_kernel(ctx.device, ctx.kernels.count_large, level.nodes, args, level.ref_count.buffer(),
                   level.chunk_start.buffer(), s.split.buffer(), s.cuts.buffer(),
                   s.chunk_rank.buffer(), s.slot_rank.buffer());
    ctx.primitives.exclusive_scan(s.slot_rank.buffer(), s.slot_rank.buffer(), slot_values);

    LevelTotals totals;
    // Each kind's first rank, and the total after the last kind: one transfer and the level's one
    // wait (a read per kind was 15 transfers a level).
    ctx.device.read_strided(s.slot_rank.buffer(), 0, slots * sizeof(cl_uint), sizeof(cl_uint),
                            totals.at.size(), totals.at.data(), "reading the large level's totals");
    return totals;
}

}  // namespace

LargeLevel LargeLevel::allocate(BuildContext& ctx, cl_uint nodes, cl_uint refs, cl_uint chunks) {
    LargeLevel level;
    level.nodes = nodes, level.refs = refs, level.chunks = chunks;
    level.node = ctx.allocate<KdLargeNode>(nodes, "large nodes");
    level.ref_start = ctx.allocate<cl_uint>(nodes, "large node reference starts");
    level.ref_count = ctx.allocate<cl_uint>(nodes, "large node reference counts");
    level.chunk_start = ctx.allocate<cl_uint>(std::size_t(nodes) + 1, "large node chunk starts");
    level.ref_tri = ctx.allocate<cl_uint>(refs, "triangle references", with_room(refs));
    level.ref_box = ctx.allocate<KdBuildBox>(refs, "reference boxes", with_room(refs));
    level.parent = ctx.allocate<cl_uint>(nodes, "large node parent slots");
    return level;
}

LargeLevel LargeLevel::root(BuildContext& ctx, TriangleBounds& triangles, const Aabb& bounds) {
    LargeLevel level;
    const cl_uint n = triangles.count;
    level.nodes = 1, level.refs = n;
    level.chunks = cl_uint((std::size_t(n) + KDRAY_REDUCE_CHUNK - 1) / KDRAY_REDUCE_CHUNK);
    level.node = ctx.allocate<KdLargeNode>(1, "large nodes");
    level.ref_start = ctx.allocate<cl_uint>(1, "large node reference starts");
    level.ref_count = ctx.allocate<cl_uint>(1, "large node reference counts");
    level.chunk_start = ctx.allocate<cl_uint>(2, "large node chunk starts");
    ctx.write(level.node, std::vector<KdLargeNode>{{build_box(bounds), 0, 0}});
    ctx.write(level.ref_start, std::vector<cl_uint>{0});
    ctx.write(level.ref_count, std::vector<cl_uint>{n});
    ctx.write(level.chunk_start, std::vector<cl_uint>{0, level.chunks});
    level.ref_tri = std::move(triangles.ref_tri);
    level.ref_box = std::move(triangles.ref_box);
    return level;
}

void DeepRoots::reserve(BuildContext& ctx, std::size_t roots, std::size_t new_refs) {
    ctx.reserve<KdLargeNode>(node, roots, count, "deep roots");
    ctx.reserve<cl_uint>(ref_start, roots, count, "deep root reference starts");
    ctx.reserve<cl_uint>(ref_count, roots, count, "deep root reference counts");
    ctx.reserve<cl_uint>(ref_tri, new_refs, refs, "deep root triangle ids");
    ctx.reserve<KdBuildBox>(ref_box, new_refs, refs, "deep root triangle boxes");
}

void DeepRoots::make_scene_root(BuildContext& ctx, TriangleBounds& triangles, const Aabb& bounds) {
    node = ctx.allocate<KdLargeNode>(1, "deep roots");
    ref_start = ctx.allocate<cl_uint>(1, "deep root reference starts");
    ref_count = ctx.allocate<cl_uint>(1, "deep root reference counts");
    ctx.write(node, std::vector<KdLargeNode>{{build_box(bounds), 0, 0}});
    ctx.write(ref_start, std::vector<cl_uint>{0});
    ctx.write(ref_count, std::vector<cl_uint>{triangles.count});
    ref_tri = std::move(triangles.ref_tri);
    ref_box = std::move(triangles.ref_box);
    count = 1;
    refs = triangles.count;
}

LargeLevel LargeLevel::next(BuildContext& ctx, const TriangleBounds& triangles, bool force_leaf,
                            BuildOutput& output, SmallRoots& small, DeepRoots& deep,
                            LargeScratch& scratch) {
    LevelSplit s;
    decide_splits(ctx, *this, force_leaf, s);
    const KdLargeLevelArgs args{
        nodes,          refs,       chunks,           output.node_count,
        small.count,    small.refs, output.leaf_refs, cl_uint(ctx.params.large_node_threshold),
        deep.deep_refs, deep.count, deep.refs,        0};
    const LevelTotals totals = classify_and_count(ctx, *this, triangles, args, s, scratch);

    /* Room for what this level creates, then write it. */
    const cl_uint new_roots = totals.total(KDRAY_SLOT_SMALL);
    const cl_uint new_small_refs = totals.total(KDRAY_SLOT_SMALL_REFS);
    output.reserve_records(ctx, std::size_t(output.node_count) + totals.new_nodes());
    small.reserve(ctx, checked_u32(std::uint64_t(small.count) + new_roots, "small roots"),
                  checked_u32(std::uint64_t(small.refs) + new_small_refs, "small references"));
    const cl_uint new_deep_roots = totals.total(KDRAY_SLOT_DEEP);
    const cl_uint new_deep_refs = totals.total(KDRAY_SLOT_DEEP_REFS);
    if (new_deep_roots > 0)
        deep.reserve(ctx, checked_u32(std::uint64_t(deep.count) + new_deep_roots, "deep roots"),
                     checked_u32(std::uint64_t(deep.refs) + new_deep_refs, "deep references"));
    const cl_uint leaf_total = checked_u32(
        std::uint64_t(output.leaf_refs) + totals.total(KDRAY_SLOT_LEAF_REFS), "leaf references");
    ctx.reserve<cl_uint>(output.leaf_store, leaf_total, output.leaf_refs, "leaf references");
    LargeLevel next =
        allocate(ctx, totals.total(KDRAY_SLOT_LARGE), totals.total(KDRAY_SLOT_LARGE_REFS),
                 totals.total(KDRAY_SLOT_LARGE_CHUNKS));
    enqueue_kernel(ctx.device, ctx.kernels.emit_large, nodes, args, node.buffer(),
                   ref_count.buffer(), s.split.buffer(), s.cuts.buffer(), s.slot_rank.buffer(),
                   output.records.buffer(), next.node.buffer(), next.ref_start.buffer(),
                   next.ref_count.buffer(), next.chunk_start.buffer(), next.parent.buffer(),
                   small.roots.buffer(), deep.node.buffer(), deep.ref_start.buffer(),
                   deep.ref_count.buffer());
    DeviceArray side_box = ctx.allocate<KdBuildBox>(2 * std::size_t(chunks), "chunk side boxes");
    enqueue_chunk_pass(ctx, ctx.kernels.distribute, ctx.kernels.distribute_groups, chunks, args,
                       ref_start.buffer(), ref_count.buffer(), chunk_start.buffer(),
                       ref_tri.buffer(), ref_box.buffer(), scratch.ref_sides.buffer(),
                       scratch.child_box.buffer(), s.split.buffer(), s.chunk_rank.buffer(),
                       s.slot_rank.buffer(), next.ref_tri.buffer(), next.ref_box.buffer(),
                       deep.ref_tri.buffer(), deep.ref_box.buffer(), small.ref_tri.buffer(),
                       small.ref_box.buffer(), small.ref_root.buffer(), output.leaf_store.buffer(),
                       side_box.buffer());
    next.from_parent.chunks = chunks;
    next.from_parent.side_box = std::move(side_box);
    next.from_parent.chunk_start = std::move(chunk_start);
    // One batch per generation: a chain's nodes are each other's parents (build_output.cl).
    for (unsigned g = 0; g <= KDRAY_MAX_CUTS; ++g)
        output.add_batch(totals.total(KDRAY_SLOT_CHILD + g));
    small.count += new_roots;
    small.refs += new_small_refs;
    deep.count += new_deep_roots;
    deep.refs += new_deep_refs;
    output.leaf_refs = leaf_total;
    return next;
}

LargeStageResult run_large_stage(BuildContext& ctx, TriangleBounds& triangles, const Aabb& bounds,
                                 BuildOutput& output, SmallRoots& small, unsigned arena_shift) {
    LargeStageResult result;
    if (triangles.count <= cl_uint(ctx.params.large_node_threshold)) {
        small.make_scene_root(ctx, triangles, bounds, output);
        return result;
    }
    DeepRoots deep;
    deep.deep_refs = ctx.depth_first_large ? deep_root_refs(ctx, triangles.count) : 0;
    if (triangles.count <= deep.deep_refs) {
        deep.make_scene_root(ctx, triangles, bounds);
    } else {
        // The kernels take the deep roots' arrays whether or not a level adds to them.
        deep.reserve(ctx, 1, 1);
        const std::size_t budget = kReferenceBudgetPerTriangle * std::size_t(triangles.count);
        LargeScratch scratch;
        for (LargeLevel level = LargeLevel::root(ctx, triangles, bounds); level.nodes > 0;) {
            ++result.levels;
            // Nodes at the depth limit become leaves in kd_split_large_nodes; over the budget,
            // every node of the level does.
            const bool over_budget = level.refs > budget;
            if (over_budget) result.budget_leaves += level.nodes;
            level = level.next(ctx, triangles, over_budget, output, small, deep, scratch);
        }
    }
    if (deep.count > 0) {
        result.depth_first_subtrees = deep.count;
        const DepthFirstResult built =
            build_depth_first(ctx, triangles, deep, output, small, arena_shift);
        result.budget_leaves += built.budget_leaves;
        result.depth_first_rounds = built.rounds;
        result.depth_first_rebuilt = built.rebuilt;
    }

    return result;
}

}  // namespace kdray::build_detail
