/* kd_texture.h — map_Kd and map_Ka lookups (conventions.md, "Textures"), in the C subset of
 * kd_render.h, which includes it: one source for the reference renderer and the render kernel.
 *
 * A hit's (u, v) is interpolated from its triangle's vt corners at the hit's barycentrics; a
 * triangle without vt (u is NaN in the table) is untextured. v = 0 is the bottom row of the image,
 * coordinates wrap (repeat), and the lookup is bilinear between texel centres. Texels are linear
 * floats in one atlas (the host decoded 8-bit images from sRGB).
 */
#ifndef KDRAY_KD_TEXTURE_H
#define KDRAY_KD_TEXTURE_H

#include "core/device/kd_shading.h"

/* The hit's texture coordinates into uv; 0 where its triangle has none or they are not finite. */
KDRAY_INLINE int kd_hit_texcoord(const KdSceneView* scene, KdHit hit, kd_f32* uv) {
    KDRAY_GLOBAL const kd_f32* t = scene->texcoords + (size_t)hit.prim * 6u;
    if (!(t[0] == t[0])) return 0;
    const kd_f32 w = 1.0f - hit.u - hit.v;
    uv[0] = w * t[0] + hit.u * t[2] + hit.v * t[4];
    uv[1] = w * t[1] + hit.u * t[3] + hit.v * t[5];
    /* The corners are finite (the OBJ pre-scan), but corners near FLT_MAX overflow when
     * interpolated: such a hit is untextured rather than a NaN that indexes outside a texture. */
    return KDRAY_ISFINITE(uv[0]) && KDRAY_ISFINITE(uv[1]);
}

/* Texel (x, y) of texture `tex`, wrapped, times `weight`, added to out. The lookup passes x in
 * [-1, width] and y in [-1, height]; the remainder wraps any other value into the texture too, so
 * that no coordinate ever reads outside it. */
KDRAY_INLINE void kd_add_texel(const KdSceneView* scene, KDRAY_GLOBAL const KdTexture* tex,
                               kd_i32 x, kd_i32 y, kd_f32 weight, kd_f32* out) {
    const kd_i32 w = (kd_i32)tex->width, h = (kd_i32)tex->height;
    x %= w;
    y %= h;
    x = x < 0 ? x + w : x;
    y = y < 0 ? y + h : y;
    KDRAY_GLOBAL const kd_f32* texel =
        scene->texels + 4u * ((size_t)tex->offset + (size_t)y * (size_t)w + (size_t)x);
    for (int c = 0; c < 3; ++c) out[c] += weight * texel[c];
}

/* Texture `id` at uv, bilinear between texel centres, into rgb. */
KDRAY_INLINE void kd_texture_lookup(const KdSceneView* scene, kd_u32 id, const kd_f32* uv,
                                    kd_f32* rgb) {
    KDRAY_GLOBAL const KdTexture* tex = scene->textures + id;
    /* Only finite coordinates wrap into [0, 1]: the float-to-int conversions below are undefined
     * for NaN or inf (INT_MIN on x86), so any other reads texel (0, 0)'s corner. */
    const int finite = KDRAY_ISFINITE(uv[0]) && KDRAY_ISFINITE(uv[1]);
    const kd_f32 u = finite ? uv[0] - KDRAY_FLOOR(uv[0]) : 0.0f;
    const kd_f32 v = finite ? uv[1] - KDRAY_FLOOR(uv[1]) : 0.0f;
    /* Texel centres at (i + 0.5) / width; row 0 is the top of the image, v = 1. */
    const kd_f32 x = u * (kd_f32)tex->width - 0.5f, y = (1.0f - v) * (kd_f32)tex->height - 0.5f;
    const kd_f32 x0 = KDRAY_FLOOR(x), y0 = KDRAY_FLOOR(y);
    const kd_f32 fx = x - x0, fy = y - y0;
    const kd_i32 ix = (kd_i32)x0, iy = (kd_i32)y0;
    kd_set3(rgb, 0.0f, 0.0f, 0.0f);
    kd_add_texel(scene, tex, ix, iy, (1.0f - fx) * (1.0f - fy), rgb);
    kd_add_texel(scene, tex, ix + 1, iy, fx * (1.0f - fy), rgb);
    kd_add_texel(scene, tex, ix, iy + 1, (1.0f - fx) * fy, rgb);
    kd_add_texel(scene, tex, ix + 1, iy + 1, fx * fy, rgb);
}

/* The diffuse and ambient colours of m at the hit: Kd and the material's ambient radiance, each
 * times its texture's texel where the material has one and the triangle has vt. */
KDRAY_INLINE void kd_surface_colours(const KdSceneView* scene, const KdView* view,
                                     KDRAY_GLOBAL const KdMaterial* m, KdHit hit, kd_f32* diffuse,
                                     kd_f32* ambient) {
    kd_set3(diffuse, m->diffuse[0], m->diffuse[1], m->diffuse[2]);
    kd_set3(ambient, m->ambient[0], m->ambient[1], m->ambient[2]);
    if (!KDRAY_EFFECT_ON(view, KDRAY_EFFECT_TEXTURES)) return;
    kd_f32 uv[2], texel[3];
    if (!kd_hit_texcoord(scene, hit, uv)) return;
    if (m->diffuse_texture != KDRAY_NO_TEXTURE) {
        kd_texture_lookup(scene, m->diffuse_texture, uv, texel);
        for (int c = 0; c < 3; ++c) diffuse[c] *= texel[c];
    }
    if (m->ambient_texture != KDRAY_NO_TEXTURE) {
        kd_texture_lookup(scene, m->ambient_texture, uv, texel);
        for (int c = 0; c < 3; ++c) ambient[c] *= texel[c];
    }
}

#endif /* KDRAY_KD_TEXTURE_H */
