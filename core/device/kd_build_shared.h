/* kd_build_shared.h — the layouts and constants of the OpenCL kd-tree builder (Zhou, Hou, Wang &
 * Guo 2008) that its host stages (the .cpp files of cl/builder) and its kernels (the .cl files of
 * cl/builder/kernels) both see: node records, per-node and per-root records of the large and small
 * stages, and the by-value argument records of the kernels with many inputs.
 *
 * The rules of core/device/kd_shared.h hold here too: the header compiles as C++ and as OpenCL C
 * (CMake inlines it into the embedded program source), shared structs hold only 32-bit scalars
 * (kd_u32, kd_i32, kd_f32) and arrays of them with explicit padding, every struct states its size,
 * the host static_asserts it and a test kernel (layout.cl) reports the device's sizeof. Constants
 * are defined here once; the host passes -D options only for true compile-time choices (the number
 * of SAH bins, the popcount of CPU devices).
 *
 * Boxes: KdBuildBox, 6 floats lo.xyz hi.xyz; arrays of boxes are flat float arrays of
 * KDRAY_BOX_FLOATS per box (primitives.cl's segmented reduction reads and writes them so). */
#ifndef KDRAY_KD_BUILD_SHARED_H
#define KDRAY_KD_BUILD_SHARED_H

#include "core/device/kd_shared.h"

/* Floats per box in the builder's box arrays: lo.xyz hi.xyz (sizeof(KdBuildBox) / 4). */
#define KDRAY_BOX_FLOATS 6

/* Elements per chunk of the segmented box reduction (primitives.cl), and so references per
 * reduction chunk of a large node, the unit the large stage's passes go by (build_large.cl). */
#define KDRAY_REDUCE_CHUNK 256u

/* KdBuildNode.axis of a small root: the small stage writes its subtree, and leaf_first is the
 * small root's index. */
#define KDRAY_SMALL_ROOT_AXIS 4u

/* Most references a small root holds: the width of the small stage's 64-bit triangle masks, and
 * so the largest large-node threshold T. */
#define KDRAY_SMALL_ROOT_MAX_REFS 64

/* Most references of a small node that re-clips its triangles to its own box
 * (build_small_reclip.cl): the size of the work-item's private table, and so the largest
 * BuildParams::small_reclip_refs. */
#define KDRAY_RECLIP_REFS 32u

/* Most bins per axis of the small stage's binned search (build_small_bins.cl): the size of its
 * histograms, and so the largest BuildParams::small_split_bins. */
#define KDRAY_SMALL_MAX_BINS 16u

/* Empty-space cuts one large node may chain in one level (each side of its box at most once). */
#define KDRAY_MAX_CUTS 6u

/* Segments of the large stage's per-child slot arrays (build_large.cl): every node of a level
 * owns two child slots (2i below, 2i+1 above), and each kind below is one segment of 2 * nodes
 * values, all scanned at once. */
#define KDRAY_SLOT_LARGE 0u        /* the child stays a large node (1/0) */
#define KDRAY_SLOT_LARGE_REFS 1u   /* ... its reference count */
#define KDRAY_SLOT_LARGE_CHUNKS 2u /* ... its reduction chunks */
#define KDRAY_SLOT_SMALL 3u        /* the child becomes a small root (1/0) */
#define KDRAY_SLOT_SMALL_REFS 4u   /* ... its reference count */
#define KDRAY_SLOT_LEAF_REFS 5u    /* references of a node that becomes a leaf (in its slot 2i) */
#define KDRAY_SLOT_DEEP 6u         /* the child goes to the depth-first schedule (1/0) */
#define KDRAY_SLOT_DEEP_REFS 7u    /* ... its reference count */
#define KDRAY_SLOT_CHILD                                                    \
    8u /* new nodes of generation 0 (then 1, ..., KDRAY_MAX_CUTS): node ids \
        */
#define KDRAY_SLOT_KINDS (KDRAY_SLOT_CHILD + KDRAY_MAX_CUTS + 1u)

/* Counts per SAH bin of a large node's reduction chunk (build_large_sah.cl): 3 axes, the
 * references whose lo and whose hi fall in the bin. */
#define KDRAY_BIN_COUNTS 6u

/* Split candidates per small-root reference: the planes of its box's lo and hi on each axis
 * (candidate k of a reference: axis k / 2, its hi when k is odd), the six lanes of a float8
 * (build_small_search.cl). A candidate's number is KDRAY_CANDIDATE_STRIDE * reference + k: the
 * lanes' own stride, so that candidate c is lane c % 8 of reference c / 8, a shift and a mask.
 * (With a stride of 6 the division and remainder were one udiv and a `freeze` after LLVM's
 * DivRemPairs, an instruction that Oclgrind 21.10's uninitialised-value check cannot run.) */
#define KDRAY_CANDIDATE_STRIDE 8u
#define KDRAY_CANDIDATE_STRIDE_SHIFT 3u

/* Split-candidate masks per small-root reference (build_small.cl): 6 candidates below and 6
 * above, each group padded to 8 ulongs, so that a reference's masks load as two ulong8. */
#define KDRAY_MASK_WORDS_PER_REF 16u
#define KDRAY_MASK_BYTES_PER_REF (KDRAY_MASK_WORDS_PER_REF * 8u)
/* References per work-item of the masks' CPU shape (kd_compute_split_masks_grouped). */
#define KDRAY_MASK_GROUP 4u

/* Work-items of every work-group the builder launches (cl/runtime/launch.h rounds each launch's
 * size up to a multiple of it): one per reference a small node may hold, since the per-level
 * small stage (build_small_level.cl) splits one node per work-group, work-item j pricing the
 * node's j-th reference. */
#define KDRAY_LAUNCH_GROUP 64u

/* KdBuildBox — 24 bytes. lo[3], hi[3]: the box's corners. */
typedef struct KdBuildBox {
    kd_f32 lo[3];
    kd_f32 hi[3];
} KdBuildBox;

/* KdBuildNode — 24 bytes. A node of the builder before its output stage lays the tree out in
 * preorder. Node ids are handed out level by level, so a child's id is always larger than its
 * parent's.
 *   axis         inner: split axis 0/1/2; leaf: KDRAY_LEAF_AXIS; small root: KDRAY_SMALL_ROOT_AXIS.
 *   split        inner: split plane position; otherwise 0.
 *   child[2]     inner: node ids of the below and above children; otherwise 0.
 *   leaf_count   leaf: number of triangles; otherwise 0.
 *   leaf_first   leaf: first entry of its run in the builder's leaf reference store; small root:
 *                its small root index (the small stage writes its subtree in KdSmallNode
 *                records of its own); inner: 0. */
typedef struct KdBuildNode {
    kd_u32 axis;
    kd_f32 split;
    kd_u32 child[2];
    kd_u32 leaf_count;
    kd_u32 leaf_first;
} KdBuildNode;

/* KdSmallNode — 16 bytes. A node of the small stage, in preorder within its small root's subtree.
 *   axis_and_offset  bits 0-1: split axis, or KDRAY_LEAF_AXIS; bits 2-31: inner: the above
 *                    child's index in the subtree; leaf: its first leaf reference, counted from
 *                    the subtree's first.
 *   split_or_count   inner: split position (float bits); leaf: triangle count.
 *   mask_lo, mask_hi leaf: bits 0-31 and 32-63 of its mask over the small root's references
 *                    (bit i: the root's i-th triangle); inner: 0. */
typedef struct KdSmallNode {
    kd_u32 axis_and_offset;
    kd_u32 split_or_count;
    kd_u32 mask_lo;
    kd_u32 mask_hi;
} KdSmallNode;

/* KdLargeNode — 32 bytes. An active node of a large-stage level (its references are given by the
 * level's start, count and chunk arrays, which the segmented reduction reads).
 *   box    the node's box (after kd_split_large_nodes: the box of its chain's last node).
 *   id     its node id (KdBuildNode index).
 *   depth  its depth in the tree (root 0). */
typedef struct KdLargeNode {
    KdBuildBox box;
    kd_u32 id;
    kd_u32 depth;
} KdLargeNode;

/* KdLargeSplit — 8 bytes. A large node's split: axis 0/1/2, or KDRAY_LEAF_AXIS when the node
 * becomes a leaf; pos the plane's position. */
typedef struct KdLargeSplit {
    kd_u32 axis;
    kd_f32 pos;
} KdLargeSplit;

/* KdLargeCuts — 56 bytes. The chain of empty-space cuts of one large node in one level.
 *   count    cuts in the chain (at most KDRAY_MAX_CUTS).
 *   code[g]  cut g: axis * 2 + (the kept side is above).
 *   pos[g]   cut g: the plane's position.
 *   pad      0. */
typedef struct KdLargeCuts {
    kd_u32 count;
    kd_u32 code[KDRAY_MAX_CUTS];
    kd_f32 pos[KDRAY_MAX_CUTS];
    kd_u32 pad;
} KdLargeCuts;

/* KdSmallRoot — 40 bytes. A small root (a node of at most KDRAY_SMALL_ROOT_MAX_REFS references
 * whose subtree the small stage builds).
 *   box        its box.
 *   ref_start  its first reference in the small roots' reference lists (a root's references are
 *              contiguous, and so are consecutive roots').
 *   ref_count  its number of references.
 *   node_id    its KdBuildNode id.
 *   depth      its depth in the tree. */
typedef struct KdSmallRoot {
    KdBuildBox box;
    kd_u32 ref_start;
    kd_u32 ref_count;
    kd_u32 node_id;
    kd_u32 depth;
} KdSmallRoot;

/* KdSmallLevelNode — 96 bytes. A node of the per-level small stage (build_small_level.cl), in
 * one batch's array of every level's nodes (level by level; a node's children are the next
 * level's, two consecutive ids). Its parent (or kd_start_small_level) writes the words up to
 * table_on; its own level writes axis, split, child and, for a leaf, root_mask.
 *   box[6]          its box, lo.xyz hi.xyz (KdBuildBox).
 *   mask_lo, hi     bits 0-31 and 32-63 of its triangles, over the re-clipped table of the
 *                   ancestor that re-clipped (table_on), else over the small root's references.
 *   root_mask_lo,hi the same triangles over the small root's references (a leaf: its own).
 *   table_box[6]    table_on: the box of the ancestor that re-clipped (its table is rebuilt from
 *                   it and table_mask at every level); else 0.
 *   table_mask_lo,hi table_on: that ancestor's triangles over the root's references, before it
 *                   re-clipped them; else 0.
 *   root            its small root's index.
 *   depth           its depth in the tree.
 *   table_on        1 when its mask is over a re-clipped table.
 *   axis            split axis 0/1/2, or KDRAY_LEAF_AXIS.
 *   split           inner: the split position; leaf: 0.
 *   child           inner: the id of its below child (the above child is child + 1); leaf: 0. */
typedef struct KdSmallLevelNode {
    kd_f32 box[6];
    kd_u32 mask_lo;
    kd_u32 mask_hi;
    kd_u32 root_mask_lo;
    kd_u32 root_mask_hi;
    kd_f32 table_box[6];
    kd_u32 table_mask_lo;
    kd_u32 table_mask_hi;
    kd_u32 root;
    kd_u32 depth;
    kd_u32 table_on;
    kd_u32 axis;
    kd_f32 split;
    kd_u32 child;
} KdSmallLevelNode;

/* KdLargeSplitArgs — 32 bytes. kd_split_large_nodes' scalars: the level's node count, the depth
 * limit, force_leaf (1: every node becomes a leaf, the level outgrew the reference budget),
 * empty_ratio C_e, the SAH costs C_t, C_i and the empty-space bonus; bins_by_node: 1 when the
 * SAH bins come summed per node (the element-parallel large stage), 0 per reduction chunk. */
typedef struct KdLargeSplitArgs {
    kd_u32 nodes;
    kd_u32 max_depth;
    kd_u32 force_leaf;
    kd_f32 empty_ratio;
    kd_f32 cost_traversal;
    kd_f32 cost_intersection;
    kd_f32 empty_bonus;
    kd_u32 bins_by_node;
} KdLargeSplitArgs;

/* KdLargeLevelArgs — 48 bytes. What the large stage's per-level kernels after the split know of
 * their level: its nodes, references and reduction chunks; where this level's new node ids,
 * small roots, small-root references and leaf references start; the large-node threshold T (more
 * references stay large); deep_refs, the most references of a large child that goes to the
 * depth-first schedule instead of the next level (0: none does), and where this level's such
 * children (deep roots) and their references start; pad 0. */
typedef struct KdLargeLevelArgs {
    kd_u32 nodes;
    kd_u32 refs;
    kd_u32 chunks;
    kd_u32 node_base;
    kd_u32 small_root_base;
    kd_u32 small_ref_base;
    kd_u32 leaf_ref_base;
    kd_u32 large_threshold;
    kd_u32 deep_refs;
    kd_u32 deep_root_base;
    kd_u32 deep_ref_base;
    kd_u32 pad;
} KdLargeLevelArgs;

/* The depth-first large stage (build_large_depth_first.cl): one work-item builds the whole large
 * subtree of one deep root, in arenas of its own that a second kernel copies into the build's
 * stores.
 * Arena kinds, each an array of nodes + 1 starts per kind (item w owns [start[w], start[w + 1])),
 * and the same numbers index the counts an item reports: */
#define KDRAY_DF_WORK 0u       /* workspace references (triangle id and clipped box) */
#define KDRAY_DF_RECORDS 1u    /* KdBuildNode records, the subtree's root first */
#define KDRAY_DF_ROOTS 2u      /* KdSmallRoot records of the small roots it makes */
#define KDRAY_DF_SMALL_REFS 3u /* their references */
#define KDRAY_DF_LEAF_REFS 4u  /* references of the large nodes that become leaves */
#define KDRAY_DF_KINDS 5u
/* In an item's counts, the WORK entry reports instead the arenas that were too small (bit k: kind
 * k), and this extra one its budget leaves: nodes left unsplit because their children could take
 * their depth over the reference budget, or would not fit the workspace. */
#define KDRAY_DF_BUDGET_LEAVES 5u
#define KDRAY_DF_COUNTS 6u

/* KdDepthFirstArgs — 32 bytes. kd_build_large_depth_first's scalars: the deep roots (the length
 * of the arena starts' rows; the work-items take a run's items off a counter,
 * build_large_depth_first.cl), the depth limit, the large-node threshold T, empty_ratio C_e, the
 * SAH costs C_t, C_i and the empty-space bonus; ref_budget, the most references a subtree's
 * nodes of one depth may hold per reference of its root (the levels' budget per triangle). */
typedef struct KdDepthFirstArgs {
    kd_u32 nodes;
    kd_u32 max_depth;
    kd_u32 large_threshold;
    kd_f32 empty_ratio;
    kd_f32 cost_traversal;
    kd_f32 cost_intersection;
    kd_f32 empty_bonus;
    kd_u32 ref_budget;
} KdDepthFirstArgs;

/* KdDepthFirstTask — 64 bytes. A node waiting on a depth-first work-item's stack (in global
 * memory, KDRAY_DF_STACK entries per item: kept out of the work-item's private memory, which
 * GPUs have little of, at the cost of one load per node).
 *   box          the node's box.
 *   tight        its references' bounds.
 *   begin, count its references' range in the item's workspace.
 *   depth        its depth in the tree.
 *   record       its record, an index in the item's record arena. */
typedef struct KdDepthFirstTask {
    KdBuildBox box;
    KdBuildBox tight;
    kd_u32 begin;
    kd_u32 count;
    kd_u32 depth;
    kd_u32 record;
} KdDepthFirstTask;

/* Stack entries per depth-first work-item: a node's children have larger depths than it, and at
 * most one of them waits while the other is split, so at most one node per depth waits. */
#define KDRAY_DF_STACK (KDRAY_MAX_DEPTH + 2)

/* KdLargeRegion — 16 bytes. The records one depth-first work-item made, for the output stage:
 * root, the deep root's record id (made by a level, in one of its batches); first and count, the
 * ids of the rest, in the order they were made (a parent before its children); pad 0. */
typedef struct KdLargeRegion {
    kd_u32 root;
    kd_u32 first;
    kd_u32 count;
    kd_u32 pad;
} KdLargeRegion;

/* KdSmallBatchArgs — 48 bytes. A batch of small roots (root_begin.., `roots` of them, whose
 * references start at ref_begin) and how the small stage builds and lays out their subtrees:
 * first_scale records per reference and root in the first pass, second_pass (1: the pass that
 * rebuilds the subtrees that outgrew the first), the depth limit, the SAH costs C_t, C_i and the
 * empty-space bonus, the node size at or below which a node re-clips (reclip_refs, at most
 * KDRAY_RECLIP_REFS; 0: never) and at or below which it is a leaf without a search (leaf_size;
 * 0: every node is searched), and small_bins: a node not on a re-clipped table is split by the
 * binned SAH over this many bins per axis of its tight box (build_small_bins.cl; at most
 * KDRAY_SMALL_MAX_BINS), 0 by the exact SAH over the split-candidate masks. */
typedef struct KdSmallBatchArgs {
    kd_u32 root_begin;
    kd_u32 roots;
    kd_u32 ref_begin;
    kd_u32 first_scale;
    kd_u32 second_pass;
    kd_u32 max_depth;
    kd_f32 cost_traversal;
    kd_f32 cost_intersection;
    kd_f32 empty_bonus;
    kd_u32 reclip_refs;
    kd_u32 leaf_size;
    kd_u32 small_bins;
} KdSmallBatchArgs;

#ifndef KDRAY_DEVICE_CODE
static_assert(KDRAY_LAUNCH_GROUP == KDRAY_SMALL_ROOT_MAX_REFS,
              "kd_split_small_level prices a node's references one per work-item of its group");
static_assert(sizeof(KdBuildBox) == KDRAY_BOX_FLOATS * sizeof(kd_f32), "KdBuildBox is 24 bytes");
static_assert(sizeof(KdBuildNode) == 24, "KdBuildNode is 24 bytes on every device");
static_assert(sizeof(KdSmallNode) == 16, "KdSmallNode is 16 bytes on every device");
static_assert(sizeof(KdLargeNode) == 32, "KdLargeNode is 32 bytes on every device");
static_assert(sizeof(KdLargeSplit) == 8, "KdLargeSplit is 8 bytes on every device");
static_assert(sizeof(KdLargeCuts) == 56, "KdLargeCuts is 56 bytes on every device");
static_assert(sizeof(KdSmallRoot) == 40, "KdSmallRoot is 40 bytes on every device");
static_assert(sizeof(KdSmallLevelNode) == 96, "KdSmallLevelNode is 96 bytes on every device");
static_assert(sizeof(KdLargeSplitArgs) == 32, "KdLargeSplitArgs is 32 bytes on every device");
static_assert(sizeof(KdLargeLevelArgs) == 48, "KdLargeLevelArgs is 48 bytes on every device");
static_assert(sizeof(KdSmallBatchArgs) == 48, "KdSmallBatchArgs is 48 bytes on every device");
static_assert(sizeof(KdDepthFirstArgs) == 32, "KdDepthFirstArgs is 32 bytes on every device");
static_assert(sizeof(KdLargeRegion) == 16, "KdLargeRegion is 16 bytes on every device");
static_assert(sizeof(KdDepthFirstTask) == 64, "KdDepthFirstTask is 64 bytes on every device");
#endif

#endif /* KDRAY_KD_BUILD_SHARED_H */
