// device_memory.h — device buffers whose bytes a build counts, so that BuildReport::device_bytes
// is the true peak of what the build held at once, and arrays that grow (with their contents
// copied on the device) for the lists whose final length is only known level by level.
#pragma once

#include <cstddef>
#include <string>

#include <CL/opencl.hpp>

#include "cl/device.h"

namespace kdray {

class DeviceMemory;

/// A device buffer counted by its DeviceMemory while it lives. Move-only.
class DeviceArray {
  public:
    DeviceArray() = default;
    DeviceArray(DeviceArray&& other) noexcept { *this = std::move(other); }
    DeviceArray& operator=(DeviceArray&& other) noexcept;
    DeviceArray(const DeviceArray&) = delete;
    DeviceArray& operator=(const DeviceArray&) = delete;
    ~DeviceArray() { release(); }

    const cl::Buffer& buffer() const { return buffer_; }
    std::size_t bytes() const { return bytes_; }

  private:
    friend class DeviceMemory;
    void release();

    cl::Buffer buffer_;
    std::size_t bytes_ = 0;
    DeviceMemory* owner_ = nullptr;
};

/// Allocates counted buffers on one device and remembers the peak of their sum.
class DeviceMemory {
  public:
    explicit DeviceMemory(ClDevice& device) : device_(device) {}

    /// A buffer of `bytes` (at least one byte is allocated); `what` names it in errors.
    DeviceArray allocate(std::size_t bytes, const std::string& what);

    /// Makes `array` hold at least `bytes`, keeping its first `used` bytes: grows to the larger of
    /// `bytes` and twice its size, so that appending level by level copies O(total) bytes.
    void reserve(DeviceArray& array, std::size_t bytes, std::size_t used, const std::string& what);

    std::size_t current_bytes() const { return current_; }
    std::size_t peak_bytes() const { return peak_; }

  private:
    friend class DeviceArray;
    ClDevice& device_;
    std::size_t current_ = 0;
    std::size_t peak_ = 0;
};

}  // namespace kdray
