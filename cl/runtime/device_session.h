// device_session.h — the one OpenCL device a kdray run uses, opened on first need (a run with the
// reference builder and tracer never touches OpenCL) and shared by the builder and the tracer.
#pragma once

#include <functional>
#include <memory>
#include <string>
#include <utility>

#include "cl/runtime/device.h"

namespace kdray {

class DeviceSession {
  public:
    explicit DeviceSession(std::string selector) : selector_(std::move(selector)) {}

    ClDevice& device() {
        if (!device_) {
            device_ = std::make_unique<ClDevice>(selector_);
            if (opened) opened(*device_);
        }
        return *device_;
    }
    bool is_open() const { return device_ != nullptr; }

    /// Called once, when the device opens: the command line says there which device runs when
    /// it chose it for the user (cli/devices.h).
    std::function<void(const ClDevice&)> opened;

  private:
    std::string selector_;
    std::unique_ptr<ClDevice> device_;
};

}  // namespace kdray
