// devices.h — the OpenCL platforms and devices kdray can use, as JSON for `kdray stats`.
#pragma once

#include <nlohmann/json.hpp>

namespace kdray::cli {

/// One entry per device (index, name, platform, type, ...); an empty array with an "error"
/// entry when there is no OpenCL platform at all.
nlohmann::json list_devices_json();

}  // namespace kdray::cli
