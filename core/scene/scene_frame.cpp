#include "core/scene/scene_frame.h"

#include <cmath>
#include <sstream>

#include "core/error.h"

namespace kdray {

SceneFrame SceneFrame::fit(DVec3 lo, DVec3 hi, const std::string& name) {
    const double extent = std::max({hi.x - lo.x, hi.y - lo.y, hi.z - lo.z});
    if (!std::isfinite(extent)) {
        std::ostringstream message;
        message << name << ": the scene's extent overflows a double (its bounds span from "
                << std::max({-lo.x, -lo.y, -lo.z}) << " below to " << std::max({hi.x, hi.y, hi.z})
                << " above the origin)";
        throw Error(message.str());
    }
    SceneFrame frame;
    // A scene of one point (every triangle collapsed, never hit) has no scale to fit.
    if (!(extent > 0)) return frame;
    // extent = m * 2^e with m in [0.5, 1): scaled by 2^-e the extent lies in [0.5, 1).
    int e = 0;
    std::frexp(extent, &e);
    // 2^-e overflows a double below 2^-1023; such a scene's triangles are all but points anyway.
    if (e < -1000) {
        std::ostringstream message;
        message << name << ": the scene's extent (" << extent
                << ") is too small for kdray to scale to float precision";
        throw Error(message.str());
    }
    frame.scale = std::ldexp(1.0, -e);
    const double cell = std::ldexp(1.0, e);
    // The centre rounded to a whole number of cells: 0 for a scene within half a cell of the
    // origin, so that it is only scaled, which is exact.
    for (int a = 0; a < 3; ++a) frame.offset[a] = std::round(0.5 * (lo[a] + hi[a]) / cell) * cell;
    return frame;
}

}  // namespace kdray
