// primitives.h — data-parallel primitives on the device (cl/runtime/kernels/primitives.cl):
// exclusive scan, stream compaction and segmented box reduction, the building blocks of Zhou et
// al.'s (2008) kd-tree construction. All calls only enqueue work on the device's in-order queue,
// except where a count must come back to the host (compact).
#pragma once

#include <cstddef>
#include <memory>

#include <CL/opencl.hpp>

#include "cl/runtime/device.h"
#include "cl/runtime/device_memory.h"

namespace kdray {

/// Cheap to construct: the program and its kernels are made once per device and kept.
class ClPrimitives {
  public:
    /// The scratch arrays (a scan's chunk sums, a compaction's positions) come from `memory`, a
    /// build's, which counts them and recycles them from call to call; without one, from a
    /// DeviceMemory of the primitives' own (which takes from the device's BufferPool). A fresh
    /// buffer per scan was an allocation and, on a CPU device, fresh pages per call.
    explicit ClPrimitives(ClDevice& device, DeviceMemory* memory = nullptr);

    /// out[k] = in[0] + ... + in[k-1] for k in [0, n], so out holds n + 1 uints and out[n] is the
    /// total. out may be in. n may be 0 (out[0] = 0). Throws Error when out is smaller.
    void exclusive_scan(const cl::Buffer& in, const cl::Buffer& out, std::size_t n);

    /// out[k] = value for k in [0, n). A kernel rather than clEnqueueFillBuffer: Oclgrind 21.10
    /// (Debian 12's) does not mark a filled buffer initialised, so its uninitialised-value check
    /// reported every later read of one; the kernel is the same single pass.
    void fill(const cl::Buffer& out, cl_uint value, std::size_t n);

    /// The first `bytes` (a multiple of 4) of `from` into `to`. A kernel rather than
    /// clEnqueueCopyBuffer for the same reason as fill: Oclgrind 21.10 resizes a buffer's
    /// initialisation record to the size of a host-side copy into it, so every later kernel write
    /// past the copied part read back as uninitialised.
    void copy(const cl::Buffer& from, const cl::Buffer& to, std::size_t bytes);

    /// Writes the values[k] with flags[k] (0 or 1) != 0 to out, in order, and returns how many
    /// (read back: it synchronises).
    std::size_t compact(const cl::Buffer& values, const cl::Buffer& flags, const cl::Buffer& out,
                        std::size_t n);

    /// chunk_start[s] = first reduction chunk of segment s, for s in [0, segments] (segments + 1
    /// uints, the last the total), from the segment sizes seg_count.
    void box_chunk_starts(const cl::Buffer& seg_count, std::size_t segments,
                          const cl::Buffer& chunk_start);

    /// seg_boxes[s] = union of boxes[seg_start[s] .. seg_start[s] + seg_count[s]) (6 floats each,
    /// lo.xyz hi.xyz; empty segments give lo = +inf, hi = -inf). chunk_start comes from
    /// box_chunk_starts and total_chunks is its last entry; chunk_boxes holds total_chunks boxes.
    void reduce_box_segments(const cl::Buffer& boxes, const cl::Buffer& seg_start,
                             const cl::Buffer& seg_count, const cl::Buffer& chunk_start,
                             std::size_t segments, std::size_t total_chunks,
                             const cl::Buffer& chunk_boxes, const cl::Buffer& seg_boxes);
    /// reduce_box_segments' second step alone: seg_boxes[s] = union of chunk_boxes[chunk_start[s]
    /// .. chunk_start[s + 1]), for chunk boxes reduced elsewhere (the builder's element-parallel
    /// large stage reduces them a work-group per chunk).
    void union_chunk_boxes(const cl::Buffer& chunk_boxes, const cl::Buffer& chunk_start,
                           std::size_t segments, const cl::Buffer& seg_boxes);

  private:
    struct Kernels;
    ClDevice& device_;
    std::unique_ptr<DeviceMemory> own_memory_;  // only when no memory was given
    DeviceMemory& memory_;
    // Created once per device (cached_kernels), shared by every ClPrimitives of the device.
    Kernels& kernels_;
};

}  // namespace kdray
