/* render.cl — the render kernels: the shared shading of core/device/kd_render.h over the kd-tree
 * built on the device. Built once per effects combination (-DKDRAY_COMPILED_EFFECTS), so a matte
 * scene's kernel holds no secondary-ray code at all, and per triangle test
 * (-DKDRAY_COMPILED_INTERSECT, watertight unless it says Moller-Trumbore).
 *
 *   kd_trace_camera_packets  (CPU devices) the primary rays of 4x4 or 4x2 pixel tiles as
 *                            packets of 16 or 8 (packet_traverse.cl, -DKDRAY_PACKET_LANES), their
 *                            hits into a buffer
 *   kd_trace_shadow_packets  (CPU devices, frames with lights) the shadow rays from those hits,
 *                            a packet per tile and light, a bit per blocked ray into a buffer
 *   kd_render_pixels         one work-item per pixel: its samples, shaded; the primary hits come
 *                            from that buffer when there is one, else they are traced here
 *   kd_shade_traced_pixels   one work-item per pixel of one sample whose hit is in that buffer,
 *                            shaded where no reflection or refraction follows
 *   kd_trace_shade_camera_packets  (CPU devices) the first and the last in one work-item per
 *                            tile, where no shadow packets come between them
 *
 * The packet kernels and the shading of their hits exist only in programs built with
 * -DKDRAY_COMPILED_PACKETS=1 (CPU devices, opencl_renderer.cpp): a packet work-item holds 35-37 KB
 * of private arrays, most of the program, which a GPU, running one ray per lane, never launches.
 *
 * Every kernel takes the tree's buffers (nodes, leaf_indices, triangles) first and a
 * KdRenderLaunch record (core/device/kd_shared.h: the view, the tree's box, the launch's rows and
 * outputs); those that shade also take the frame's read-only arrays in one buffer, scene_data,
 * with the KdSceneLayout record of where each lies; then the buffers the kernel writes. */
#include "core/device/kd_render.h"
/* After kd_render.h: the embedding inlines a header's text at its first #include only
 * (embed_kernels.cmake), so the headers that packet_traverse.cl shares must come in outside the
 * #if. */
#ifndef KDRAY_COMPILED_PACKETS
#error "render.cl is built with -DKDRAY_COMPILED_PACKETS=0 or 1 (opencl_renderer.cpp)"
#endif
#if KDRAY_COMPILED_PACKETS
#include "cl/renderer/kernels/packet_traverse.cl"
#endif

/* The scene view the kernels read: the tree's buffers, the launch's box, and the frame's arrays
 * at their byte offsets in scene_data. vertex_normals is 0 where the scene has none (flat
 * shading). */
KDRAY_INLINE void kd_scene_view(__global const KdNode* nodes, __global const kd_u32* leaf_indices,
                                __global const float* triangles, __global const uchar* scene_data,
                                const KdSceneLayout* layout, const KdRenderLaunch* launch,
                                KdSceneView* scene) {
    scene->nodes = nodes;
    scene->leaf_indices = leaf_indices;
    scene->triangles = triangles;
    scene->vertex_normals = layout->has_vertex_normals
                                ? (__global const float*)(scene_data + layout->vertex_normals)
                                : 0;
    scene->material_ids = (__global const kd_u32*)(scene_data + layout->material_ids);
    scene->materials = (__global const KdMaterial*)(scene_data + layout->materials);
    scene->lights = (__global const KdLight*)(scene_data + layout->lights);
    scene->emitters = (__global const KdEmitter*)(scene_data + layout->emitters);
    scene->texcoords = (__global const float*)(scene_data + layout->texcoords);
    scene->textures = (__global const KdTexture*)(scene_data + layout->textures);
    scene->texels = (__global const float*)(scene_data + layout->texels);
    for (int i = 0; i < 6; ++i) scene->bounds[i] = launch->bounds[i];
    scene->intersect = KDRAY_COMPILED_INTERSECT;
}

#if KDRAY_COMPILED_PACKETS
/* kd_hash and kd_unit_float of core/device/kd_render.h, per lane. */
KDRAY_INLINE kd_packet_uint kd_packet_hash(kd_packet_uint x) {
    KDRAY_LOWBIAS32(x);
    return x;
}
KDRAY_INLINE kd_packet_float kd_packet_unit_float(kd_packet_uint h) {
    return KDRAY_UNIT_FLOAT(kd_packet_convert_float, h);
}

/* Primary ray r of pixels (x, y), one per lane: kd_primary_ray and kd_camera_ray of core/
 * kd_render.h through the same macros, so that each lane's ray is the scalar one bit for bit. */
KDRAY_INLINE KdPacketRays kd_primary_packet(const KdView* view, kd_packet_uint x, kd_packet_uint y,
                                            kd_u32 r, kd_packet_int valid) {
    kd_packet_float px = kd_packet_convert_float(x) + 0.5f, py = kd_packet_convert_float(y) + 0.5f;
    if (view->spp > 1u && r != view->spp && view->sampler == KDRAY_SAMPLER_INDEPENDENT) {
        const kd_packet_uint h = kd_packet_hash(KDRAY_SAMPLE_KEY(view, x, y, r));
        px = kd_packet_convert_float(x) + kd_packet_unit_float(h);
        py = kd_packet_convert_float(y) + kd_packet_unit_float(kd_packet_hash(h));
    } else if (view->spp > 1u && r != view->spp) {
        const kd_packet_uint h = kd_packet_hash(KDRAY_PIXEL_KEY(view, x, y));
        px = kd_packet_convert_float(x) + kd_packet_unit_float(h + r * KDRAY_R2_STEP0);
        py = kd_packet_convert_float(y) +
             kd_packet_unit_float(kd_packet_hash(h) + r * KDRAY_R2_STEP1);
    }
    const kd_packet_float sx = KDRAY_SCREEN_X(view, px);
    const kd_packet_float sy = KDRAY_SCREEN_Y(view, py);
    KdPacketRays rays;
    for (int a = 0; a < 3; ++a) {
        rays.org[a] = (kd_packet_float)(view->origin[a]);
        rays.dir[a] = KDRAY_CAMERA_DIR(view, a, sx, sy);
    }
    const kd_packet_float inv = KDRAY_INV_LENGTH3(rays.dir[0], rays.dir[1], rays.dir[2]);
    for (int a = 0; a < 3; ++a) rays.dir[a] = rays.dir[a] * inv;
    rays.tmin = (kd_packet_float)(0.0f);
    rays.tmax = (kd_packet_float)(KDRAY_INF);
    rays.valid = valid;
    return rays;
}

/* Ray r (kd_primary_ray) of the pixels of the tile whose top left pixel is (x0, row0) of the
 * launch's rows, traced as one packet: the rays in *rays, lane i's hit in out[i]; lane i is pixel
 * (x0 + i % KDRAY_PACKET_TILE_WIDTH, row0 + i / KDRAY_PACKET_TILE_WIDTH). */
KDRAY_HOT_INLINE void kd_trace_camera_tile(__global const KdNode* nodes,
                                           __global const kd_u32* leaf_indices,
                                           __global const float* triangles,
                                           const KdRenderLaunch* launch, kd_u32 x0, kd_u32 row0,
                                           kd_u32 r, KdPacketRays* rays, KdHit* out) {
    const KdView v = launch->view;
    float box[6];
    for (int i = 0; i < 6; ++i) box[i] = launch->bounds[i];
    const kd_packet_uint lane = KDRAY_PACKET_LANE_INDEX;
    const kd_packet_uint x = x0 + lane % KDRAY_PACKET_TILE_WIDTH,
                         row = row0 + lane / KDRAY_PACKET_TILE_WIDTH;
    const kd_packet_int valid = (x < v.width) & (row < launch->rows);
    *rays = kd_primary_packet(&v, x, launch->first_row + row, r, valid);
    kd_trace_packet(nodes, leaf_indices, triangles, box, rays, 0, out);
}

/* Work-item (tile x, tile y, primary ray r) traces ray r (kd_primary_ray) of the tile's pixels,
 * rows first_row.. first_row + rows of the image (the launch's), into
 * hits[r * rows * width + pixel], pixel counted from first_row. */
__kernel void kd_trace_camera_packets(__global const KdNode* nodes,
                                      __global const kd_u32* leaf_indices,
                                      __global const float* triangles, const KdRenderLaunch launch,
                                      __global KdHit* hits) {
    const kd_u32 x0 = (kd_u32)get_global_id(0) * KDRAY_PACKET_TILE_WIDTH;
    const kd_u32 row0 = (kd_u32)get_global_id(1) * KDRAY_PACKET_TILE_ROWS;
    const kd_u32 r = (kd_u32)get_global_id(2);
    const kd_u32 rows = launch.rows, width = launch.view.width;
    if (x0 >= width || row0 >= rows || r >= kd_primary_rays_per_pixel(&launch.view)) return;
    KdPacketRays rays;
    KdHit out[KDRAY_PACKET_LANES];
    kd_trace_camera_tile(nodes, leaf_indices, triangles, &launch, x0, row0, r, &rays, out);
    __global KdHit* plane = hits + (size_t)r * rows * width;
    for (int i = 0; i < KDRAY_PACKET_LANES; ++i) {
        const kd_u32 xi = x0 + (kd_u32)(i % KDRAY_PACKET_TILE_WIDTH);
        const kd_u32 ri = row0 + (kd_u32)(i / KDRAY_PACKET_TILE_WIDTH);
        if (xi < width && ri < rows) plane[(size_t)ri * width + xi] = out[i];
    }
}

#if (KDRAY_COMPILED_EFFECTS & KDRAY_EFFECT_SHADOWS) != 0
/* Work-item (tile x, tile y, primary ray r): the shadow rays from the hits of ray r of the tile's
 * pixels (kd_trace_camera_packets' hits, laid out as it writes them) toward each light, a packet
 * per light, into occluded (the same layout): bit i where light i's shadow ray is blocked. Each
 * lane's shadow ray is the one kd_direct_light casts (the same shared functions), and its any-hit
 * walk finds it blocked exactly when kd_trace_occluded does. Bits of rays kd_direct_light will
 * not cast (a light behind the surface) stay 0 and are never read. At most
 * KDRAY_PACKET_SHADOW_LIGHTS lights. */
__kernel void kd_trace_shadow_packets(__global const KdNode* nodes,
                                      __global const kd_u32* leaf_indices,
                                      __global const float* triangles,
                                      __global const uchar* scene_data, const KdSceneLayout layout,
                                      const KdRenderLaunch launch, __global const KdHit* traced,
                                      __global kd_u32* occluded) {
    const kd_u32 x0 = (kd_u32)get_global_id(0) * KDRAY_PACKET_TILE_WIDTH;
    const kd_u32 row0 = (kd_u32)get_global_id(1) * KDRAY_PACKET_TILE_ROWS;
    const kd_u32 r = (kd_u32)get_global_id(2);
    const kd_u32 first_row = launch.first_row, rows = launch.rows;
    if (x0 >= launch.view.width || row0 >= rows || r >= kd_primary_rays_per_pixel(&launch.view))
        return;
    /* With spp > 1, ray spp is the AOV's centre ray, which nothing shades. */
    if (launch.view.spp > 1u && r == launch.view.spp) return;
    const KdView v = launch.view;
    KdSceneView scene;
    kd_scene_view(nodes, leaf_indices, triangles, scene_data, &layout, &launch, &scene);
    /* Per lane (pixel (x0 + i % KDRAY_PACKET_TILE_WIDTH, row0 + i / KDRAY_PACKET_TILE_WIDTH)): its
     * hit's point and geometric and shading normals, as kd_trace_sample computes them. */
    kd_f32 p[KDRAY_PACKET_LANES][3], ng[KDRAY_PACKET_LANES][3], ns[KDRAY_PACKET_LANES][3];
    int inside[KDRAY_PACKET_LANES], has_hit[KDRAY_PACKET_LANES];
    kd_u32 blocked[KDRAY_PACKET_LANES];
    size_t at[KDRAY_PACKET_LANES];
    for (int i = 0; i < KDRAY_PACKET_LANES; ++i) {
        const kd_u32 xi = x0 + (kd_u32)(i % KDRAY_PACKET_TILE_WIDTH);
        const kd_u32 ri = row0 + (kd_u32)(i / KDRAY_PACKET_TILE_WIDTH);
        blocked[i] = 0u;
        has_hit[i] = 0;
        at[i] = (size_t)r * rows * v.width + (size_t)ri * v.width + xi;
        inside[i] = xi < v.width && ri < rows;
        if (!inside[i]) continue;
        const KdHit hit = traced[at[i]];
        if (hit.prim == KDRAY_NO_HIT) continue;
        KdRay primary;
        kd_primary_ray(&v, xi, first_row + ri, r, &primary);
        kd_facing_normal(triangles + (size_t)hit.prim * KDRAY_FLOATS_PER_TRIANGLE, primary.dir,
                         ng[i]);
        kd_shading_normal(&scene, hit, ng[i], ns[i]);
        kd_hit_point(&primary, hit.t, p[i]);
        has_hit[i] = 1;
    }
    float box[6];
    for (int i = 0; i < 6; ++i) box[i] = launch.bounds[i];
    const kd_u32 light_count = kd_shining_lights(&v);
    for (kd_u32 light = 0; light < light_count; ++light) {
        float org[3][KDRAY_PACKET_LANES], dir[3][KDRAY_PACKET_LANES], tmax[KDRAY_PACKET_LANES];
        int valid[KDRAY_PACKET_LANES];
        int any_ray = 0;
        for (int i = 0; i < KDRAY_PACKET_LANES; ++i) {
            valid[i] = 0;
            tmax[i] = 0.0f;
            for (int a = 0; a < 3; ++a) org[a][i] = dir[a][i] = 1.0f;
            if (!has_hit[i]) continue;
            kd_f32 to_light[3], irradiance[3], distance;
            kd_light_at(&scene, &v, light_count, light, p[i], to_light, irradiance, &distance);
            if (kd_light_cosine(ng[i], ns[i], to_light) <= 0.0f) continue;
            KdRay shadow;
            kd_shadow_ray(&v, p[i], ng[i], to_light, distance, &shadow);
            for (int a = 0; a < 3; ++a) {
                org[a][i] = shadow.org[a];
                dir[a][i] = shadow.dir[a];
            }
            tmax[i] = shadow.tmax;
            valid[i] = -1;
            any_ray = 1;
        }
        if (!any_ray) continue;
        KdPacketRays rays;
        for (int a = 0; a < 3; ++a) {
            rays.org[a] = kd_packet_vload(0, org[a]);
            rays.dir[a] = kd_packet_vload(0, dir[a]);
        }
        rays.tmin = (kd_packet_float)(0.0f);
        rays.tmax = kd_packet_vload(0, tmax);
        rays.valid = kd_packet_vload(0, valid);
        KdHit out[KDRAY_PACKET_LANES];
        kd_trace_packet(nodes, leaf_indices, triangles, box, &rays, 1, out);
        for (int i = 0; i < KDRAY_PACKET_LANES; ++i)
            if (valid[i] && out[i].prim != KDRAY_NO_HIT) blocked[i] |= 1u << light;
    }
    for (int i = 0; i < KDRAY_PACKET_LANES; ++i)
        if (inside[i]) occluded[at[i]] = blocked[i];
}
#endif
#endif /* KDRAY_COMPILED_PACKETS */

/* The one sample of a pixel, its primary ray (kd_primary_ray's) and that ray's hit *hit, shaded
 * by kd_trace_direct_sample alone (blocked: the lights kd_trace_shadow_packets found blocked from
 * it, or 0 where the shading casts its own shadow rays). */
KDRAY_HOT_INLINE void kd_direct_pixel(const KdSceneView* scene, const KdView* view,
                                      const KdRay* primary, const KdHit* hit,
                                      __global const kd_u32* blocked, KdPixel* pixel) {
    pixel->rays.primary = pixel->rays.shadow = 0u;
    pixel->rays.reflection = pixel->rays.refraction = pixel->rays.area_shadow = 0u;
    kd_trace_direct_sample(scene, view, primary, hit, blocked, 0, pixel->rgb, &pixel->rays,
                           &pixel->centre_hit, pixel->normal);
}

/* Pixel (x, y)'s results into the frame's buffers (normals as launch->outputs asks). */
KDRAY_INLINE void kd_store_pixel(const KdRenderLaunch* launch, kd_u32 x, kd_u32 y,
                                 const KdPixel* pixel, __global float* rgb, __global KdHit* hits,
                                 __global float* normals, __global KdRayCounts* ray_counts) {
    const size_t i = (size_t)y * launch->view.width + x;
    for (int c = 0; c < 3; ++c) rgb[3 * i + c] = pixel->rgb[c];
    if (launch->outputs & KDRAY_RENDER_NORMALS)
        for (int c = 0; c < 3; ++c) normals[3 * i + c] = pixel->normal[c];
    hits[i] = pixel->centre_hit;
#if KDRAY_COMPILED_EFFECTS != 0
    ray_counts[i] = pixel->rays;
#endif
}

/* The work-item of pixel (get_global_id(0), first_row + get_global_id(1)), for both pixel kernels
 * below. direct_only: the pixel's one sample, whose primary hit is in traced, shaded by
 * kd_trace_direct_sample alone; a constant in each kernel, so that kd_shade_traced_pixels holds
 * no primary walk and no pending-ray stack. */
KDRAY_HOT_INLINE void kd_pixel_work_item(
    __global const KdNode* nodes, __global const kd_u32* leaf_indices,
    __global const float* triangles, __global const uchar* scene_data, const KdSceneLayout* layout,
    const KdRenderLaunch* launch, __global float* rgb, __global KdHit* hits,
    __global float* normals, __global KdRayCounts* ray_counts, __global const KdHit* traced,
    __global const kd_u32* occluded, const int direct_only) {
    const KdView* view = &launch->view;
    const kd_u32 rows = launch->rows, outputs = launch->outputs;
    const kd_u32 x = (kd_u32)get_global_id(0);
    const kd_u32 row = (kd_u32)get_global_id(1);
    if (x >= view->width || row >= rows) return;
    const kd_u32 y = launch->first_row + row;
    KdSceneView scene;
    kd_scene_view(nodes, leaf_indices, triangles, scene_data, layout, launch, &scene);
    const size_t in_launch = (size_t)row * view->width + x;
    __global const kd_u32* blocked =
        (outputs & KDRAY_RENDER_TRACED_SHADOWS) ? occluded + in_launch : 0;
    KdPixel pixel;
    if (direct_only) {
        const KdHit hit = traced[in_launch];
        KdRay primary;
        kd_primary_ray(view, x, y, 0u, &primary);
        kd_direct_pixel(&scene, view, &primary, &hit, blocked, &pixel);
    } else {
        kd_render_pixel(&scene, view, x, y,
                        (outputs & KDRAY_RENDER_TRACED_PRIMARY) ? traced + in_launch : 0, blocked,
                        rows * view->width, &pixel);
    }
    kd_store_pixel(launch, x, y, &pixel, rgb, hits, normals, ray_counts);
}

/* One pixel per work-item; launch.outputs: KDRAY_RENDER_* bits. With KDRAY_RENDER_TRACED_PRIMARY
 * the primary rays' hits are in traced (as kd_trace_camera_packets writes them), else every ray
 * is traced here. */
__kernel void kd_render_pixels(__global const KdNode* nodes, __global const kd_u32* leaf_indices,
                               __global const float* triangles, __global const uchar* scene_data,
                               const KdSceneLayout layout, const KdRenderLaunch launch,
                               __global float* rgb, __global KdHit* hits, __global float* normals,
                               __global KdRayCounts* ray_counts, __global const KdHit* traced,
                               __global const kd_u32* occluded) {
    kd_pixel_work_item(nodes, leaf_indices, triangles, scene_data, &layout, &launch, rgb, hits,
                       normals, ray_counts, traced, occluded, 0);
}

/* The `cost` AOV of the launch's pixels (kd_pixel_cost: the centre ray's walk, counted), into
 * costs[y * width + x]; launched after the pixels only for frames that write it. The walk reads
 * only the tree, its box and the triangle test, so the view's shading arrays stay unset. */
__kernel void kd_trace_costs(__global const KdNode* nodes, __global const kd_u32* leaf_indices,
                             __global const float* triangles, const KdRenderLaunch launch,
                             __global KdTraceCost* costs) {
    const kd_u32 x = (kd_u32)get_global_id(0);
    const kd_u32 row = (kd_u32)get_global_id(1);
    if (x >= launch.view.width || row >= launch.rows) return;
    KdSceneView scene;
    scene.nodes = nodes;
    scene.leaf_indices = leaf_indices;
    scene.triangles = triangles;
    for (int i = 0; i < 6; ++i) scene.bounds[i] = launch.bounds[i];
    scene.intersect = KDRAY_COMPILED_INTERSECT;
    const kd_u32 y = launch.first_row + row;
    KdTraceCost cost;
    kd_pixel_cost(&scene, &launch.view, x, y, &cost);
    costs[(size_t)y * launch.view.width + x] = cost;
}

#if KDRAY_COMPILED_PACKETS
/* kd_render_pixels for spp 1 with the primary hits traced, in a kernel without reflection and
 * refraction: kd_render_pixel's one sample and its shading, nothing else. */
__kernel void kd_shade_traced_pixels(__global const KdNode* nodes,
                                     __global const kd_u32* leaf_indices,
                                     __global const float* triangles,
                                     __global const uchar* scene_data, const KdSceneLayout layout,
                                     const KdRenderLaunch launch, __global float* rgb,
                                     __global KdHit* hits, __global float* normals,
                                     __global KdRayCounts* ray_counts, __global const KdHit* traced,
                                     __global const kd_u32* occluded) {
    kd_pixel_work_item(nodes, leaf_indices, triangles, scene_data, &layout, &launch, rgb, hits,
                       normals, ray_counts, traced, occluded, 1);
}

/* kd_trace_camera_packets and kd_shade_traced_pixels in one work-item, for frames of one sample
 * per pixel whose shading casts no secondary rays and whose shadow rays (if any) are not traced
 * as packets: the tile's primary rays as one packet, then each of its pixels shaded from its
 * lane's hit, which never goes through a buffer. The hits and the image are the two kernels'
 * bit for bit (the same functions on the same values); the buffer's 16 bytes per pixel, written
 * by one kernel and read back cold by the next, cost the bunny's primary frame about a tenth of
 * its trace. A work-item per tile, as the packet kernels launch. */
__kernel void kd_trace_shade_camera_packets(
    __global const KdNode* nodes, __global const kd_u32* leaf_indices,
    __global const float* triangles, __global const uchar* scene_data, const KdSceneLayout layout,
    const KdRenderLaunch launch, __global float* rgb, __global KdHit* hits, __global float* normals,
    __global KdRayCounts* ray_counts) {
    const kd_u32 x0 = (kd_u32)get_global_id(0) * KDRAY_PACKET_TILE_WIDTH;
    const kd_u32 row0 = (kd_u32)get_global_id(1) * KDRAY_PACKET_TILE_ROWS;
    const kd_u32 rows = launch.rows, width = launch.view.width;
    if (x0 >= width || row0 >= rows || get_global_id(2) != 0) return;
    KdPacketRays rays;
    KdHit traced[KDRAY_PACKET_LANES];
    kd_trace_camera_tile(nodes, leaf_indices, triangles, &launch, x0, row0, 0u, &rays, traced);
    /* Each lane's ray is kd_primary_ray's for its pixel bit for bit (kd_primary_packet). */
    float dir[3][KDRAY_PACKET_LANES];
    for (int a = 0; a < 3; ++a) kd_packet_vstore(rays.dir[a], 0, dir[a]);
    KdSceneView scene;
    kd_scene_view(nodes, leaf_indices, triangles, scene_data, &layout, &launch, &scene);
    for (int i = 0; i < KDRAY_PACKET_LANES; ++i) {
        const kd_u32 xi = x0 + (kd_u32)(i % KDRAY_PACKET_TILE_WIDTH);
        const kd_u32 ri = row0 + (kd_u32)(i / KDRAY_PACKET_TILE_WIDTH);
        if (xi >= width || ri >= rows) continue;
        KdRay primary;
        for (int a = 0; a < 3; ++a) {
            primary.org[a] = launch.view.origin[a];
            primary.dir[a] = dir[a][i];
        }
        primary.tmin = 0.0f;
        primary.tmax = KDRAY_INF;
        KdPixel pixel;
        kd_direct_pixel(&scene, &launch.view, &primary, &traced[i], 0, &pixel);
        kd_store_pixel(&launch, xi, launch.first_row + ri, &pixel, rgb, hits, normals, ray_counts);
    }
}
#endif /* KDRAY_COMPILED_PACKETS */
