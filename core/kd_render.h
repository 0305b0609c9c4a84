/* kd_render.h — camera rays and shading, written once in the C subset that compiles as C++ (the
 * reference renderer) and as OpenCL C (the render kernel), as pbrt-v4 shares its integrators
 * between CPU and GPU. The reference image is therefore the oracle for the OpenCL image: the same
 * samples, the same rays, the same arithmetic.
 *
 * Shading is Whitted-style: emission, ambient light by Ka, Lambert diffuse and a Blinn-Phong
 * highlight under point and directional lights and emissive triangles (kd_area_light.h) with
 * shadow rays, ideal mirror reflection, and
 * dielectric reflection and refraction weighted by the Fresnel equations, up to the render file's
 * max_depth; smooth where the scene has vertex normals (kd_shading_normal). Which of shadows,
 * reflection, refraction, ambient light and area lights exist at all is decided per frame from its
 * materials and lights: in a kernel by -DKDRAY_COMPILED_EFFECTS (code a scene does not call for is
 * not even compiled), on the host by KdView.effects.
 */
#ifndef KDRAY_KD_RENDER_H
#define KDRAY_KD_RENDER_H

#include "core/kd_shared.h"
#include "core/kd_traverse.h"

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
 *   KDRAY_SAMPLE_KEY    what kd_hash turns into the jitter of sample r of pixel (x, y)
 *   KDRAY_UNIT_FLOAT    a hash's top 24 bits as a float in [0, 1), through `to_float` */
#define KDRAY_INV_LENGTH3(x, y, z) (1.0f / KDRAY_SQRT((x) * (x) + (y) * (y) + (z) * (z)))
#define KDRAY_SCREEN_X(view, px) \
    ((2.0f * (px) / (kd_f32)(view)->width - 1.0f) * (view)->tan_half_fov * (view)->aspect)
#define KDRAY_SCREEN_Y(view, py) \
    ((1.0f - 2.0f * (py) / (kd_f32)(view)->height) * (view)->tan_half_fov)
#define KDRAY_CAMERA_DIR(view, a, sx, sy) \
    ((view)->forward[a] + ((view)->right[a] * (sx) + (view)->up[a] * (sy)))
#define KDRAY_SAMPLE_KEY(view, x, y, r) \
    (((y) * (view)->width + (x)) * 0x9E3779B9u ^ kd_hash((r) + (view)->seed))
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

#include "core/kd_area_light.h"
#include "core/kd_texture.h"

/* Direct light at p (geometric normal ng, facing the viewer; shading normal ns) for the eye
 * direction `dir`: the ambient light it reflects (with KDRAY_EFFECT_AMBIENT), and diffuse and
 * highlight by ns under every light, each behind a shadow ray that leaves from ng's side, and one
 * sample of the emitters' light (with KDRAY_EFFECT_AREA_LIGHTS); with shadows off and no
 * emitters, under the headlight.
 * occluded, when not 0, says which of the shadow rays from p are blocked (bit i for light i, as
 * kd_trace_shadow_packets traced them); else each shadow ray is traced here. */
KDRAY_HOT_INLINE void kd_direct_light(const KdSceneView* scene, const KdView* view,
                                      KDRAY_GLOBAL const KdMaterial* m, KdHit hit, const kd_f32* p,
                                      const kd_f32* ng, const kd_f32* ns, const kd_f32* dir,
                                      KDRAY_GLOBAL const kd_u32* occluded, kd_f32* out,
                                      KdRayCounts* rays) {
    kd_f32 diffuse[3], ambient[3];
    kd_surface_colours(scene, view, m, hit, diffuse, ambient);
    /* Ambient light, reflected by Ka (the material's ambient holds Ka x the render file's). */
    if (KDRAY_EFFECT_ON(view, KDRAY_EFFECT_AMBIENT))
        for (int c = 0; c < 3; ++c) out[c] += ambient[c];
    const kd_u32 light_count = kd_shining_lights(view);
    /* The headlight only when there are neither lights nor emitters (conventions.md). */
    const kd_u32 lights = light_count != 0u
                              ? light_count
                              : (KDRAY_EFFECT_ON(view, KDRAY_EFFECT_AREA_LIGHTS) ? 0u : 1u);
    for (kd_u32 i = 0; i < lights; ++i) {
        kd_f32 to_light[3], irradiance[3], distance;
        kd_light_at(scene, view, light_count, i, p, to_light, irradiance, &distance);
        const kd_f32 cos_l = kd_light_cosine(ng, ns, to_light);
        if (cos_l <= 0.0f) continue;
        if (light_count != 0u) {
            rays->shadow += 1u;
            if (occluded) {
                if ((*occluded >> i) & 1u) continue;
            } else {
                KdRay shadow;
                kd_shadow_ray(view, p, ng, to_light, distance, &shadow);
                if (kd_scene_occluded(scene, &shadow)) continue;
            }
        }
        kd_reflected(m, diffuse, ns, dir, to_light, irradiance, cos_l, out);
    }
    if (KDRAY_EFFECT_ON(view, KDRAY_EFFECT_AREA_LIGHTS))
        kd_area_light(scene, view, m, diffuse, p, ng, ns, dir, out, rays);
}

/* One sample when neither reflection nor refraction is on: the primary ray and its direct light,
 * with no pending-ray stack (a private array of KDRAY_MAX_BOUNCES + 1 rays per work-item that a
 * CPU device keeps in memory and a GPU in scratch). Its arithmetic is kd_trace_sample's for a
 * tree of one ray (weight 1, nothing pushed), so the two give identical colours. */
KDRAY_HOT_INLINE void kd_trace_direct_sample(const KdSceneView* scene, const KdView* view,
                                             const KdRay* primary, const KdHit* traced,
                                             KDRAY_GLOBAL const kd_u32* occluded, kd_f32* rgb,
                                             KdRayCounts* rays, KdHit* first_hit,
                                             kd_f32* first_normal) {
    rays->primary += 1u;
    KdHit hit;
    if (traced)
        hit = *traced;
    else
        kd_scene_closest(scene, primary, &hit);
    kd_f32 ng[3] = {0.0f, 0.0f, 0.0f};
    if (hit.prim != KDRAY_NO_HIT)
        kd_facing_normal(scene->triangles + (size_t)hit.prim * KDRAY_FLOATS_PER_TRIANGLE,
                         primary->dir, ng);
    if (first_hit) {
        *first_hit = hit;
        kd_set3(first_normal, ng[0], ng[1], ng[2]);
    }
    if (hit.prim == KDRAY_NO_HIT) {
        for (int c = 0; c < 3; ++c) rgb[c] = 0.0f + view->background[c];
        return;
    }
    KDRAY_GLOBAL const KdMaterial* m = scene->materials + scene->material_ids[hit.prim];
    kd_f32 p[3], ns[3], direct[3] = {0.0f, 0.0f, 0.0f};
    kd_hit_point(primary, hit.t, p);
    kd_shading_normal(scene, hit, ng, ns);
    const kd_f32 surface = 1.0f - m->transmit_fraction;
    if (surface > 0.0f)
        kd_direct_light(scene, view, m, hit, p, ng, ns, primary->dir, occluded, direct, rays);
    kd_f32 emitted[3] = {0.0f, 0.0f, 0.0f};
    if (KDRAY_EFFECT_ON(view, KDRAY_EFFECT_AREA_LIGHTS))
        kd_emitted(scene->triangles + (size_t)hit.prim * KDRAY_FLOATS_PER_TRIANGLE, m, primary->dir,
                   emitted);
    for (int c = 0; c < 3; ++c)
        rgb[c] = KDRAY_FMIN(0.0f + (emitted[c] + surface * direct[c]), KDRAY_RADIANCE_MAX);
}

/* Traces one sample's ray tree from the primary ray and returns its colour. The primary ray's
 * hit is `traced` when it was traced already (by the packet kernel), else it is traced here;
 * likewise the shadow rays from that hit (`occluded`, as kd_direct_light reads it). The pending
 * stack holds at most one ray per level: each traced ray pushes at most two, one of which is
 * traced next. */
KDRAY_HOT_INLINE void kd_trace_sample(const KdSceneView* scene, const KdView* view,
                                      const KdRay* primary, const KdHit* traced,
                                      KDRAY_GLOBAL const kd_u32* occluded, kd_f32* rgb,
                                      KdRayCounts* rays, KdHit* first_hit, kd_f32* first_normal) {
    if (!KDRAY_EFFECT_ON(view, KDRAY_EFFECT_REFLECTION | KDRAY_EFFECT_REFRACTION)) {
        kd_trace_direct_sample(scene, view, primary, traced, occluded, rgb, rays, first_hit,
                               first_normal);
        return;
    }
    KdPendingRay stack[KDRAY_MAX_BOUNCES + 1];
    const kd_f32 one[3] = {1.0f, 1.0f, 1.0f};
    kd_pending(primary->org, primary->dir, one, 1u, 0u, &stack[0]);
    int pending = 1;
    kd_set3(rgb, 0.0f, 0.0f, 0.0f);
    while (pending > 0) {
        const KdPendingRay r = stack[--pending];
        if (r.kind == 0u)
            rays->primary += 1u;
        else if (r.kind == 1u)
            rays->reflection += 1u;
        else
            rays->refraction += 1u;
        KdHit hit;
        if (r.kind == 0u && traced)
            hit = *traced;
        else
            kd_scene_closest(scene, &r.ray, &hit);
        kd_f32 ng[3] = {0.0f, 0.0f, 0.0f};
        KDRAY_GLOBAL const kd_f32* tri = scene->triangles;
        if (hit.prim != KDRAY_NO_HIT) {
            tri += (size_t)hit.prim * KDRAY_FLOATS_PER_TRIANGLE;
            kd_facing_normal(tri, r.ray.dir, ng);
        }
        if (r.kind == 0u && first_hit) {
            *first_hit = hit;
            kd_set3(first_normal, ng[0], ng[1], ng[2]);
        }
        if (hit.prim == KDRAY_NO_HIT) {
            for (int c = 0; c < 3; ++c)
                rgb[c] = KDRAY_FMIN(rgb[c] + r.weight[c] * view->background[c], KDRAY_RADIANCE_MAX);
            continue;
        }

        /* Emission and direct light on the part of the surface that is not dielectric. */
        KDRAY_GLOBAL const KdMaterial* m = scene->materials + scene->material_ids[hit.prim];
        kd_f32 p[3], ns[3], direct[3] = {0.0f, 0.0f, 0.0f};
        kd_hit_point(&r.ray, hit.t, p);
        kd_shading_normal(scene, hit, ng, ns);
        const kd_f32 surface = 1.0f - m->transmit_fraction;
        if (surface > 0.0f)
            kd_direct_light(scene, view, m, hit, p, ng, ns, r.ray.dir, r.kind == 0u ? occluded : 0,
                            direct, rays);
        kd_f32 emitted[3] = {0.0f, 0.0f, 0.0f};
        if (KDRAY_EFFECT_ON(view, KDRAY_EFFECT_AREA_LIGHTS)) kd_emitted(tri, m, r.ray.dir, emitted);
        for (int c = 0; c < 3; ++c)
            rgb[c] = KDRAY_FMIN(rgb[c] + r.weight[c] * (emitted[c] + surface * direct[c]),
                                KDRAY_RADIANCE_MAX);
        if (r.depth >= view->max_depth) continue;

        /* Secondary rays: the mirror, and the dielectric's Fresnel-weighted pair. */
        const int dielectric = KDRAY_EFFECT_ON(view, KDRAY_EFFECT_REFRACTION) &&
                               (m->flags & KDRAY_MATERIAL_DIELECTRIC) &&
                               m->transmit_fraction > 0.0f;
        kd_f32 eta = 0.0f;
        if (dielectric) {
            /* The geometric normal faces the ray, so the ray enters when it opposes the
             * triangle's own winding normal; kdray's OBJ meshes give no inside/outside, so
             * entering is judged from the winding: counter-clockwise faces outwards. */
            const kd_f32 e1[3] = {tri[3] - tri[0], tri[4] - tri[1], tri[5] - tri[2]};
            const kd_f32 e2[3] = {tri[6] - tri[0], tri[7] - tri[1], tri[8] - tri[2]};
            const kd_f32 wn[3] = {e1[1] * e2[2] - e1[2] * e2[1], e1[2] * e2[0] - e1[0] * e2[2],
                                  e1[0] * e2[1] - e1[1] * e2[0]};
            eta = kd_dot3(wn, r.ray.dir) < 0.0f ? 1.0f / m->ior : m->ior;
        }
        const kd_f32* n =
            scene->vertex_normals && kd_shading_normal_bends(r.ray.dir, ng, ns, eta) ? ns : ng;
        const kd_f32 cos_i = -kd_dot3(r.ray.dir, n);
        kd_f32 reflect_dir[3], reflect_w[3] = {0.0f, 0.0f, 0.0f};
        kd_reflect(r.ray.dir, n, cos_i, reflect_dir);
        if (KDRAY_EFFECT_ON(view, KDRAY_EFFECT_REFLECTION) && (m->flags & KDRAY_MATERIAL_MIRROR))
            for (int c = 0; c < 3; ++c) reflect_w[c] = r.weight[c] * surface * m->specular[c];
        if (dielectric) {
            kd_f32 cos_t;
            const kd_f32 fresnel = kd_fresnel(cos_i, eta, &cos_t);
            kd_f32 refract_w[3];
            for (int c = 0; c < 3; ++c) {
                const kd_f32 share = r.weight[c] * m->transmit_fraction * m->filter[c];
                reflect_w[c] += share * fresnel;
                refract_w[c] = share * (1.0f - fresnel);
            }
            if (fresnel < 1.0f && KDRAY_FMAX(refract_w[0], KDRAY_FMAX(refract_w[1], refract_w[2])) >
                                      KDRAY_MIN_PATH_WEIGHT) {
                kd_f32 org[3], dir[3];
                kd_refract(r.ray.dir, n, eta, cos_i, cos_t, dir);
                for (int a = 0; a < 3; ++a) org[a] = p[a] - ng[a] * view->ray_epsilon;
                kd_normalize3(dir);
                kd_pending(org, dir, refract_w, r.depth + 1u, 2u, &stack[pending++]);
            }
        }
        if (KDRAY_FMAX(reflect_w[0], KDRAY_FMAX(reflect_w[1], reflect_w[2])) >
            KDRAY_MIN_PATH_WEIGHT) {
            kd_f32 org[3];
            for (int a = 0; a < 3; ++a) org[a] = p[a] + ng[a] * view->ray_epsilon;
            kd_pending(org, reflect_dir, reflect_w, r.depth + 1u, 1u, &stack[pending++]);
        }
    }
}

/* The primary rays of a pixel: spp samples, jittered inside the pixel when spp > 1 and else the
 * ray through its centre, and with spp > 1 one more, the centre ray, for the AOV (conventions.md:
 * AOVs always come from the centre ray). */
KDRAY_INLINE kd_u32 kd_primary_rays_per_pixel(const KdView* view) {
    return view->spp > 1u ? view->spp + 1u : 1u;
}

/* Primary ray `r` (< kd_primary_rays_per_pixel) of pixel (x, y): sample r, or the centre ray for
 * r == spp. */
KDRAY_HOT_INLINE void kd_primary_ray(const KdView* view, kd_u32 x, kd_u32 y, kd_u32 r, KdRay* ray) {
    if (view->spp <= 1u || r == view->spp) {
        kd_camera_ray(view, (kd_f32)x + 0.5f, (kd_f32)y + 0.5f, ray);
        return;
    }
    const kd_u32 h = kd_hash(KDRAY_SAMPLE_KEY(view, x, y, r));
    kd_camera_ray(view, (kd_f32)x + kd_unit_float(h), (kd_f32)y + kd_unit_float(kd_hash(h)), ray);
}

/* The `cost` AOV of pixel (x, y): the nodes visited and triangles tested by the walk of its
 * centre ray (kd_trace with the scene's triangle test), the very walk that finds the AOV's hit.
 * A pass of its own, run only for frames that write the cost, so that the walks that shade
 * carry no counters (their kd_trace gets a literal 0 and the counting compiles away) and packet
 * walks need no counting of their own. */
KDRAY_INLINE void kd_pixel_cost(const KdSceneView* scene, const KdView* view, kd_u32 x, kd_u32 y,
                                KdTraceCost* cost) {
    KdRay centre;
    kd_primary_ray(view, x, y, view->spp, &centre);
    KdHit hit;
    cost->nodes = cost->triangles = 0u;
    kd_trace(scene->nodes, scene->leaf_indices, scene->triangles, scene->bounds, &centre, 0,
             scene->intersect, &hit, cost);
}

/* One pixel: spp samples, their mean colour, and the centre ray's hit for the AOV. `traced`,
 * when not 0, holds the hits of the pixel's primary rays, already traced: the hit of ray r at
 * traced[r * traced_stride]; `occluded`, when not 0, the blocked shadow rays from those hits
 * (kd_direct_light) at the same places. */
KDRAY_HOT_INLINE void kd_render_pixel(const KdSceneView* scene, const KdView* view, kd_u32 x,
                                      kd_u32 y, KDRAY_GLOBAL const KdHit* traced,
                                      KDRAY_GLOBAL const kd_u32* occluded, kd_u32 traced_stride,
                                      KdPixel* pixel) {
    KdPixel out;
    kd_set3(out.rgb, 0.0f, 0.0f, 0.0f);
    out.rays.primary = out.rays.shadow = out.rays.reflection = out.rays.refraction = 0u;
    out.rays.area_shadow = 0u;
    if (view->spp > 1u) {
        /* The AOV's centre ray: an extra primary ray. */
        KdRay centre;
        kd_primary_ray(view, x, y, view->spp, &centre);
        if (traced)
            out.centre_hit = traced[view->spp * traced_stride];
        else
            kd_scene_closest(scene, &centre, &out.centre_hit);
        out.rays.primary += 1u;
        kd_set3(out.normal, 0.0f, 0.0f, 0.0f);
        if (out.centre_hit.prim != KDRAY_NO_HIT) {
            kd_facing_normal(
                scene->triangles + (size_t)out.centre_hit.prim * KDRAY_FLOATS_PER_TRIANGLE,
                centre.dir, out.normal);
        }
    }
    for (kd_u32 s = 0; s < view->spp; ++s) {
        kd_f32 rgb[3];
        KdHit hit;
        if (traced) hit = traced[s * traced_stride];
        if (traced && hit.prim == KDRAY_NO_HIT) {
            /* A traced primary ray that missed is the background, as kd_trace_sample makes it,
             * without the ray: most of a framed mesh's pixels (the dragon's: 85%). */
            out.rays.primary += 1u;
            if (view->spp == 1u) {
                out.centre_hit = hit;
                kd_set3(out.normal, 0.0f, 0.0f, 0.0f);
            }
            for (int c = 0; c < 3; ++c)
                out.rgb[c] = KDRAY_FMIN(out.rgb[c] + view->background[c], KDRAY_RADIANCE_MAX);
            continue;
        }
        KdRay primary;
        kd_primary_ray(view, x, y, s, &primary);
        kd_trace_sample(scene, view, &primary, traced ? &hit : 0,
                        occluded ? occluded + s * traced_stride : 0, rgb, &out.rays,
                        view->spp == 1u ? &out.centre_hit : 0, out.normal);
        for (int c = 0; c < 3; ++c)
            out.rgb[c] = KDRAY_FMIN(out.rgb[c] + rgb[c], KDRAY_RADIANCE_MAX);
    }
    for (int c = 0; c < 3; ++c) out.rgb[c] /= (kd_f32)view->spp;
    *pixel = out;
}

#endif /* KDRAY_KD_RENDER_H */
