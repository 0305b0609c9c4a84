/* kd_shared.h — every struct and constant that host C++ and OpenCL C both see.
 *
 * This is the one place these layouts are written down: the kernels include it (CMake inlines it
 * into the embedded program source) and the host includes it from core/ and cl/. Rules, so that
 * both compilers lay the structs out identically: only 32-bit scalars (kd_u32, kd_i32, kd_f32),
 * arrays of them and structs of this header made of them, explicit padding, no
 * bool/size_t/pointers/enums/bitfields/float3. Every struct states its size; the host
 * static_asserts it (and the offset of a nested struct's next word) and a test kernel reports the
 * device's sizeof.
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

/* Defined when the header is compiled as OpenCL C (OpenCL C 1.2 compilers define the first,
 * implementations the second). */
#if defined(__OPENCL_C_VERSION__) || defined(__OPENCL_VERSION__)
#define KDRAY_DEVICE_CODE 1
#endif

/* Every device helper is KDRAY_INLINE: `static inline` in OpenCL C. A plain `inline` there has
 * C99's meaning, an inline definition that needs an external one elsewhere whenever the compiler
 * keeps a call; none exists, so a compiler that inlines less (NVIDIA's driver, clang for
 * nvptx64 at -O2, anything at -cl-opt-disable) failed to link the program (kd_price_candidates,
 * kd_clip_node_table, kd_group_clip_table were left unresolved). `static` gives each helper
 * internal linkage: a kept call goes to the program's own copy. On the host it is C++'s
 * `inline`. */
#if defined(__OPENCL_C_VERSION__) || defined(__OPENCL_VERSION__)
#define KDRAY_INLINE_LINKAGE static inline
#else
#define KDRAY_INLINE_LINKAGE inline
#endif

/* Functions whose inlining a kernel's speed depends on: PoCL (LLVM at -O2) left the walk, the
 * triangle test, kd_trace_sample and the builder's triangle clipping as calls, which keeps their
 * callers' constants in memory behind pointers (and, for a box passed by value, made a stalled
 * store-to-load copy per call). Compilers without the attribute get plain inline. */
#if defined(__clang__) || defined(__GNUC__)
#define KDRAY_HOT_INLINE KDRAY_INLINE_LINKAGE __attribute__((always_inline))
#else
#define KDRAY_HOT_INLINE KDRAY_INLINE_LINKAGE
#endif

#ifdef KDRAY_DEVICE_CODE
typedef uint kd_u32;
typedef int kd_i32;
typedef float kd_f32;
#define KDRAY_INLINE KDRAY_INLINE_LINKAGE
#define KDRAY_AS_FLOAT(u) as_float(u)
#define KDRAY_AS_UINT(f) as_uint(f)
#else
#include <bit>
#include <cstddef>
#include <cstdint>
typedef std::uint32_t kd_u32;
typedef std::int32_t kd_i32;
typedef float kd_f32;
#define KDRAY_INLINE KDRAY_INLINE_LINKAGE
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

KDRAY_INLINE kd_u32 kd_node_axis(KdNode n) {
    return n.axis_and_offset & 3u;
}
KDRAY_INLINE int kd_node_is_leaf(KdNode n) {
    return kd_node_axis(n) == KDRAY_LEAF_AXIS;
}
KDRAY_INLINE kd_f32 kd_node_split(KdNode n) {
    return KDRAY_AS_FLOAT(n.split_or_count);
}
KDRAY_INLINE kd_u32 kd_node_above_child(KdNode n) {
    return n.axis_and_offset >> 2;
}
KDRAY_INLINE kd_u32 kd_leaf_count(KdNode n) {
    return n.split_or_count;
}
KDRAY_INLINE kd_u32 kd_leaf_offset(KdNode n) {
    return n.axis_and_offset >> 2;
}

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

#ifndef KDRAY_DEVICE_CODE
static_assert(sizeof(KdNode) == 8, "KdNode is 8 bytes on every device");
static_assert(sizeof(KdRay) == 32, "KdRay is 32 bytes on every device");
static_assert(sizeof(KdHit) == 16, "KdHit is 16 bytes on every device");
#endif

/* ---- Rendering: what the render kernel and the reference renderer both read. ---- */

/* Longest path a render follows (render file max_depth); sizes the pending-ray stack. */
#define KDRAY_MAX_BOUNCES 16

/* Effects a frame calls for (KdView.effects; kernels also get them as -DKDRAY_COMPILED_EFFECTS). */
#define KDRAY_EFFECT_SHADOWS 1u
#define KDRAY_EFFECT_REFLECTION 2u
#define KDRAY_EFFECT_REFRACTION 4u
#define KDRAY_EFFECT_AMBIENT 8u      /* Ka x the render file's ambient light */
#define KDRAY_EFFECT_AREA_LIGHTS 16u /* emissive triangles light the scene (kd_area_light.h) */
#define KDRAY_EFFECT_TEXTURES 32u    /* map_Kd and map_Ka at the hits' vt (kd_texture.h) */
/* The path integrator (kd_path.h) in place of Whitted's ray tree: the render file's
 * "integrator": "path". Never with KDRAY_EFFECT_AMBIENT, whose light it computes instead. */
#define KDRAY_EFFECT_PATH 64u

/* What kd_render_pixels reads and writes besides the image and the centre hits
 * (KdRenderLaunch.outputs): the primary rays' hits come traced already (by
 * kd_trace_camera_packets), so do the shadow rays from them (by kd_trace_shadow_packets), and the
 * centre hits' normals are wanted. Per-pixel ray counts are written exactly when the kernel was
 * built with some effect: without any, a pixel casts its primary rays and nothing else. */
#define KDRAY_RENDER_TRACED_PRIMARY 1u
#define KDRAY_RENDER_NORMALS 2u
#define KDRAY_RENDER_TRACED_SHADOWS 4u

/* kd_trace_camera_packets traces the primary rays of tiles of KDRAY_PACKET_TILE_WIDTH x
 * KDRAY_PACKET_TILE_HEIGHT(lanes) pixels, one work-item each, as one packet: the lanes of an
 * OpenCL vector, 8 (float8, a 4x2 tile) or 16 (float16, 4x4), the device's native float width
 * (AVX2 or AVX-512), which the host picks per device and passes as -DKDRAY_PACKET_LANES;
 * kd_trace_shadow_packets the shadow rays from their hits, a packet per light, for frames of at
 * most KDRAY_PACKET_SHADOW_LIGHTS lights (a bit each per primary hit). Lane i is pixel
 * (i % KDRAY_PACKET_TILE_WIDTH, i / KDRAY_PACKET_TILE_WIDTH) of its tile. */
#define KDRAY_PACKET_TILE_WIDTH 4
#define KDRAY_PACKET_TILE_HEIGHT(lanes) ((lanes) / KDRAY_PACKET_TILE_WIDTH)
#define KDRAY_PACKET_SHADOW_LIGHTS 32u

/* KdMaterial flags. */
#define KDRAY_MATERIAL_MIRROR 1u     /* ideal mirror reflection weighted by specular (illum 3, 5) */
#define KDRAY_MATERIAL_DIELECTRIC 2u /* Fresnel reflection + refraction, see transmit_fraction */
#define KDRAY_MATERIAL_HIGHLIGHT 4u  /* Blinn-Phong highlight from specular and shininess */

/* A material's texture slot that holds no texture. */
#define KDRAY_NO_TEXTURE 0xFFFFFFFFu

/* KdMaterial — 96 bytes.
 *   diffuse[3]   Kd                      shininess  Ns (Blinn-Phong exponent)
 *   specular[3]  Ks                      ior        Ni (1 when absent or not above 0)
 *   emission[3]  Ke                      transmit_fraction  share of light that meets the
 *                                        dielectric (1 for illum 4/6/7, 1 - d for d < 1, ...)
 *   filter[3]    colour of transmitted light (Tf where it means transmission, else 1)
 *   flags        KDRAY_MATERIAL_* bits
 *   ambient[3]   the ambient radiance it reflects: Ka x the render file's ambient (per frame)
 *   diffuse_texture, ambient_texture  map_Kd's and map_Ka's entry of the texture table, or
 *                KDRAY_NO_TEXTURE
 *   pad          0 */
typedef struct KdMaterial {
    kd_f32 diffuse[3];
    kd_f32 shininess;
    kd_f32 specular[3];
    kd_f32 ior;
    kd_f32 emission[3];
    kd_f32 transmit_fraction;
    kd_f32 filter[3];
    kd_u32 flags;
    kd_f32 ambient[3];
    kd_u32 diffuse_texture;
    kd_u32 ambient_texture;
    kd_u32 pad[3];
} KdMaterial;

/* KdTexture — 16 bytes: one image of the texel atlas (4 linear floats per texel, r g b and an
 * unused fourth, rows top first). offset: its first texel; width, height in texels; pad: 0. */
typedef struct KdTexture {
    kd_u32 offset;
    kd_u32 width;
    kd_u32 height;
    kd_u32 pad;
} KdTexture;

#define KDRAY_LIGHT_POINT 0u
#define KDRAY_LIGHT_DIRECTIONAL 1u

/* KdLight — 32 bytes. type KDRAY_LIGHT_*; vec: point position, or the unit direction a
 * directional light travels; power: point intensity (falls off as 1/r^2) or directional
 * irradiance; pad: 0. */
typedef struct KdLight {
    kd_u32 type;
    kd_f32 vec[3];
    kd_f32 power[3];
    kd_u32 pad;
} KdLight;

/* KdEmitter — 16 bytes: one emissive triangle of a frame's table, which the host builds in order
 * of triangle id. triangle: its id; cdf: the probability of choosing it or one before it (the
 * last entry's is 1); probability: of choosing it, luminance(Ke) x area / the table's total;
 * pad: 0. */
typedef struct KdEmitter {
    kd_u32 triangle;
    kd_f32 cdf;
    kd_f32 probability;
    kd_u32 pad;
} KdEmitter;

/* KdView — 112 bytes: the camera basis of conventions.md and the frame's render settings.
 *   origin, forward, right, up: camera position and unit basis; tan_half_fov = tan(fov_y / 2);
 *   aspect = width / height; background colour; spp samples per pixel; max_depth: Whitted's
 *   ray generations (<= KDRAY_MAX_BOUNCES), or with KDRAY_EFFECT_PATH the most path segments
 *   (0xFFFFFFFF: unbounded, Russian roulette ends paths); light_count lights, which shine only with
 * KDRAY_EFFECT_SHADOWS (without: a headlight along the view direction, no shadow rays); effects
 * KDRAY_EFFECT_* bits; seed for the sample jitter; ray_epsilon: how far secondary rays start off
 * the surface (scaled to the scene by the host); emitter_count: entries of the emitter table (read
 * only with KDRAY_EFFECT_AREA_LIGHTS); sampler: KDRAY_SAMPLER_LOW_DISCREPANCY (0, every render's)
 * or KDRAY_SAMPLER_INDEPENDENT (tests whose statistics assume independent samples); pad: 0. */
#define KDRAY_SAMPLER_LOW_DISCREPANCY 0u
#define KDRAY_SAMPLER_INDEPENDENT 1u
typedef struct KdView {
    kd_f32 origin[3];
    kd_f32 tan_half_fov;
    kd_f32 forward[3];
    kd_f32 aspect;
    kd_f32 right[3];
    kd_u32 width;
    kd_f32 up[3];
    kd_u32 height;
    kd_f32 background[3];
    kd_u32 spp;
    kd_u32 max_depth;
    kd_u32 light_count;
    kd_u32 effects;
    kd_u32 seed;
    kd_f32 ray_epsilon;
    kd_u32 emitter_count;
    kd_u32 sampler;
    kd_u32 pad;
} KdView;

/* KdRayCounts — 20 bytes: rays cast for one pixel, by kind; area_shadow: shadow rays toward
 * points on emissive triangles (shadow: toward the render file's lights). */
typedef struct KdRayCounts {
    kd_u32 primary;
    kd_u32 shadow;
    kd_u32 reflection;
    kd_u32 refraction;
    kd_u32 area_shadow;
} KdRayCounts;

/* KdTraceCost — 8 bytes: the work of kd-tree walks (kd_trace), the `cost` AOV of one centre ray:
 * nodes: tree nodes visited (inner and leaf; a ray that misses the root box visits none);
 * triangles: ray-triangle tests run (a triangle in several leaves counts once per leaf). */
typedef struct KdTraceCost {
    kd_u32 nodes;
    kd_u32 triangles;
} KdTraceCost;

/* ---- The render kernels' by-value arguments. ----
 *
 * The render kernels (cl/renderer/kernels/render.cl) take the tree's three buffers (nodes,
 * leaf_indices, triangles: the builder's own, traced where it left them), their outputs, and two
 * records: KdRenderLaunch, what a launch knows besides its buffers, and KdSceneLayout, where the
 * frame's read-only shading arrays lie in one buffer, `scene_data`. Each array of that buffer
 * starts at a byte offset that is a multiple of KDRAY_SCENE_ALIGN: of every element's alignment
 * (4 bytes: the structs above hold only 32-bit words) and of a cache line (64 bytes on a CPU,
 * 128 on a GPU), so that no array starts inside the line where the one before it ends. */
#define KDRAY_SCENE_ALIGN 128u

/* KdSceneLayout — 48 bytes: the byte offsets in `scene_data` of the frame's read-only arrays, in
 * the order they lie there (the host lays them out: cl/renderer/scene_arrays.h), and which are
 * present. An array the frame does not use (lights without shadows, the texture arrays without
 * textures) has no bytes and an offset that is never read.
 *   materials       KdMaterial per material id (Scene::material_ids' values)
 *   lights          KdLight, KdView.light_count of them
 *   emitters        KdEmitter, KdView.emitter_count of them (read with area lights only)
 *   textures        the texture table, KdTexture per texture (with textures only)
 *   material_ids    kd_u32 per triangle
 *   vertex_normals  KDRAY_FLOATS_PER_TRIANGLE floats per triangle: unit normals at its corners
 *                   (read only when has_vertex_normals)
 *   texcoords       6 floats per triangle: its vt corners, u NaN where it has none (textures)
 *   texels          the texel atlas, 4 floats per texel (textures); last, so that it alone may
 *                   reach past the 4 GiB that 32-bit offsets address
 *   has_vertex_normals  1: the scene has vertex normals and shades smooth; 0: flat
 *   pad             0 */
typedef struct KdSceneLayout {
    kd_u32 materials;
    kd_u32 lights;
    kd_u32 emitters;
    kd_u32 textures;
    kd_u32 material_ids;
    kd_u32 vertex_normals;
    kd_u32 texcoords;
    kd_u32 texels;
    kd_u32 has_vertex_normals;
    kd_u32 pad[3];
} KdSceneLayout;

/* KdRenderLaunch — 160 bytes: what a launch of a render kernel (kd_trace_camera_packets,
 * kd_trace_shadow_packets, kd_render_pixels, kd_shade_traced_pixels) knows besides its buffers.
 *   view       bytes 0-111: the frame's camera and settings (KdView, 32-bit words only, so
 *              nested without padding)
 *   bounds     the tree's root box, lo.xyz hi.xyz
 *   first_row  the launch's first image row; rows: its number of rows (work-items past them
 *              return at once)
 *   outputs    KDRAY_RENDER_* bits
 *   pad        0 */
typedef struct KdRenderLaunch {
    KdView view;
    kd_f32 bounds[6];
    kd_u32 first_row;
    kd_u32 rows;
    kd_u32 outputs;
    kd_u32 pad[3];
} KdRenderLaunch;

#ifndef KDRAY_DEVICE_CODE
static_assert(sizeof(KdMaterial) == 96, "KdMaterial is 96 bytes on every device");
static_assert(sizeof(KdTexture) == 16, "KdTexture is 16 bytes on every device");
static_assert(sizeof(KdLight) == 32, "KdLight is 32 bytes on every device");
static_assert(sizeof(KdView) == 112, "KdView is 112 bytes on every device");
static_assert(sizeof(KdRayCounts) == 20, "KdRayCounts is 20 bytes on every device");
static_assert(sizeof(KdTraceCost) == 8, "KdTraceCost is 8 bytes on every device");
static_assert(sizeof(KdEmitter) == 16, "KdEmitter is 16 bytes on every device");
static_assert(sizeof(KdSceneLayout) == 48, "KdSceneLayout is 48 bytes on every device");
static_assert(sizeof(KdRenderLaunch) == 160, "KdRenderLaunch is 160 bytes on every device");
static_assert(offsetof(KdRenderLaunch, bounds) == sizeof(KdView),
              "KdRenderLaunch's view is nested without padding");
#endif

#endif /* KDRAY_KD_SHARED_H */
