#include "cli/devices.h"

#include "cl/runtime/device.h"
#include "core/error.h"

#include <spdlog/spdlog.h>

namespace kdray::cli {

nlohmann::json list_devices_json() {
    std::vector<ClDeviceInfo> devices;
    try {
        devices = list_cl_devices();
    } catch (const Error& e) {
        return nlohmann::json::array({{{"error", e.what()}}});
    }
    nlohmann::json out = nlohmann::json::array();
    for (const ClDeviceInfo& d : devices) {
        out.push_back({{"index", d.index},
                       {"name", d.name},
                       {"platform", d.platform},
                       {"vendor", d.vendor},
                       {"type", d.type},
                       {"version", d.version},
                       {"compute_units", d.compute_units},
                       {"global_mem_bytes", d.global_mem_bytes},
                       {"max_alloc_bytes", d.max_alloc_bytes}});
        if (d.type == "CPU") out.back()["threads_pinned"] = d.threads_pinned;
    }
    return out;
}

void say_when_no_gpu(DeviceSession& session, const std::string& selector) {
    if (!selector.empty()) return;
    session.opened = [](const ClDevice& device) {
        if (device.is_gpu()) return;
        spdlog::info(
            "no OpenCL GPU found: kdray runs on the {} device '{}' ({}); `kdray stats` lists "
            "the devices",
            device.info().type, device.info().name, device.info().platform);
    };
}

void say_packets_off_cpu(DeviceSession& session) {
    session.opened = [before = session.opened](const ClDevice& device) {
        if (before) before(device);
        if (device.is_cpu()) return;
        // Measured by scripts/gpu_compile.py on the 8-lane packet programs: 17,152-17,728 bytes
        // of private memory per work-item for nvptx, 19,040-19,776 for amdgcn, against a budget
        // of 4096; a GPU spills them to global memory.
        spdlog::warn(
            "--packets on: packets are a CPU path (a work-item traces 8 rays in vector "
            "registers, about 17-20 KB of private memory per work-item on GPUs); on the {} "
            "device '{}' they run, that memory spilled, where --packets auto would trace one "
            "ray per work-item",
            device.info().type, device.info().name);
    };
}

}  // namespace kdray::cli
