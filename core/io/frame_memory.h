// frame_memory.h — what one frame of an image size costs in memory, host and device, so that a
// render too large for the machine is refused before it starts (a 23000 x 23000 render file once
// grew past 19 GB of host memory and kept going) instead of failing, or swapping, halfway.
#pragma once

#include <cstdint>

namespace kdray {

struct FrameMemory {
    std::uint64_t host_bytes = 0;    // the frame's buffers and encoded files on the host
    std::uint64_t device_bytes = 0;  // the render kernels' per-pixel buffers on the device
    std::uint64_t largest_device_buffer = 0;
};

/// The per-pixel buffers of a width x height frame (kd_shared.h's KdHit and KdRayCounts, the
/// float image, the AOV's normals when `aov`), host and device, plus the encoded image files.
FrameMemory estimate_frame_memory(std::uint64_t width, std::uint64_t height, bool aov);

/// The host's physical memory in bytes (0 when unknown).
std::uint64_t physical_memory_bytes();

}  // namespace kdray
