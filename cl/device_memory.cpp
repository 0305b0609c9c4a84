// device_memory.cpp — counted device buffers and growable device arrays.
#include "cl/device_memory.h"

#include <algorithm>
#include <utility>

#include "cl/cl_error.h"

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

void DeviceArray::release() {
    if (owner_) owner_->current_ -= bytes_;
    buffer_ = cl::Buffer();
    bytes_ = 0;
    owner_ = nullptr;
}

DeviceArray DeviceMemory::allocate(std::size_t bytes, const std::string& what) {
    DeviceArray array;
    array.buffer_ = device_.allocate(bytes, what);
    array.bytes_ = std::max<std::size_t>(bytes, 1);
    array.owner_ = this;
    current_ += array.bytes_;
    peak_ = std::max(peak_, current_);
    return array;
}

void DeviceMemory::reserve(DeviceArray& array, std::size_t bytes, std::size_t used,
                           const std::string& what) {
    if (array.owner_ && bytes <= array.bytes_) return;
    DeviceArray grown = allocate(std::max(bytes, 2 * array.bytes_), what);
    if (used > 0)
        with_cl_context("growing " + what, [&] {
            device_.queue().enqueueCopyBuffer(array.buffer_, grown.buffer_, 0, 0, used);
        });
    array = std::move(grown);
}

}  // namespace kdray
