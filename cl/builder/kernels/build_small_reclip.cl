/* build_small_reclip.cl — re-clipping in the small-node stage (build_small.cl), kdray's one
 * departure from Zhou et al.'s small stage: a node's own table of clipped candidates and masks. It
 * holds no kernel of its own. */
#ifndef KDRAY_BUILD_SMALL_RECLIP_CL
#define KDRAY_BUILD_SMALL_RECLIP_CL

#include "cl/builder/kernels/build_small_search.cl"

/* Re-clipping (not in Zhou et al.): the masks hold the small root's boxes, which no split inside
 * its subtree clips, so a long diagonal triangle that a few splits have cut keeps the root's box:
 * the SAH counts it on both sides of planes it does not reach inside the node, and its own
 * candidates are not its bounds there. A node of at most KDRAY_RECLIP_REFS references of which
 * some extend past its box (at most the batch's reclip_refs) gets a table of its own: those
 * references' triangles clipped to the node's box (the large stage's clipping), the candidates and
 * masks of them over the node's references alone, in private memory; its subtree is split with that
 * table. Only the first such node on a path does this (its descendants use its table), so one table
 * per work-item is live: the walk is depth first, and the nodes pending on the stack above a
 * clipped node are all its descendants. KDRAY_RECLIP_REFS is in kd_build_shared.h; the batch's
 * reclip_refs lowers it. */

typedef struct KdClippedTable {
    float candidates[KDRAY_RECLIP_REFS * 8]; /* per reference: its clipped box's candidate lanes */
    /* per reference: 8 lanes below, 8 above (as side_masks) */
    uint masks[KDRAY_RECLIP_REFS * KDRAY_MASK_WORDS_PER_REF];
    uchar ref[KDRAY_RECLIP_REFS];              /* its index in the small root's list */
    KdTrianglePlane planes[KDRAY_RECLIP_REFS]; /* per reference: its triangle's plane */
} KdClippedTable;

/* Entry l's masks over the first n entries of table t (each of its six candidates: which entries'
 * boxes lie below, which above), stored in t->masks. A macro, not a function: the per-root stage's
 * table is a work-item's (private memory) and the per-level stage's a work-group's (local), and
 * OpenCL 1.2 has no address space that a function could take both in. */
#define KD_TABLE_ENTRY_MASKS(t, l, n)                                                              \
    do {                                                                                           \
        const float8 pos_ = vload8((l), (t)->candidates);                                          \
        const int8 planar_above_ = kd_planar_above_lanes(pos_);                                    \
        uint8 below_bits_ = (uint8)(0), above_bits_ = (uint8)(0);                                  \
        for (uint m_ = 0; m_ < (n); ++m_) {                                                        \
            const float8 other_ = vload8(m_, (t)->candidates);                                     \
            int8 is_below_, is_above_;                                                             \
            kd_candidate_sides(pos_, planar_above_, other_.s00224466, other_.s11335577,            \
                               &is_below_, &is_above_);                                            \
            below_bits_ |= as_uint8(is_below_) & (1u << m_);                                       \
            above_bits_ |= as_uint8(is_above_) & (1u << m_);                                       \
        }                                                                                          \
        vstore8(below_bits_, 0, (t)->masks + (l) * KDRAY_MASK_WORDS_PER_REF);                      \
        vstore8(above_bits_, 1, (t)->masks + (l) * KDRAY_MASK_WORDS_PER_REF);                      \
    } while (0)

/* A reference's box *b (its triangle at tri) clipped to a re-clipping node's box: unchanged when
 * it lies inside, else the triangle's clipped bounds within the old box; 0 when the triangle
 * misses the node's box (it leaves the node). The one rule of both small-stage shapes
 * (kd_clip_node_table, and build_small_level.cl's work-groups). */
KDRAY_INLINE int kd_reclip_box(KdBox box, __global const float* tri, KdBox* b) {
    if (!(any(b->lo < box.lo) || any(b->hi > box.hi))) return 1;
    b->lo = fmax(b->lo, box.lo);
    b->hi = fmax(fmin(b->hi, box.hi), b->lo);
    KdBox clipped;
    if (!kd_clip_triangle_bounds(tri, box, &clipped)) return 0;
    b->lo = fmin(fmax(b->lo, clipped.lo), b->hi);
    b->hi = fmax(fmin(b->hi, clipped.hi), b->lo);
    return 1;
}

/* The table of the node (box, its references `mask` over the small root's list from start), or 0
 * when none of them extends past the box (clipping changes nothing). *mask becomes the node's
 * references over the table; a triangle that misses the box leaves the node. */
KDRAY_INLINE int kd_clip_node_table(KdBox box, ulong* mask, uint start,
                                    __global const float* ref_box, __global const uint* ref_tri,
                                    __global const float* triangles, KdClippedTable* t) {
    int any_cut = 0;
    for (ulong rest = *mask; rest != 0 && !any_cut; rest &= rest - 1) {
        const KdBox b = kd_load_box(ref_box, start + kd_lowest_bit(rest));
        any_cut = any(b.lo < box.lo) || any(b.hi > box.hi);
    }
    if (!any_cut) return 0;
    uint n = 0;
    for (ulong rest = *mask; rest != 0; rest &= rest - 1) {
        const uint j = kd_lowest_bit(rest);
        KdBox b = kd_load_box(ref_box, start + j);
        __global const float* tri =
            triangles + (size_t)ref_tri[start + j] * KDRAY_FLOATS_PER_TRIANGLE;
        if (!kd_reclip_box(box, tri, &b)) continue;
        t->ref[n] = (uchar)j;
        t->planes[n] = kd_triangle_plane(tri);
        vstore8((float8)(b.lo.x, b.hi.x, b.lo.y, b.hi.y, b.lo.z, b.hi.z, 0.0f, 0.0f), n,
                t->candidates);
        ++n;
    }
    for (uint l = 0; l < n; ++l) KD_TABLE_ENTRY_MASKS(t, l, n);
    *mask = (1ul << n) - 1ul;
    return 1;
}

/* kd_best_small_split over a clipped table. */
KDRAY_INLINE uint kd_best_clipped_split(KdBox box, ulong mask, const KdClippedTable* t,
                                        float cost_traversal, float cost_intersection,
                                        float empty_bonus) {
    KdSplitSearch s;
    kd_start_split_search(&s, box, mask, cost_traversal, cost_intersection, empty_bonus);
    for (ulong rest = mask; rest != 0; rest &= rest - 1) {
        const uint l = kd_lowest_bit(rest);
        kd_price_candidates(&s, vload8(l, t->candidates),
                            convert_ulong8(vload8(0, t->masks + l * KDRAY_MASK_WORDS_PER_REF)),
                            convert_ulong8(vload8(1, t->masks + l * KDRAY_MASK_WORDS_PER_REF)),
                            l * KDRAY_CANDIDATE_STRIDE);
    }
    return kd_cheapest_candidate(&s);
}

/* A mask over a clipped table as a mask over the small root's references. */
KDRAY_INLINE ulong kd_root_mask(const KdClippedTable* t, ulong mask) {
    ulong root = 0;
    for (ulong rest = mask; rest != 0; rest &= rest - 1) root |= 1ul << t->ref[kd_lowest_bit(rest)];
    return root;
}

#endif /* KDRAY_BUILD_SMALL_RECLIP_CL */
