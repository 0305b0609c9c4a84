/* packet_traverse.cl — the kd-tree walk of core/device/kd_traverse.h for a packet of 8 or 16 rays
 * at once (KDRAY_PACKET_LANES: the device's native float width), in the lanes of OpenCL vectors
 * (float8 or kd_packet_float), after Wald, Slusallek, Benthin & Wagner,
 * "Interactive rendering with coherent ray tracing" (Eurographics 2001): one walk through the tree
 * shared by the packet, each node's split computed for all lanes in one vector operation, each
 * leaf's triangles tested against all lanes together. It is for CPU devices, whose work-items run
 * one after another and whose SIMD units a single ray's walk leaves idle (PoCL does not vectorise a
 * walk across work-items: its control flow diverges); a GPU already runs one ray per lane.
 * Included by render.cl; it holds no kernel of its own.
 *
 * Every lane is the scalar walk exactly: it visits the same nodes with the same [tmin, tmax] in
 * the same order and tests the same triangles in the same order with the same arithmetic, so its
 * hit equals kd_trace's bit for bit, ties between triangles included. The packet's walk is the
 * union of its lanes' walks: a lane takes part in a node only when its own walk visits it (its
 * mask), and when lanes want a node's children in opposite orders the node's children are
 * visited three times: below (for the lanes that go below first), above (for all), below (for
 * the lanes that go above first). Coherent rays (a camera tile) share nearly every node.
 *
 * Only the watertight test has a packet form; Moller-Trumbore renders trace one ray at a time. */
#ifndef KDRAY_PACKET_TRAVERSE_CL
#define KDRAY_PACKET_TRAVERSE_CL

#include "core/device/kd_traverse.h"

/* The packet's vector types and the built-ins that name a width. Lanes beyond the device's
 * native width would be split by the compiler into several registers per operation and gain
 * nothing; fewer leave part of each register idle (core/device/kd_shared.h). */
#if KDRAY_PACKET_LANES == 16
typedef float16 kd_packet_float;
typedef int16 kd_packet_int;
typedef uint16 kd_packet_uint;
#define kd_packet_vload vload16
#define kd_packet_vstore vstore16
#define kd_packet_convert_float convert_float16
#define kd_packet_convert_double convert_double16
#define kd_packet_as_uint as_uint16
#define kd_packet_double double16
#define KDRAY_PACKET_LANE_INDEX \
    ((kd_packet_uint)(0, 1, 2, 3, 4, 5, 6, 7, 8, 9, 10, 11, 12, 13, 14, 15))
#elif KDRAY_PACKET_LANES == 8
typedef float8 kd_packet_float;
typedef int8 kd_packet_int;
typedef uint8 kd_packet_uint;
#define kd_packet_vload vload8
#define kd_packet_vstore vstore8
#define kd_packet_convert_float convert_float8
#define kd_packet_convert_double convert_double8
#define kd_packet_as_uint as_uint8
#define kd_packet_double double8
#define KDRAY_PACKET_LANE_INDEX ((kd_packet_uint)(0, 1, 2, 3, 4, 5, 6, 7))
#else
#error "packets are a float8 or a float16: build with -DKDRAY_PACKET_LANES=8 or 16"
#endif
#define KDRAY_PACKET_TILE_ROWS KDRAY_PACKET_TILE_HEIGHT(KDRAY_PACKET_LANES)

/* Whether any lane of a mask (each lane 0 or -1) is set. OpenCL's any() is, in PoCL, a chain of
 * shuffles with a branch per step; a reduction of the lanes' sign bits compiles to a mask test. */
/* KDRAY_PACKET_PORTABLE_ANY: OpenCL's any() alone, for Oclgrind 21.10, which has no
 * llvm.vector.reduce.or (tests/oclgrind_check.py's packet cases). */
#if defined(__clang__) && defined(__has_builtin) && !defined(KDRAY_PACKET_PORTABLE_ANY)
#if __has_builtin(__builtin_reduce_or)
#define KDRAY_PACKET_ANY(m) (__builtin_reduce_or((m) < 0) != 0)
#endif
#endif
#ifndef KDRAY_PACKET_ANY
#define KDRAY_PACKET_ANY(m) any(m)
#endif

/* Per-lane constants of the walk and of the watertight test (KdRayPrecomp, one lane per ray). */
typedef struct KdPacket {
    kd_packet_float org[3], dir[3], inv_dir[3];
    kd_packet_int kx, ky, kz;
    kd_packet_float sx, sy, sz;
    kd_packet_float ox, oy, oz; /* org[kx], org[ky], org[kz] */
    kd_packet_float tmin;       /* the rays' own tmin: hits nearer than it do not count */
} KdPacket;

typedef struct KdPacketHit {
    kd_packet_float t, u, v;
    kd_packet_uint prim;
} KdPacketHit;

/* Component `axis` (uniform over the packet) of a vector triple. */
KDRAY_INLINE kd_packet_float kd_packet_axis(const kd_packet_float* v, uint axis) {
    return axis == 0 ? v[0] : (axis == 1 ? v[1] : v[2]);
}

/* Per lane, component k[lane] of the triangle corner c (three floats). */
KDRAY_INLINE kd_packet_float kd_packet_pick(kd_packet_int k, __global const float* c) {
    return select(select((kd_packet_float)(c[2]), (kd_packet_float)(c[1]), k == 1),
                  (kd_packet_float)(c[0]), k == 0);
}

/* kd_plane_distance for the lanes in `lanes`, lane by lane through the scalar function, so that a
 * packet's distances are the single ray's bit for bit; `fallback` elsewhere. Only lanes whose ray
 * passes inside the triangle with a poorly conditioned float t get here (kd_float_t_condition),
 * which is rare on ordinary meshes. */
KDRAY_INLINE kd_packet_float kd_packet_plane_distance(const KdPacket* p, __global const float* tri,
                                                      kd_packet_int lanes,
                                                      kd_packet_float fallback) {
    float t[KDRAY_PACKET_LANES], o[3][KDRAY_PACKET_LANES], d[3][KDRAY_PACKET_LANES];
    int in[KDRAY_PACKET_LANES];
    kd_packet_vstore(fallback, 0, t);
    kd_packet_vstore(lanes, 0, in);
    for (int a = 0; a < 3; ++a) {
        kd_packet_vstore(p->org[a], 0, o[a]);
        kd_packet_vstore(p->dir[a], 0, d[a]);
    }
    for (int lane = 0; lane < KDRAY_PACKET_LANES; ++lane)
        if (in[lane])
            t[lane] = kd_plane_distance(tri, o[0][lane], o[1][lane], o[2][lane], d[0][lane],
                                        d[1][lane], d[2][lane], t[lane]);
    return kd_packet_vload(0, t);
}

#if !KDRAY_EXACT_FP64
/* kd_exact_edges in float-float for the lanes in `lanes`, lane by lane through the scalar
 * function (bit for bit the single ray's); only rays with an edge function exactly zero get here.
 */
KDRAY_INLINE void kd_packet_exact_edges(kd_packet_int lanes, kd_packet_float ax, kd_packet_float ay,
                                        kd_packet_float bx, kd_packet_float by, kd_packet_float cx,
                                        kd_packet_float cy, kd_packet_float* u, kd_packet_float* v,
                                        kd_packet_float* w) {
    float c[6][KDRAY_PACKET_LANES], out[3][KDRAY_PACKET_LANES];
    int in[KDRAY_PACKET_LANES];
    kd_packet_vstore(lanes, 0, in);
    kd_packet_vstore(ax, 0, c[0]);
    kd_packet_vstore(ay, 0, c[1]);
    kd_packet_vstore(bx, 0, c[2]);
    kd_packet_vstore(by, 0, c[3]);
    kd_packet_vstore(cx, 0, c[4]);
    kd_packet_vstore(cy, 0, c[5]);
    kd_packet_vstore(*u, 0, out[0]);
    kd_packet_vstore(*v, 0, out[1]);
    kd_packet_vstore(*w, 0, out[2]);
    for (int lane = 0; lane < KDRAY_PACKET_LANES; ++lane)
        if (in[lane])
            kd_exact_edges(c[0][lane], c[1][lane], c[2][lane], c[3][lane], c[4][lane], c[5][lane],
                           0, &out[0][lane], &out[1][lane], &out[2][lane]);
    *u = kd_packet_vload(0, out[0]);
    *v = kd_packet_vload(0, out[1]);
    *w = kd_packet_vload(0, out[2]);
}
#endif

/* kd_intersect_triangle for the lanes in `active`, operation for operation: a lane whose test
 * accepts the triangle takes it as its best hit. */
KDRAY_HOT_INLINE void kd_packet_intersect(const KdPacket* p, __global const float* tri, uint id,
                                          kd_packet_int active, KdPacketHit* best) {
    const kd_packet_float a_x = kd_packet_pick(p->kx, tri) - p->ox,
                          a_y = kd_packet_pick(p->ky, tri) - p->oy,
                          a_z = kd_packet_pick(p->kz, tri) - p->oz;
    const kd_packet_float b_x = kd_packet_pick(p->kx, tri + 3) - p->ox,
                          b_y = kd_packet_pick(p->ky, tri + 3) - p->oy,
                          b_z = kd_packet_pick(p->kz, tri + 3) - p->oz;
    const kd_packet_float c_x = kd_packet_pick(p->kx, tri + 6) - p->ox,
                          c_y = kd_packet_pick(p->ky, tri + 6) - p->oy,
                          c_z = kd_packet_pick(p->kz, tri + 6) - p->oz;
    const kd_packet_float ax = a_x - p->sx * a_z, ay = a_y - p->sy * a_z;
    const kd_packet_float bx = b_x - p->sx * b_z, by = b_y - p->sy * b_z;
    const kd_packet_float cx = c_x - p->sx * c_z, cy = c_y - p->sy * c_z;
    kd_packet_float u = cx * by - cy * bx;
    kd_packet_float v = ax * cy - ay * cx;
    kd_packet_float w = bx * ay - by * ax;
    const kd_packet_int zero = active & ((u == 0.0f) | (v == 0.0f) | (w == 0.0f));
    if (KDRAY_PACKET_ANY(zero)) {
#if KDRAY_EXACT_FP64
        const kd_packet_double dax = kd_packet_convert_double(ax),
                               day = kd_packet_convert_double(ay);
        const kd_packet_double dbx = kd_packet_convert_double(bx),
                               dby = kd_packet_convert_double(by);
        const kd_packet_double dcx = kd_packet_convert_double(cx),
                               dcy = kd_packet_convert_double(cy);
        u = select(u, kd_packet_convert_float(dcx * dby - dcy * dbx), zero);
        v = select(v, kd_packet_convert_float(dax * dcy - day * dcx), zero);
        w = select(w, kd_packet_convert_float(dbx * day - dby * dax), zero);
#else
        kd_packet_exact_edges(zero, ax, ay, bx, by, cx, cy, &u, &v, &w);
#endif
    }
    kd_packet_int ok =
        active & ~(((u < 0.0f) | (v < 0.0f) | (w < 0.0f)) & ((u > 0.0f) | (v > 0.0f) | (w > 0.0f)));
    const kd_packet_float det = u + v + w;
    ok &= det != 0.0f;
    if (!KDRAY_PACKET_ANY(ok)) return;
    const kd_packet_float az = p->sz * a_z, bz = p->sz * b_z, cz = p->sz * c_z;
    const kd_packet_float inv_det = 1.0f / det;
    const kd_packet_float t_float = (u * az + v * bz + w * cz) * inv_det;
    /* kd_float_t_condition and its uses, operation for operation. */
    const kd_packet_float sx = fabs(p->sx), sy = fabs(p->sy);
    const kd_packet_float max_ax = fabs(a_x) + sx * fabs(a_z), max_ay = fabs(a_y) + sy * fabs(a_z);
    const kd_packet_float max_bx = fabs(b_x) + sx * fabs(b_z), max_by = fabs(b_y) + sy * fabs(b_z);
    const kd_packet_float max_cx = fabs(c_x) + sx * fabs(c_z), max_cy = fabs(c_y) + sy * fabs(c_z);
    const kd_packet_float du =
        max_cx * fabs(by) + fabs(cx) * max_by + max_cy * fabs(bx) + fabs(cy) * max_bx;
    const kd_packet_float dv =
        max_ax * fabs(cy) + fabs(ax) * max_cy + max_ay * fabs(cx) + fabs(ay) * max_cx;
    const kd_packet_float dw =
        max_bx * fabs(ay) + fabs(bx) * max_ay + max_by * fabs(ax) + fabs(by) * max_ax;
    const kd_packet_float spread =
        du * fabs(az - t_float) + dv * fabs(bz - t_float) + dw * fabs(cz - t_float);
    const kd_packet_float scaled_z = fabs(u * az) + fabs(v * bz) + fabs(w * cz);
    const kd_packet_float condition = (spread + scaled_z) * fabs(inv_det);
    const kd_packet_float t_error = KDRAY_T_ERROR_PER_CONDITION * condition;
    ok &= (t_float + t_error >= p->tmin) & (t_float - t_error < best->t);
    if (!KDRAY_PACKET_ANY(ok)) return;
    const kd_packet_int refine = ok & (condition > KDRAY_T_REFINE_CONDITION * fabs(t_float));
    const kd_packet_float t =
        KDRAY_PACKET_ANY(refine) ? kd_packet_plane_distance(p, tri, refine, t_float) : t_float;
    ok &= (t >= p->tmin) & (t < best->t);
    best->t = select(best->t, t, ok);
    best->prim = select(best->prim, (kd_packet_uint)(id), kd_packet_as_uint(ok));
    best->u = select(best->u, v * inv_det, ok);
    best->v = select(best->v, w * inv_det, ok);
}

/* A node some lanes still have to visit, with their [tmin, tmax]. */
typedef struct KdPacketEntry {
    kd_packet_float tmin, tmax;
    kd_packet_int lanes;
    uint node;
} KdPacketEntry;

/* Up to KDRAY_PACKET_LANES rays, one per lane: origins, directions and [tmin, tmax]; lanes not in
 * `valid` are not traced and miss. */
typedef struct KdPacketRays {
    kd_packet_float org[3], dir[3];
    kd_packet_float tmin, tmax;
    kd_packet_int valid;
} KdPacketRays;

/* Per lane, v[k[lane]] of a vector triple. */
KDRAY_INLINE kd_packet_float kd_packet_pick3(kd_packet_int k, const kd_packet_float* v) {
    return select(select(v[2], v[1], k == 1), v[0], k == 0);
}

/* The packet's walk and triangle constants: kd_ray_precompute and kd_clip_to_box of core/
 * kd_traverse.h for every lane at once, operation for operation, so that each lane's values are
 * the scalar ones bit for bit (the packet tests compare every hit). Gathering the scalar setup of
 * 16 rays into the lanes instead cost a third of the packet kernel (15 of 45 ms for the BART
 * Kitchen at 1024x768). *tmin, *tmax: each lane's interval inside the root box; *active: the
 * valid lanes whose ray meets it; best: no hit before each ray's tmax. */
KDRAY_HOT_INLINE void kd_packet_setup(const float* bounds, const KdPacketRays* rays, KdPacket* p,
                                      kd_packet_float* tmin, kd_packet_float* tmax,
                                      kd_packet_int* active, KdPacketHit* best) {
    for (int a = 0; a < 3; ++a) {
        p->org[a] = rays->org[a];
        p->dir[a] = rays->dir[a];
        p->inv_dir[a] = 1.0f / rays->dir[a];
    }
    /* The axis where the direction is largest becomes the ray's z; x and y swap when it points
     * backwards (kd_ray_precompute). */
    const kd_packet_float ax = fabs(p->dir[0]), ay = fabs(p->dir[1]), az = fabs(p->dir[2]);
    p->kz = select(select((kd_packet_int)(2), (kd_packet_int)(1), ay > az),
                   select((kd_packet_int)(2), (kd_packet_int)(0), ax > az), ax > ay);
    const kd_packet_int kx = select(p->kz + 1, (kd_packet_int)(0), p->kz == 2);
    const kd_packet_int ky = select(kx + 1, (kd_packet_int)(0), kx == 2);
    const kd_packet_int swap = kd_packet_pick3(p->kz, p->dir) < 0.0f;
    p->kx = select(kx, ky, swap);
    p->ky = select(ky, kx, swap);
    const kd_packet_float dx = kd_packet_pick3(p->kx, p->dir), dy = kd_packet_pick3(p->ky, p->dir),
                          dz = kd_packet_pick3(p->kz, p->dir);
    p->sx = dx / dz;
    p->sy = dy / dz;
    p->sz = 1.0f / dz;
    p->ox = kd_packet_pick3(p->kx, p->org);
    p->oy = kd_packet_pick3(p->ky, p->org);
    p->oz = kd_packet_pick3(p->kz, p->org);
    p->tmin = rays->tmin;
    /* The clip to the root box (kd_clip_to_box): a lane parallel to a slab misses outside it. */
    kd_packet_float t0 = rays->tmin, t1 = rays->tmax;
    kd_packet_int meets = rays->valid;
    for (int a = 0; a < 3; ++a) {
        const kd_packet_int parallel = p->dir[a] == 0.0f;
        meets &= ~(parallel & ((p->org[a] < bounds[a]) | (p->org[a] > bounds[3 + a])));
        const kd_packet_float tn = (bounds[a] - p->org[a]) * p->inv_dir[a];
        const kd_packet_float tf = (bounds[3 + a] - p->org[a]) * p->inv_dir[a];
        const kd_packet_float near_t = fmin(tn, tf), far_t = fmax(tn, tf) * 1.0000004f;
        t0 = select(fmax(t0, near_t), t0, parallel);
        t1 = select(fmin(t1, far_t), t1, parallel);
    }
    *tmin = t0;
    *tmax = t1;
    *active = meets & (t0 <= t1);
    best->t = rays->tmax;
    best->u = best->v = (kd_packet_float)(0.0f);
    best->prim = (kd_packet_uint)(KDRAY_NO_HIT);
}

/* Nearest hits of the packet's rays (lanes not valid miss), each as kd_trace_closest gives it for
 * the ray alone; with any_hit (a constant at each call), a hit wherever a lane's walk finds its
 * first: the lanes that hit are exactly those kd_trace_occluded finds blocked, since until then
 * each lane tests what the scalar walk tests. */
KDRAY_HOT_INLINE void kd_trace_packet(__global const KdNode* nodes,
                                      __global const kd_u32* leaf_indices,
                                      __global const float* triangles, const float* bounds,
                                      const KdPacketRays* rays, const int any_hit, KdHit* hits) {
    KdPacket p;
    kd_packet_float tmin, tmax;
    kd_packet_int active;
    KdPacketHit best;
    kd_packet_setup(bounds, rays, &p, &tmin, &tmax, &active, &best);
    /* Each inner node pushes at most two entries (kd_trace: one), KDRAY_MAX_DEPTH levels deep. */
    KdPacketEntry stack[2 * KDRAY_MAX_DEPTH];
    int top = 0;
    uint node_index = 0;
    for (;;) {
        /* A lane stops where its best hit lies before the node (kd_trace's test), or at any
         * hit for any_hit. */
        active &= ~(best.t < tmin);
        if (any_hit) active &= best.prim == (kd_packet_uint)(KDRAY_NO_HIT);
        if (KDRAY_PACKET_ANY(active)) {
            const KdNode node = nodes[node_index];
            if (!kd_node_is_leaf(node)) {
                const uint axis = kd_node_axis(node);
                const float split = kd_node_split(node);
                const kd_packet_float o = kd_packet_axis(p.org, axis),
                                      d = kd_packet_axis(p.dir, axis);
                const kd_packet_float t_plane = (split - o) * kd_packet_axis(p.inv_dir, axis);
                /* Per lane, kd_trace's cases: a ray lying in the plane visits both children,
                 * below first, over its whole interval; any other visits the child on its
                 * origin's side (first) and the other (second) as the plane's distance says. */
                const kd_packet_int in_plane = (d == 0.0f) & (o == split);
                const kd_packet_int below_first =
                    in_plane | (o < split) | ((o == split) & (d > 0.0f));
                const kd_packet_int only_first = (t_plane > tmax) | (t_plane < 0.0f);
                const kd_packet_int only_second = ~only_first & (t_plane < tmin);
                const kd_packet_int both = ~only_first & ~only_second;
                const kd_packet_int first = active & (in_plane | only_first | both);
                const kd_packet_int second = active & (in_plane | only_second | both);
                const kd_packet_float first_tmax =
                    select(select(tmax, t_plane, both), tmax, in_plane);
                const kd_packet_float second_tmin =
                    select(select(tmin, t_plane, both), tmin, in_plane);
                KdPacketEntry below, above;
                below.node = node_index + 1;
                below.lanes = select(second, first, below_first);
                below.tmin = select(second_tmin, tmin, below_first);
                below.tmax = select(tmax, first_tmax, below_first);
                above.node = kd_node_above_child(node);
                above.lanes = select(first, second, below_first);
                above.tmin = select(tmin, second_tmin, below_first);
                above.tmax = select(first_tmax, tmax, below_first);
                /* Lanes that visit both children above first see below again after above. */
                const kd_packet_int below_later = below.lanes & above.lanes & ~below_first;
                if (KDRAY_PACKET_ANY(below_later)) {
                    stack[top] = below;
                    stack[top].lanes = below_later;
                    ++top;
                }
                if (KDRAY_PACKET_ANY(above.lanes)) stack[top++] = above;
                below.lanes &= ~below_later;
                if (KDRAY_PACKET_ANY(below.lanes)) {
                    node_index = below.node;
                    active = below.lanes;
                    tmin = below.tmin;
                    tmax = below.tmax;
                    continue;
                }
            } else {
                const uint count = kd_leaf_count(node), offset = kd_leaf_offset(node);
                for (uint i = 0; i < count; ++i) {
                    const uint id = leaf_indices[offset + i];
                    kd_packet_intersect(&p, triangles + (size_t)id * KDRAY_FLOATS_PER_TRIANGLE, id,
                                        active, &best);
                }
            }
        }
        if (top == 0) break;
        --top;
        node_index = stack[top].node;
        active = stack[top].lanes;
        tmin = stack[top].tmin;
        tmax = stack[top].tmax;
    }
    float t[KDRAY_PACKET_LANES], u[KDRAY_PACKET_LANES], v[KDRAY_PACKET_LANES];
    uint prim[KDRAY_PACKET_LANES];
    kd_packet_vstore(best.t, 0, t);
    kd_packet_vstore(best.u, 0, u);
    kd_packet_vstore(best.v, 0, v);
    kd_packet_vstore(best.prim, 0, prim);
    for (int i = 0; i < KDRAY_PACKET_LANES; ++i) {
        hits[i].prim = prim[i];
        hits[i].t = prim[i] == KDRAY_NO_HIT ? KDRAY_INF : t[i];
        hits[i].u = u[i];
        hits[i].v = v[i];
    }
}

#endif /* KDRAY_PACKET_TRAVERSE_CL */
