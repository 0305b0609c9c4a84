// device_memory.cpp — counted device buffers and growable device arrays.
#include "cl/runtime/device_memory.h"

#include <algorithm>
#include <utility>

#include "cl/runtime/cl_error.h"
#include "cl/runtime/primitives.h"

namespace kdray {

DeviceArray& DeviceArray::operator=(DeviceArray&& other) noexcept {
    if (this != &other) {
        release();
        buffer_ = std::move(other.buffer_);
        bytes_ = std::exchange(other.bytes_, 0);
        owner_ = std::exchange(other.owner_, nullptr);
    }
    return *this;
}

cl::Buffer DeviceArray::detach() {
    if (owner_) owner_->current_ -= bytes_;
    owner_ = nullptr;
    bytes_ = 0;
    return std::exchange(buffer_, cl::Buffer());
}

void DeviceArray::release() {
    if (owner_) owner_->recycle(std::move(buffer_), bytes_);
    buffer_ = cl::Buffer();
    bytes_ = 0;
    owner_ = nullptr;
}

DeviceArray DeviceMemory::allocate(std::size_t bytes, const std::string& what, std::size_t room) {
    bytes = std::max<std::size_t>(bytes, 1);
    DeviceArray array;
    array.owner_ = this;
    // The smallest spare that fits and wastes at most half of itself (small requests may take any
    // spare up to 4 KiB, the size of a page): the build's own, else one an earlier build left.
    const std::size_t limit = std::max<std::size_t>(2 * bytes, 4096);
    std::size_t taken_bytes = 0;
    array.buffer_ = spares_.take(bytes, limit, &taken_bytes);
    if (array.buffer_()) {
        array.bytes_ = taken_bytes;
        return array;  // already counted in current_
    }
    array.buffer_ = device_.buffer_pool().take(bytes, limit, &taken_bytes);
    array.bytes_ = taken_bytes;
    if (!array.buffer_()) {
        array.bytes_ = std::max(bytes, room);
        array.buffer_ = device_.allocate(array.bytes_, what);
    }
    current_ += array.bytes_;
    peak_ = std::max(peak_, current_);
    return array;
}

void DeviceMemory::recycle(cl::Buffer buffer, std::size_t bytes) {
    spares_.keep(std::move(buffer), bytes);
    // Spares beyond half of what is in use go to the device's pool, oldest first, so that
    // recycling raises the build's peak only a little while it keeps the buffers of the level
    // before, which the next level's arrays mostly fit (kernel time 52 -> 30 ms per build; with
    // no bound it was 30 ms too, but the peak 225 MB). To the pool, not released: the next build
    // takes them (released, the depth-first large stage's arenas were fresh pages in every
    // Kitchen build: 5 new buffers of 1-11 MB each, 2 after). Half rather than all of it: device bytes per
    // triangle Kitchen 901 -> 804, Robots 979 -> 889, Sponza 1026 -> 952, build time the same
    // within noise (kdray build --repeat 7, alternated twice, quiet 2-core PoCL).
    while (!closing_ && 2 * spares_.bytes() > current_ - spares_.bytes() && !spares_.empty())
        current_ -= spares_.move_oldest_into(device_.buffer_pool());
}

DeviceMemory::~DeviceMemory() {
    spares_.move_into(device_.buffer_pool());
}

void DeviceMemory::reserve(DeviceArray& array, std::size_t bytes, std::size_t used,
                           const std::string& what, ClPrimitives& primitives) {
    if (array.owner_ && bytes <= array.bytes_) return;
    DeviceArray grown = allocate(std::max(bytes, 2 * array.bytes_), what);
    if (used > 0)
        with_cl_context("growing " + what,
                        [&] { primitives.copy(array.buffer_, grown.buffer_, used); });
    array = std::move(grown);
}

}  // namespace kdray
