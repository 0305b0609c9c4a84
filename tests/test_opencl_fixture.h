// test_opencl_fixture.h — the one OpenCL device every OpenCL test in the process shares: opening a
// context and building programs is the slow part (a cold PoCL compile is about a second), so it
// happens once, and the program cache keeps each program built once.
#pragma once

#include "cl/runtime/device.h"

namespace kdray::test {

/// The default device (first GPU, else first device), opened on first use. These tests never
/// skip: CI installs PoCL, and a missing platform is a failure with the install hint in it.
inline ClDevice& opencl_test_device() {
    static ClDevice device("");
    return device;
}

}  // namespace kdray::test
