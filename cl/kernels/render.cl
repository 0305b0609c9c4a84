/* render.cl — one work-item per pixel: the shared shading of core/kd_render.h over the kd-tree
 * built on the device. Built once per effects combination (-DKDRAY_COMPILED_EFFECTS), so a matte
 * scene's kernel holds no secondary-ray code at all, and per triangle test
 * (-DKDRAY_COMPILED_INTERSECT, watertight unless it says Moller-Trumbore). */
#include "core/kd_render.h"

__kernel void kd_render_pixels(__global const KdNode* nodes, __global const kd_u32* leaf_indices,
                               __global const float* triangles,
                               __global const kd_u32* material_ids,
                               __global const KdMaterial* materials,
                               __global const KdLight* lights, __global const float* bounds,
                               const KdView view, const kd_u32 first_row, const kd_u32 rows,
                               __global float* rgb, __global KdHit* hits,
                               __global float* normals, __global KdRayCounts* ray_counts) {
    const kd_u32 x = (kd_u32)get_global_id(0);
    const kd_u32 row = (kd_u32)get_global_id(1);
    if (x >= view.width || row >= rows) return;
    const kd_u32 y = first_row + row;

    KdSceneView scene;
    scene.nodes = nodes;
    scene.leaf_indices = leaf_indices;
    scene.triangles = triangles;
    scene.material_ids = material_ids;
    scene.materials = materials;
    scene.lights = lights;
    for (int i = 0; i < 6; ++i) scene.bounds[i] = bounds[i];
    scene.intersect = KDRAY_COMPILED_INTERSECT;

    const KdView v = view;
    const KdPixel pixel = kd_render_pixel(&scene, &v, x, y);
    const size_t i = (size_t)y * view.width + x;
    for (int c = 0; c < 3; ++c) {
        rgb[3 * i + c] = pixel.rgb[c];
        normals[3 * i + c] = pixel.normal[c];
    }
    hits[i] = pixel.centre_hit;
    ray_counts[i] = pixel.rays;
}
