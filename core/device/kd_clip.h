/* kd_clip.h — Sutherland–Hodgman clipping of a convex polygon against an axis-aligned plane: the
 * "perfect split" clipping of Wald & Havran (2006), §4.3, that Zhou et al. (2008), §4.1, apply to
 * triangles straddling a large node's split ("the bounding box of each triangle is clipped to the
 * node"). Written once, in the C subset that compiles as C++ and as OpenCL C (as kd_traverse.h
 * is), for the three places that clip triangles: the OpenCL builder's kernels (in float), the
 * reference builder (core/geometry/triangle_clip.cpp) and the tree checker
 * (core/tree/tree_check.cpp), both in double.
 *
 * The coordinate type is KDRAY_CLIP_REAL: float unless the including file defines it first (the
 * host's double-precision users do; the header is included with one type per translation unit).
 * Polygons are arrays of points of three coordinates; a triangle cut by the six planes of a box
 * has at most 3 + 6 = KDRAY_CLIP_MAX_VERTICES corners. */
#ifndef KDRAY_KD_CLIP_H
#define KDRAY_KD_CLIP_H

#include "core/device/kd_shared.h"

#ifndef KDRAY_CLIP_REAL
#define KDRAY_CLIP_REAL kd_f32
#endif

/* Most corners of a triangle clipped to a box: each of the six planes adds at most one. */
#define KDRAY_CLIP_MAX_VERTICES 9

/* Keeps the part of the convex polygon in[0, count) on the inner side of the plane x[axis] = pos
 * (x >= pos when keep_above, else x <= pos), written to out; returns its corner count (at most
 * count + 1). A corner on the plane is inside. A crossing point gets exactly `pos` on the axis, so
 * that no rounding drift puts it outside the plane it lies on; its other coordinates come from the
 * edge's parameter at the plane, computed from the signed distances to the plane. */
KDRAY_HOT_INLINE kd_u32 kd_clip_polygon_to_plane(const KDRAY_CLIP_REAL (*in)[3], kd_u32 count,
                                                 kd_u32 axis, KDRAY_CLIP_REAL pos, int keep_above,
                                                 KDRAY_CLIP_REAL (*out)[3]) {
    kd_u32 n = 0;
    for (kd_u32 v = 0; v < count; ++v) {
        const KDRAY_CLIP_REAL* a = in[v];
        const KDRAY_CLIP_REAL* b = in[(v + 1) % count];
        const KDRAY_CLIP_REAL da = a[axis] - pos, db = b[axis] - pos;
        const int in_a = keep_above ? da >= 0 : da <= 0;
        const int in_b = keep_above ? db >= 0 : db <= 0;
        if (in_a) {
            for (kd_u32 k = 0; k < 3; ++k) out[n][k] = a[k];
            ++n;
        }
        if (in_a != in_b) {
            /* The edge crosses the plane, so da != db. */
            const KDRAY_CLIP_REAL t = da / (da - db);
            for (kd_u32 k = 0; k < 3; ++k) out[n][k] = a[k] + (b[k] - a[k]) * t;
            out[n][axis] = pos;
            ++n;
        }
    }
    return n;
}

#endif /* KDRAY_KD_CLIP_H */
