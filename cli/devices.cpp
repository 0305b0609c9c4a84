#include "cli/devices.h"

#include "cl/runtime/device.h"
#include "core/error.h"

namespace kdray::cli {

nlohmann::json list_devices_json() {
    std::vector<ClDeviceInfo> devices;
    try {
        devices = list_cl_devices();
    } catch (const Error& e) {
        return nlohmann::json::array({{{"error", e.what()}}});
    }
    nlohmann::json out = nlohmann::json::array();
    for (const ClDeviceInfo& d : devices)
        out.push_back({{"index", d.index},
                       {"name", d.name},
                       {"platform", d.platform},
                       {"vendor", d.vendor},
                       {"type", d.type},
                       {"version", d.version},
                       {"compute_units", d.compute_units},
                       {"global_mem_bytes", d.global_mem_bytes},
                       {"max_alloc_bytes", d.max_alloc_bytes}});
    return out;
}

}  // namespace kdray::cli
