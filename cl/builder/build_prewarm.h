// build_prewarm.h — the first build's large buffers, made and touched before it (Issue #28, "cold
// = warm"). A build takes its arrays from the device's BufferPool when one of about the right size
// is there (DeviceMemory::allocate), and warm builds find the last build's there; a first build
// makes them all afresh, and on a CPU device (PoCL) fresh buffers are fresh host pages: the
// Kitchen's first build took 20k page faults against 0.1-4.5k for the builds after it, 99.6
// against 63-83 ms. Sized from the triangle count alone (the load knows it before the device
// opens), the buffers that hold most of those pages are made and filled while the builder's
// programs build, and left in the pool for the first build to take. The host memory the tree is
// downloaded into is made and written before that (prewarm_host_tree), and OpenClTreeBuilder
// holds it for the first build.
#pragma once

#include <cstddef>
#include <vector>

#include "cl/builder/opencl_builder.h"
#include "cl/runtime/device.h"

namespace kdray::build_detail {

/// A buffer the first build is expected to ask for: `bytes` for a scene of the given triangle
/// count, large enough for every request of bytes/2..bytes (BufferPool::take's limit).
struct ExpectedBuffer {
    const char* what;  // the builder's name of the array it stands for
    std::size_t bytes;
};

/// The buffers worth making ahead for a build of `triangles` triangles with `params` (none for
/// small scenes, whose pages are few; no masks for binned small nodes, which make none).
std::vector<ExpectedBuffer> expected_build_buffers(std::size_t triangles,
                                                   const BuildParams& params);

/// Makes expected_build_buffers(triangles, params) on `device`, enqueues a fill of each (without
/// waiting: the device writes them while the host builds programs) and gives them to its
/// BufferPool. Returns the bytes made.
std::size_t prewarm_build_buffers(ClDevice& device, std::size_t triangles,
                                  const BuildParams& params);

/// Host memory for the first build's downloaded tree (build_opencl's host_storage): vectors of
/// the capacity a scene of `triangles` triangles needs, their pages written once, empty for
/// small scenes.
KdTree prewarm_host_tree(std::size_t triangles);

/// A closed surface: a unit UV sphere of 2 * rings * segments triangles (tests' scenes).
Scene uv_sphere(int rings, int segments);

/// A closed surface without high-valence vertices: a unit sphere of 12 n^2 triangles, each face of
/// a cube cut n x n and pushed out onto the sphere (the warm-up's scene).
Scene cube_sphere(int n);

/// Builds a small generated scene with `params`, so that each of the builder's kernels has been
/// launched once: a first launch costs more than a later one (PoCL compiles or loads the kernel's
/// work-group function then), about 1 ms of the CornellBox's 1.8 ms first build against 0.6 ms.
/// Sized after `triangles`, the scene the first build will be given, while that is small.
void warm_up_launches(ClDevice& device, const BuildParams& params, std::size_t triangles);

}  // namespace kdray::build_detail
