// scene_arrays.h — a frame's read-only shading arrays (materials, lights, emitters, the texture
// table and atlas, and the per-triangle material ids, vertex normals and texture coordinates) in
// one device buffer, laid out as core/device/kd_shared.h's KdSceneLayout describes, so that the
// render kernels take one buffer and one record for them instead of a buffer each.
//
// Each array is written from the host straight to its offset (one write each, as when each had a
// buffer of its own): packing adds no copy. The tree's nodes, leaf indices and triangles are not
// packed: the builder leaves them on the device in buffers of its own, and packing them would
// copy them every frame.
#pragma once

#include <cstddef>
#include <vector>

#include <CL/opencl.hpp>

#include "cl/runtime/device.h"
#include "core/device/kd_shared.h"
#include "core/render/render_setup.h"
#include "core/scene/scene.h"

namespace kdray {

/// One array on the host: its first byte and its size.
struct HostArray {
    const void* data = nullptr;
    std::size_t bytes = 0;

    template <class T>
    static HostArray of(const std::vector<T>& v) {
        return {v.data(), v.size() * sizeof(T)};
    }
};

/// The arrays a frame's render kernels read, one per KdSceneLayout offset; an array the frame
/// does not use is empty.
struct SceneArrays {
    HostArray materials, lights, emitters, textures, material_ids, vertex_normals, texcoords,
        texels;
};

/// The frame's arrays: the texture arrays with textures only, the vertex normals where the scene
/// has them.
SceneArrays frame_scene_arrays(const Scene& scene, const RenderInputs& inputs);

/// Where each array lies: in KdSceneLayout's order, each at the first multiple of
/// KDRAY_SCENE_ALIGN at or after the end of the one before. *total: the bytes of the whole.
/// Throws Error when an offset would pass 32 bits (every array but the last, the texel atlas,
/// must end within 4 GiB: a scene of tens of millions of triangles).
KdSceneLayout layout_scene_arrays(const SceneArrays& arrays, std::size_t* total);

/// The arrays in one new device buffer with their layout, written through one mapping of the
/// buffer (the host arrays may change once it returns).
struct DeviceSceneArrays {
    cl::Buffer buffer;
    KdSceneLayout layout{};
};
DeviceSceneArrays upload_scene_arrays(ClDevice& device, const SceneArrays& arrays);

}  // namespace kdray
