/* kd_path.h — the path integrator of the render file's "integrator": "path" (docs/path-tracing.md),
 * in the C subset of kd_render.h, which includes it: one source for the reference renderer and
 * the render kernel, which compiles it only with KDRAY_EFFECT_PATH in its effects.
 *
 * A unidirectional path tracer in the shape of pbrt-v4's PathIntegrator: at each vertex, next-event
 * estimation of the render file's point and directional lights (delta lights: light sampling
 * alone) and of one point on the emissive triangles (kd_area_light.h's choice by power), then one
 * direction sampled from the material's lobes. An emitter that a sampled direction hits adds its
 * radiance weighted by the power heuristic against the light sample that could have found it, so
 * each of the two strategies carries the light where its density is the larger (Veach 1997, 9.2).
 * Russian roulette ends paths after KDRAY_PATH_ROULETTE_DEPTH segments.
 *
 * The materials are Whitted's (kd_render.h), as lobes: a Lambertian Kd, the normalised
 * Blinn-Phong highlight Ks/Ns, the ideal mirror Ks, and the dielectric's Fresnel pair, on the
 * shares 1 - transmit_fraction and transmit_fraction of the surface. No private arrays: a path
 * is a loop over one ray.
 *
 * Random numbers: dimension i of sample s of pixel (x, y) is coordinate i & 1 of point s of the
 * pixel's R2 sequence (kd_shading.h), rotated by a hash of the pixel's key and of i / 2: a
 * function of (pixel, s, i) alone, so that the host and a kernel draw the same numbers along the
 * same path whatever order they trace pixels in, and a pixel's samples are stratified in each
 * pair of dimensions. Each vertex has pairs of its own (KDRAY_PATH_DIMENSIONS_PER_VERTEX), one for
 * its light sample's emitter and point, one for its lobe and direction, so that those 2D choices
 * are stratified as points: with three numbers each, an event's pair straddled two pairs, and the
 * light's point (u1, u2) took coordinates of two unrelated sequences.
 */
#ifndef KDRAY_KD_PATH_H
#define KDRAY_KD_PATH_H

#include "core/device/kd_area_light.h"
#include "core/device/kd_shading.h"
#include "core/device/kd_texture.h"

/* Segments a path has before Russian roulette may end it: the first bounces carry most of the
 * light and are never cut. */
#define KDRAY_PATH_ROULETTE_DEPTH 3u
/* A path survives roulette with probability min(its largest throughput channel, this): below 1,
 * so that a path of throughput 1 (a white mirror room) still ends. */
#define KDRAY_PATH_MAX_SURVIVAL 0.95f
/* The dimensions a path vertex draws: its light sample's pair, its lobes' pair, and the first
 * coordinate of a third pair for roulette. */
#define KDRAY_PATH_DIMENSIONS_PER_VERTEX 6u
/* The path integrator's numbers' own key (kd_sample_random). */
#define KDRAY_PATH_SALT 0x68E31DA4u

/* A unit-length basis (t, b, n) around the unit vector n, without a branch on which axis to
 * cross with (Duff et al., "Building an orthonormal basis, revisited", JCGT 2017). */
KDRAY_HOT_INLINE void kd_path_basis(const kd_f32* n, kd_f32* t, kd_f32* b) {
    const kd_f32 sign = n[2] >= 0.0f ? 1.0f : -1.0f;
    const kd_f32 a = -1.0f / (sign + n[2]);
    const kd_f32 c = n[0] * n[1] * a;
    kd_set3(t, 1.0f + sign * n[0] * n[0] * a, sign * c, -sign * n[0]);
    kd_set3(b, c, sign + n[1] * n[1] * a, -n[1]);
}

/* The direction (x, y, z) of the frame around n, in the scene. */
KDRAY_HOT_INLINE void kd_path_to_world(const kd_f32* n, kd_f32 x, kd_f32 y, kd_f32 z, kd_f32* out) {
    kd_f32 t[3], b[3];
    kd_path_basis(n, t, b);
    for (int a = 0; a < 3; ++a) out[a] = x * t[a] + y * b[a] + z * n[a];
    kd_normalize3(out);
}

KDRAY_INLINE kd_f32 kd_mean3(const kd_f32* v) {
    return (v[0] + v[1] + v[2]) * (1.0f / 3.0f);
}

/* A hit's material as weighted lobes: each lobe's colour (its share of the surface included) and
 * the probability of sampling it, in proportion to the colour's mean. */
typedef struct KdPathLobes {
    kd_f32 diffuse[3]; /* (1 - transmit_fraction) Kd, textured: the Lambertian albedo */
    kd_f32 gloss[3];   /* (1 - transmit_fraction) Ks of the Blinn-Phong highlight, else 0 */
    kd_f32 mirror[3];  /* (1 - transmit_fraction) Ks of the ideal mirror, else 0 */
    kd_f32 glass[3];   /* transmit_fraction Tf of the dielectric, else 0 */
    kd_f32 p_diffuse, p_gloss, p_mirror, p_glass;
    kd_f32 shininess;
} KdPathLobes;

KDRAY_HOT_INLINE void kd_path_lobes(const KdSceneView* scene, const KdView* view,
                                    KDRAY_GLOBAL const KdMaterial* m, KdHit hit, KdPathLobes* l) {
    kd_f32 ambient[3];
    kd_surface_colours(scene, view, m, hit, l->diffuse, ambient);
    const kd_f32 surface = 1.0f - m->transmit_fraction;
    const int gloss = (m->flags & KDRAY_MATERIAL_HIGHLIGHT) != 0u;
    /* Without the effect the lobe's light is lost, as a Whitted ray tree that stops there. */
    const int mirror =
        KDRAY_EFFECT_ON(view, KDRAY_EFFECT_REFLECTION) && (m->flags & KDRAY_MATERIAL_MIRROR) != 0u;
    const int glass = KDRAY_EFFECT_ON(view, KDRAY_EFFECT_REFRACTION) &&
                      (m->flags & KDRAY_MATERIAL_DIELECTRIC) != 0u && m->transmit_fraction > 0.0f;
    for (int c = 0; c < 3; ++c) {
        l->diffuse[c] *= surface;
        l->gloss[c] = gloss ? surface * m->specular[c] : 0.0f;
        l->mirror[c] = mirror ? surface * m->specular[c] : 0.0f;
        l->glass[c] = glass ? m->transmit_fraction * m->filter[c] : 0.0f;
    }
    l->shininess = m->shininess;
    const kd_f32 wd = kd_mean3(l->diffuse), wg = kd_mean3(l->gloss), wm = kd_mean3(l->mirror);
    const kd_f32 wt = kd_mean3(l->glass), total = wd + wg + wm + wt;
    const kd_f32 scale = total > 0.0f ? 1.0f / total : 0.0f;
    l->p_diffuse = wd * scale;
    l->p_gloss = wg * scale;
    l->p_mirror = wm * scale;
    l->p_glass = wt * scale;
}

/* The non-delta lobes (diffuse and highlight) for light arriving from wi at cosine cos_l > 0 with
 * the shading normal ns, seen along the ray direction `dir`: the BRDF times cos_l into f_cos,
 * and the density per solid angle with which kd_path_sample_lobes draws wi. */
KDRAY_HOT_INLINE kd_f32 kd_path_evaluate(const KdPathLobes* l, const kd_f32* ns, const kd_f32* dir,
                                         const kd_f32* wi, kd_f32 cos_l, kd_f32* f_cos) {
    kd_f32 highlight = 0.0f, pdf_gloss = 0.0f;
    if (l->p_gloss > 0.0f) {
        kd_f32 h[3] = {wi[0] - dir[0], wi[1] - dir[1], wi[2] - dir[2]};
        kd_normalize3(h);
        const kd_f32 cos_h = kd_dot3(ns, h), cos_wh = kd_dot3(wi, h);
        if (cos_h > 0.0f) {
            const kd_f32 lobe = kd_pow_positive(cos_h, l->shininess);
            /* kd_reflected's normalised Blinn-Phong, (Ns + 8) / (8 pi) cos_h^Ns. */
            highlight = (l->shininess + 8.0f) / (8.0f * KDRAY_PI) * lobe;
            /* Half vectors drawn with density (Ns + 1) / (2 pi) cos_h^Ns, mapped to wi by the
             * reflection's Jacobian 1 / (4 wi.h). */
            if (cos_wh > 0.0f)
                pdf_gloss = (l->shininess + 1.0f) / (2.0f * KDRAY_PI) * lobe / (4.0f * cos_wh);
        }
    }
    for (int c = 0; c < 3; ++c)
        f_cos[c] = (l->diffuse[c] / KDRAY_PI + l->gloss[c] * highlight) * cos_l;
    return l->p_diffuse * cos_l / KDRAY_PI + l->p_gloss * pdf_gloss;
}

/* The power heuristic (exponent 2) of a strategy of density a against one of density b. */
KDRAY_INLINE kd_f32 kd_power_heuristic(kd_f32 a, kd_f32 b) {
    return a * a / (a * a + b * b);
}

/* The probability with which kd_pick_emitter chooses triangle `prim`, 0 when it is not in the
 * table (the table lists emitters in order of triangle id). */
KDRAY_INLINE kd_f32 kd_emitter_probability(KDRAY_GLOBAL const KdEmitter* emitters, kd_u32 count,
                                           kd_u32 prim) {
    kd_u32 lo = 0u, hi = count;
    while (lo < hi) {
        const kd_u32 mid = (lo + hi) / 2u;
        if (emitters[mid].triangle < prim)
            lo = mid + 1u;
        else
            hi = mid;
    }
    return lo < count && emitters[lo].triangle == prim ? emitters[lo].probability : 0.0f;
}

/* The light of the render file's point and directional lights (or the headlight) at p, reflected
 * by the non-delta lobes toward `dir`, into out: delta lights, which only light sampling finds. */
KDRAY_HOT_INLINE void kd_path_delta_lights(const KdSceneView* scene, const KdView* view,
                                           const KdPathLobes* l, const kd_f32* p, const kd_f32* ng,
                                           const kd_f32* ns, const kd_f32* dir, kd_f32* out,
                                           KdRayCounts* rays) {
    const kd_u32 light_count = kd_shining_lights(view);
    /* The headlight only when there are neither lights nor emitters (conventions.md). */
    const kd_u32 lights = light_count != 0u
                              ? light_count
                              : (KDRAY_EFFECT_ON(view, KDRAY_EFFECT_AREA_LIGHTS) ? 0u : 1u);
    for (kd_u32 i = 0; i < lights; ++i) {
        kd_f32 to_light[3], irradiance[3], distance, f_cos[3];
        kd_light_at(scene, view, light_count, i, p, to_light, irradiance, &distance);
        const kd_f32 cos_l = kd_light_cosine(ng, ns, to_light);
        if (cos_l <= 0.0f) continue;
        if (light_count != 0u) {
            rays->shadow += 1u;
            KdRay shadow;
            kd_shadow_ray(view, p, ng, to_light, distance, &shadow);
            if (kd_scene_occluded(scene, &shadow)) continue;
        }
        kd_path_evaluate(l, ns, dir, to_light, cos_l, f_cos);
        for (int c = 0; c < 3; ++c) out[c] += f_cos[c] * irradiance[c];
    }
}

/* One light sample of the emitters at p, as kd_area_light draws it (an emitter by power and a
 * uniform point on it from one pair of dimensions, a shadow ray), weighted by the power heuristic
 * against the lobes' sampling of the same direction, into out. */
KDRAY_HOT_INLINE void kd_path_area_light(const KdSceneView* scene, const KdView* view,
                                         const KdPathLobes* l, const kd_f32* p, const kd_f32* ng,
                                         const kd_f32* ns, const kd_f32* dir,
                                         KdSampleRandom* random, kd_f32* out, KdRayCounts* rays) {
    kd_f32 u1, u2;
    KDRAY_GLOBAL const KdEmitter* e = kd_pick_emitter_pair(scene, view, random, &u1, &u2);
    KDRAY_GLOBAL const kd_f32* tri =
        scene->triangles + (size_t)e->triangle * KDRAY_FLOATS_PER_TRIANGLE;
    KdRay shadow;
    kd_f32 to_light[3], d2, distance, cos_light, twice_area;
    if (!kd_emitter_point(tri, p, ng, view->ray_epsilon, u1, u2, &shadow, to_light, &d2, &distance,
                          &cos_light, &twice_area))
        return;
    const kd_f32 cos_l = kd_light_cosine(ng, ns, to_light);
    if (cos_l <= 0.0f) return;
    kd_f32 f_cos[3];
    const kd_f32 pdf_lobes = kd_path_evaluate(l, ns, dir, to_light, cos_l, f_cos);
    /* The light sample's density per solid angle: (probability / area) d^2 / cos_light. */
    const kd_f32 pdf_light = e->probability / (0.5f * twice_area) * d2 / cos_light;
    if (!(pdf_light > 0.0f) || !KDRAY_ISFINITE(pdf_light)) return;
    rays->area_shadow += 1u;
    for (int a = 0; a < 3; ++a) shadow.dir[a] = to_light[a];
    shadow.tmin = 0.0f;
    shadow.tmax = distance - view->ray_epsilon;
    if (kd_scene_occluded(scene, &shadow)) return;
    KDRAY_GLOBAL const KdMaterial* light = scene->materials + scene->material_ids[e->triangle];
    const kd_f32 weight = kd_power_heuristic(pdf_light, pdf_lobes) / pdf_light;
    for (int c = 0; c < 3; ++c) out[c] += f_cos[c] * light->emission[c] * weight;
}

/* A direction drawn from the lobes at a hit (ng: geometric normal facing the ray, ns: shading
 * normal, p: the point, tri: its triangle), for the ray direction `dir`: the next ray into
 * `next`, the throughput factor f cos / pdf into `factor`, and the density per solid angle into
 * *pdf, 0 for a delta lobe (mirror, glass), which no light sample can find. Returns 0 when the
 * path ends (no lobe, or a direction below the surface), 1 for a reflected ray and 2 for a
 * refracted one. */
KDRAY_HOT_INLINE int kd_path_sample_lobes(const KdSceneView* scene, const KdView* view,
                                          KDRAY_GLOBAL const KdMaterial* m,
                                          KDRAY_GLOBAL const kd_f32* tri, const KdPathLobes* l,
                                          const kd_f32* p, const kd_f32* ng, const kd_f32* ns,
                                          const kd_f32* dir, KdSampleRandom* random, KdRay* next,
                                          kd_f32* factor, kd_f32* pdf) {
    /* One pair of dimensions (the caller's): the first coordinate picks the lobe and, stretched
     * over the lobe's share (kd_stretch_chosen), becomes u1, so that the direction (u1, u2) is
     * stratified over the pixel's samples as a 2D point. */
    const kd_f32 u = kd_sample_uniform(random), u2 = kd_sample_uniform(random);
    const kd_f32 diffuse_end = l->p_diffuse, gloss_end = diffuse_end + l->p_gloss;
    const kd_f32 mirror_end = gloss_end + l->p_mirror;
    kd_f32 lobe_start = 0.0f, lobe_share = l->p_diffuse;
    if (u >= diffuse_end) {
        lobe_start = diffuse_end;
        lobe_share = l->p_gloss;
    }
    if (u >= gloss_end) {
        lobe_start = gloss_end;
        lobe_share = l->p_mirror;
    }
    if (u >= mirror_end) {
        lobe_start = mirror_end;
        lobe_share = l->p_glass;
    }
    const kd_f32 u1 = kd_stretch_chosen(u, lobe_start, lobe_share);
    kd_f32 wi[3];
    next->tmin = 0.0f;
    next->tmax = KDRAY_INF;
    *pdf = 0.0f;
    if (u < gloss_end) {
        if (u < diffuse_end) {
            /* Cosine-weighted about ns (Malley's method). */
            const kd_f32 r = KDRAY_SQRT(u1);
            kd_f32 sin_phi, cos_phi;
            kd_sincos_turn(u2, &sin_phi, &cos_phi);
            kd_path_to_world(ns, r * cos_phi, r * sin_phi, KDRAY_SQRT(KDRAY_FMAX(0.0f, 1.0f - u1)),
                             wi);
        } else {
            /* A half vector about ns, cos_h = u1^(1 / (Ns + 1)), and wi the mirror of -dir. */
            const kd_f32 cos_h =
                kd_pow_positive(KDRAY_FMAX(u1, 1e-30f), 1.0f / (l->shininess + 1.0f));
            const kd_f32 sin_h = KDRAY_SQRT(KDRAY_FMAX(0.0f, 1.0f - cos_h * cos_h));
            kd_f32 h[3], sin_phi, cos_phi;
            kd_sincos_turn(u2, &sin_phi, &cos_phi);
            kd_path_to_world(ns, sin_h * cos_phi, sin_h * sin_phi, cos_h, h);
            kd_reflect(dir, h, -kd_dot3(dir, h), wi);
            kd_normalize3(wi);
        }
        const kd_f32 cos_l = kd_light_cosine(ng, ns, wi);
        if (cos_l <= 0.0f) return 0;
        *pdf = kd_path_evaluate(l, ns, dir, wi, cos_l, factor);
        if (!(*pdf > 0.0f)) return 0;
        for (int c = 0; c < 3; ++c) factor[c] /= *pdf;
        for (int a = 0; a < 3; ++a) {
            next->org[a] = p[a] + ng[a] * view->ray_epsilon;
            next->dir[a] = wi[a];
        }
        return 1;
    }
    const int glass = u >= mirror_end;
    if (glass && !(l->p_glass > 0.0f)) return 0; /* no lobe at all: u fell past every share */
    /* Mirror and glass as kd_trace_sample turns them: the same eta and the same normal. */
    kd_f32 eta = 0.0f;
    if (glass) {
        kd_f32 wn[3];
        kd_winding_normal(tri, wn);
        eta = kd_dot3(wn, dir) < 0.0f ? 1.0f / m->ior : m->ior;
    }
    const kd_f32* n = scene->vertex_normals && kd_shading_normal_bends(dir, ng, ns, eta) ? ns : ng;
    const kd_f32 cos_i = -kd_dot3(dir, n);
    int refracted = 0;
    kd_f32 cos_t = 0.0f;
    if (glass) {
        /* Reflection or refraction in proportion to the Fresnel reflectance, which cancels. */
        const kd_f32 fresnel = kd_fresnel(cos_i, eta, &cos_t);
        refracted = u1 >= fresnel;
        for (int c = 0; c < 3; ++c) factor[c] = l->glass[c] / l->p_glass;
    } else {
        for (int c = 0; c < 3; ++c) factor[c] = l->mirror[c] / l->p_mirror;
    }
    if (refracted) {
        kd_refract(dir, n, eta, cos_i, cos_t, wi);
        kd_normalize3(wi);
    } else {
        kd_reflect(dir, n, cos_i, wi);
    }
    const kd_f32 side = refracted ? -1.0f : 1.0f;
    for (int a = 0; a < 3; ++a) {
        next->org[a] = p[a] + side * ng[a] * view->ray_epsilon;
        next->dir[a] = wi[a];
    }
    return refracted ? 2 : 1;
}

/* One sample of the path integrator from the primary ray, its colour into rgb. The primary ray's
 * hit is `traced` when it was traced already (by the packet kernel). random: the sample's
 * numbers (kd_sample_random). */
KDRAY_HOT_INLINE void kd_trace_path_sample(const KdSceneView* scene, const KdView* view,
                                           const KdRay* primary, const KdHit* traced,
                                           KdSampleRandom* random, kd_f32* rgb, KdRayCounts* rays,
                                           KdHit* first_hit, kd_f32* first_normal) {
    rays->primary += 1u;
    kd_f32 beta[3] = {1.0f, 1.0f, 1.0f};
    kd_set3(rgb, 0.0f, 0.0f, 0.0f);
    KdRay ray = *primary;
    /* The density with which the last vertex's lobes drew `ray`, 0 after a delta lobe or from
     * the camera: an emitter that ray hits then counts whole. */
    kd_f32 last_pdf = 0.0f;
    for (kd_u32 segments = 1u;; ++segments) {
        KdHit hit;
        if (segments == 1u && traced)
            hit = *traced;
        else
            kd_scene_closest(scene, &ray, &hit);
        kd_f32 ng[3] = {0.0f, 0.0f, 0.0f};
        KDRAY_GLOBAL const kd_f32* tri = scene->triangles;
        if (hit.prim != KDRAY_NO_HIT) {
            tri += (size_t)hit.prim * KDRAY_FLOATS_PER_TRIANGLE;
            kd_facing_normal(tri, ray.dir, ng);
        }
        if (segments == 1u && first_hit) {
            *first_hit = hit;
            kd_set3(first_normal, ng[0], ng[1], ng[2]);
        }
        /* Found: the background, as radiance from every direction a path leaves the scene in. */
        if (hit.prim == KDRAY_NO_HIT) {
            for (int c = 0; c < 3; ++c)
                rgb[c] = KDRAY_FMIN(rgb[c] + beta[c] * view->background[c], KDRAY_RADIANCE_MAX);
            return;
        }
        KDRAY_GLOBAL const KdMaterial* m = scene->materials + scene->material_ids[hit.prim];
        kd_f32 p[3], ns[3];
        kd_hit_point(&ray, hit.t, p);
        kd_shading_normal(scene, hit, ng, ns);

        /* Found: an emitter, weighted against the light sample of the last vertex. */
        if (KDRAY_EFFECT_ON(view, KDRAY_EFFECT_AREA_LIGHTS)) {
            kd_f32 emitted[3];
            kd_emitted(tri, m, ray.dir, emitted);
            if (emitted[0] > 0.0f || emitted[1] > 0.0f || emitted[2] > 0.0f) {
                kd_f32 weight = 1.0f;
                if (last_pdf > 0.0f) {
                    kd_f32 wn[3];
                    kd_winding_normal(tri, wn);
                    const kd_f32 twice_area = KDRAY_SQRT(kd_dot3(wn, wn));
                    const kd_f32 cos_light = -kd_dot3(wn, ray.dir) / twice_area;
                    const kd_f32 probability =
                        kd_emitter_probability(scene->emitters, view->emitter_count, hit.prim);
                    const kd_f32 pdf_light =
                        probability / (0.5f * twice_area) * hit.t * hit.t / cos_light;
                    if (pdf_light > 0.0f && KDRAY_ISFINITE(pdf_light))
                        weight = kd_power_heuristic(last_pdf, pdf_light);
                }
                for (int c = 0; c < 3; ++c)
                    rgb[c] = KDRAY_FMIN(rgb[c] + beta[c] * weight * emitted[c], KDRAY_RADIANCE_MAX);
            }
        }
        if (segments >= view->max_depth) return;

        /* Each vertex draws from dimensions of its own, whichever events it has: its light
         * sample's pair, its lobes' pair, and roulette's number, so that a pair means the same
         * event at the same depth in every sample of the pixel. */
        const kd_u32 first_dimension = (segments - 1u) * KDRAY_PATH_DIMENSIONS_PER_VERTEX;
        random->dimension = first_dimension;

        /* Next events: the lights, one more segment each. */
        KdPathLobes lobes;
        kd_path_lobes(scene, view, m, hit, &lobes);
        if (lobes.p_diffuse + lobes.p_gloss > 0.0f) {
            kd_f32 direct[3] = {0.0f, 0.0f, 0.0f};
            kd_path_delta_lights(scene, view, &lobes, p, ng, ns, ray.dir, direct, rays);
            if (KDRAY_EFFECT_ON(view, KDRAY_EFFECT_AREA_LIGHTS))
                kd_path_area_light(scene, view, &lobes, p, ng, ns, ray.dir, random, direct, rays);
            for (int c = 0; c < 3; ++c)
                rgb[c] = KDRAY_FMIN(rgb[c] + beta[c] * direct[c], KDRAY_RADIANCE_MAX);
        }

        /* The next segment, drawn from the lobes. */
        random->dimension = first_dimension + 2u;
        kd_f32 factor[3];
        KdRay next;
        const int kind = kd_path_sample_lobes(scene, view, m, tri, &lobes, p, ng, ns, ray.dir,
                                              random, &next, factor, &last_pdf);
        if (kind == 0) return;
        for (int c = 0; c < 3; ++c) beta[c] *= factor[c];
        kd_f32 largest = KDRAY_FMAX(beta[0], KDRAY_FMAX(beta[1], beta[2]));
        if (!(largest > 0.0f) || !KDRAY_ISFINITE(largest)) return;
        /* Russian roulette: an unbiased end to paths whose throughput has fallen. */
        if (segments >= KDRAY_PATH_ROULETTE_DEPTH) {
            const kd_f32 survive = KDRAY_FMIN(largest, KDRAY_PATH_MAX_SURVIVAL);
            random->dimension = first_dimension + 4u;
            if (kd_sample_uniform(random) >= survive) return;
            for (int c = 0; c < 3; ++c) beta[c] /= survive;
        }
        if (kind == 1)
            rays->reflection += 1u;
        else
            rays->refraction += 1u;
        ray = next;
    }
}

#endif /* KDRAY_KD_PATH_H */
