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

}  // namespace kdray::cli
