#include "cl/renderer/scene_arrays.h"

#include <cstdint>
#include <cstring>
#include <string>

#include "cl/runtime/cl_error.h"
#include "core/error.h"

namespace kdray {
namespace {

/// An array of SceneArrays and the KdSceneLayout offset that says where it lies.
struct Section {
    HostArray SceneArrays::*array;
    kd_u32 KdSceneLayout::*offset;
    const char* name;
};

/// KdSceneLayout's order: the texel atlas last, the one array that may reach past 4 GiB.
constexpr Section kSections[] = {
    {&SceneArrays::materials, &KdSceneLayout::materials, "materials"},
    {&SceneArrays::lights, &KdSceneLayout::lights, "lights"},
    {&SceneArrays::emitters, &KdSceneLayout::emitters, "emitter table"},
    {&SceneArrays::textures, &KdSceneLayout::textures, "texture table"},
    {&SceneArrays::material_ids, &KdSceneLayout::material_ids, "material ids"},
    {&SceneArrays::vertex_normals, &KdSceneLayout::vertex_normals, "vertex normals"},
    {&SceneArrays::texcoords, &KdSceneLayout::texcoords, "texture coordinates"},
    {&SceneArrays::texels, &KdSceneLayout::texels, "texel atlas"},
};

}  // namespace

SceneArrays frame_scene_arrays(const Scene& scene, const RenderInputs& inputs) {
    SceneArrays a;
    a.materials = HostArray::of(inputs.materials);
    a.lights = HostArray::of(inputs.lights);
    a.emitters = HostArray::of(inputs.emitters);
    a.material_ids = HostArray::of(scene.material_ids);
    a.vertex_normals = HostArray::of(scene.vertex_normals);
    if (inputs.effects.textures) {
        a.textures = HostArray::of(scene.texture_table);
        a.texcoords = HostArray::of(scene.texcoords);
        a.texels = HostArray::of(scene.texels);
    }
    return a;
}

KdSceneLayout layout_scene_arrays(const SceneArrays& arrays, std::size_t* total) {
    KdSceneLayout layout{};
    std::uint64_t end = 0;
    for (const Section& s : kSections) {
        const std::uint64_t at =
            (end + KDRAY_SCENE_ALIGN - 1) / KDRAY_SCENE_ALIGN * KDRAY_SCENE_ALIGN;
        if (at > UINT32_MAX)
            throw Error("the scene's " + std::string(s.name) + " would start " +
                        std::to_string(at) +
                        " bytes into the render kernels' scene buffer, past the 4 GiB that its "
                        "32-bit offsets address");
        layout.*s.offset = kd_u32(at);
        end = at + (arrays.*s.array).bytes;
    }
    layout.has_vertex_normals = arrays.vertex_normals.bytes != 0 ? 1u : 0u;
    *total = std::size_t(end);
    return layout;
}

DeviceSceneArrays upload_scene_arrays(ClDevice& device, const SceneArrays& arrays) {
    DeviceSceneArrays out;
    std::size_t total = 0;
    out.layout = layout_scene_arrays(arrays, &total);
    out.buffer = device.allocate(total, "scene arrays");
    device.write_mapped(
        out.buffer, total,
        [&](unsigned char* base) {
            std::size_t end = 0;
            for (const Section& s : kSections) {
                const HostArray& a = arrays.*s.array;
                const std::size_t at = out.layout.*s.offset;
                if (a.bytes == 0) continue;
                std::memset(base + end, 0, at - end); /* the alignment gap: defined bytes */
                std::memcpy(base + at, a.data, a.bytes);
                end = at + a.bytes;
            }
            std::memset(base + end, 0, total - end);
        },
        "uploading the scene arrays");
    return out;
}

}  // namespace kdray
