/* kd_shared.h — every struct and constant that host C++ and OpenCL C both see.
 *
 * This is the one place these layouts are written down: the kernels include it (CMake inlines it
 * into the embedded program source) and the host includes it from core/ and cl/. Rules, so that
 * both compilers lay the structs out identically: only 32-bit scalars (kd_u32, kd_i32, kd_f32) and
 * arrays of them, explicit padding, no bool/size_t/pointers/enums/bitfields/float3. Every struct
 * states its size; the host static_asserts it and a test kernel reports the device's sizeof.
 *
 * Tree layout (preorder, as in pbrt's KdTreeAccel): node 0 is the root; an inner node's below
 * child is the next node in the array and its above child's index is stored in the node. A leaf
 * names a run [offset, offset + count) of leaf_indices, whose entries are triangle ids as
 * conventions.md numbers them. Walking a leaf's triangles:
 *
 *     for (kd_u32 i = 0; i < kd_leaf_count(n); ++i)
 *         tri = leaf_indices[kd_leaf_offset(n) + i];
 */
#ifndef KDRAY_KD_SHARED_H
#define KDRAY_KD_SHARED_H

#ifdef __OPENCL_VERSION__
typedef uint kd_u32;
typedef int kd_i32;
typedef float kd_f32;
#define KDRAY_INLINE inline
#define KDRAY_AS_FLOAT(u) as_float(u)
#define KDRAY_AS_UINT(f) as_uint(f)
#else
#include <bit>
#include <cstdint>
typedef std::uint32_t kd_u32;
typedef std::int32_t kd_i32;
typedef float kd_f32;
#define KDRAY_INLINE inline
#define KDRAY_AS_FLOAT(u) std::bit_cast<float>(static_cast<kd_u32>(u))
#define KDRAY_AS_UINT(f) std::bit_cast<kd_u32>(static_cast<float>(f))
#endif

/* Deepest level a tree may have (root = depth 0). Builders stop splitting at this depth and the
 * traversal stack has exactly this many entries, so the two can never disagree. */
#define KDRAY_MAX_DEPTH 64
/* Axis value stored in a node's low two bits to mark a leaf. */
#define KDRAY_LEAF_AXIS 3u
/* prim id of a ray that hit nothing (conventions.md, AOV prim_id). */
#define KDRAY_NO_HIT 0xFFFFFFFFu
/* Largest node index or leaf offset the 30 offset bits hold. */
#define KDRAY_MAX_OFFSET 0x3FFFFFFFu

/* KdNode — 8 bytes.
 *   split_or_count   inner: split plane position (float bits); leaf: number of triangles.
 *   axis_and_offset  bits 0-1: split axis 0/1/2, or KDRAY_LEAF_AXIS for a leaf.
 *                    bits 2-31: inner: index of the above child; leaf: first leaf_indices entry. */
typedef struct KdNode {
    kd_u32 split_or_count;
    kd_u32 axis_and_offset;
} KdNode;

/* KdRay — 32 bytes. org xyz, tmin, dir xyz (need not be unit length), tmax. */
typedef struct KdRay {
    kd_f32 org[3];
    kd_f32 tmin;
    kd_f32 dir[3];
    kd_f32 tmax;
} KdRay;

/* KdHit — 16 bytes. t: ray parameter of the nearest hit (+inf on a miss); prim: triangle id or
 * KDRAY_NO_HIT; u, v: barycentric coordinates of the hit for vertices 1 and 2. */
typedef struct KdHit {
    kd_f32 t;
    kd_u32 prim;
    kd_f32 u;
    kd_f32 v;
} KdHit;

/* Triangles travel as a flat kd_f32 array, 9 per triangle: v0.xyz v1.xyz v2.xyz. */
#define KDRAY_FLOATS_PER_TRIANGLE 9

KDRAY_INLINE kd_u32 kd_node_axis(KdNode n) { return n.axis_and_offset & 3u; }
KDRAY_INLINE int kd_node_is_leaf(KdNode n) { return kd_node_axis(n) == KDRAY_LEAF_AXIS; }
KDRAY_INLINE kd_f32 kd_node_split(KdNode n) { return KDRAY_AS_FLOAT(n.split_or_count); }
KDRAY_INLINE kd_u32 kd_node_above_child(KdNode n) { return n.axis_and_offset >> 2; }
KDRAY_INLINE kd_u32 kd_leaf_count(KdNode n) { return n.split_or_count; }
KDRAY_INLINE kd_u32 kd_leaf_offset(KdNode n) { return n.axis_and_offset >> 2; }

KDRAY_INLINE KdNode kd_make_inner(kd_u32 axis, kd_f32 split, kd_u32 above_child) {
    KdNode n;
    n.split_or_count = KDRAY_AS_UINT(split);
    n.axis_and_offset = (above_child << 2) | axis;
    return n;
}

KDRAY_INLINE KdNode kd_make_leaf(kd_u32 count, kd_u32 offset) {
    KdNode n;
    n.split_or_count = count;
    n.axis_and_offset = (offset << 2) | KDRAY_LEAF_AXIS;
    return n;
}

#ifndef __OPENCL_VERSION__
static_assert(sizeof(KdNode) == 8, "KdNode is 8 bytes on every device");
static_assert(sizeof(KdRay) == 32, "KdRay is 32 bytes on every device");
static_assert(sizeof(KdHit) == 16, "KdHit is 16 bytes on every device");
#endif

#endif /* KDRAY_KD_SHARED_H */
