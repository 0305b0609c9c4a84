/* packet_traverse.cl — the kd-tree walk of core/device/kd_traverse.h for a packet of 16 rays at
 * once, in the lanes of OpenCL vectors (float16), after Wald, Slusallek, Benthin & Wagner,
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

#if KDRAY_PACKET_SIZE != 16
#error "packets are the 16 lanes of a float16 (core/device/kd_shared.h, KDRAY_PACKET_TILE)"
#endif

/* Whether any lane of a mask (each lane 0 or -1) is set. OpenCL's any() is, in PoCL, a chain of
 * shuffles with a branch per step; a reduction of the lanes' sign bits compiles to a mask test. */
#if defined(__clang__) && defined(__has_builtin)
#if __has_builtin(__builtin_reduce_or)
#define KDRAY_PACKET_ANY(m) (__builtin_reduce_or((m) < 0) != 0)
#endif
#endif
#ifndef KDRAY_PACKET_ANY
#define KDRAY_PACKET_ANY(m) any(m)
#endif

/* Per-lane constants of the walk and of the watertight test (KdRayPrecomp, one lane per ray). */
typedef struct KdPacket {
    float16 org[3], dir[3], inv_dir[3];
    int16 kx, ky, kz;
    float16 sx, sy, sz;
    float16 ox, oy, oz; /* org[kx], org[ky], org[kz] */
    float16 tmin;       /* the rays' own tmin: hits nearer than it do not count */
} KdPacket;

typedef struct KdPacketHit {
    float16 t, u, v;
    uint16 prim;
} KdPacketHit;

/* Component `axis` (uniform over the packet) of a vector triple. */
KDRAY_INLINE float16 kd_packet_axis(const float16* v, uint axis) {
    return axis == 0 ? v[0] : (axis == 1 ? v[1] : v[2]);
}

/* Per lane, component k[lane] of the triangle corner c (three floats). */
KDRAY_INLINE float16 kd_packet_pick(int16 k, __global const float* c) {
    return select(select((float16)(c[2]), (float16)(c[1]), k == 1), (float16)(c[0]), k == 0);
}

/* kd_plane_distance for the lanes in `lanes`, lane by lane through the scalar function, so that a
 * packet's distances are the single ray's bit for bit; `fallback` elsewhere. Only lanes whose ray
 * passes inside the triangle with a poorly conditioned float t get here (kd_float_t_condition),
 * which is rare on ordinary meshes. */
KDRAY_INLINE float16 kd_packet_plane_distance(const KdPacket* p, __global const float* tri,
                                              int16 lanes, float16 fallback) {
    float t[16], o[3][16], d[3][16];
    int in[16];
    vstore16(fallback, 0, t);
    vstore16(lanes, 0, in);
    for (int a = 0; a < 3; ++a) {
        vstore16(p->org[a], 0, o[a]);
        vstore16(p->dir[a], 0, d[a]);
    }
    for (int lane = 0; lane < 16; ++lane)
        if (in[lane])
            t[lane] = kd_plane_distance(tri, o[0][lane], o[1][lane], o[2][lane], d[0][lane],
                                        d[1][lane], d[2][lane], t[lane]);
    return vload16(0, t);
}

#if !KDRAY_EXACT_FP64
/* kd_exact_edges in float-float for the lanes in `lanes`, lane by lane through the scalar
 * function (bit for bit the single ray's); only rays with an edge function exactly zero get here. */
KDRAY_INLINE void kd_packet_exact_edges(int16 lanes, float16 ax, float16 ay, float16 bx,
                                        float16 by, float16 cx, float16 cy, float16* u, float16* v,
                                        float16* w) {
    float c[6][16], out[3][16];
    int in[16];
    vstore16(lanes, 0, in);
    vstore16(ax, 0, c[0]);
    vstore16(ay, 0, c[1]);
    vstore16(bx, 0, c[2]);
    vstore16(by, 0, c[3]);
    vstore16(cx, 0, c[4]);
    vstore16(cy, 0, c[5]);
    vstore16(*u, 0, out[0]);
    vstore16(*v, 0, out[1]);
    vstore16(*w, 0, out[2]);
    for (int lane = 0; lane < 16; ++lane)
        if (in[lane])
            kd_exact_edges(c[0][lane], c[1][lane], c[2][lane], c[3][lane], c[4][lane], c[5][lane],
                           0, &out[0][lane], &out[1][lane], &out[2][lane]);
    *u = vload16(0, out[0]);
    *v = vload16(0, out[1]);
    *w = vload16(0, out[2]);
}
#endif

/* kd_intersect_triangle for the lanes in `active`, operation for operation: a lane whose test
 * accepts the triangle takes it as its best hit. */
KDRAY_HOT_INLINE void kd_packet_intersect(const KdPacket* p, __global const float* tri, uint id,
                                          int16 active, KdPacketHit* best) {
    const float16 a_x = kd_packet_pick(p->kx, tri) - p->ox,
                  a_y = kd_packet_pick(p->ky, tri) - p->oy,
                  a_z = kd_packet_pick(p->kz, tri) - p->oz;
    const float16 b_x = kd_packet_pick(p->kx, tri + 3) - p->ox,
                  b_y = kd_packet_pick(p->ky, tri + 3) - p->oy,
                  b_z = kd_packet_pick(p->kz, tri + 3) - p->oz;
    const float16 c_x = kd_packet_pick(p->kx, tri + 6) - p->ox,
                  c_y = kd_packet_pick(p->ky, tri + 6) - p->oy,
                  c_z = kd_packet_pick(p->kz, tri + 6) - p->oz;
    const float16 ax = a_x - p->sx * a_z, ay = a_y - p->sy * a_z;
    const float16 bx = b_x - p->sx * b_z, by = b_y - p->sy * b_z;
    const float16 cx = c_x - p->sx * c_z, cy = c_y - p->sy * c_z;
    float16 u = cx * by - cy * bx;
    float16 v = ax * cy - ay * cx;
    float16 w = bx * ay - by * ax;
    const int16 zero = active & ((u == 0.0f) | (v == 0.0f) | (w == 0.0f));
    if (KDRAY_PACKET_ANY(zero)) {
#if KDRAY_EXACT_FP64
        const double16 dax = convert_double16(ax), day = convert_double16(ay);
        const double16 dbx = convert_double16(bx), dby = convert_double16(by);
        const double16 dcx = convert_double16(cx), dcy = convert_double16(cy);
        u = select(u, convert_float16(dcx * dby - dcy * dbx), zero);
        v = select(v, convert_float16(dax * dcy - day * dcx), zero);
        w = select(w, convert_float16(dbx * day - dby * dax), zero);
#else
        kd_packet_exact_edges(zero, ax, ay, bx, by, cx, cy, &u, &v, &w);
#endif
    }
    int16 ok =
        active & ~(((u < 0.0f) | (v < 0.0f) | (w < 0.0f)) & ((u > 0.0f) | (v > 0.0f) | (w > 0.0f)));
    const float16 det = u + v + w;
    ok &= det != 0.0f;
    if (!KDRAY_PACKET_ANY(ok)) return;
    const float16 az = p->sz * a_z, bz = p->sz * b_z, cz = p->sz * c_z;
    const float16 inv_det = 1.0f / det;
    const float16 t_float = (u * az + v * bz + w * cz) * inv_det;
    /* kd_float_t_condition and its uses, operation for operation. */
    const float16 sx = fabs(p->sx), sy = fabs(p->sy);
    const float16 max_ax = fabs(a_x) + sx * fabs(a_z), max_ay = fabs(a_y) + sy * fabs(a_z);
    const float16 max_bx = fabs(b_x) + sx * fabs(b_z), max_by = fabs(b_y) + sy * fabs(b_z);
    const float16 max_cx = fabs(c_x) + sx * fabs(c_z), max_cy = fabs(c_y) + sy * fabs(c_z);
    const float16 du =
        max_cx * fabs(by) + fabs(cx) * max_by + max_cy * fabs(bx) + fabs(cy) * max_bx;
    const float16 dv =
        max_ax * fabs(cy) + fabs(ax) * max_cy + max_ay * fabs(cx) + fabs(ay) * max_cx;
    const float16 dw =
        max_bx * fabs(ay) + fabs(bx) * max_ay + max_by * fabs(ax) + fabs(by) * max_ax;
    const float16 spread =
        du * fabs(az - t_float) + dv * fabs(bz - t_float) + dw * fabs(cz - t_float);
    const float16 scaled_z = fabs(u * az) + fabs(v * bz) + fabs(w * cz);
    const float16 condition = (spread + scaled_z) * fabs(inv_det);
    const float16 t_error = KDRAY_T_ERROR_PER_CONDITION * condition;
    ok &= (t_float + t_error >= p->tmin) & (t_float - t_error < best->t);
    if (!KDRAY_PACKET_ANY(ok)) return;
    const int16 refine = ok & (condition > KDRAY_T_REFINE_CONDITION * fabs(t_float));
    const float16 t =
        KDRAY_PACKET_ANY(refine) ? kd_packet_plane_distance(p, tri, refine, t_float) : t_float;
    ok &= (t >= p->tmin) & (t < best->t);
    best->t = select(best->t, t, ok);
    best->prim = select(best->prim, (uint16)(id), as_uint16(ok));
    best->u = select(best->u, v * inv_det, ok);
    best->v = select(best->v, w * inv_det, ok);
}

/* A node some lanes still have to visit, with their [tmin, tmax]. */
typedef struct KdPacketEntry {
    float16 tmin, tmax;
    int16 lanes;
    uint node;
} KdPacketEntry;

/* Up to 16 rays, one per lane: origins, directions and [tmin, tmax]; lanes not in `valid` are
 * not traced and miss. */
typedef struct KdPacketRays {
    float16 org[3], dir[3];
    float16 tmin, tmax;
    int16 valid;
} KdPacketRays;

/* Per lane, v[k[lane]] of a vector triple. */
KDRAY_INLINE float16 kd_packet_pick3(int16 k, const float16* v) {
    return select(select(v[2], v[1], k == 1), v[0], k == 0);
}

/* The packet's walk and triangle constants: kd_ray_precompute and kd_clip_to_box of core/
 * kd_traverse.h for every lane at once, operation for operation, so that each lane's values are
 * the scalar ones bit for bit (the packet tests compare every hit). Gathering the scalar setup of
 * 16 rays into the lanes instead cost a third of the packet kernel (15 of 45 ms for the BART
 * Kitchen at 1024x768). *tmin, *tmax: each lane's interval inside the root box; *active: the
 * valid lanes whose ray meets it; best: no hit before each ray's tmax. */
KDRAY_HOT_INLINE void kd_packet_setup(const float* bounds, const KdPacketRays* rays, KdPacket* p,
                                      float16* tmin, float16* tmax, int16* active,
                                      KdPacketHit* best) {
    for (int a = 0; a < 3; ++a) {
        p->org[a] = rays->org[a];
        p->dir[a] = rays->dir[a];
        p->inv_dir[a] = 1.0f / rays->dir[a];
    }
    /* The axis where the direction is largest becomes the ray's z; x and y swap when it points
     * backwards (kd_ray_precompute). */
    const float16 ax = fabs(p->dir[0]), ay = fabs(p->dir[1]), az = fabs(p->dir[2]);
    p->kz = select(select((int16)(2), (int16)(1), ay > az), select((int16)(2), (int16)(0), ax > az),
                   ax > ay);
    const int16 kx = select(p->kz + 1, (int16)(0), p->kz == 2);
    const int16 ky = select(kx + 1, (int16)(0), kx == 2);
    const int16 swap = kd_packet_pick3(p->kz, p->dir) < 0.0f;
    p->kx = select(kx, ky, swap);
    p->ky = select(ky, kx, swap);
    const float16 dx = kd_packet_pick3(p->kx, p->dir), dy = kd_packet_pick3(p->ky, p->dir),
                  dz = kd_packet_pick3(p->kz, p->dir);
    p->sx = dx / dz;
    p->sy = dy / dz;
    p->sz = 1.0f / dz;
    p->ox = kd_packet_pick3(p->kx, p->org);
    p->oy = kd_packet_pick3(p->ky, p->org);
    p->oz = kd_packet_pick3(p->kz, p->org);
    p->tmin = rays->tmin;
    /* The clip to the root box (kd_clip_to_box): a lane parallel to a slab misses outside it. */
    float16 t0 = rays->tmin, t1 = rays->tmax;
    int16 meets = rays->valid;
    for (int a = 0; a < 3; ++a) {
        const int16 parallel = p->dir[a] == 0.0f;
        meets &= ~(parallel & ((p->org[a] < bounds[a]) | (p->org[a] > bounds[3 + a])));
        const float16 tn = (bounds[a] - p->org[a]) * p->inv_dir[a];
        const float16 tf = (bounds[3 + a] - p->org[a]) * p->inv_dir[a];
        const float16 near_t = fmin(tn, tf), far_t = fmax(tn, tf) * 1.0000004f;
        t0 = select(fmax(t0, near_t), t0, parallel);
        t1 = select(fmin(t1, far_t), t1, parallel);
    }
    *tmin = t0;
    *tmax = t1;
    *active = meets & (t0 <= t1);
    best->t = rays->tmax;
    best->u = best->v = (float16)(0.0f);
    best->prim = (uint16)(KDRAY_NO_HIT);
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
    float16 tmin, tmax;
    int16 active;
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
        if (any_hit) active &= best.prim == (uint16)(KDRAY_NO_HIT);
        if (KDRAY_PACKET_ANY(active)) {
            const KdNode node = nodes[node_index];
            if (!kd_node_is_leaf(node)) {
                const uint axis = kd_node_axis(node);
                const float split = kd_node_split(node);
                const float16 o = kd_packet_axis(p.org, axis), d = kd_packet_axis(p.dir, axis);
                const float16 t_plane = (split - o) * kd_packet_axis(p.inv_dir, axis);
                /* Per lane, kd_trace's cases: a ray lying in the plane visits both children,
                 * below first, over its whole interval; any other visits the child on its
                 * origin's side (first) and the other (second) as the plane's distance says. */
                const int16 in_plane = (d == 0.0f) & (o == split);
                const int16 below_first = in_plane | (o < split) | ((o == split) & (d > 0.0f));
                const int16 only_first = (t_plane > tmax) | (t_plane < 0.0f);
                const int16 only_second = ~only_first & (t_plane < tmin);
                const int16 both = ~only_first & ~only_second;
                const int16 first = active & (in_plane | only_first | both);
                const int16 second = active & (in_plane | only_second | both);
                const float16 first_tmax = select(select(tmax, t_plane, both), tmax, in_plane);
                const float16 second_tmin = select(select(tmin, t_plane, both), tmin, in_plane);
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
                const int16 below_later = below.lanes & above.lanes & ~below_first;
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
    float t[KDRAY_PACKET_SIZE], u[KDRAY_PACKET_SIZE], v[KDRAY_PACKET_SIZE];
    uint prim[KDRAY_PACKET_SIZE];
    vstore16(best.t, 0, t);
    vstore16(best.u, 0, u);
    vstore16(best.v, 0, v);
    vstore16(best.prim, 0, prim);
    for (int i = 0; i < KDRAY_PACKET_SIZE; ++i) {
        hits[i].prim = prim[i];
        hits[i].t = prim[i] == KDRAY_NO_HIT ? KDRAY_INF : t[i];
        hits[i].u = u[i];
        hits[i].v = v[i];
    }
}

#endif /* KDRAY_PACKET_TRAVERSE_CL */
