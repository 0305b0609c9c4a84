// kdray_programs — prints, as JSON, every OpenCL program kdray can build (cl/program_catalogue.h):
// its kernel file, its full build options and its embedded source (shared headers inlined, with
// #line markers). A maintenance tool: scripts/gpu_compile.py compiles its output for NVIDIA and
// AMD targets with clang and libclc.
//
//   kdray_programs [--device gpu|cpu] [--no-correctly-rounded]
#include <cstring>
#include <iostream>
#include <string>

#include <nlohmann/json.hpp>

#include "cl/program_catalogue.h"
#include "cl/runtime/embedded_kernels.h"

int main(int argc, char** argv) {
    bool cpu = false, correctly_rounded = true;
    for (int i = 1; i < argc; ++i) {
        const std::string arg = argv[i];
        if (arg == "--device" && i + 1 < argc &&
            (!std::strcmp(argv[i + 1], "gpu") || !std::strcmp(argv[i + 1], "cpu")))
            cpu = std::string(argv[++i]) == "cpu";
        else if (arg == "--no-correctly-rounded")
            correctly_rounded = false;
        else {
            std::cerr << "usage: kdray_programs [--device gpu|cpu] [--no-correctly-rounded]\n";
            return 2;
        }
    }
    nlohmann::json out;
    out["device"] = cpu ? "cpu" : "gpu";
    out["programs"] = nlohmann::json::array();
    for (const kdray::ProgramSpec& p : kdray::buildable_programs(cpu, correctly_rounded))
        out["programs"].push_back({{"file", p.file},
                                   {"options", p.options},
                                   {"source", std::string(kdray::embedded_kernel_source(p.file))}});
    std::cout << out.dump() << "\n";
    return 0;
}
