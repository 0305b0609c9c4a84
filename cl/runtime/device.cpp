// device.cpp — platform/device enumeration and selection, and the context and queue of the chosen
// device.
#include "cl/runtime/device.h"

#include <algorithm>
#include <cctype>
#include <chrono>
#include <condition_variable>
#include <cstdio>
#include <cstdlib>
#include <filesystem>
#include <map>
#include <mutex>
#include <system_error>

#include <unistd.h>

#include "cl/runtime/cl_error.h"
#include "cl/runtime/driver_environment.h"
#include "cl/runtime/driver_threads.h"
#include "cl/runtime/program_cache.h"
#include "cl/runtime/work_group.h"
#include "core/error.h"

namespace kdray {
namespace {

std::string device_type_name(cl_device_type type) {
    if (type & CL_DEVICE_TYPE_GPU) return "GPU";
    if (type & CL_DEVICE_TYPE_CPU) return "CPU";
    if (type & CL_DEVICE_TYPE_ACCELERATOR) return "accelerator";
    return "other";
}

std::string lower(std::string s) {
    std::transform(s.begin(), s.end(), s.begin(),
                   [](unsigned char c) { return static_cast<char>(std::tolower(c)); });
    return s;
}

// PoCL keeps compiled kernels in $POCL_CACHE_DIR, else $XDG_CACHE_HOME/pocl, else
// $HOME/.cache/pocl; its cache is what makes the second run of kdray skip the ~1 s compile. Where
// that default is not writable (a sandbox with a read-only home), point it at the temporary
// directory instead of letting every run recompile. Other implementations ignore the variable.
void ensure_writable_kernel_cache() {
    if (std::getenv("POCL_CACHE_DIR")) return;
    std::filesystem::path base;
    if (const char* xdg = std::getenv("XDG_CACHE_HOME"); xdg && *xdg)
        base = xdg;
    else if (const char* home = std::getenv("HOME"); home && *home)
        base = std::filesystem::path(home) / ".cache";
    std::error_code ec;
    if (!base.empty()) {
        std::filesystem::create_directories(base, ec);
        if (!ec && ::access(base.c_str(), W_OK) == 0) return;
    }
    const auto fallback = std::filesystem::temp_directory_path(ec) / "kdray-pocl-cache";
    if (ec) return;
    std::filesystem::create_directories(fallback, ec);
    if (!ec) ::setenv("POCL_CACHE_DIR", fallback.c_str(), 0);
}

struct FoundDevice {
    cl::Device device;
    ClDeviceInfo info;
};

std::vector<FoundDevice> find_devices() {
    ensure_writable_kernel_cache();
    ensure_open_file_limit();
    ask_cpu_driver_to_pin_threads();
    std::vector<cl::Platform> platforms;
    // The ICD loader reports "no platform" as an error code (CL_PLATFORM_NOT_FOUND_KHR) rather than
    // an empty list.
    // With CL_HPP_ENABLE_EXCEPTIONS the bindings throw that code instead of returning it.
    cl_int status = CL_SUCCESS;
    try {
        status = cl::Platform::get(&platforms);
    } catch (const cl::Error& e) {
        status = e.err();
    }
    if (status != CL_SUCCESS || platforms.empty())
        throw Error(no_device_message(
            "no OpenCL platform found (clGetPlatformIDs: " + cl_error_name(status) + ")"));
    std::vector<FoundDevice> found;
    for (const cl::Platform& platform : platforms) {
        std::vector<cl::Device> devices;
        try {
            platform.getDevices(CL_DEVICE_TYPE_ALL, &devices);
        } catch (const cl::Error& e) {
            if (e.err() == CL_DEVICE_NOT_FOUND) continue;  // a platform with no device
            throw_cl_error("listing OpenCL devices", e.what(), e.err());
        }
        const std::string platform_name = platform.getInfo<CL_PLATFORM_NAME>();
        for (cl::Device& device : devices) {
            ClDeviceInfo info;
            info.index = static_cast<int>(found.size());
            info.platform = platform_name;
            info.name = device.getInfo<CL_DEVICE_NAME>();
            info.vendor = device.getInfo<CL_DEVICE_VENDOR>();
            info.type = device_type_name(device.getInfo<CL_DEVICE_TYPE>());
            info.version = device.getInfo<CL_DEVICE_VERSION>();
            info.compute_units = device.getInfo<CL_DEVICE_MAX_COMPUTE_UNITS>();
            info.global_mem_bytes = device.getInfo<CL_DEVICE_GLOBAL_MEM_SIZE>();
            info.max_alloc_bytes = device.getInfo<CL_DEVICE_MAX_MEM_ALLOC_SIZE>();
            // Asked without the bindings' exceptions: a device that cannot answer has no fp64.
            cl_device_fp_config fp64 = 0;
            info.fp64 = clGetDeviceInfo(device(), CL_DEVICE_DOUBLE_FP_CONFIG, sizeof(fp64), &fp64,
                                        nullptr) == CL_SUCCESS &&
                        fp64 != 0;
            // The C++ bindings keep the terminating NUL of string queries.
            for (std::string* s : {&info.name, &info.vendor, &info.version})
                while (!s->empty() && s->back() == '\0') s->pop_back();
            info.threads_pinned = pins_its_threads(info);
            found.push_back({device, info});
        }
    }
    return found;
}

bool is_index(const std::string& s) {
    return !s.empty() && s.size() < 6 &&
           std::all_of(s.begin(), s.end(), [](unsigned char c) { return std::isdigit(c); });
}

std::vector<ClDeviceInfo> infos(const std::vector<FoundDevice>& found) {
    std::vector<ClDeviceInfo> out;
    for (const FoundDevice& f : found) out.push_back(f.info);
    return out;
}

}  // namespace

std::vector<ClDeviceInfo> list_cl_devices() {
    return with_cl_context("listing OpenCL devices", [] { return infos(find_devices()); });
}

std::string describe_cl_devices(const std::vector<ClDeviceInfo>& devices) {
    std::string s;
    for (const ClDeviceInfo& d : devices)
        s += (s.empty() ? "" : "; ") + std::to_string(d.index) + ": " + d.name + " (" + d.vendor +
             ", " + d.type + ", " + d.version + ")";
    return s;
}

/* Every buffer allocate() makes is in the ledger until the runtime deletes it. The runtime says
 * so through a destructor callback (clSetMemObjectDestructorCallback, OpenCL 1.1), which may come
 * from its own thread and after the ClDevice is gone, so each callback holds the ledger. Why a
 * ledger: kdray's cl_mem objects are allocated inside the OpenCL runtime, and LeakSanitizer's fast
 * unwinder stops at the runtime's first frame (PoCL has no frame pointers; the slow unwinder
 * made the sanitizer run 3-8x slower), so its suppressions, which must hide PoCL's own memory
 * (16 bytes lost per kernel compile on a cold cache), hid a leaked buffer of kdray's as well. */
struct BufferLedger {
    std::mutex mutex;
    std::condition_variable emptied;  // notified when the last live buffer is deleted
    std::map<cl_mem, std::string> live;
};

namespace {

void CL_CALLBACK forget_deleted_buffer(cl_mem mem, void* user_data) {
    // The callback's own reference to the ledger, which may outlive the ClDevice.
    std::unique_ptr<std::shared_ptr<BufferLedger>> ledger(
        static_cast<std::shared_ptr<BufferLedger>*>(user_data));
    const std::lock_guard<std::mutex> lock((*ledger)->mutex);
    (*ledger)->live.erase(mem);
    if ((*ledger)->live.empty()) (*ledger)->emptied.notify_all();
}

}  // namespace

ClDevice::ClDevice(const std::string& selector)
    : ledger_(std::make_shared<BufferLedger>()), program_cache_(std::make_unique<ProgramCache>()) {
    with_cl_context("opening OpenCL device '" + selector + "'", [&] {
        std::vector<FoundDevice> found = find_devices();
        if (found.empty())
            throw Error(no_device_message("OpenCL platforms exist but have no devices"));
        const FoundDevice* chosen = nullptr;
        if (selector.empty()) {
            for (const FoundDevice& f : found)
                if (f.info.type == "GPU") {
                    chosen = &f;
                    break;
                }
            if (!chosen) chosen = &found.front();
        } else if (const std::string type = lower(selector);
                   type == "gpu" || type == "cpu" || type == "accelerator") {
            // A device type, as pbrt's --gpu and Blender's Cycles device setting choose; a name
            // containing "gpu" or "cpu" is still reachable by more of its name.
            for (const FoundDevice& f : found)
                if (lower(f.info.type) == type) {
                    chosen = &f;
                    break;
                }
            if (!chosen)
                throw Error("no OpenCL device of type " +
                            device_type_name(type == "gpu"   ? CL_DEVICE_TYPE_GPU
                                             : type == "cpu" ? CL_DEVICE_TYPE_CPU
                                                             : CL_DEVICE_TYPE_ACCELERATOR) +
                            " here; the devices are " + describe_cl_devices(infos(found)));
        } else if (is_index(selector)) {
            const std::size_t index = std::stoul(selector);
            if (index < found.size()) chosen = &found[index];
        } else {
            for (const FoundDevice& f : found)
                if (lower(f.info.name).find(lower(selector)) != std::string::npos) {
                    chosen = &f;
                    break;
                }
        }
        if (!chosen)
            throw Error("no OpenCL device matches '" + selector +
                        "' (give an index or a part of the name); the devices are " +
                        describe_cl_devices(infos(found)));
        device_ = chosen->device;
        info_ = chosen->info;
        context_ = cl::Context(device_);
        queue_ = cl::CommandQueue(context_, device_);  // in order, no profiling
    });
    buffer_pool_ = BufferPool(std::min<std::uint64_t>(info_.global_mem_bytes / 8, 1ull << 30));
}

cl::Buffer ClDevice::allocate(std::size_t bytes, const std::string& what) const {
    const std::size_t size = std::max<std::size_t>(bytes, 1);
    if (size > info_.max_alloc_bytes)
        throw Error(what + ": " + std::to_string(size) + " bytes exceed the device's largest " +
                    "allocation (CL_DEVICE_MAX_MEM_ALLOC_SIZE = " +
                    std::to_string(info_.max_alloc_bytes) + " bytes) on " + info_.name);
    cl_int status = CL_SUCCESS;
    cl_mem mem = clCreateBuffer(context_(), CL_MEM_READ_WRITE, size, nullptr, &status);
    if (status != CL_SUCCESS) throw_cl_allocation_error(what, size, status);
    allocated_bytes_ += size;
    cl::Buffer buffer(mem);  // takes ownership of the one reference clCreateBuffer returned
    {
        const std::lock_guard<std::mutex> lock(ledger_->mutex);
        ledger_->live.emplace(mem, what);
    }
    auto callback_ledger = std::make_unique<std::shared_ptr<BufferLedger>>(ledger_);
    status = clSetMemObjectDestructorCallback(mem, forget_deleted_buffer, callback_ledger.get());
    if (status == CL_SUCCESS) {
        callback_ledger.release();  // forget_deleted_buffer deletes it
    } else {
        const std::lock_guard<std::mutex> lock(ledger_->mutex);
        ledger_->live.erase(mem);  // a runtime without the callback: the buffer goes unrecorded
    }
    return buffer;
}

void ClDevice::read(const cl::Buffer& buffer, std::size_t offset, std::size_t bytes, void* to,
                    const std::string& what) {
    ++traffic_.syncs, ++traffic_.transfers;
    with_cl_context(what, [&] { queue_.enqueueReadBuffer(buffer, CL_TRUE, offset, bytes, to); });
}

void ClDevice::write(const cl::Buffer& buffer, std::size_t offset, std::size_t bytes,
                     const void* from, const std::string& what) {
    ++traffic_.syncs, ++traffic_.transfers;
    with_cl_context(what, [&] { queue_.enqueueWriteBuffer(buffer, CL_TRUE, offset, bytes, from); });
}

void ClDevice::write_mapped(const cl::Buffer& buffer, std::size_t bytes,
                            const std::function<void(unsigned char* base)>& fill,
                            const std::string& what) {
    if (bytes == 0) return;
    ++traffic_.syncs, ++traffic_.transfers;
    with_cl_context(what, [&] {
        auto* base = static_cast<unsigned char*>(
            queue_.enqueueMapBuffer(buffer, CL_TRUE, CL_MAP_WRITE_INVALIDATE_REGION, 0, bytes));
        fill(base);
        queue_.enqueueUnmapMemObject(buffer, base);
    });
}

void ClDevice::enqueue_read(const cl::Buffer& buffer, std::size_t offset, std::size_t bytes,
                            void* to, const std::string& what) {
    ++traffic_.transfers;
    with_cl_context(what, [&] { queue_.enqueueReadBuffer(buffer, CL_FALSE, offset, bytes, to); });
}

void ClDevice::enqueue_write(const cl::Buffer& buffer, std::size_t offset, std::size_t bytes,
                             const void* from, const std::string& what) {
    ++traffic_.transfers;
    with_cl_context(what,
                    [&] { queue_.enqueueWriteBuffer(buffer, CL_FALSE, offset, bytes, from); });
}

void ClDevice::finish(const std::string& what) {
    ++traffic_.syncs;
    with_cl_context(what, [&] { queue_.finish(); });
}

void ClDevice::read_strided(const cl::Buffer& buffer, std::size_t offset, std::size_t stride,
                            std::size_t bytes, std::size_t count, void* to,
                            const std::string& what) {
    if (count == 0) return;
    ++traffic_.syncs, ++traffic_.transfers;
    with_cl_context(what, [&] {
        const cl::array<cl::size_type, 3> origin{offset, 0, 0}, host_origin{0, 0, 0},
            region{bytes, count, 1};
        queue_.enqueueReadBufferRect(buffer, CL_TRUE, origin, host_origin, region, stride,
                                     stride * count, bytes, bytes * count, to);
    });
}

void ClDevice::launch(cl::Kernel& kernel, const cl::NDRange& global, const cl::NDRange& local) {
    ++traffic_.launches;
    queue_.enqueueNDRangeKernel(kernel, cl::NullRange, global, local);
}

std::size_t ClDevice::group_1d(cl::Kernel& kernel, std::size_t preferred) {
    const auto key = std::make_pair(kernel(), preferred);
    const auto found = group_1d_.find(key);
    if (found != group_1d_.end()) return found->second.group;
    const std::size_t group = choose_group_1d(kernel.getInfo<CL_KERNEL_FUNCTION_NAME>(),
                                              query_kernel_limits(kernel, device_()), preferred);
    group_1d_.emplace(key, Group1d{kernel, group});
    return group;
}

std::vector<std::string> ClDevice::live_buffers() const {
    const std::lock_guard<std::mutex> lock(ledger_->mutex);
    std::vector<std::string> names;
    for (const auto& [mem, what] : ledger_->live) names.push_back(what);
    return names;
}

ClDevice::~ClDevice() {
    group_1d_.clear();       // kernels, released with the programs (before thread-local exit)
    program_cache_.reset();  // its kernels may hold the last references to buffers
    buffer_pool_.clear();
#ifdef KDRAY_SANITIZE
    // A runtime may delete a buffer only once the commands that use it are done.
    try {
        queue_.finish();
    } catch (const cl::Error&) {
        return;  // a failed device: nothing can be said of its buffers
    }
    // Even after finish() PoCL drops a finished command's references to its buffers on its own
    // threads, so the last deletions can come a little later: the sanitizer run's `build
    // --small-stage` test saw 9 of the builder's buffers "leak" in about 1 run of 3 with two tests
    // at a time. A leaked buffer is never deleted; a released one is, within milliseconds.
    {
        std::unique_lock<std::mutex> lock(ledger_->mutex);
        ledger_->emptied.wait_for(lock, std::chrono::seconds(5),
                                  [&] { return ledger_->live.empty(); });
    }
    const std::vector<std::string> live = live_buffers();
    if (live.empty()) return;
    std::string names;
    for (const std::string& name : live) names += (names.empty() ? "" : ", ") + name;
    std::fprintf(stderr,
                 "kdray: leak: %zu OpenCL buffer(s) never released when the device closed: %s\n",
                 live.size(), names.c_str());
    std::_Exit(23);  // LeakSanitizer's exit status
#endif
}

}  // namespace kdray
