/* kd_traverse.h — the kd-tree walk (the triangle tests it calls are in kd_intersect.h and
 * kd_intersect_moller.h), written once in the C subset that compiles both as C++ (the reference
 * tracer, the brute-force oracle) and as OpenCL C (the trace kernels). Sharing the code is what
 * makes the OpenCL tracer's hits identical to the reference's.
 *
 * Pointers into tree and triangle buffers carry KDRAY_GLOBAL (OpenCL's __global, nothing in C++);
 * unqualified pointers are private/host memory.
 */
#ifndef KDRAY_KD_TRAVERSE_H
#define KDRAY_KD_TRAVERSE_H

#include "core/device/kd_intersect.h"

/* The fast, non-watertight alternative and KDRAY_USE_MOLLER, which picks between the two. */
#include "core/device/kd_intersect_moller.h"

/* Clips the ray's [*t0, *t1] to the box {lo, hi}. Returns 0 when they do not overlap. A ray
 * lying in a box face (flat boxes included) counts as inside. */
KDRAY_HOT_INLINE int kd_clip_to_box(const KdRayPrecomp* p, const kd_f32* lo, const kd_f32* hi,
                                    kd_f32* t0, kd_f32* t1) {
    for (int a = 0; a < 3; ++a) {
        /* Parallel to this slab: inside it (faces included) or never. The slab distances would be
         * 0 * inf = NaN for an origin lying in a face. */
        if (p->dir[a] == 0.0f) {
            if (p->org[a] < lo[a] || p->org[a] > hi[a]) return 0;
            continue;
        }
        kd_f32 tn = (lo[a] - p->org[a]) * p->inv_dir[a];
        kd_f32 tf = (hi[a] - p->org[a]) * p->inv_dir[a];
        kd_f32 near_t = KDRAY_FMIN(tn, tf), far_t = KDRAY_FMAX(tn, tf);
        /* Widen the far distance by a few ulps (pbrt's 1 + 2 gamma(3)) so that rounding never
         * loses a triangle lying in the box's face. */
        far_t *= 1.0000004f;
        *t0 = KDRAY_FMAX(*t0, near_t);
        *t1 = KDRAY_FMIN(*t1, far_t);
    }
    return *t0 <= *t1;
}

typedef struct KdTraversalEntry {
    kd_u32 node;
    kd_f32 tmin, tmax;
} KdTraversalEntry;

/* Nearest hit of `ray` in the tree or, with any_hit, the first hit found in [tmin, tmax) (shadow
 * rays need no more), with the triangle test `intersect` names (KDRAY_INTERSECT_*; a kernel
 * ignores it for its compile-time KDRAY_COMPILED_INTERSECT). bounds: the root box as lo.xyz,
 * hi.xyz. The stack has KDRAY_MAX_DEPTH entries: one push per inner node on the current path, and
 * builders never make a path deeper than that. Hits are accepted wherever they lie on the ray (a
 * triangle in a leaf may extend beyond it); the walk ends when the best hit is nearer than the next
 * node's entry. `cost`, when not 0, is added the nodes this walk visits and the triangles it tests
 * (the `cost` AOV); every caller but the cost pass passes a literal 0, and since the walk is
 * always inlined the counting then compiles away (see kd_pixel_cost for the measurement). */
KDRAY_HOT_INLINE void kd_trace(KDRAY_GLOBAL const KdNode* nodes,
                               KDRAY_GLOBAL const kd_u32* leaf_indices,
                               KDRAY_GLOBAL const kd_f32* triangles, const kd_f32* bounds,
                               const KdRay* ray, int any_hit, kd_u32 intersect, KdHit* hit,
                               KdTraceCost* cost) {
    hit->t = ray->tmax;
    hit->prim = KDRAY_NO_HIT;
    hit->u = 0.0f;
    hit->v = 0.0f;
    KdRayPrecomp p;
    kd_ray_precompute(ray, &p);
    kd_f32 tmin = ray->tmin, tmax = ray->tmax;
    if (!kd_clip_to_box(&p, bounds, bounds + 3, &tmin, &tmax)) {
        hit->t = KDRAY_INF;
        return;
    }

    KdTraversalEntry stack[KDRAY_MAX_DEPTH];
    int stack_size = 0;
    kd_u32 node_index = 0;
    for (;;) {
        /* Stop when the best hit lies before this node. */
        if (hit->t < tmin) break;
        KdNode node = nodes[node_index];
        if (cost) cost->nodes += 1u;
        if (!kd_node_is_leaf(node)) {
            /* Inner node: visit the child on the origin's side first, the other if the ray
             * crosses the plane within [tmin, tmax]. */
            const kd_u32 axis = kd_node_axis(node);
            const kd_f32 split = kd_node_split(node);
            const kd_f32 o = KDRAY_PICK3(p.org, axis), d = KDRAY_PICK3(p.dir, axis);
            const kd_u32 below = node_index + 1, above = kd_node_above_child(node);
            if (d == 0.0f && o == split) {
                /* Lying in the plane: both children hold triangles the ray may hit. */
                stack[stack_size].node = above;
                stack[stack_size].tmin = tmin;
                stack[stack_size].tmax = tmax;
                ++stack_size;
                node_index = below;
                continue;
            }
            const kd_f32 t_plane = (split - o) * KDRAY_PICK3(p.inv_dir, axis);
            /* On the plane, the child the ray leaves is visited first over [tmin, 0] (hits at
             * t = 0 on triangles lying in the plane), then the one it enters over [0, tmax]. */
            const int below_first = (o < split) || (o == split && d > 0.0f);
            const kd_u32 first = below_first ? below : above;
            const kd_u32 second = below_first ? above : below;
            if (t_plane > tmax || t_plane < 0.0f) {
                node_index = first;
            } else if (t_plane < tmin) {
                node_index = second;
            } else {
                stack[stack_size].node = second;
                stack[stack_size].tmin = t_plane;
                stack[stack_size].tmax = tmax;
                ++stack_size;
                node_index = first;
                tmax = t_plane;
            }
            continue;
        }
        /* Leaf: test its triangles, then resume from the stack. */
        const kd_u32 count = kd_leaf_count(node), offset = kd_leaf_offset(node);
        for (kd_u32 i = 0; i < count; ++i) {
            if (cost) cost->triangles += 1u;
            const kd_u32 id = leaf_indices[offset + i];
            KDRAY_GLOBAL const kd_f32* tri = triangles + (size_t)id * KDRAY_FLOATS_PER_TRIANGLE;
            const int new_best = KDRAY_USE_MOLLER(intersect)
                                     ? kd_intersect_triangle_moller(&p, tri, id, ray->tmin, hit)
                                     : kd_intersect_triangle(&p, tri, id, ray->tmin, hit);
            if (new_best && any_hit) return;
        }
        if (stack_size == 0) break;
        --stack_size;
        node_index = stack[stack_size].node;
        tmin = stack[stack_size].tmin;
        tmax = stack[stack_size].tmax;
    }
    if (hit->prim == KDRAY_NO_HIT) hit->t = KDRAY_INF;
}

KDRAY_HOT_INLINE void kd_trace_closest(KDRAY_GLOBAL const KdNode* nodes,
                                       KDRAY_GLOBAL const kd_u32* leaf_indices,
                                       KDRAY_GLOBAL const kd_f32* triangles, const kd_f32* bounds,
                                       const KdRay* ray, KdHit* hit) {
    kd_trace(nodes, leaf_indices, triangles, bounds, ray, 0, KDRAY_INTERSECT_WATERTIGHT, hit, 0);
}

/* 1 when anything blocks the ray within [tmin, tmax). Both helpers use the watertight test. */
KDRAY_HOT_INLINE int kd_trace_occluded(KDRAY_GLOBAL const KdNode* nodes,
                                       KDRAY_GLOBAL const kd_u32* leaf_indices,
                                       KDRAY_GLOBAL const kd_f32* triangles, const kd_f32* bounds,
                                       const KdRay* ray) {
    KdHit hit;
    kd_trace(nodes, leaf_indices, triangles, bounds, ray, 1, KDRAY_INTERSECT_WATERTIGHT, &hit, 0);
    return hit.prim != KDRAY_NO_HIT;
}

#endif /* KDRAY_KD_TRAVERSE_H */
