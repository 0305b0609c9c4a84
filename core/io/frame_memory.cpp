#include "core/io/frame_memory.h"

#include <unistd.h>

#include <algorithm>

#include "core/device/kd_shared.h"

namespace kdray {

FrameMemory estimate_frame_memory(std::uint64_t width, std::uint64_t height, bool aov) {
    const std::uint64_t pixels = width * height;
    const std::uint64_t rgb = 3 * sizeof(float), hit = sizeof(KdHit), counts = sizeof(KdRayCounts);
    // With the AOV, its normals and the centre rays' walk costs (KdTraceCost).
    const std::uint64_t normals = aov ? 3 * sizeof(float) + sizeof(KdTraceCost) : 0;
    // The 8-bit image and its encoding (at most its raw size, a little over), the AOV's seven
    // 32-bit channels and their encoding.
    const std::uint64_t encoded = 2 * 3 + (aov ? 2 * 7 * 4 : 0);
    FrameMemory m;
    // Host: the read-back image, hits, per-pixel counts, normals (twice: read back, converted).
    m.host_bytes = pixels * (rgb + hit + counts + 2 * normals + encoded);
    m.device_bytes = pixels * (rgb + hit + counts + normals);
    m.largest_device_buffer =
        pixels * std::max<std::uint64_t>(rgb, std::max<std::uint64_t>(hit, counts));
    return m;
}

std::uint64_t physical_memory_bytes() {
    const long pages = ::sysconf(_SC_PHYS_PAGES), page_size = ::sysconf(_SC_PAGESIZE);
    return pages > 0 && page_size > 0 ? std::uint64_t(pages) * std::uint64_t(page_size) : 0;
}

}  // namespace kdray
