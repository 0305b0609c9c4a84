// devices.h — the OpenCL platforms and devices kdray can use, as JSON for `kdray stats`, and the
// line that says when kdray runs on a CPU device because there is no GPU.
#pragma once

#include <string>

#include <nlohmann/json.hpp>

#include "cl/runtime/device_session.h"

namespace kdray::cli {

/// One entry per device (index, name, platform, type, ...); an empty array with an "error"
/// entry when there is no OpenCL platform at all.
nlohmann::json list_devices_json();

/// When `session` opens a device that is not a GPU although `selector` (--device) asked for none,
/// one info line says so: the device's name alone did not tell a user that no GPU was found.
void say_when_no_gpu(DeviceSession& session, const std::string& selector);

/// `--packets on` on a device that is not a CPU: the packets run there as asked, but they are
/// built for a CPU's vector registers, so say what they cost (docs/gpu-kernels.md's budgets).
void say_packets_off_cpu(DeviceSession& session);

}  // namespace kdray::cli
