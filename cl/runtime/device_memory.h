// device_memory.h — device buffers whose bytes a build counts, so that BuildReport::device_bytes
// is the true peak of what the build held at once, and arrays that grow (with their contents
// copied on the device) for the lists whose final length is only known level by level.
//
// A released buffer is kept for reuse by a later allocation of about its size: a build allocates
// a fresh set of per-level arrays at each of its 30 to 60 levels, and on a CPU device (PoCL) every
// fresh buffer is fresh host pages, so the page faults of touching them cost about 50 ms of CPU
// time per kitchen build (perf, kernel samples per build) before the buffers were recycled. What
// a build holds when it ends goes to the device's BufferPool for the next build. Reuse is safe on
// the device's in-order queue: work enqueued on a recycled buffer runs after every earlier
// command that used it.
#pragma once

#include <cstddef>
#include <string>
#include <vector>

#include <CL/opencl.hpp>

#include "cl/runtime/device.h"

namespace kdray {

class DeviceMemory;
class ClPrimitives;

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
    /// The buffer, no longer counted or recycled: for buffers that outlive the build (the tree
    /// handed to the renderer), which no later build may take.
    cl::Buffer detach();

  private:
    friend class DeviceMemory;
    void release();

    cl::Buffer buffer_;
    std::size_t bytes_ = 0;
    DeviceMemory* owner_ = nullptr;
};

/// Allocates counted buffers on one device (its own spares first, then the device's BufferPool,
/// then new ones), recycles released ones, and remembers the peak of the bytes it held at once (in
/// use or kept for reuse).
class DeviceMemory {
  public:
    explicit DeviceMemory(ClDevice& device) : device_(device) {}
    /// Gives the spares it still holds to the device's BufferPool.
    ~DeviceMemory();
    /// From now on every released buffer is kept (for the BufferPool), none given back: for the
    /// end of a build, when its arrays are released one after another.
    void close() { closing_ = true; }
    DeviceMemory(const DeviceMemory&) = delete;
    DeviceMemory& operator=(const DeviceMemory&) = delete;

    /// A buffer of at least `bytes` (at least one byte; a recycled buffer may be up to twice as
    /// large); `what` names it in errors. A new buffer, when no kept one fits, has `room` bytes
    /// if that is more: room for the slightly larger requests that follow (growing arrays).
    DeviceArray allocate(std::size_t bytes, const std::string& what, std::size_t room = 0);

    /// Makes `array` hold at least `bytes`, keeping its first `used` bytes: grows to the larger of
    /// `bytes` and twice its size, so that appending level by level copies O(total) bytes.
    void reserve(DeviceArray& array, std::size_t bytes, std::size_t used, const std::string& what,
                 ClPrimitives& primitives);

    std::size_t current_bytes() const { return current_; }
    std::size_t peak_bytes() const { return peak_; }

  private:
    friend class DeviceArray;
    void recycle(cl::Buffer buffer, std::size_t bytes);

    ClDevice& device_;
    BufferPool spares_;  // released buffers, for reuse (their bytes also counted in current_)
    bool closing_ = false;
    std::size_t current_ = 0;
    std::size_t peak_ = 0;
};

}  // namespace kdray
