/* kd_area_light.h — emissive triangles as lights (conventions.md, "Emitters"), in the C subset of
 * kd_render.h, which includes it: one source for the reference renderer and the render kernel.
 *
 * A triangle whose material has Ke > 0 emits radiance Ke from its front side only, the side its
 * winding normal cross(p1 - p0, p2 - p0) points to, as pbrt and Mitsuba do. A shading point
 * receives their light by one sample per hit: an emitter chosen by emitted power (the host's
 * KdEmitter table, a CDF over luminance(Ke) x area), a uniform point on it, and one shadow ray
 * to that point. The estimate of the irradiance it brings is Ke cos_light / (d^2 pdf), pdf the
 * probability density of the point per unit area (the emitter's probability / its area).
 *
 * A pixel's samples draw their numbers from its low-discrepancy sequence (kd_shading.h's
 * KdSampleRandom), so that with spp > 1 the light samples of a pixel spread over the emitters
 * evenly instead of clumping; with one sample, or independent samples, each number comes from a
 * hash of the shading point and the ray that reached it. Either way the host and a kernel draw
 * the same samples from the same hits.
 */
#ifndef KDRAY_KD_AREA_LIGHT_H
#define KDRAY_KD_AREA_LIGHT_H

#include "core/device/kd_shading.h"

/* The winding normal of triangle `tri`, not unit length: twice its area long. */
KDRAY_INLINE void kd_winding_normal(KDRAY_GLOBAL const kd_f32* tri, kd_f32* wn) {
    const kd_f32 e1[3] = {tri[3] - tri[0], tri[4] - tri[1], tri[5] - tri[2]};
    const kd_f32 e2[3] = {tri[6] - tri[0], tri[7] - tri[1], tri[8] - tri[2]};
    kd_set3(wn, e1[1] * e2[2] - e1[2] * e2[1], e1[2] * e2[0] - e1[0] * e2[2],
            e1[0] * e2[1] - e1[1] * e2[0]);
}

/* The radiance a ray along `dir` sees of triangle `tri` with material m: Ke from the front side,
 * nothing from the back. */
KDRAY_INLINE void kd_emitted(KDRAY_GLOBAL const kd_f32* tri, KDRAY_GLOBAL const KdMaterial* m,
                             const kd_f32* dir, kd_f32* out) {
    kd_f32 wn[3];
    kd_winding_normal(tri, wn);
    const int front = kd_dot3(wn, dir) < 0.0f;
    kd_set3(out, front ? m->emission[0] : 0.0f, front ? m->emission[1] : 0.0f,
            front ? m->emission[2] : 0.0f);
}

/* The random key of a shading point p reached along `dir`: its bits and the frame's seed. */
KDRAY_INLINE kd_u32 kd_shading_key(const KdView* view, const kd_f32* p, const kd_f32* dir) {
    kd_u32 h = kd_hash(KDRAY_AS_UINT(dir[0]) ^ view->seed);
    h = kd_hash(h ^ KDRAY_AS_UINT(dir[1]));
    h = kd_hash(h ^ KDRAY_AS_UINT(dir[2]));
    h = kd_hash(h ^ KDRAY_AS_UINT(p[0]));
    h = kd_hash(h ^ KDRAY_AS_UINT(p[1]));
    return kd_hash(h ^ KDRAY_AS_UINT(p[2]));
}

/* The emitter of the table whose CDF interval holds u in [0, 1): the first with u < cdf. */
KDRAY_INLINE kd_u32 kd_pick_emitter(KDRAY_GLOBAL const KdEmitter* emitters, kd_u32 count,
                                    kd_f32 u) {
    kd_u32 lo = 0u, hi = count - 1u;
    while (lo < hi) {
        const kd_u32 mid = (lo + hi) / 2u;
        if (u < emitters[mid].cdf)
            hi = mid;
        else
            lo = mid + 1u;
    }
    return lo;
}

/* An emitter and the numbers (u1, u2) of a point on it from one pair of the sample's dimensions
 * (the next whole pair: an odd dimension left over is skipped): the first coordinate picks the
 * emitter and, stretched over the emitter's interval of the CDF (kd_stretch_chosen), becomes u1;
 * the second is u2. So a pixel's samples are stratified over the emitters and the points
 * on them together. */
KDRAY_HOT_INLINE KDRAY_GLOBAL const KdEmitter* kd_pick_emitter_pair(const KdSceneView* scene,
                                                                    const KdView* view,
                                                                    KdSampleRandom* random,
                                                                    kd_f32* u1, kd_f32* u2) {
    random->dimension = (random->dimension + 1u) & ~1u;
    const kd_f32 u = kd_sample_uniform(random);
    *u2 = kd_sample_uniform(random);
    const kd_u32 i = kd_pick_emitter(scene->emitters, view->emitter_count, u);
    KDRAY_GLOBAL const KdEmitter* e = scene->emitters + i;
    const kd_f32 below = i > 0u ? scene->emitters[i - 1u].cdf : 0.0f;
    *u1 = kd_stretch_chosen(u, below, e->probability);
    return e;
}

/* What a light sample sees of emitter triangle `tri` from p: the point at the square-root warp of
 * (u1, u2) (pbrt's uniform point on a triangle) and the shadow ray toward it, from ng's side of p
 * (as kd_shadow_ray starts it, so that the ray stops short of the emitter by ray_epsilon, whatever
 * the angle to it): shadow->org, the unit direction to_light, the squared distance d2 and the
 * distance to the point, the emitter's cosine toward p and twice its area. Returns 0 when the
 * point is p itself or p sees the emitter's back. Whitted's light sample and the path
 * integrator's (kd_path.h) both take their point here. */
KDRAY_HOT_INLINE int kd_emitter_point(KDRAY_GLOBAL const kd_f32* tri, const kd_f32* p,
                                      const kd_f32* ng, kd_f32 ray_epsilon, kd_f32 u1, kd_f32 u2,
                                      KdRay* shadow, kd_f32* to_light, kd_f32* d2, kd_f32* distance,
                                      kd_f32* cos_light, kd_f32* twice_area) {
    const kd_f32 su = KDRAY_SQRT(u1);
    const kd_f32 b1 = su * (1.0f - u2), b2 = su * u2, b0 = 1.0f - su;
    for (int a = 0; a < 3; ++a) {
        shadow->org[a] = p[a] + ng[a] * ray_epsilon;
        to_light[a] = b0 * tri[a] + b1 * tri[3 + a] + b2 * tri[6 + a] - shadow->org[a];
    }
    *d2 = kd_dot3(to_light, to_light);
    if (!(*d2 > 0.0f)) return 0;
    *distance = KDRAY_SQRT(*d2);
    kd_set3(to_light, to_light[0] / *distance, to_light[1] / *distance, to_light[2] / *distance);
    kd_f32 wn[3];
    kd_winding_normal(tri, wn);
    *twice_area = KDRAY_SQRT(kd_dot3(wn, wn));
    /* Its front faces p when the winding normal opposes the direction from p to it. */
    *cos_light = -kd_dot3(wn, to_light) / *twice_area;
    return *cos_light > 0.0f;
}

/* One sample of the light of the frame's emitters at p (geometric normal ng, facing the viewer;
 * shading normal ns) for the eye direction `dir`, reflected by m with the diffuse colour
 * `diffuse` (kd_reflected, the BRDF times
 * the cosine, as the point and directional lights are), into out; one area-light shadow ray.
 * random: the sample's numbers, or 0 to hash them from the shading point. */
KDRAY_HOT_INLINE void kd_area_light(const KdSceneView* scene, const KdView* view,
                                    KDRAY_GLOBAL const KdMaterial* m, const kd_f32* diffuse,
                                    const kd_f32* p, const kd_f32* ng, const kd_f32* ns,
                                    const kd_f32* dir, KdSampleRandom* random, kd_f32* out,
                                    KdRayCounts* rays) {
    KDRAY_GLOBAL const KdEmitter* e;
    kd_f32 u1, u2;
    if (random) {
        e = kd_pick_emitter_pair(scene, view, random, &u1, &u2);
    } else {
        const kd_u32 h0 = kd_shading_key(view, p, dir), h1 = kd_hash(h0), h2 = kd_hash(h1);
        e = scene->emitters +
            kd_pick_emitter(scene->emitters, view->emitter_count, kd_unit_float(h0));
        u1 = kd_unit_float(h1);
        u2 = kd_unit_float(h2);
    }
    KDRAY_GLOBAL const kd_f32* tri =
        scene->triangles + (size_t)e->triangle * KDRAY_FLOATS_PER_TRIANGLE;
    KdRay shadow;
    kd_f32 to_light[3], d2, distance, cos_light, twice_area;
    if (!kd_emitter_point(tri, p, ng, view->ray_epsilon, u1, u2, &shadow, to_light, &d2, &distance,
                          &cos_light, &twice_area))
        return;
    const kd_f32 cos_l = kd_light_cosine(ng, ns, to_light);
    if (cos_l <= 0.0f) return;
    rays->area_shadow += 1u;
    for (int a = 0; a < 3; ++a) shadow.dir[a] = to_light[a];
    shadow.tmin = 0.0f;
    shadow.tmax = distance - view->ray_epsilon;
    if (kd_scene_occluded(scene, &shadow)) return;
    /* Ke cos_light / (d^2 pdf), pdf = probability / area. */
    const kd_f32 scale = cos_light * (0.5f * twice_area) / (d2 * e->probability);
    KDRAY_GLOBAL const KdMaterial* light = scene->materials + scene->material_ids[e->triangle];
    kd_f32 irradiance[3];
    for (int c = 0; c < 3; ++c) irradiance[c] = light->emission[c] * scale;
    kd_reflected(m, diffuse, ns, dir, to_light, irradiance, cos_l, out);
}

#endif /* KDRAY_KD_AREA_LIGHT_H */
