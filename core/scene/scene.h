// scene.h — a triangle scene as kdray loads it from OBJ/MTL: a flat triangle soup numbered as
// conventions.md says (tinyobjloader's ObjReader order, shape by shape, face by face), one material
// index per triangle, and the materials of the MTL files in kdray's small material model.
#pragma once

#include <cstddef>
#include <filesystem>
#include <string>
#include <vector>

#include "core/device/kd_shared.h"
#include "core/geometry/math.h"
#include "core/scene/scene_frame.h"

namespace kdray {

/// The MTL fields kdray uses (Ka, Kd, Ks, Ns, Ni, d/Tr, Tf, Ke, illum), with MTL's defaults.
struct Material {
    std::string name;
    Vec3 ambient{0, 0, 0};           // Ka: reflects the render file's ambient light
    Vec3 diffuse{0.8f, 0.8f, 0.8f};  // Kd
    Vec3 specular{0, 0, 0};          // Ks
    float shininess = 0.0f;          // Ns
    float ior = 1.0f;                // Ni
    float dissolve = 1.0f;           // d (or 1 - Tr): 1 is opaque
    Vec3 transmission{0, 0, 0};      // Tf
    Vec3 emission{0, 0, 0};          // Ke
    int illum = 2;                   // MTL illumination model
    /// map_Kd's and map_Ka's entries of Scene::texture_table, or -1 (none, or its file missing).
    int diffuse_texture = -1, ambient_texture = -1;

    /// Ideal mirror reflection weighted by Ks: illum 3 or 5 with a non-zero Ks.
    bool is_mirror() const;
    /// The share of light that meets the dielectric (Fresnel reflection and refraction): 1 for
    /// illum 4, 6 and 7; 1 - d for d < 1; and, for exporters that mark glass only by Tf (BART),
    /// the largest Tf component when it lies strictly between 0 and 1 (Tf 1 1 1 is the common
    /// "no filter" default of opaque materials). 0 for opaque materials.
    float transmit_fraction() const;
    /// Colour of the transmitted light: Tf normalised, where Tf marked the glass; else white.
    Vec3 transmission_filter() const;
    bool transmits() const { return transmit_fraction() > 0.0f; }
    /// Spawns reflection rays: a mirror, or a dielectric's Fresnel reflection.
    bool reflects() const { return is_mirror() || transmits(); }
    bool reflects_ambient() const { return ambient.x > 0 || ambient.y > 0 || ambient.z > 0; }
    bool emits() const { return emission.x > 0 || emission.y > 0 || emission.z > 0; }
    bool has_highlight() const {
        return (specular.x > 0 || specular.y > 0 || specular.z > 0) && shininess > 0;
    }
};

struct Scene {
    std::filesystem::path path;
    /// Where the triangles lie: load_obj fits a frame to the file's coordinates (scene_frame.h);
    /// a scene made in memory (make_scene) is traced as given, in the identity frame.
    SceneFrame frame;
    /// KDRAY_FLOATS_PER_TRIANGLE floats per triangle, in `frame`: v0.xyz v1.xyz v2.xyz.
    std::vector<float> triangles;
    /// Shading normals, KDRAY_FLOATS_PER_TRIANGLE floats per triangle (unit normals at v0, v1,
    /// v2), from the OBJ's `vn`; empty when no face gives any, and the shading is then flat (the
    /// geometric normal). A corner without a usable `vn` has its triangle's geometric normal.
    std::vector<float> vertex_normals;
    /// Index into materials for every triangle. Triangles without a material use the last entry,
    /// a grey diffuse default that the loader appends only when some triangle needs it.
    std::vector<kd_u32> material_ids;
    std::vector<Material> materials;
    /// Texture coordinates, 6 floats per triangle (u, v at v0, v1, v2) from the OBJ's `vt`; u is
    /// NaN for a triangle without them (it renders untextured); empty when no face gives any.
    std::vector<float> texcoords;
    /// The images of map_Kd and map_Ka, each once: the table and the atlas of linear texels, 4
    /// floats each (r g b, 0), rows top first (kd_texture.h reads them).
    std::vector<KdTexture> texture_table;
    std::vector<float> texels;
    /// Warnings met while loading (a missing MTL file, say), one line each, for stats.json.
    std::vector<std::string> warnings;
    /// Triangles of zero area: kept (they are never hit) and counted in the statistics.
    std::size_t zero_area_triangles = 0;

    std::size_t triangle_count() const { return triangles.size() / KDRAY_FLOATS_PER_TRIANGLE; }
    Vec3 vertex(std::size_t triangle, int corner) const {
        const float* p = &triangles[triangle * KDRAY_FLOATS_PER_TRIANGLE + 3 * corner];
        return {p[0], p[1], p[2]};
    }
    /// A corner in the scene's own units (the file's coordinates, as rounded in the frame).
    DVec3 scene_vertex(std::size_t triangle, int corner) const {
        return frame.scene_point(vertex(triangle, corner));
    }
    Aabb triangle_bounds(std::size_t triangle) const {
        Aabb b;
        for (int k = 0; k < 3; ++k) b.grow(vertex(triangle, k));
        return b;
    }
    /// The scene's bounds; this is the root box of every tree built over it.
    Aabb bounds() const;
    bool has_vertex_normals() const { return !vertex_normals.empty(); }
    bool has_texcoords() const { return !texcoords.empty(); }
    /// Bytes of the texel atlas and its table: the textures' memory on the device.
    std::size_t texture_bytes() const {
        return texels.size() * sizeof(float) + texture_table.size() * sizeof(KdTexture);
    }
};

/// The cross product of a triangle's edges (v1 - v0) x (v2 - v0), in double, where the product of
/// float differences is all but exact: zero exactly when the triangle has no area.
void triangle_cross_double(const float* triangle, double out[3]);

/// Counts the zero-area triangles into scene.zero_area_triangles and collapses each to its first
/// corner. They keep their numbers but can never be hit: three distinct collinear corners would
/// no longer be collinear after a ray-space transform rounds them. The area test is in double,
/// where the cross product of float differences is all but exact. Also throws Error naming the
/// triangle when a coordinate is not finite.
void collapse_zero_area_triangles(Scene& scene);

/// Loads an OBJ file (and the MTL files it names). Throws Error naming the file, the line where
/// it can, and the problem: an unreadable file, a non-finite or malformed vertex coordinate, a face
/// index out of range, an empty scene.
Scene load_obj(const std::filesystem::path& path);

/// Builds a scene from a triangle soup in memory (tests and generated scenes): one default grey
/// material, every triangle using it. Throws Error on a non-finite coordinate.
Scene make_scene(std::vector<float> triangles, std::string name = "<memory>");

}  // namespace kdray
