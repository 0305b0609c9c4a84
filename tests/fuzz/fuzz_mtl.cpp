// fuzz_mtl.cpp — libFuzzer target for the MTL pre-scan (prepare_mtl) and, behind it,
// tinyobjloader's LoadMtl on the text the pre-scan returns, as the loader runs them. kdray::Error
// is the expected outcome of a bad file; a sanitizer report, another exception, or an accepted file
// whose materials hold a value the pre-scan promises to reject is a bug.
#include <tiny_obj_loader.h>

#include <cmath>
#include <cstdint>
#include <cstdio>
#include <cstdlib>
#include <map>
#include <sstream>
#include <string>
#include <vector>

#include "core/error.h"
#include "core/scene/mtl_prepare.h"

namespace {

[[noreturn]] void bug(const char* what) {
    std::fprintf(stderr, "fuzz_mtl: invariant broken: %s\n", what);
    std::abort();
}

void check_colour(const tinyobj::real_t* c) {
    for (int k = 0; k < 3; ++k)
        if (!std::isfinite(c[k]) || c[k] < 0) bug("accepted a non-finite or negative colour");
}

}  // namespace

extern "C" int LLVMFuzzerTestOneInput(const std::uint8_t* data, std::size_t size) {
    std::string text;
    try {
        text = kdray::prepare_mtl({reinterpret_cast<const char*>(data), size}, "fuzz.mtl");
    } catch (const kdray::Error&) {
        return 0;
    }
    std::istringstream in(text);
    std::map<std::string, int> names;
    std::vector<tinyobj::material_t> materials;
    std::string warn, err;
    tinyobj::LoadMtl(&names, &materials, &in, &warn, &err);
    for (const tinyobj::material_t& m : materials) {
        check_colour(m.ambient);
        check_colour(m.diffuse);
        check_colour(m.specular);
        check_colour(m.emission);
        check_colour(m.transmittance);
        if (!std::isfinite(m.shininess) || m.shininess < 0) bug("accepted a bad Ns");
        if (!std::isfinite(m.ior) || m.ior < 0) bug("accepted a bad Ni");
        if (!(m.dissolve >= 0 && m.dissolve <= 1)) bug("accepted a d or Tr outside [0, 1]");
    }
    return 0;
}
