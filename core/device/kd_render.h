/* kd_render.h — camera rays and shading, written once in the C subset that compiles as C++ (the
 * reference renderer) and as OpenCL C (the render kernel), as pbrt-v4 shares its integrators
 * between CPU and GPU. The reference image is therefore the oracle for the OpenCL image: the same
 * samples, the same rays, the same arithmetic.
 *
 * Shading is Whitted-style by default (the path integrator of kd_path.h where the render file
 * asks for it): emission, ambient light by Ka, Lambert diffuse and a Blinn-Phong
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

#include "core/device/kd_area_light.h"
#include "core/device/kd_shading.h"
#include "core/device/kd_texture.h"

/* Whitted's area-light numbers' own key (kd_sample_random), apart from the path integrator's. */
#define KDRAY_WHITTED_LIGHT_SALT 0x2C1B3C6Du

/* The path integrator: always on the host (the reference renders either), in a kernel only when
 * its effects ask for it, so that a Whitted program holds none of it. */
#if !defined(KDRAY_DEVICE_CODE) || (KDRAY_COMPILED_EFFECTS & KDRAY_EFFECT_PATH) != 0
#define KDRAY_PATH_COMPILED 1
#include "core/device/kd_path.h"
#else
#define KDRAY_PATH_COMPILED 0
#endif

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
                                      KDRAY_GLOBAL const kd_u32* occluded, KdSampleRandom* random,
                                      kd_f32* out, KdRayCounts* rays) {
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
        kd_area_light(scene, view, m, diffuse, p, ng, ns, dir, random, out, rays);
}

/* One sample when neither reflection nor refraction is on: the primary ray and its direct light,
 * with no pending-ray stack (a private array of KDRAY_MAX_BOUNCES + 1 rays per work-item that a
 * CPU device keeps in memory and a GPU in scratch). Its arithmetic is kd_trace_sample's for a
 * tree of one ray (weight 1, nothing pushed), so the two give identical colours. */
KDRAY_HOT_INLINE void kd_trace_direct_sample(const KdSceneView* scene, const KdView* view,
                                             const KdRay* primary, const KdHit* traced,
                                             KDRAY_GLOBAL const kd_u32* occluded,
                                             KdSampleRandom* random, kd_f32* rgb,
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
        kd_direct_light(scene, view, m, hit, p, ng, ns, primary->dir, occluded, random, direct,
                        rays);
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
                                      KDRAY_GLOBAL const kd_u32* occluded, KdSampleRandom* random,
                                      kd_f32* rgb, KdRayCounts* rays, KdHit* first_hit,
                                      kd_f32* first_normal) {
    if (!KDRAY_EFFECT_ON(view, KDRAY_EFFECT_REFLECTION | KDRAY_EFFECT_REFRACTION)) {
        kd_trace_direct_sample(scene, view, primary, traced, occluded, random, rgb, rays,
                               first_hit, first_normal);
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
                            random, direct, rays);
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
    if (view->sampler == KDRAY_SAMPLER_INDEPENDENT) {
        const kd_u32 h = kd_hash(KDRAY_SAMPLE_KEY(view, x, y, r));
        kd_camera_ray(view, (kd_f32)x + kd_unit_float(h), (kd_f32)y + kd_unit_float(kd_hash(h)),
                      ray);
        return;
    }
    /* The pixel's R2 sequence (kd_shading.h) in the jitter's own rotation. */
    const kd_u32 h = kd_hash(KDRAY_PIXEL_KEY(view, x, y));
    kd_camera_ray(view, (kd_f32)x + kd_unit_float(h + r * KDRAY_R2_STEP0),
                  (kd_f32)y + kd_unit_float(kd_hash(h) + r * KDRAY_R2_STEP1), ray);
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
#if KDRAY_PATH_COMPILED
        if (KDRAY_EFFECT_ON(view, KDRAY_EFFECT_PATH)) {
            KdSampleRandom random;
            kd_sample_random(view, x, y, s, KDRAY_PATH_SALT, &random);
            kd_trace_path_sample(scene, view, &primary, traced ? &hit : 0, &random, rgb, &out.rays,
                                 view->spp == 1u ? &out.centre_hit : 0, out.normal);
        } else
#endif
        {
            /* Whitted's area-light samples from the pixel's sequence when there are several
             * samples to spread (kd_area_light.h); one sample hashes its own. */
            KdSampleRandom light_random;
            const int stratified = view->spp > 1u && view->sampler != KDRAY_SAMPLER_INDEPENDENT;
            if (stratified) kd_sample_random(view, x, y, s, KDRAY_WHITTED_LIGHT_SALT, &light_random);
            kd_trace_sample(scene, view, &primary, traced ? &hit : 0,
                            occluded ? occluded + s * traced_stride : 0,
                            stratified ? &light_random : 0, rgb, &out.rays,
                            view->spp == 1u ? &out.centre_hit : 0, out.normal);
        }
        for (int c = 0; c < 3; ++c)
            out.rgb[c] = KDRAY_FMIN(out.rgb[c] + rgb[c], KDRAY_RADIANCE_MAX);
    }
    for (int c = 0; c < 3; ++c) out.rgb[c] /= (kd_f32)view->spp;
    *pixel = out;
}

#endif /* KDRAY_KD_RENDER_H */
