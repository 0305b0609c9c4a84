// primitives.cpp — host side of the scan, compaction and segmented reduction kernels.
#include "cl/runtime/primitives.h"

#include <algorithm>

#include "cl/runtime/launch.h"
#include "cl/runtime/program_cache.h"
#include "core/error.h"

namespace kdray {

struct ClPrimitives::Kernels {
    cl::Kernel scan_chunks, scan_single, add_chunk_offsets, add_offsets_by_chunk, compact_by_flags;
    cl::Kernel fill, copy;
    cl::Kernel reduce_box_chunks, reduce_box_segments, count_box_chunks;
};

ClPrimitives::ClPrimitives(ClDevice& device, DeviceMemory* memory)
    : device_(device),
      own_memory_(memory ? nullptr : std::make_unique<DeviceMemory>(device)),
      memory_(memory ? *memory : *own_memory_),
      kernels_(cached_kernels<Kernels>(device, "", [&] {
          const cl::Program program = cached_program(device, "primitives.cl");
          Kernels k;
          k.scan_chunks = make_kernel(program, "kd_scan_chunks");
          k.scan_single = make_kernel(program, "kd_scan_single");
          k.add_chunk_offsets = make_kernel(program, "kd_add_chunk_offsets");
          k.add_offsets_by_chunk = make_kernel(program, "kd_add_chunk_offsets_by_chunk");
          k.compact_by_flags = make_kernel(program, "kd_compact_by_flags");
          k.fill = make_kernel(program, "kd_fill_uint");
          k.copy = make_kernel(program, "kd_copy_uint");
          k.reduce_box_chunks = make_kernel(program, "kd_reduce_box_chunks");
          k.reduce_box_segments = make_kernel(program, "kd_reduce_box_segments");
          k.count_box_chunks = make_kernel(program, "kd_count_box_chunks");
          return k;
      })) {}

namespace {
/// The longest scan one work-item does on a CPU device (exclusive_scan).
constexpr std::size_t kCpuSingleScan = 4096;
}  // namespace

void ClPrimitives::exclusive_scan(const cl::Buffer& in, const cl::Buffer& out, std::size_t n) {
    // The total goes to out[n]: a buffer of n entries would be written past its end, which no
    // CPU device notices (a scan of second-pass offsets did so until Oclgrind reported it).
    const std::size_t out_bytes =
        with_cl_context("asking a scan's output size", [&] { return out.getInfo<CL_MEM_SIZE>(); });
    if (out_bytes < (n + 1) * sizeof(cl_uint))
        throw Error("exclusive scan of " + std::to_string(n) + " values into a buffer of " +
                    std::to_string(out_bytes) + " bytes: it needs " +
                    std::to_string((n + 1) * sizeof(cl_uint)) + " (the total comes last)");
    // Chunk length: enough chunks to fill the device (a few hundred items per compute unit), at
    // least 16 elements so the sequential loop amortises the launch, and one chunk for small n.
    const std::size_t lanes = std::max<std::size_t>(1, device_.info().compute_units) * 256;
    const std::size_t chunk = std::max<std::size_t>(16, (n + lanes - 1) / lanes);
    // On a CPU device one work-item scans a few thousand values in microseconds, less than the
    // chunked scan's two launches and its recursion over the sums (a large level's slot scan of
    // ~26k values made 7 launches, its sums' scans 5 of them). A GPU's single work-item walks
    // memory at its latency: there only the shortest arrays are scanned so.
    const std::size_t single_limit = device_.is_cpu() ? kCpuSingleScan : 16;
    if (n <= std::max(chunk, single_limit)) {
        enqueue_kernel(device_, kernels_.scan_single, 1, in, out, cl_uint(n));
        return;
    }
    // Scan: chunk sums, then the scan of the sums (recursively), then add the chunk offsets.
    const std::size_t chunks = (n + chunk - 1) / chunk;
    // Released at return while the launches below may still be queued: a later command that
    // reuses it runs after them on the in-order queue (device_memory.h).
    const DeviceArray sums_array =
        memory_.allocate((chunks + 1) * sizeof(cl_uint), "scan chunk sums");
    const cl::Buffer& sums = sums_array.buffer();
    enqueue_kernel(device_, kernels_.scan_chunks, chunks, in, out, cl_uint(n), cl_uint(chunk),
                   cl_uint(chunks), sums);
    exclusive_scan(sums, sums, chunks);
    // On a CPU device one work-item per element costs more than the adding: by chunk, a 10^6
    // scan on PoCL (2 cores, bench_primitives, median of 7) went from 3.2 to 0.51 ms, 10^5 from
    // 0.38 to 0.09. GPUs keep one item per element, which coalesces.
    if (device_.is_cpu())
        enqueue_kernel(device_, kernels_.add_offsets_by_chunk, chunks, out, cl_uint(n),
                       cl_uint(chunk), cl_uint(chunks), sums);
    else
        enqueue_kernel(device_, kernels_.add_chunk_offsets, n, out, cl_uint(n), cl_uint(chunk),
                       cl_uint(chunks), sums);
}

void ClPrimitives::fill(const cl::Buffer& out, cl_uint value, std::size_t n) {
    enqueue_kernel(device_, kernels_.fill, n, out, value, cl_uint(n));
}

void ClPrimitives::copy(const cl::Buffer& from, const cl::Buffer& to, std::size_t bytes) {
    if (bytes % sizeof(cl_uint) != 0)
        throw Error("internal: a device copy of " + std::to_string(bytes) +
                    " bytes, not a whole number of 32-bit words");
    const std::size_t n = bytes / sizeof(cl_uint);
    enqueue_kernel(device_, kernels_.copy, n, from, to, cl_uint(n));
}

std::size_t ClPrimitives::compact(const cl::Buffer& values, const cl::Buffer& flags,
                                  const cl::Buffer& out, std::size_t n) {
    const DeviceArray positions_array =
        memory_.allocate((n + 1) * sizeof(cl_uint), "compaction positions");
    const cl::Buffer& positions = positions_array.buffer();
    exclusive_scan(flags, positions, n);
    enqueue_kernel(device_, kernels_.compact_by_flags, n, values, flags, positions, cl_uint(n),
                   out);
    cl_uint count = 0;
    device_.read(positions, n * sizeof(cl_uint), sizeof(count), &count,
                 "reading the compacted count");
    return count;
}

void ClPrimitives::box_chunk_starts(const cl::Buffer& seg_count, std::size_t segments,
                                    const cl::Buffer& chunk_start) {
    enqueue_kernel(device_, kernels_.count_box_chunks, segments, seg_count, cl_uint(segments),
                   chunk_start);
    exclusive_scan(chunk_start, chunk_start, segments);
}

void ClPrimitives::reduce_box_segments(const cl::Buffer& boxes, const cl::Buffer& seg_start,
                                       const cl::Buffer& seg_count, const cl::Buffer& chunk_start,
                                       std::size_t segments, std::size_t total_chunks,
                                       const cl::Buffer& chunk_boxes, const cl::Buffer& seg_boxes) {
    enqueue_kernel(device_, kernels_.reduce_box_chunks, total_chunks, boxes, seg_start, seg_count,
                   chunk_start, cl_uint(segments), cl_uint(total_chunks), chunk_boxes);
    union_chunk_boxes(chunk_boxes, chunk_start, segments, seg_boxes);
}

void ClPrimitives::union_chunk_boxes(const cl::Buffer& chunk_boxes, const cl::Buffer& chunk_start,
                                     std::size_t segments, const cl::Buffer& seg_boxes) {
    enqueue_kernel(device_, kernels_.reduce_box_segments, segments, chunk_boxes, chunk_start,
                   cl_uint(segments), seg_boxes);
}

}  // namespace kdray
