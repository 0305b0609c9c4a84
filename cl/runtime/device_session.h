// device_session.h — the one OpenCL device a kdray run uses, opened on first need (a run with the
// reference builder and tracer never touches OpenCL) and shared by the builder and the tracer.
#pragma once

#include <memory>
#include <string>
#include <utility>

#include "cl/runtime/device.h"

namespace kdray {

class DeviceSession {
  public:
    explicit DeviceSession(std::string selector) : selector_(std::move(selector)) {}

    ClDevice& device() {
        if (!device_) device_ = std::make_unique<ClDevice>(selector_);
        return *device_;
    }
    bool is_open() const { return device_ != nullptr; }

  private:
    std::string selector_;
    std::unique_ptr<ClDevice> device_;
};

}  // namespace kdray
