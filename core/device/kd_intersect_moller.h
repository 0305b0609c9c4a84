/* kd_intersect_moller.h — the Möller–Trumbore ray–triangle test (Möller and Trumbore 1997, "Fast,
 * Minimum Storage Ray/Triangle Intersection", JGT 2(1)), the fast alternative to kd_traverse.h's
 * watertight test, in the same C subset that compiles as C++ and as OpenCL C.
 *
 * It is not watertight: each triangle computes its barycentrics from its own edge vectors, so two
 * triangles sharing an edge round differently along it and a ray through the edge (or a vertex)
 * can fail both tests and slip through a closed mesh. scripts/accuracy_vs_time.py counts such
 * leaks; `kdray render --intersect moller` selects this test, watertight stays the default.
 *
 * Which test a trace uses (KDRAY_INTERSECT_*): on the host a run-time value, in a kernel the
 * compile-time -DKDRAY_COMPILED_INTERSECT (one cached program per choice, as for the effects), so
 * that a kernel contains one test only.
 */
#ifndef KDRAY_KD_INTERSECT_MOLLER_H
#define KDRAY_KD_INTERSECT_MOLLER_H

#include "core/device/kd_intersect.h"

#define KDRAY_INTERSECT_WATERTIGHT 0u
#define KDRAY_INTERSECT_MOLLER 1u

#ifdef KDRAY_DEVICE_CODE
#ifndef KDRAY_COMPILED_INTERSECT
#define KDRAY_COMPILED_INTERSECT KDRAY_INTERSECT_WATERTIGHT
#endif
#define KDRAY_USE_MOLLER(intersect) (KDRAY_COMPILED_INTERSECT == KDRAY_INTERSECT_MOLLER)
#else
#define KDRAY_USE_MOLLER(intersect) ((intersect) == KDRAY_INTERSECT_MOLLER)
#endif

/* Tests triangle `id` (9 floats at tri) and, when it is hit at t in [tmin, best->t), makes it the
 * best hit, with the barycentrics of the second and third corners in best->u and best->v as the
 * watertight test gives them. No epsilon on the determinant: only a ray exactly parallel to the
 * plane (det == 0) is rejected, so tiny triangles stay hittable whatever the scene's scale.
 * Returns 1 on a new best hit. */
KDRAY_HOT_INLINE int kd_intersect_triangle_moller(const KdRayPrecomp* p,
                                                  KDRAY_GLOBAL const kd_f32* tri, kd_u32 id,
                                                  kd_f32 tmin, KdHit* best) {
    const kd_f32 e1x = tri[3] - tri[0], e1y = tri[4] - tri[1], e1z = tri[5] - tri[2];
    const kd_f32 e2x = tri[6] - tri[0], e2y = tri[7] - tri[1], e2z = tri[8] - tri[2];
    /* pvec = dir x e2; det = e1 . pvec, the triple product [dir, e2, e1]. */
    const kd_f32 px = p->dir[1] * e2z - p->dir[2] * e2y;
    const kd_f32 py = p->dir[2] * e2x - p->dir[0] * e2z;
    const kd_f32 pz = p->dir[0] * e2y - p->dir[1] * e2x;
    const kd_f32 det = e1x * px + e1y * py + e1z * pz;
    if (det == 0.0f) return 0;
    const kd_f32 inv_det = 1.0f / det;
    const kd_f32 tx = p->org[0] - tri[0], ty = p->org[1] - tri[1], tz = p->org[2] - tri[2];
    const kd_f32 u = (tx * px + ty * py + tz * pz) * inv_det;
    if (u < 0.0f || u > 1.0f) return 0;
    /* qvec = tvec x e1 */
    const kd_f32 qx = ty * e1z - tz * e1y, qy = tz * e1x - tx * e1z, qz = tx * e1y - ty * e1x;
    const kd_f32 v = (p->dir[0] * qx + p->dir[1] * qy + p->dir[2] * qz) * inv_det;
    if (v < 0.0f || u + v > 1.0f) return 0;
    const kd_f32 t = (e2x * qx + e2y * qy + e2z * qz) * inv_det;
    if (t < tmin || t >= best->t) return 0;
    best->t = t;
    best->prim = id;
    best->u = u;
    best->v = v;
    return 1;
}

#endif /* KDRAY_KD_INTERSECT_MOLLER_H */
