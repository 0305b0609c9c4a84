// backends.h — the one place a builder and a tracer are chosen by name ("opencl" or
// "reference", as the command line says): the factory knows core's reference implementations
// and cl/'s OpenCL ones, and hands back core's interfaces. The OpenCL ones share the run's
// DeviceSession.
#pragma once

#include <memory>
#include <string>

#include "cl/runtime/device_session.h"
#include "core/render/tracer.h"
#include "core/tree/tree.h"
#include "core/tree/tree_builder.h"

namespace kdray {

/// The builder called `name`. The OpenCL builder opens the device on first need.
std::unique_ptr<TreeBuilder> make_tree_builder(const std::string& name, const BuildParams& params,
                                               DeviceSession& session);

/// The tracer called `name`; the reference tracer runs on `threads` host threads (0: all). The
/// OpenCL tracer opens the device now, so that a bad device fails before any output is made.
std::unique_ptr<Tracer> make_tracer(const std::string& name, int threads, DeviceSession& session);

}  // namespace kdray
