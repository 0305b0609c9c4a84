/* build_common.cl — helpers the kd-tree build kernels share (included by build_large.cl,
 * build_small.cl and build_output.cl; it holds no kernel of its own).
 *
 * Boxes travel as KDRAY_BOX_FLOATS floats, lo.xyz hi.xyz (KdBuildBox,
 * core/device/kd_build_shared.h, where the builder's records and constants are defined); triangle
 * references carry their box clipped to the node that holds them, as in Zhou et al. (2008), §4.1
 * ("the bounding box of each triangle is clipped to the node"). */
#ifndef KDRAY_BUILD_COMMON_CL
#define KDRAY_BUILD_COMMON_CL

#include "core/device/kd_shared.h"
#include "core/device/kd_build_shared.h"
#include "core/device/kd_clip.h"

/* Child bits of a reference: bit 0 = below (lower coordinates), bit 1 = above. */
#define KDRAY_BELOW 1u
#define KDRAY_ABOVE 2u

typedef struct KdBox {
    float3 lo, hi;
} KdBox;

KDRAY_INLINE float kd_axis_of(float3 v, uint axis) {
    return axis == 0 ? v.x : (axis == 1 ? v.y : v.z);
}

KDRAY_INLINE float3 kd_with_axis(float3 v, uint axis, float x) {
    if (axis == 0) v.x = x;
    else if (axis == 1) v.y = x;
    else v.z = x;
    return v;
}

KDRAY_INLINE KdBox kd_load_box(__global const float* boxes, size_t i) {
    __global const float* b = boxes + i * KDRAY_BOX_FLOATS;
    KdBox box;
    box.lo = (float3)(b[0], b[1], b[2]);
    box.hi = (float3)(b[3], b[4], b[5]);
    return box;
}

KDRAY_INLINE void kd_store_box(__global float* boxes, size_t i, KdBox box) {
    __global float* b = boxes + i * KDRAY_BOX_FLOATS;
    b[0] = box.lo.x, b[1] = box.lo.y, b[2] = box.lo.z;
    b[3] = box.hi.x, b[4] = box.hi.y, b[5] = box.hi.z;
}

/* A box of a shared record (KdLargeNode, KdSmallRoot) as a KdBox, and back. */
KDRAY_INLINE KdBox kd_box_of(KdBuildBox b) {
    KdBox box;
    box.lo = (float3)(b.lo[0], b.lo[1], b.lo[2]);
    box.hi = (float3)(b.hi[0], b.hi[1], b.hi[2]);
    return box;
}

KDRAY_INLINE KdBuildBox kd_build_box_of(KdBox box) {
    KdBuildBox b;
    b.lo[0] = box.lo.x, b.lo[1] = box.lo.y, b.lo[2] = box.lo.z;
    b.hi[0] = box.hi.x, b.hi[1] = box.hi.y, b.hi[2] = box.hi.z;
    return b;
}

KDRAY_INLINE float kd_box_area(KdBox b) {
    const float3 e = fmax(b.hi - b.lo, (float3)(0.0f));
    return 2.0f * (e.x * e.y + e.y * e.z + e.z * e.x);
}

/* The box of one side of a split: below keeps [lo, split], above [split, hi] on the axis. */
KDRAY_INLINE KdBox kd_child_box(KdBox b, uint axis, float split, uint side) {
    if (side == 0) b.hi = kd_with_axis(b.hi, axis, split);
    else b.lo = kd_with_axis(b.lo, axis, split);
    return b;
}

/* The one rule for which children of the plane `split` a reference spanning [lo, hi] on the axis
 * goes to, used alike by the large-node split, the small-node split masks and therefore the SAH
 * counts: below when it starts below the plane, above when it ends above it, so a triangle that
 * only touches the plane stays on its own side. A reference lying flat in the plane goes to one
 * side only, `planar_sides` (below for a median or SAH split, the kept side for an empty-space
 * cut): a ray that meets it crosses or lies in the plane, so the walk visits both children anyway,
 * and copying it to both would double every face of an axis-aligned model at every split. */
KDRAY_INLINE uint kd_classify(float lo, float hi, float split, uint planar_sides) {
    uint sides = 0;
    if (lo < split) sides |= KDRAY_BELOW;
    if (hi > split) sides |= KDRAY_ABOVE;
    return sides ? sides : planar_sides;
}

/* Bounds of the part of triangle `tri` (9 floats) inside `box`: the "perfect split" clipping that
 * the reference builder does too (Wald & Havran 2006), by Sutherland–Hodgman against the box's six
 * planes (core/device/kd_clip.h, the one clipping routine of host and device). The box is first
 * grown by a few ulps of its magnitude so that float rounding in the clipping can only make the
 * result larger, never lose a part that really enters the box; the result is then cut back to the
 * box. Returns 0 when the triangle misses the grown box. */
KDRAY_HOT_INLINE int kd_clip_triangle_bounds(__global const float* tri, KdBox box, KdBox* out) {
    const float3 magnitude = fmax(fabs(box.lo), fabs(box.hi));
    const float eps = 8.0f * FLT_EPSILON * fmax(magnitude.x, fmax(magnitude.y, magnitude.z));
    const float3 lo = box.lo - eps, hi = box.hi + eps;
    float poly[2][KDRAY_CLIP_MAX_VERTICES][3];
    for (uint v = 0; v < 3; ++v)
        for (uint k = 0; k < 3; ++k) poly[0][v][k] = tri[3 * v + k];
    uint count = 3;
    /* A plane that the whole triangle lies inside of changes nothing: skip it. In the large
     * stage a straddling triangle usually crosses only the split plane. Kitchen, perf record of
     * 13 builds, same sitting, 3 runs each: clipping 32 -> 22 M cycles per build; trees
     * byte-identical on kitchen, bunny, dragon_res2, sponza and bart-robots. */
    const float3 c0 = vload3(0, tri), c1 = vload3(1, tri), c2 = vload3(2, tri);
    const float3 tri_lo = fmin(c0, fmin(c1, c2)), tri_hi = fmax(c0, fmax(c1, c2));
    uint cur = 0;
    for (uint plane = 0; plane < 6 && count > 0; ++plane) {
        const uint axis = plane / 2;
        const int keep_above = (plane % 2) == 0; /* even planes: x >= lo; odd: x <= hi */
        const float pos = kd_axis_of(keep_above ? lo : hi, axis);
        if (keep_above ? kd_axis_of(tri_lo, axis) >= pos : kd_axis_of(tri_hi, axis) <= pos)
            continue;
        /* C (unlike C++) does not convert float (*)[3] to const float (*)[3] implicitly. */
        count = kd_clip_polygon_to_plane((const float(*)[3])poly[cur], count, axis, pos, keep_above,
                                         poly[1 - cur]);
        cur = 1 - cur;
    }
    if (count == 0) return 0;
    float3 bmin = vload3(0, poly[cur][0]), bmax = bmin;
    for (uint v = 1; v < count; ++v) {
        const float3 p = vload3(0, poly[cur][v]);
        bmin = fmin(bmin, p);
        bmax = fmax(bmax, p);
    }
    out->lo = fmin(fmax(bmin, box.lo), box.hi);
    out->hi = fmax(fmin(bmax, box.hi), box.lo);
    return 1;
}

/* A triangle's plane for kd_plane_misses_box: a corner, the normal, and the normal's rounding
 * (a few ulps of |e1| |e2| per component). */
typedef struct KdTrianglePlane {
    float3 corner, normal;
    float normal_error;
} KdTrianglePlane;

KDRAY_INLINE KdTrianglePlane kd_triangle_plane(__global const float* tri) {
    KdTrianglePlane p;
    p.corner = (float3)(tri[0], tri[1], tri[2]);
    const float3 e1 = (float3)(tri[3], tri[4], tri[5]) - p.corner;
    const float3 e2 = (float3)(tri[6], tri[7], tri[8]) - p.corner;
    p.normal = cross(e1, e2);
    p.normal_error = 1e-4f * length(e1) * length(e2);
    return p;
}

/* Whether a triangle's plane misses the box: its corners all lie on one side of it (the normal's
 * test of Akenine-Moller's triangle-box overlap), by more than the rounding of the normal, which
 * a sliver or a collapsed triangle makes as large as the normal itself. */
KDRAY_INLINE int kd_plane_misses_box(const KdTrianglePlane* p, KdBox box) {
    const float3 centre = 0.5f * (box.lo + box.hi), half_extent = 0.5f * (box.hi - box.lo);
    const float3 to_centre = centre - p->corner;
    const float distance = dot(p->normal, to_centre), radius = dot(fabs(p->normal), half_extent);
    /* The distances are off by the normal's rounding times the lever arm. */
    const float reach = fabs(to_centre.x) + fabs(to_centre.y) + fabs(to_centre.z) + half_extent.x +
                        half_extent.y + half_extent.z;
    const float slack = 1e-5f * (fabs(distance) + radius) + p->normal_error * reach;
    return fabs(distance) > radius + slack;
}

/* The index of the lowest set bit of a mask of a small root's references (bits != 0). */
KDRAY_INLINE uint kd_lowest_bit(ulong bits) {
    return (uint)popcount((bits & (0ul - bits)) - 1ul);
}

/* Index of the last of the n ascending `starts` that is <= x: the segment holding element x. */
KDRAY_INLINE uint kd_find_segment(__global const uint* starts, uint n, uint x) {
    uint lo = 0, hi = n;
    while (hi - lo > 1) {
        const uint mid = (lo + hi) / 2;
        if (starts[mid] <= x) lo = mid;
        else hi = mid;
    }
    return lo;
}

KDRAY_INLINE KdBuildNode kd_build_leaf(uint count, uint first) {
    KdBuildNode n;
    n.axis = KDRAY_LEAF_AXIS;
    n.split = 0.0f;
    n.child[0] = 0;
    n.child[1] = 0;
    n.leaf_count = count;
    n.leaf_first = first;
    return n;
}

/* The record of a small root (§4.2): its subtree is the small stage's, in the records below. */
KDRAY_INLINE KdBuildNode kd_build_small_root(uint root) {
    KdBuildNode n = kd_build_leaf(0, root);
    n.axis = KDRAY_SMALL_ROOT_AXIS;
    return n;
}

KDRAY_INLINE KdBuildNode kd_build_inner(uint axis, float split, uint below, uint above) {
    KdBuildNode n;
    n.axis = axis;
    n.split = split;
    n.child[0] = below;
    n.child[1] = above;
    n.leaf_count = 0;
    n.leaf_first = 0;
    return n;
}

/* Small-stage records (KdSmallNode): an inner node, whose above child's index its subtree's
 * builder fills in later, and a leaf of `count` triangles, the set bits of `mask`, whose
 * references start at `first` (counted from the subtree's first). */
KDRAY_INLINE KdSmallNode kd_small_inner(uint axis, float split) {
    KdSmallNode n;
    n.axis_and_offset = axis;
    n.split_or_count = as_uint(split);
    n.mask_lo = 0;
    n.mask_hi = 0;
    return n;
}

KDRAY_INLINE KdSmallNode kd_small_leaf(uint first, uint count, ulong mask) {
    KdSmallNode n;
    n.axis_and_offset = KDRAY_LEAF_AXIS | (first << 2);
    n.split_or_count = count;
    n.mask_lo = (uint)mask;
    n.mask_hi = (uint)(mask >> 32);
    return n;
}

/* Preorder placement of an inner node's children, given where the node and its first leaf
 * reference go: the below child right after its parent, the above child after the below child's
 * subtree (subtree_nodes and subtree_refs: each subtree's node and leaf reference counts). The one
 * rule of the output stage and of the per-level small stage. */
KDRAY_INLINE void kd_place_children(uint id, uint below, uint above,
                                    __global const uint* subtree_nodes,
                                    __global const uint* subtree_refs, __global uint* position,
                                    __global uint* leaf_position) {
    position[below] = position[id] + 1;
    position[above] = position[id] + 1 + subtree_nodes[below];
    leaf_position[below] = leaf_position[id];
    leaf_position[above] = leaf_position[id] + subtree_refs[below];
}

#endif /* KDRAY_BUILD_COMMON_CL */
