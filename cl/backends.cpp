#include "cl/backends.h"

#include "cl/builder/opencl_tree_builder.h"
#include "cl/renderer/opencl_tracer.h"
#include "core/error.h"
#include "core/render/reference_tracer.h"
#include "core/tree/reference_builder.h"

namespace kdray {

std::unique_ptr<TreeBuilder> make_tree_builder(const std::string& name, const BuildParams& params,
                                               DeviceSession& session) {
    if (name == "opencl") return std::make_unique<OpenClTreeBuilder>(session, params);
    if (name == "reference") return std::make_unique<ReferenceTreeBuilder>(params);
    throw UsageError("unknown builder '" + name + "' (opencl or reference)");
}

std::unique_ptr<Tracer> make_tracer(const std::string& name, int threads, DeviceSession& session) {
    if (name == "opencl") return std::make_unique<OpenClTracer>(session.device());
    if (name == "reference") return std::make_unique<ReferenceTracer>(threads);
    throw UsageError("unknown tracer '" + name + "' (opencl or reference)");
}

}  // namespace kdray
