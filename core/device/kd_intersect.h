/* kd_intersect.h — the shared C subset's macros (KDRAY_GLOBAL, KDRAY_INF, ...) and the watertight
 * ray–triangle test with its per-ray constants, written once for C++ and OpenCL C. A header of its
 * own so that includes run one way: kd_traverse.h includes it and kd_intersect_moller.h, and
 * kd_intersect_moller.h includes it for KdRayPrecomp.
 */
#ifndef KDRAY_KD_INTERSECT_H
#define KDRAY_KD_INTERSECT_H

#include "core/device/kd_shared.h"

#ifdef KDRAY_DEVICE_CODE
/* Host and device must round alike for identical hits: no contraction into FMA (GCC with
 * -std=c++20 does not contract either). */
#pragma OPENCL FP_CONTRACT OFF
#define KDRAY_GLOBAL __global
#define KDRAY_FMIN fmin
#define KDRAY_FMAX fmax
#define KDRAY_FABS fabs
#define KDRAY_INF INFINITY
#else
#include <cmath>
#define KDRAY_GLOBAL
#define KDRAY_FMIN std::fmin
#define KDRAY_FMAX std::fmax
#define KDRAY_FABS std::fabs
#define KDRAY_INF INFINITY
#endif

/* The triangle test's two exact steps (the edge fallback and the refined distance) run in double
 * where the device has it and in float-float arithmetic (core/device/kd_float_float.h) where it has
 * not. KDRAY_DOUBLE_AVAILABLE: whether double code is compiled at all (always on the host, so host
 * tests can run both paths side by side). KDRAY_EXACT_FP64: the path kd_intersect_triangle takes.
 * -DKDRAY_FORCE_NO_FP64=1 makes a device with fp64 compile as one without (the renderer passes it
 * when KDRAY_FORCE_NO_FP64 is set in the environment, to test the float-float path on PoCL). */
#if defined(KDRAY_FORCE_NO_FP64) && KDRAY_FORCE_NO_FP64
#define KDRAY_EXACT_FP64 0
#ifdef KDRAY_DEVICE_CODE
#define KDRAY_DOUBLE_AVAILABLE 0
#else
#define KDRAY_DOUBLE_AVAILABLE 1
#endif
#elif !defined(KDRAY_DEVICE_CODE) || defined(cl_khr_fp64)
#define KDRAY_EXACT_FP64 1
#define KDRAY_DOUBLE_AVAILABLE 1
#else
#define KDRAY_EXACT_FP64 0
#define KDRAY_DOUBLE_AVAILABLE 0
#endif
#if KDRAY_DOUBLE_AVAILABLE && defined(KDRAY_DEVICE_CODE)
#pragma OPENCL EXTENSION cl_khr_fp64 : enable
#endif

#include "core/device/kd_float_float.h"

/* Component k (0, 1 or 2) of a three-float array by selects, not by a variable index: a private
 * array indexed by a variable cannot live in registers (on a GPU it goes to scratch memory). */
#define KDRAY_PICK3(v, k) ((k) == 0 ? (v)[0] : ((k) == 1 ? (v)[1] : (v)[2]))

/* Functions here and in the other shared headers hand back structs through an out pointer rather
 * than return them: OpenCL C returns a struct through a hidden `noalias` pointer, and inlining
 * such a call leaves llvm.experimental.noalias.scope.decl calls in the kernel, which Oclgrind
 * 21.10 (the strict second implementation the tests run) cannot execute: the render kernel could
 * not even be created there. */

/* Per-ray constants of the watertight test (Woop, Benthin, Wald 2013, "Watertight Ray/Triangle
 * Intersection", JCGT 2(1)): the axis kz where the direction is largest becomes the ray's z, kx and
 * ky are swapped to keep the winding when dir[kz] < 0, and the shear maps the direction onto +z. */
typedef struct KdRayPrecomp {
    kd_f32 org[3];
    kd_f32 dir[3];
    kd_f32 inv_dir[3];
    kd_i32 kx, ky, kz;
    kd_f32 sx, sy, sz;
    kd_f32 ox, oy, oz; /* org[kx], org[ky], org[kz] */
} KdRayPrecomp;

KDRAY_HOT_INLINE void kd_ray_precompute(const KdRay* ray, KdRayPrecomp* p) {
    for (int a = 0; a < 3; ++a) {
        p->org[a] = ray->org[a];
        p->dir[a] = ray->dir[a];
        p->inv_dir[a] = 1.0f / ray->dir[a];
    }
    kd_f32 ax = KDRAY_FABS(ray->dir[0]), ay = KDRAY_FABS(ray->dir[1]), az = KDRAY_FABS(ray->dir[2]);
    p->kz = (ax > ay) ? (ax > az ? 0 : 2) : (ay > az ? 1 : 2);
    p->kx = (p->kz + 1) % 3;
    p->ky = (p->kx + 1) % 3;
    if (KDRAY_PICK3(ray->dir, p->kz) < 0.0f) {
        kd_i32 swap = p->kx;
        p->kx = p->ky;
        p->ky = swap;
    }
    const kd_f32 dx = KDRAY_PICK3(ray->dir, p->kx), dy = KDRAY_PICK3(ray->dir, p->ky),
                 dz = KDRAY_PICK3(ray->dir, p->kz);
    p->sx = dx / dz;
    p->sy = dy / dz;
    p->sz = 1.0f / dz;
    p->ox = KDRAY_PICK3(ray->org, p->kx);
    p->oy = KDRAY_PICK3(ray->org, p->ky);
    p->oz = KDRAY_PICK3(ray->org, p->kz);
}

/* The distance along the ray (org, dir) to the plane of triangle tri, exact to far more than a
 * float: the watertight test's t is a sum of products of the vertices in ray space, in which a
 * far corner of a long thin triangle swamps the near ones (a 1e4-long needle: t off by 1.5e-4
 * relative). Here the plane's normal comes from the edges and t = n.(p0 - org) / n.dir, exact to
 * about 1e-12 relative whatever the triangle's shape, then rounded once to float. The inside test
 * stays the float one, so the test stays watertight. `fp64` picks double (1) or float-float (0):
 * both round the same near-exact value, so they agree but for a near-tie of floats. Where the
 * plane is parallel to the ray (or, in float-float, a value overflows), `fallback`, the float t. */
#if KDRAY_DOUBLE_AVAILABLE
KDRAY_HOT_INLINE kd_f32 kd_plane_distance_fp64(KDRAY_GLOBAL const kd_f32* tri, kd_f32 ox, kd_f32 oy,
                                               kd_f32 oz, kd_f32 dx, kd_f32 dy, kd_f32 dz,
                                               kd_f32 fallback) {
    const double p0x = (double)tri[0], p0y = (double)tri[1], p0z = (double)tri[2];
    const double e1x = (double)tri[3] - p0x, e1y = (double)tri[4] - p0y, e1z = (double)tri[5] - p0z;
    const double e2x = (double)tri[6] - p0x, e2y = (double)tri[7] - p0y, e2z = (double)tri[8] - p0z;
    const double nx = e1y * e2z - e1z * e2y, ny = e1z * e2x - e1x * e2z, nz = e1x * e2y - e1y * e2x;
    const double along = nx * (double)dx + ny * (double)dy + nz * (double)dz;
    if (along == 0.0) return fallback;
    const double to_plane =
        nx * (p0x - (double)ox) + ny * (p0y - (double)oy) + nz * (p0z - (double)oz);
    return (kd_f32)(to_plane / along);
}
#endif

/* One component of the float-float cross product: a1 b2 - a2 b1 of float-float a and b. */
KDRAY_HOT_INLINE void kd_ff_cross_component(kd_f32 a1h, kd_f32 a1l, kd_f32 a2h, kd_f32 a2l,
                                            kd_f32 b1h, kd_f32 b1l, kd_f32 b2h, kd_f32 b2l,
                                            kd_f32* hi, kd_f32* lo) {
    kd_f32 ph, pl, qh, ql;
    kd_ff_mul(a1h, a1l, b2h, b2l, &ph, &pl);
    kd_ff_mul(a2h, a2l, b1h, b1l, &qh, &ql);
    kd_ff_add(ph, pl, -qh, -ql, hi, lo);
}

/* x . (ah + al, ...) of a float-float vector a and a float-float x, accumulated in float-float. */
KDRAY_HOT_INLINE void kd_ff_dot3(const kd_f32* ah, const kd_f32* al, const kd_f32* xh,
                                 const kd_f32* xl, kd_f32* hi, kd_f32* lo) {
    kd_f32 sh, sl, ph, pl;
    kd_ff_mul(ah[0], al[0], xh[0], xl[0], &sh, &sl);
    kd_ff_mul(ah[1], al[1], xh[1], xl[1], &ph, &pl);
    kd_ff_add(sh, sl, ph, pl, &sh, &sl);
    kd_ff_mul(ah[2], al[2], xh[2], xl[2], &ph, &pl);
    kd_ff_add(sh, sl, ph, pl, hi, lo);
}

KDRAY_HOT_INLINE kd_f32 kd_plane_distance_ff(KDRAY_GLOBAL const kd_f32* tri, kd_f32 ox, kd_f32 oy,
                                             kd_f32 oz, kd_f32 dx, kd_f32 dy, kd_f32 dz,
                                             kd_f32 fallback) {
    /* Differences of two floats are exact as float-float pairs. */
    kd_f32 e1h[3], e1l[3], e2h[3], e2l[3], th[3], tl[3];
    const kd_f32 o[3] = {ox, oy, oz};
    for (int a = 0; a < 3; ++a) {
        kd_two_sum(tri[3 + a], -tri[a], &e1h[a], &e1l[a]);
        kd_two_sum(tri[6 + a], -tri[a], &e2h[a], &e2l[a]);
        kd_two_sum(tri[a], -o[a], &th[a], &tl[a]);
    }
    kd_f32 nh[3], nl[3];
    kd_ff_cross_component(e1h[1], e1l[1], e1h[2], e1l[2], e2h[1], e2l[1], e2h[2], e2l[2], &nh[0],
                          &nl[0]);
    kd_ff_cross_component(e1h[2], e1l[2], e1h[0], e1l[0], e2h[2], e2l[2], e2h[0], e2l[0], &nh[1],
                          &nl[1]);
    kd_ff_cross_component(e1h[0], e1l[0], e1h[1], e1l[1], e2h[0], e2l[0], e2h[1], e2l[1], &nh[2],
                          &nl[2]);
    const kd_f32 dh[3] = {dx, dy, dz}, dl[3] = {0.0f, 0.0f, 0.0f};
    kd_f32 along_h, along_l, to_h, to_l, t_h, t_l;
    kd_ff_dot3(nh, nl, dh, dl, &along_h, &along_l);
    if (along_h == 0.0f) return fallback;
    kd_ff_dot3(nh, nl, th, tl, &to_h, &to_l);
    kd_ff_div(to_h, to_l, along_h, along_l, &t_h, &t_l);
    /* NaN or an infinity: a value left float's range; the float t is the better answer then. */
    return KDRAY_FABS(t_h) < KDRAY_INF ? t_h : fallback;
}

KDRAY_HOT_INLINE kd_f32 kd_plane_distance_with(KDRAY_GLOBAL const kd_f32* tri, kd_f32 ox, kd_f32 oy,
                                               kd_f32 oz, kd_f32 dx, kd_f32 dy, kd_f32 dz,
                                               kd_f32 fallback, int fp64) {
#if KDRAY_DOUBLE_AVAILABLE
    if (fp64) return kd_plane_distance_fp64(tri, ox, oy, oz, dx, dy, dz, fallback);
#else
    (void)fp64;
#endif
    return kd_plane_distance_ff(tri, ox, oy, oz, dx, dy, dz, fallback);
}

/* kd_plane_distance_with the device's path (KDRAY_EXACT_FP64). */
KDRAY_HOT_INLINE kd_f32 kd_plane_distance(KDRAY_GLOBAL const kd_f32* tri, kd_f32 ox, kd_f32 oy,
                                          kd_f32 oz, kd_f32 dx, kd_f32 dy, kd_f32 dz,
                                          kd_f32 fallback) {
    return kd_plane_distance_with(tri, ox, oy, oz, dx, dy, dz, fallback, KDRAY_EXACT_FP64);
}

/* The watertight test's scaled barycentrics recomputed without rounding to zero: each is a
 * difference of two products of floats, exact in double (48-bit products) and exact in sign in
 * float-float (kd_ff_diff_of_products); both then round it once to float. An exact zero stays
 * zero and a nonzero value keeps its sign, which is what makes the test watertight on edges. */
KDRAY_HOT_INLINE void kd_exact_edges(kd_f32 ax, kd_f32 ay, kd_f32 bx, kd_f32 by, kd_f32 cx,
                                     kd_f32 cy, int fp64, kd_f32* u, kd_f32* v, kd_f32* w) {
#if KDRAY_DOUBLE_AVAILABLE
    if (fp64) {
        *u = (kd_f32)((double)cx * (double)by - (double)cy * (double)bx);
        *v = (kd_f32)((double)ax * (double)cy - (double)ay * (double)cx);
        *w = (kd_f32)((double)bx * (double)ay - (double)by * (double)ax);
        return;
    }
#else
    (void)fp64;
#endif
    *u = kd_ff_diff_of_products(cx, by, cy, bx);
    *v = kd_ff_diff_of_products(ax, cy, ay, cx);
    *w = kd_ff_diff_of_products(bx, ay, by, ax);
}

/* The condition of the watertight test's float t = (u az + v bz + w cz) / det, in units of t:
 * its rounding error is a few epsilons of it. Each sheared coordinate (ax = a_x - sx a_z, ...)
 * is off by an epsilon of |a_x| + |sx a_z| (max_ax), so u = cx by - cy bx by an epsilon of
 * max_cx |by| + |cx| max_by + ...; and since det = u + v + w, an error du moves t by
 * du (az - t) / det. With the roundings of the scaled z (|u az| + ... over |det|) that is about
 * |t| for a triangle hit in front of the ray, near or far, and much more only where the corners'
 * z spread far around the hit: a long thin triangle seen along its length. */
KDRAY_HOT_INLINE kd_f32 kd_float_t_condition(const KdRayPrecomp* p, kd_f32 a_x, kd_f32 a_y,
                                             kd_f32 a_z, kd_f32 b_x, kd_f32 b_y, kd_f32 b_z,
                                             kd_f32 c_x, kd_f32 c_y, kd_f32 c_z, kd_f32 ax,
                                             kd_f32 ay, kd_f32 bx, kd_f32 by, kd_f32 cx, kd_f32 cy,
                                             kd_f32 u, kd_f32 v, kd_f32 w, kd_f32 az, kd_f32 bz,
                                             kd_f32 cz, kd_f32 t, kd_f32 inv_det) {
    const kd_f32 sx = KDRAY_FABS(p->sx), sy = KDRAY_FABS(p->sy);
    const kd_f32 max_ax = KDRAY_FABS(a_x) + sx * KDRAY_FABS(a_z),
                 max_ay = KDRAY_FABS(a_y) + sy * KDRAY_FABS(a_z);
    const kd_f32 max_bx = KDRAY_FABS(b_x) + sx * KDRAY_FABS(b_z),
                 max_by = KDRAY_FABS(b_y) + sy * KDRAY_FABS(b_z);
    const kd_f32 max_cx = KDRAY_FABS(c_x) + sx * KDRAY_FABS(c_z),
                 max_cy = KDRAY_FABS(c_y) + sy * KDRAY_FABS(c_z);
    const kd_f32 du = max_cx * KDRAY_FABS(by) + KDRAY_FABS(cx) * max_by + max_cy * KDRAY_FABS(bx) +
                      KDRAY_FABS(cy) * max_bx;
    const kd_f32 dv = max_ax * KDRAY_FABS(cy) + KDRAY_FABS(ax) * max_cy + max_ay * KDRAY_FABS(cx) +
                      KDRAY_FABS(ay) * max_cx;
    const kd_f32 dw = max_bx * KDRAY_FABS(ay) + KDRAY_FABS(bx) * max_ay + max_by * KDRAY_FABS(ax) +
                      KDRAY_FABS(by) * max_ax;
    const kd_f32 spread =
        du * KDRAY_FABS(az - t) + dv * KDRAY_FABS(bz - t) + dw * KDRAY_FABS(cz - t);
    const kd_f32 scaled_z = KDRAY_FABS(u * az) + KDRAY_FABS(v * bz) + KDRAY_FABS(w * cz);
    return (spread + scaled_z) * KDRAY_FABS(inv_det);
}

/* 16 epsilons of the condition bound the float t's error with room to spare: a candidate
 * outside [tmin, best) by more is rejected on the float t. Where the condition is at most 4 |t|
 * the float t is within a few ulps and is kept; only the rest (long thin triangles, seen along
 * their length) pay for kd_plane_distance: refining every candidate cost the Kitchen's primary
 * rays 18% of their trace time. */
#define KDRAY_T_ERROR_PER_CONDITION (16.0f * 1.1920929e-7f)
#define KDRAY_T_REFINE_CONDITION 4.0f

/* Tests triangle `id` (9 floats at tri) and, when it is hit at t in [tmin, best->t), makes it the
 * best hit. Watertight: a ray through a shared edge or vertex hits at least one of the triangles
 * that share it. A triangle with two equal corners is never hit; three distinct collinear corners
 * stop being collinear after rounding into ray space, which is why scenes collapse zero-area
 * triangles to a point when they are loaded (collapse_zero_area_triangles). Returns 1 on a new
 * best hit. `fp64`: the arithmetic of the exact steps, double (1) or float-float (0); the walk
 * passes the device's (kd_intersect_triangle), host tests pass both. */
KDRAY_HOT_INLINE int kd_intersect_triangle_with(const KdRayPrecomp* p,
                                                KDRAY_GLOBAL const kd_f32* tri, kd_u32 id,
                                                kd_f32 tmin, KdHit* best, int fp64) {
    /* Vertices relative to the ray origin, then sheared and scaled into ray space. The permuted
     * components are read straight from the triangle (a variable offset into global memory costs
     * nothing), so no private array is indexed by kx/ky/kz; the arithmetic is unchanged. */
    const kd_u32 kx = (kd_u32)p->kx, ky = (kd_u32)p->ky, kz = (kd_u32)p->kz;
    const kd_f32 a_x = tri[kx] - p->ox, a_y = tri[ky] - p->oy, a_z = tri[kz] - p->oz;
    const kd_f32 b_x = tri[3 + kx] - p->ox, b_y = tri[3 + ky] - p->oy, b_z = tri[3 + kz] - p->oz;
    const kd_f32 c_x = tri[6 + kx] - p->ox, c_y = tri[6 + ky] - p->oy, c_z = tri[6 + kz] - p->oz;
    const kd_f32 ax = a_x - p->sx * a_z, ay = a_y - p->sy * a_z;
    const kd_f32 bx = b_x - p->sx * b_z, by = b_y - p->sy * b_z;
    const kd_f32 cx = c_x - p->sx * c_z, cy = c_y - p->sy * c_z;

    /* Scaled barycentrics; an exact zero is ambiguous in float and is recomputed exactly. */
    kd_f32 u = cx * by - cy * bx;
    kd_f32 v = ax * cy - ay * cx;
    kd_f32 w = bx * ay - by * ax;
    if (u == 0.0f || v == 0.0f || w == 0.0f)
        kd_exact_edges(ax, ay, bx, by, cx, cy, fp64, &u, &v, &w);
    if ((u < 0.0f || v < 0.0f || w < 0.0f) && (u > 0.0f || v > 0.0f || w > 0.0f)) return 0;
    const kd_f32 det = u + v + w;
    if (det == 0.0f) return 0;

    const kd_f32 az = p->sz * a_z, bz = p->sz * b_z, cz = p->sz * c_z;
    const kd_f32 inv_det = 1.0f / det;
    const kd_f32 t_float = (u * az + v * bz + w * cz) * inv_det;
    const kd_f32 condition =
        kd_float_t_condition(p, a_x, a_y, a_z, b_x, b_y, b_z, c_x, c_y, c_z, ax, ay, bx, by, cx, cy,
                             u, v, w, az, bz, cz, t_float, inv_det);
    const kd_f32 t_error = KDRAY_T_ERROR_PER_CONDITION * condition;
    if (!(t_float + t_error >= tmin && t_float - t_error < best->t)) return 0;
    const kd_f32 t = condition > KDRAY_T_REFINE_CONDITION * KDRAY_FABS(t_float)
                         ? kd_plane_distance_with(tri, p->org[0], p->org[1], p->org[2], p->dir[0],
                                                  p->dir[1], p->dir[2], t_float, fp64)
                         : t_float;
    if (!(t >= tmin && t < best->t)) return 0;
    best->t = t;
    best->prim = id;
    best->u = v * inv_det;
    best->v = w * inv_det;
    return 1;
}

/* kd_intersect_triangle_with the device's path (KDRAY_EXACT_FP64): what the walk calls. */
KDRAY_HOT_INLINE int kd_intersect_triangle(const KdRayPrecomp* p, KDRAY_GLOBAL const kd_f32* tri,
                                           kd_u32 id, kd_f32 tmin, KdHit* best) {
    return kd_intersect_triangle_with(p, tri, id, tmin, best, KDRAY_EXACT_FP64);
}

#endif /* KDRAY_KD_INTERSECT_H */
