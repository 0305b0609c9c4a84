// device.h — the OpenCL device kdray runs on: listing every platform's devices (for `kdray stats`),
// choosing one by index or name, and the context and in-order queue that the builder and tracer
// share. Nothing here assumes a particular implementation: PoCL on a CPU and a vendor GPU driver
// are reached the same way, through the ICD loader.
#pragma once

#include <cstddef>
#include <cstdint>
#include <functional>
#include <map>
#include <memory>
#include <string>
#include <vector>

#include <CL/opencl.hpp>

#include "cl/runtime/buffer_pool.h"

namespace kdray {

/// One device as `kdray stats` reports it. `index` is its position in list_cl_devices(), the
/// number that ClDevice's selector accepts.
struct ClDeviceInfo {
    int index = 0;
    std::string platform;
    std::string name;
    std::string vendor;
    std::string type;     // "GPU", "CPU", "accelerator", ...
    std::string version;  // CL_DEVICE_VERSION, e.g. "OpenCL 3.0 PoCL ..."
    unsigned compute_units = 0;
    std::uint64_t global_mem_bytes = 0;
    std::uint64_t max_alloc_bytes = 0;
    /// Whether the device has double precision (CL_DEVICE_DOUBLE_FP_CONFIG not 0: cl_khr_fp64).
    bool fp64 = false;
    /// Whether the driver keeps each of its worker threads on one CPU: PoCL's pthread device on
    /// Linux, asked to (driver_threads.h).
    bool threads_pinned = false;
};

/// Every device of every platform, in platform order. Throws Error, with the command that installs
/// PoCL, when the ICD loader finds no platform at all.
std::vector<ClDeviceInfo> list_cl_devices();

struct BufferLedger;
class ProgramCache;

/// What the host has asked of a device's queue, counted where it is asked (ClDevice's blocking
/// calls, launch.h's enqueue_kernel): a build reports the difference over its run. On a discrete
/// GPU each sync is a round trip of 10-50 microseconds in which the device idles, so a build's
/// syncs are a floor on its time that no faster kernel lowers.
struct DeviceTraffic {
    std::uint64_t syncs = 0;      // host waits: blocking reads and writes, finishes
    std::uint64_t launches = 0;   // kernels enqueued
    std::uint64_t transfers = 0;  // reads and writes between host and device, blocking or not
};

/// An opened device: its context, one in-order command queue, and the buffers that finished builds
/// gave back (BufferPool).
class ClDevice {
  public:
    /// selector: "" picks the first GPU, or the first device when there is no GPU; "gpu", "cpu"
    /// or "accelerator" (any case) the first device of that type; a number picks that index of
    /// list_cl_devices(); anything else picks the first device whose name contains it
    /// (case-insensitive). Throws Error listing the devices when nothing matches.
    explicit ClDevice(const std::string& selector = "");
    /// Releases the kept buffers; in a sanitizer build (KDRAY_SANITIZE) a buffer of allocate()'s
    /// still alive then is reported by its name and fails the process (exit 23, as LeakSanitizer
    /// does): LeakSanitizer itself cannot tell kdray's buffers from the runtime's own memory.
    ~ClDevice();
    ClDevice(const ClDevice&) = delete;
    ClDevice& operator=(const ClDevice&) = delete;

    const cl::Context& context() const { return context_; }
    const cl::Device& device() const { return device_; }
    cl::CommandQueue& queue() { return queue_; }
    const ClDeviceInfo& info() const { return info_; }
    /// Whether the device is the host's own processor (PoCL's CPU device, say), where the stages
    /// that are shaped by device kind take their CPU shape. The one place kdray asks the kind.
    bool is_cpu() const { return info_.type == "CPU"; }
    /// Whether CL_DEVICE_TYPE says GPU: the stages shaped for GPUs (the builder's per-level small
    /// stage) take that shape by default there.
    bool is_gpu() const { return info_.type == "GPU"; }

    /// A device buffer of `bytes` (at least 1, since OpenCL forbids empty buffers). Throws Error
    /// naming `what` and the size when it exceeds CL_DEVICE_MAX_MEM_ALLOC_SIZE or fails.
    cl::Buffer allocate(std::size_t bytes, const std::string& what) const;
    /// The bytes of every buffer allocate() has made: what reuse (DeviceMemory, BufferPool)
    /// saved shows as bytes not allocated (tests).
    std::uint64_t allocated_bytes() const { return allocated_bytes_; }
    /// The names (allocate's `what`) of the buffers allocate() made that the runtime has not
    /// deleted yet: every reference to them released, and the commands using them done.
    std::vector<std::string> live_buffers() const;

    /// Every transfer between host and device, every host wait and every launch on the queue
    /// goes through these, so that traffic() counts them. read and write wait for the transfer;
    /// enqueue_read and enqueue_write do not (`to` or `from` must then live until the next
    /// wait). `what` names the step in errors.
    void read(const cl::Buffer& buffer, std::size_t offset, std::size_t bytes, void* to,
              const std::string& what);
    void write(const cl::Buffer& buffer, std::size_t offset, std::size_t bytes, const void* from,
               const std::string& what);
    void enqueue_read(const cl::Buffer& buffer, std::size_t offset, std::size_t bytes, void* to,
                      const std::string& what);
    void enqueue_write(const cl::Buffer& buffer, std::size_t offset, std::size_t bytes,
                       const void* from, const std::string& what);
    void finish(const std::string& what);
    /// Writes the whole of `buffer`'s first `bytes` through one mapping: fill(base) writes every
    /// byte of [base, base + bytes). One transfer and one wait (the map's), for data gathered from
    /// several host arrays. A write per part would be a transfer each, and Oclgrind 21.10's
    /// uninitialised-value checker keeps only a buffer's last partial host write.
    void write_mapped(const cl::Buffer& buffer, std::size_t bytes,
                      const std::function<void(unsigned char* base)>& fill,
                      const std::string& what);
    /// Waits for `count` values of `bytes` each, `stride` bytes apart from byte `offset` of
    /// `buffer`, packed into `to`: one transfer (clEnqueueReadBufferRect, a row per value) where
    /// a read per value was a transfer each. The buffer must hold count * stride bytes past
    /// `offset` (some implementations check the whole last row).
    void read_strided(const cl::Buffer& buffer, std::size_t offset, std::size_t stride,
                      std::size_t bytes, std::size_t count, void* to, const std::string& what);
    /// Enqueues `kernel` (its arguments already set) over `global` items in groups of `local`,
    /// counted in traffic().launches; errors are the caller's (cl::Error).
    void launch(cl::Kernel& kernel, const cl::NDRange& global, const cl::NDRange& local);
    /// The work-group size of a 1D launch of `kernel` that prefers `preferred` (choose_group_1d
    /// over the kernel's limits), queried once per kernel: a build makes ~700 launches of a few
    /// dozen kernels, and the query is five driver calls.
    std::size_t group_1d(cl::Kernel& kernel, std::size_t preferred);
    const DeviceTraffic& traffic() const { return traffic_; }

    /// Buffers kept for the next build: at most an eighth of the device's memory, and 1 GiB.
    BufferPool& buffer_pool() { return buffer_pool_; }

    /// The programs and kernels built for this device (cl/runtime/program_cache.h), released with
    /// it. Thread-safe through its own locks, hence usable on a const device.
    ProgramCache& program_cache() const { return *program_cache_; }

  private:
    /// group_1d's answers; each keeps its kernel, so that no other kernel takes its handle.
    struct Group1d {
        cl::Kernel kernel;
        std::size_t group;
    };
    std::map<std::pair<cl_kernel, std::size_t>, Group1d> group_1d_;
    cl::Device device_;
    cl::Context context_;
    cl::CommandQueue queue_;
    ClDeviceInfo info_;
    BufferPool buffer_pool_;
    DeviceTraffic traffic_;
    mutable std::uint64_t allocated_bytes_ = 0;
    std::shared_ptr<BufferLedger> ledger_;  // the buffers of allocate() not deleted yet
    std::unique_ptr<ProgramCache> program_cache_;
};

/// The devices on one line, for error messages: "0: NAME (VENDOR, TYPE, VERSION); 1: ...".
std::string describe_cl_devices(const std::vector<ClDeviceInfo>& devices);

}  // namespace kdray
