/* render.cl — the render kernels: the shared shading of core/kd_render.h over the kd-tree built on
 * the device. Built once per effects combination (-DKDRAY_COMPILED_EFFECTS), so a matte scene's
 * kernel holds no secondary-ray code at all, and per triangle test (-DKDRAY_COMPILED_INTERSECT,
 * watertight unless it says Moller-Trumbore).
 *
 *   kd_trace_camera_packets  (CPU devices) the primary rays of 4x4 pixel tiles as packets of 16
 *                            (packet_traverse.cl), their hits into a buffer
 *   kd_render_pixels         one work-item per pixel: its samples, shaded; the primary hits come
 *                            from that buffer when there is one, else they are traced here */
#include "cl/kernels/packet_traverse.cl"
#include "core/kd_render.h"

/* Pixels per packet: a 4x4 tile (KDRAY_PACKET_SIZE lanes). */
#define KDRAY_PACKET_TILE 4

/* The scene view both kernels read. */
inline KdSceneView kd_scene_view(__global const KdNode* nodes, __global const kd_u32* leaf_indices,
                                 __global const float* triangles,
                                 __global const kd_u32* material_ids,
                                 __global const KdMaterial* materials,
                                 __global const KdLight* lights, __global const float* bounds) {
    KdSceneView scene;
    scene.nodes = nodes;
    scene.leaf_indices = leaf_indices;
    scene.triangles = triangles;
    scene.material_ids = material_ids;
    scene.materials = materials;
    scene.lights = lights;
    for (int i = 0; i < 6; ++i) scene.bounds[i] = bounds[i];
    scene.intersect = KDRAY_COMPILED_INTERSECT;
    return scene;
}

/* Work-item (tile x, tile y, primary ray r) traces ray r (kd_primary_ray) of the tile's pixels,
 * rows first_row.. first_row + rows of the image, into hits[r * rows * width + pixel], pixel
 * counted from first_row. */
__kernel void kd_trace_camera_packets(__global const KdNode* nodes,
                                      __global const kd_u32* leaf_indices,
                                      __global const float* triangles, __global const float* bounds,
                                      const KdView view, const kd_u32 first_row, const kd_u32 rows,
                                      __global KdHit* hits) {
    const kd_u32 x0 = (kd_u32)get_global_id(0) * KDRAY_PACKET_TILE;
    const kd_u32 row0 = (kd_u32)get_global_id(1) * KDRAY_PACKET_TILE;
    const kd_u32 r = (kd_u32)get_global_id(2);
    if (x0 >= view.width || row0 >= rows || r >= kd_primary_rays_per_pixel(&view)) return;
    const KdView v = view;
    float box[6];
    for (int i = 0; i < 6; ++i) box[i] = bounds[i];
    KdRay rays[KDRAY_PACKET_SIZE];
    int valid[KDRAY_PACKET_SIZE];
    for (int i = 0; i < KDRAY_PACKET_SIZE; ++i) {
        const kd_u32 x = x0 + (kd_u32)(i % KDRAY_PACKET_TILE);
        const kd_u32 row = row0 + (kd_u32)(i / KDRAY_PACKET_TILE);
        valid[i] = x < v.width && row < rows;
        rays[i] = kd_primary_ray(&v, valid[i] ? x : x0, first_row + (valid[i] ? row : row0), r);
    }
    KdHit out[KDRAY_PACKET_SIZE];
    kd_trace_packet(nodes, leaf_indices, triangles, box, rays, valid, out);
    __global KdHit* plane = hits + (size_t)r * rows * v.width;
    for (int i = 0; i < KDRAY_PACKET_SIZE; ++i)
        if (valid[i])
            plane[(size_t)(row0 + i / KDRAY_PACKET_TILE) * v.width + x0 + i % KDRAY_PACKET_TILE] =
                out[i];
}

/* One pixel per work-item. use_traced: the primary rays' hits are in traced (as
 * kd_trace_camera_packets writes them), else every ray is traced here. */
__kernel void kd_render_pixels(__global const KdNode* nodes, __global const kd_u32* leaf_indices,
                               __global const float* triangles, __global const kd_u32* material_ids,
                               __global const KdMaterial* materials, __global const KdLight* lights,
                               __global const float* bounds, const KdView view,
                               const kd_u32 first_row, const kd_u32 rows, __global float* rgb,
                               __global KdHit* hits, __global float* normals,
                               __global KdRayCounts* ray_counts, __global const KdHit* traced,
                               const kd_u32 use_traced) {
    const kd_u32 x = (kd_u32)get_global_id(0);
    const kd_u32 row = (kd_u32)get_global_id(1);
    if (x >= view.width || row >= rows) return;
    const kd_u32 y = first_row + row;
    const KdSceneView scene =
        kd_scene_view(nodes, leaf_indices, triangles, material_ids, materials, lights, bounds);
    const KdView v = view;
    const size_t in_launch = (size_t)row * view.width + x;
    const KdPixel pixel =
        kd_render_pixel(&scene, &v, x, y, use_traced ? traced + in_launch : 0, rows * view.width);
    const size_t i = (size_t)y * view.width + x;
    for (int c = 0; c < 3; ++c) {
        rgb[3 * i + c] = pixel.rgb[c];
        normals[3 * i + c] = pixel.normal[c];
    }
    hits[i] = pixel.centre_hit;
    ray_counts[i] = pixel.rays;
}
