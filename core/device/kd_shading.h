/* kd_shading.h — the pieces of shading that kd_render.h, kd_area_light.h and kd_texture.h all
 * use, in the same C subset (one source for the reference renderer and the render kernel): the
 * effect and math macros, the scene's buffers as both sides hold them (KdSceneView), vector
 * helpers, camera rays, hashing, normals, Fresnel, lights and shadow rays. A header of its own so
 * that includes run one way: kd_render.h includes kd_area_light.h and kd_texture.h, and all three
 * include this.
 */
#ifndef KDRAY_KD_SHADING_H
#define KDRAY_KD_SHADING_H

#include "core/device/kd_shared.h"
#include "core/device/kd_traverse.h"

#ifdef KDRAY_DEVICE_CODE
#ifndef KDRAY_COMPILED_EFFECTS
#error "render kernels need -DKDRAY_COMPILED_EFFECTS=<KDRAY_EFFECT_* bits>"
#endif
#define KDRAY_EFFECT_ON(view, bit) ((KDRAY_COMPILED_EFFECTS & (bit)) != 0u)
#define KDRAY_SQRT sqrt
#define KDRAY_EXP2 exp2
#define KDRAY_LOG2 log2
#define KDRAY_FLOOR floor
#define KDRAY_ISFINITE isfinite
#else
#define KDRAY_EFFECT_ON(view, bit) (((view)->effects & (bit)) != 0u)
#define KDRAY_SQRT std::sqrt
#define KDRAY_EXP2 std::exp2
#define KDRAY_LOG2 std::log2
#define KDRAY_FLOOR std::floor
#define KDRAY_ISFINITE std::isfinite
#endif

#define KDRAY_PI 3.14159265358979323846f
/* The largest float (FLT_MAX, spelled out for both compilers). Every sum of radiance saturates
 * there: Ke 3e38, a valid finite Kd-range value, summed over 16 samples to inf, and a bound on Ke
 * could not prevent it, since a pixel's radiance also grows with the lights, the emitters'
 * geometry and the bounces. Below it every sum is bit for bit what it was. */
#define KDRAY_RADIANCE_MAX 3.40282346638528859812e+38f
/* A path whose weight falls below this adds nothing visible; it is not followed. */
#define KDRAY_MIN_PATH_WEIGHT 1e-3f

/* Scene buffers as both sides hold them. */
typedef struct KdSceneView {
    KDRAY_GLOBAL const KdNode* nodes;
    KDRAY_GLOBAL const kd_u32* leaf_indices;
    KDRAY_GLOBAL const kd_f32* triangles;
    /* Unit normals at each triangle's corners (KDRAY_FLOATS_PER_TRIANGLE per triangle), or 0:
     * the scene shades flat. */
    KDRAY_GLOBAL const kd_f32* vertex_normals;
    KDRAY_GLOBAL const kd_u32* material_ids;
    KDRAY_GLOBAL const KdMaterial* materials;
    KDRAY_GLOBAL const KdLight* lights;
    /* The frame's emitter table (view->emitter_count entries; read with area lights only). */
    KDRAY_GLOBAL const KdEmitter* emitters;
    /* With textures only: each triangle's vt corners (6 floats, u NaN where it has none), the
     * texture table and the texel atlas (kd_texture.h). */
    KDRAY_GLOBAL const kd_f32* texcoords;
    KDRAY_GLOBAL const KdTexture* textures;
    KDRAY_GLOBAL const kd_f32* texels;
    kd_f32 bounds[6];
    kd_u32 intersect; /* KDRAY_INTERSECT_*: the ray-triangle test (a kernel's is compiled in) */
} KdSceneView;

/* Nearest hit, and occlusion, in the scene with its triangle test. */
KDRAY_HOT_INLINE void kd_scene_closest(const KdSceneView* scene, const KdRay* ray, KdHit* hit) {
    kd_trace(scene->nodes, scene->leaf_indices, scene->triangles, scene->bounds, ray, 0,
             scene->intersect, hit, 0);
}
KDRAY_HOT_INLINE int kd_scene_occluded(const KdSceneView* scene, const KdRay* ray) {
    KdHit hit;
    kd_trace(scene->nodes, scene->leaf_indices, scene->triangles, scene->bounds, ray, 1,
             scene->intersect, &hit, 0);
    return hit.prim != KDRAY_NO_HIT;
}

/* What one pixel produces. */
typedef struct KdPixel {
    kd_f32 rgb[3];
    KdHit centre_hit; /* the AOV: the hit of the ray through the pixel centre */
    kd_f32 normal[3]; /* geometric normal of centre_hit, facing the ray (0 on a miss) */
    KdRayCounts rays;
} KdPixel;

KDRAY_INLINE void kd_set3(kd_f32* out, kd_f32 x, kd_f32 y, kd_f32 z) {
    out[0] = x;
    out[1] = y;
    out[2] = z;
}
KDRAY_INLINE kd_f32 kd_dot3(const kd_f32* a, const kd_f32* b) {
    return a[0] * b[0] + a[1] * b[1] + a[2] * b[2];
}
/* The camera ray's arithmetic, written once as macros over any float type: kd_camera_ray and
 * kd_primary_ray below evaluate them on scalars, render.cl's kd_primary_packet on the float16
 * lanes of a packet, with the same operations in the same order, so that each lane's ray is the
 * scalar one bit for bit.
 *   KDRAY_INV_LENGTH3   1 / |(x, y, z)|, by which kd_normalize3 scales
 *   KDRAY_SCREEN_X/Y    conventions.md's sx and sy of image position (px, py) in pixels
 *   KDRAY_CAMERA_DIR    axis a of the direction before normalising, f + (r * sx + u * sy)
 *   KDRAY_SAMPLE_KEY    what kd_hash turns into the jitter of sample r of pixel (x, y), when
 *                       the samples are independent (KDRAY_SAMPLER_INDEPENDENT)
 *   KDRAY_PIXEL_KEY     what kd_hash turns into the rotation of pixel (x, y)'s sample sequence
 *   KDRAY_UNIT_FLOAT    a hash's top 24 bits as a float in [0, 1), through `to_float` */
#define KDRAY_INV_LENGTH3(x, y, z) (1.0f / KDRAY_SQRT((x) * (x) + (y) * (y) + (z) * (z)))
#define KDRAY_SCREEN_X(view, px) \
    ((2.0f * (px) / (kd_f32)(view)->width - 1.0f) * (view)->tan_half_fov * (view)->aspect)
#define KDRAY_SCREEN_Y(view, py) \
    ((1.0f - 2.0f * (py) / (kd_f32)(view)->height) * (view)->tan_half_fov)
#define KDRAY_CAMERA_DIR(view, a, sx, sy) \
    ((view)->forward[a] + ((view)->right[a] * (sx) + (view)->up[a] * (sy)))
/* The seed hashed before it meets r: with r + seed, sample r of seed k was sample r - 1 of seed
 * k + 1, and renders of nearby seeds (frames) shared all but one of their samples. */
#define KDRAY_SAMPLE_KEY(view, x, y, r) \
    (((y) * (view)->width + (x)) * 0x9E3779B9u ^ kd_hash((r) ^ kd_hash((view)->seed)))
#define KDRAY_PIXEL_KEY(view, x, y) (((y) * (view)->width + (x)) * 0x9E3779B9u ^ (view)->seed)
/* A pixel's samples are low-discrepancy (#30): sample s's numbers in a pair of dimensions are the
 * R2 sequence's point s (Roberts 2018: the Kronecker sequence of the plastic number g, steps 1/g
 * and 1/g^2), rotated per pixel and pair by a hash (Cranley & Patterson 1976). Each number is
 * uniform for any rotation, so estimates stay unbiased, and a pixel's samples cover each pair's
 * square evenly instead of clumping as independent hashes do. The steps are 2^32 / g and
 * 2^32 / g^2 in 32-bit fixed point: the wrap-around of s * step is the fraction, exact at any s. */
#define KDRAY_R2_STEP0 3242174889u
#define KDRAY_R2_STEP1 2447445414u
#define KDRAY_UNIT_FLOAT(to_float, h) (to_float((h) >> 8) * (1.0f / 16777216.0f))

/* Unit vector, computed as Embree's peer does (multiply by 1 / length), so that centre rays
 * match it bit for bit. */
KDRAY_INLINE void kd_normalize3(kd_f32* a) {
    const kd_f32 inv = KDRAY_INV_LENGTH3(a[0], a[1], a[2]);
    kd_set3(a, a[0] * inv, a[1] * inv, a[2] * inv);
}

/* The ray through image position (px, py) in pixels, conventions.md's camera model, evaluated in
 * the same order as ../shared/peers/embree: d = normalize(f + (r * sx + u * sy)). */
KDRAY_HOT_INLINE void kd_camera_ray(const KdView* view, kd_f32 px, kd_f32 py, KdRay* ray) {
    const kd_f32 sx = KDRAY_SCREEN_X(view, px);
    const kd_f32 sy = KDRAY_SCREEN_Y(view, py);
    for (int a = 0; a < 3; ++a) {
        ray->org[a] = view->origin[a];
        ray->dir[a] = KDRAY_CAMERA_DIR(view, a, sx, sy);
    }
    kd_normalize3(ray->dir);
    ray->tmin = 0.0f;
    ray->tmax = KDRAY_INF;
}

/* x^y for x > 0, as 2^(y log2 x) on both sides: OpenCL's pow in PoCL (an extended-precision
 * exp and log) took 17% of a BART Kitchen frame's CPU time (perf, primary rays with a headlight),
 * exp2 and log2 a fraction of it; the highlight needs no more than float accuracy. */
KDRAY_HOT_INLINE kd_f32 kd_pow_positive(kd_f32 x, kd_f32 y) {
    return KDRAY_EXP2(y * KDRAY_LOG2(x));
}

/* sin and cos of the angle 2 pi u (a fraction of a turn, u in [0, 1)) on both sides, within
 * about an ulp: the turn's nearest quarter k is exact (4 u - k in [-1/2, 1/2]), and the rest, at
 * most pi / 4, takes the Taylor series to the term below float's precision. PoCL's sin and cos
 * each reduced their argument in a call of their own (__pocl_argReductionS: 5% of the path
 * kernel's time); this is a few multiplies, and host and kernel compute the same floats. */
KDRAY_HOT_INLINE void kd_sincos_turn(kd_f32 u, kd_f32* sin_out, kd_f32* cos_out) {
    const kd_f32 x = 4.0f * u, k = KDRAY_FLOOR(x + 0.5f);
    const kd_f32 a = (x - k) * (0.5f * KDRAY_PI), a2 = a * a;
    const kd_f32 s =
        a + a * a2 *
                (-1.0f / 6.0f +
                 a2 * (1.0f / 120.0f + a2 * (-1.0f / 5040.0f + a2 * (1.0f / 362880.0f))));
    const kd_f32 c =
        1.0f + a2 * (-0.5f + a2 * (1.0f / 24.0f +
                                   a2 * (-1.0f / 720.0f +
                                         a2 * (1.0f / 40320.0f + a2 * (-1.0f / 3628800.0f)))));
    const kd_i32 quarter = (kd_i32)k & 3;
    *sin_out = quarter == 0 ? s : (quarter == 1 ? c : (quarter == 2 ? -s : -c));
    *cos_out = quarter == 0 ? c : (quarter == 1 ? -s : (quarter == 2 ? -c : s));
}

/* A 32-bit integer hash (Wellons' lowbias32): decorrelated jitter without per-pixel state. The
 * steps are a macro so that a kernel can hash a vector of 32-bit lanes with the same code. */
#define KDRAY_LOWBIAS32(x) \
    ((x) ^= (x) >> 16, (x) *= 0x7feb352du, (x) ^= (x) >> 15, (x) *= 0x846ca68bu, (x) ^= (x) >> 16)
KDRAY_INLINE kd_u32 kd_hash(kd_u32 x) {
    KDRAY_LOWBIAS32(x);
    return x;
}
KDRAY_INLINE kd_f32 kd_unit_float(kd_u32 h) {
    return KDRAY_UNIT_FLOAT((kd_f32), h);
}

/* The random numbers of one sample beyond its camera jitter: its pixel's key (the sample's own
 * with independent samples), its index, the pixel's sample count, the dimensions drawn so far, and
 * whether the samples are independent. Dimension i of sample s is coordinate i & 1 of a point of
 * the pixel's R2 sequence, rotated by a hash of the key and of the pair i / 2: a function of
 * (pixel, s, i) alone, so that the host and a kernel draw the same numbers whatever order they
 * shade pixels in, and a pixel's samples are stratified in each pair of dimensions. Every pair
 * takes its points in an order of its own, a permutation of the pixel's sample indices (kd_permute,
 * Kollig & Keller's padding): the R2 sequence with its one pair of steps, in the same order in
 * every pair, makes each pair a shifted copy of the others (and of the camera jitter), so that an
 * emitter's choice and the point on it, say, would move in lockstep over a pixel's samples and
 * lose their stratification. The path integrator draws its vertices' numbers from it (kd_path.h),
 * Whitted's integrator its area-light samples (kd_area_light.h). */
typedef struct KdSampleRandom {
    kd_u32 key;
    kd_u32 sample;
    kd_u32 count;
    kd_u32 dimension;
    kd_u32 independent;
    /* The last pair drawn from, plus 1 (0: none yet), its rotation and its permuted index: both
     * coordinates of a pair share them, and the hashes and kd_permute were a sixth of a path
     * kernel's time when each number computed them anew. */
    kd_u32 cached_pair;
    kd_u32 pair_rotation;
    kd_u32 pair_index;
} KdSampleRandom;

/* A permutation of [0, n), chosen by `seed`, applied to i < n: Kensler's hash-based permutation
 * ("Correlated Multi-Jittered Sampling", Pixar 2013), cycle-walking inside the next power of two
 * (fewer than two rounds on average). */
KDRAY_INLINE kd_u32 kd_permute(kd_u32 i, kd_u32 n, kd_u32 seed) {
    kd_u32 w = n - 1u;
    w |= w >> 1;
    w |= w >> 2;
    w |= w >> 4;
    w |= w >> 8;
    w |= w >> 16;
    do {
        i ^= seed;
        i *= 0xe170893du;
        i ^= seed >> 16;
        i ^= (i & w) >> 4;
        i ^= seed >> 8;
        i *= 0x0929eb3fu;
        i ^= seed >> 23;
        i ^= (i & w) >> 1;
        i *= 1u | seed >> 27;
        i *= 0x6935fa69u;
        i ^= (i & w) >> 11;
        i *= 0x74dcb303u;
        i ^= (i & w) >> 2;
        i *= 0x9e501cc3u;
        i ^= (i & w) >> 2;
        i *= 0xc860a3dfu;
        i &= w;
        i ^= i >> 5;
    } while (i >= n);
    return (i + seed) % n;
}

KDRAY_HOT_INLINE kd_f32 kd_sample_uniform(KdSampleRandom* r) {
    const kd_u32 d = r->dimension++;
    if (r->independent) return kd_unit_float(kd_hash(r->key ^ kd_hash((d + 1u) * 0x9E3779B9u)));
    if (r->cached_pair != (d >> 1) + 1u) {
        const kd_u32 pair = kd_hash(r->key ^ kd_hash((d >> 1) * 0x9E3779B9u + 0x632BE5ABu));
        r->cached_pair = (d >> 1) + 1u;
        r->pair_rotation = pair;
        /* Both coordinates of a pair take the same point, so that the pair stays an R2 point. */
        r->pair_index = r->count > 1u ? kd_permute(r->sample, r->count, pair) : r->sample;
    }
    const kd_u32 rotation = (d & 1u) ? kd_hash(r->pair_rotation) : r->pair_rotation;
    return kd_unit_float(rotation + r->pair_index * ((d & 1u) ? KDRAY_R2_STEP1 : KDRAY_R2_STEP0));
}

/* A number u in [0, 1) that chose an interval [start, start + share) of [0, 1), stretched over
 * that interval back to [0, 1) (pbrt's reuse of a sample): uniform again, and independent of the
 * choice, so that one coordinate of a pair both chooses and places. */
KDRAY_INLINE kd_f32 kd_stretch_chosen(kd_f32 u, kd_f32 start, kd_f32 share) {
    return share > 0.0f ? KDRAY_FMIN((u - start) / share, 0.99999994f) : 0.0f;
}

/* The random numbers of sample s of pixel (x, y) for the integrator `salt` names: a key of their
 * own beside the jitter's. (Set through a pointer: a struct returned by value is an sret
 * argument, which LLVM marks noalias and then, inlined, declares with
 * llvm.experimental.noalias.scope.decl, an intrinsic that Oclgrind 21.10 cannot run.) */
KDRAY_INLINE void kd_sample_random(const KdView* view, kd_u32 x, kd_u32 y, kd_u32 s, kd_u32 salt,
                                   KdSampleRandom* r) {
    r->independent = view->sampler == KDRAY_SAMPLER_INDEPENDENT;
    r->key = kd_hash(
        (r->independent ? KDRAY_SAMPLE_KEY(view, x, y, s) : KDRAY_PIXEL_KEY(view, x, y)) ^ salt);
    r->sample = s;
    r->count = view->spp;
    r->dimension = 0u;
    r->cached_pair = r->pair_rotation = r->pair_index = 0u;
}

/* Geometric unit normal of a triangle, facing against `dir`. */
KDRAY_HOT_INLINE void kd_facing_normal(KDRAY_GLOBAL const kd_f32* tri, const kd_f32* dir,
                                       kd_f32* n) {
    const kd_f32 e1[3] = {tri[3] - tri[0], tri[4] - tri[1], tri[5] - tri[2]};
    const kd_f32 e2[3] = {tri[6] - tri[0], tri[7] - tri[1], tri[8] - tri[2]};
    kd_set3(n, e1[1] * e2[2] - e1[2] * e2[1], e1[2] * e2[0] - e1[0] * e2[2],
            e1[0] * e2[1] - e1[1] * e2[0]);
    kd_normalize3(n);
    if (kd_dot3(n, dir) > 0.0f) kd_set3(n, -n[0], -n[1], -n[2]);
}

/* The shading normal at a hit whose geometric normal, facing the ray, is ng: the corners' normals
 * interpolated at the hit's barycentrics, made unit length and turned to ng's side (a mesh's
 * normals need not agree with its winding, and either side of a triangle may be seen); ng itself
 * in a scene without vertex normals, or where the corners' normals cancel. */
KDRAY_HOT_INLINE void kd_shading_normal(const KdSceneView* scene, KdHit hit, const kd_f32* ng,
                                        kd_f32* ns) {
    kd_set3(ns, ng[0], ng[1], ng[2]);
    if (!scene->vertex_normals) return;
    KDRAY_GLOBAL const kd_f32* vn =
        scene->vertex_normals + (size_t)hit.prim * KDRAY_FLOATS_PER_TRIANGLE;
    const kd_f32 w = 1.0f - hit.u - hit.v;
    kd_f32 n[3];
    for (int a = 0; a < 3; ++a) n[a] = w * vn[a] + hit.u * vn[3 + a] + hit.v * vn[6 + a];
    const kd_f32 length2 = kd_dot3(n, n);
    if (!(length2 > 0.0f)) return;
    const kd_f32 scale = (kd_dot3(n, ng) < 0.0f ? -1.0f : 1.0f) / KDRAY_SQRT(length2);
    kd_set3(ns, n[0] * scale, n[1] * scale, n[2] * scale);
}

/* Unpolarised Fresnel reflectance of a dielectric for cos_i = cos(incidence) > 0 and
 * eta = n_incident / n_transmitted; 1 on total internal reflection. *cos_t returns the
 * transmitted angle's cosine. */
KDRAY_INLINE kd_f32 kd_fresnel(kd_f32 cos_i, kd_f32 eta, kd_f32* cos_t) {
    const kd_f32 sin2_t = eta * eta * (1.0f - cos_i * cos_i);
    if (sin2_t >= 1.0f) {
        *cos_t = 0.0f;
        return 1.0f;
    }
    *cos_t = KDRAY_SQRT(1.0f - sin2_t);
    const kd_f32 r_s = (eta * cos_i - *cos_t) / (eta * cos_i + *cos_t);
    const kd_f32 r_p = (cos_i - eta * *cos_t) / (cos_i + eta * *cos_t);
    return 0.5f * (r_s * r_s + r_p * r_p);
}

/* The mirror direction of dir about the unit normal n, cos_i = -dir . n. */
KDRAY_INLINE void kd_reflect(const kd_f32* dir, const kd_f32* n, kd_f32 cos_i, kd_f32* out) {
    for (int a = 0; a < 3; ++a) out[a] = dir[a] + 2.0f * cos_i * n[a];
}

/* The refracted direction of dir through the unit normal n, not yet unit length, for eta and
 * the cosines cos_i and cos_t of kd_fresnel. */
KDRAY_INLINE void kd_refract(const kd_f32* dir, const kd_f32* n, kd_f32 eta, kd_f32 cos_i,
                             kd_f32 cos_t, kd_f32* out) {
    for (int a = 0; a < 3; ++a) out[a] = eta * dir[a] + (eta * cos_i - cos_t) * n[a];
}

/* Whether the shading normal ns may bend a hit's secondary rays (dir: the incoming ray; ng: the
 * geometric normal, facing it; eta: n_incident / n_transmitted at a dielectric, 0 where nothing
 * refracts): not when a ray it bends would leave on the wrong side of the surface, the mirror
 * ray into it or the refracted ray back out, as a normal interpolated across a coarse mesh does
 * near its silhouette; the geometric normal bends every ray the right way. */
KDRAY_HOT_INLINE int kd_shading_normal_bends(const kd_f32* dir, const kd_f32* ng, const kd_f32* ns,
                                             kd_f32 eta) {
    const kd_f32 cos_i = -kd_dot3(dir, ns);
    if (!(cos_i > 0.0f)) return 0;
    kd_f32 bent[3], cos_t;
    kd_reflect(dir, ns, cos_i, bent);
    if (!(kd_dot3(bent, ng) > 0.0f)) return 0;
    if (eta > 0.0f && kd_fresnel(cos_i, eta, &cos_t) < 1.0f) {
        kd_refract(dir, ns, eta, cos_i, cos_t, bent);
        if (!(kd_dot3(bent, ng) < 0.0f)) return 0;
    }
    return 1;
}

/* The cosine by which a light in direction to_light shines on a surface (geometric normal ng,
 * shading normal ns): by ns, and 0 unless the light is in front of both. A light behind the
 * triangle's own plane lights nothing, even where the interpolated normal faces it: its shadow
 * ray would only cross the triangle again (or slip past the mesh near an edge). */
KDRAY_HOT_INLINE kd_f32 kd_light_cosine(const kd_f32* ng, const kd_f32* ns,
                                        const kd_f32* to_light) {
    const kd_f32 cos_l = kd_dot3(ns, to_light);
    return kd_dot3(ng, to_light) > 0.0f && cos_l > 0.0f ? cos_l : 0.0f;
}

/* A ray waiting to be traced, with the share of the pixel it carries. */
typedef struct KdPendingRay {
    KdRay ray;
    kd_f32 weight[3];
    kd_u32 depth; /* 1 for primary rays */
    kd_u32 kind;  /* 0 primary, 1 reflection, 2 refraction */
} KdPendingRay;

KDRAY_INLINE void kd_pending(const kd_f32* org, const kd_f32* dir, const kd_f32* weight,
                             kd_u32 depth, kd_u32 kind, KdPendingRay* r) {
    for (int a = 0; a < 3; ++a) {
        r->ray.org[a] = org[a];
        r->ray.dir[a] = dir[a];
        r->weight[a] = weight[a];
    }
    r->ray.tmin = 0.0f;
    r->ray.tmax = KDRAY_INF;
    r->depth = depth;
    r->kind = kind;
}

/* The lights that shine on a frame's surfaces: the render file's, which shine only with shadows
 * on; without, the headlight. Shadows are on exactly when the render file has lights
 * (decide_effects), so a kernel without them knows at compile time that its one light is the
 * headlight: a loop of one trip, unrolled (PoCL, BART Kitchen headlight frame: trace 43 -> 37
 * ms). Returns the render file's light count, 0 for the headlight. */
KDRAY_HOT_INLINE kd_u32 kd_shining_lights(const KdView* view) {
    return KDRAY_EFFECT_ON(view, KDRAY_EFFECT_SHADOWS) ? view->light_count : 0u;
}

/* Light i of the render file's light_count at p (light_count 0: the headlight): the unit
 * direction toward it, the irradiance it brings and its distance (infinite for the headlight and
 * directional lights). */
KDRAY_HOT_INLINE void kd_light_at(const KdSceneView* scene, const KdView* view, kd_u32 light_count,
                                  kd_u32 i, const kd_f32* p, kd_f32* to_light, kd_f32* irradiance,
                                  kd_f32* distance) {
    *distance = KDRAY_INF;
    if (light_count == 0u) {
        /* No lights in the render file: a headlight, which casts no visible shadow. */
        kd_set3(to_light, -view->forward[0], -view->forward[1], -view->forward[2]);
        kd_set3(irradiance, 1.0f, 1.0f, 1.0f);
        return;
    }
    KDRAY_GLOBAL const KdLight* light = scene->lights + i;
    if (light->type == KDRAY_LIGHT_POINT) {
        kd_set3(to_light, light->vec[0] - p[0], light->vec[1] - p[1], light->vec[2] - p[2]);
        const kd_f32 d2 = kd_dot3(to_light, to_light);
        *distance = KDRAY_SQRT(d2);
        kd_set3(to_light, to_light[0] / *distance, to_light[1] / *distance,
                to_light[2] / *distance);
        kd_set3(irradiance, light->power[0] / d2, light->power[1] / d2, light->power[2] / d2);
    } else {
        kd_set3(to_light, -light->vec[0], -light->vec[1], -light->vec[2]);
        kd_set3(irradiance, light->power[0], light->power[1], light->power[2]);
    }
}

/* The point at t along `ray`. */
KDRAY_HOT_INLINE void kd_hit_point(const KdRay* ray, kd_f32 t, kd_f32* p) {
    for (int a = 0; a < 3; ++a) p[a] = ray->org[a] + t * ray->dir[a];
}

/* The shadow ray from p (normal n) toward a light `distance` away along to_light. */
KDRAY_HOT_INLINE void kd_shadow_ray(const KdView* view, const kd_f32* p, const kd_f32* n,
                                    const kd_f32* to_light, kd_f32 distance, KdRay* shadow) {
    for (int a = 0; a < 3; ++a) {
        shadow->org[a] = p[a] + n[a] * view->ray_epsilon;
        shadow->dir[a] = to_light[a];
    }
    shadow->tmin = 0.0f;
    shadow->tmax = distance - view->ray_epsilon;
}

/* What m reflects toward the eye (direction `dir` of the ray that arrived) of the irradiance a
 * light brings from direction to_light at cosine cos_l with the shading normal ns: Lambert
 * diffuse (of colour `diffuse`, Kd textured) and the Blinn-Phong highlight, added to out. */
KDRAY_HOT_INLINE void kd_reflected(KDRAY_GLOBAL const KdMaterial* m, const kd_f32* diffuse,
                                   const kd_f32* ns, const kd_f32* dir, const kd_f32* to_light,
                                   const kd_f32* irradiance, kd_f32 cos_l, kd_f32* out) {
    kd_f32 highlight = 0.0f;
    if (m->flags & KDRAY_MATERIAL_HIGHLIGHT) {
        kd_f32 h[3] = {to_light[0] - dir[0], to_light[1] - dir[1], to_light[2] - dir[2]};
        kd_normalize3(h);
        const kd_f32 cos_h = kd_dot3(ns, h);
        /* Normalised Blinn-Phong: (Ns + 8) / (8 pi) keeps the highlight's energy fixed. */
        if (cos_h > 0.0f)
            highlight =
                (m->shininess + 8.0f) / (8.0f * KDRAY_PI) * kd_pow_positive(cos_h, m->shininess);
    }
    for (int c = 0; c < 3; ++c)
        out[c] += (diffuse[c] / KDRAY_PI + m->specular[c] * highlight) * irradiance[c] * cos_l;
}

#endif /* KDRAY_KD_SHADING_H */
