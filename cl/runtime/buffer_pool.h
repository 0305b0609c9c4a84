// buffer_pool.h — the device buffers that finished builds gave back, kept on the device for the
// next build. An animation rebuilds its tree every frame with arrays of about the same sizes, and
// on a CPU device (PoCL) a fresh buffer is fresh host pages: the page faults of touching them were
// 45 ms of kernel-mode CPU per dragon res2 build (25k faults, mostly its 52 MB of node records and
// 40 MB of masks, which glibc maps afresh each time), 15% of the build's CPU time. With the pool:
// 1.8k faults and 7 ms, build 141.7 -> 123.3 ms (median of 5 interleaved rounds of 7 builds);
// Kitchen and Sponza, whose arrays glibc already reused, unchanged. A build counts in its device
// bytes what it takes from the pool; what the pool keeps between builds is at most its capacity.
//
// DeviceMemory keeps a build's own spares in one too (without a capacity: it bounds them itself).
#pragma once

#include <cstddef>
#include <cstdint>
#include <vector>

#include <CL/opencl.hpp>

namespace kdray {

class BufferPool {
  public:
    /// capacity: the most bytes the pool keeps; beyond it the oldest buffers are released.
    explicit BufferPool(std::size_t capacity = SIZE_MAX) : capacity_(capacity) {}

    /// The smallest kept buffer of bytes..limit bytes, removed from the pool, and its size in
    /// *taken_bytes; an empty cl::Buffer when none fits.
    cl::Buffer take(std::size_t bytes, std::size_t limit, std::size_t* taken_bytes);
    /// Keeps `buffer` (of `bytes`) for a later take.
    void keep(cl::Buffer buffer, std::size_t bytes);
    /// Releases the oldest kept buffer; returns its size (0 when the pool is empty).
    std::size_t release_oldest();
    /// Gives the oldest kept buffer to `other`; returns its size (0 when the pool is empty).
    std::size_t move_oldest_into(BufferPool& other);
    /// Gives every kept buffer to `other`, oldest first.
    void move_into(BufferPool& other);
    /// Releases every kept buffer.
    void clear();

    std::size_t bytes() const { return bytes_; }
    /// The most bytes the pool keeps.
    std::size_t capacity() const { return capacity_; }
    bool empty() const { return kept_.empty(); }

  private:
    struct Kept {
        std::size_t bytes;
        cl::Buffer buffer;
    };
    std::vector<Kept> kept_;  // oldest first
    std::size_t bytes_ = 0;
    std::size_t capacity_;
};

}  // namespace kdray
